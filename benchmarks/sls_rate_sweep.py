"""The pull-off force of a standard linear solid over pull speed: issue 10's target workload
(50 speeds of ``configs/sls_finite_punch.yaml`` in a few seconds on two cores).

    python benchmarks/sls_rate_sweep.py [--speeds 50] [--rtol 1e-4] [--workers 2]

Speeds log-spaced from 1e-7 to 1 m/s (the relaxed to the glassy limit), to separation. After
a warm-up that fills numba's disk cache, the whole sweep is timed (process start-up
included), then each speed alone in this process (warm) to show where the time goes. Prints
the peak force, the estimate, the notes and the time per speed.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from pulloff import solvers  # noqa: E402
from pulloff.io.scene_file import load_scene, override  # noqa: E402
from pulloff.studies.sweeps import Axis, sweep  # noqa: E402

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "sls_finite_punch.yaml"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speeds", type=int, default=50)
    ap.add_argument("--rtol", type=float, default=1e-4)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    scene = load_scene(CONFIG, overrides=[f"numerics.rtol={args.rtol}",
                                          "model.until=separation"])
    speeds = tuple(float(v) for v in np.logspace(-7, 0, args.speeds))
    solvers.simulate(scene)  # warm-up: compile or load the numba cache
    t0 = time.perf_counter()
    result = sweep(scene, [Axis("loading.v", speeds)], workers=args.workers)
    wall = time.perf_counter() - t0
    failed = int((result.table["status"] != "ok").sum())
    print(f"{len(speeds)} speeds, rtol {args.rtol:g}, {args.workers} processes: {wall:.1f} s "
          f"(target 5 s), {failed} failed", flush=True)
    print(f"{'v [m/s]':>9} {'time [s]':>9} {'F_peak_total [N]':>17} {'estimate':>9} notes")
    for v in speeds:
        start = time.perf_counter()
        res = solvers.simulate(override(scene, [f"loading.v={v}"]))
        took = time.perf_counter() - start
        print(f"{v:9.2e} {took:9.2f} {res.F_peak_total:17.6e} {res.error_estimate:9.1e} "
              f"{'; '.join(res.notes)}", flush=True)


if __name__ == "__main__":
    main()
