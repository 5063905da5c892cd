"""The flat punch to separation by quadrature (the default for rigid pulls since the
eighteenth session) against the moving-edge reference and the contact stepper, warm, one
thread.

    python benchmarks/edge_quadrature.py [--rtol 1e-4 1e-6] [--repeat 3] [--stepper]

For each scene of ``tests/data/edge_reference.json`` pulled by a rigid machine (the shipped
moving-edge configs and four at other speeds): the solver that ran it, the median warm time
(compiling done by a first run, reported apart), its worst relative error of the onset time
and force, the separation time and the two peak forces against the reference, and its
estimate. ``--stepper`` adds the contact stepper (``numerics.method: stepper``) beside it.
Results go to ``benchmarks/results/edge_quadrature.txt``.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from pulloff import solvers  # noqa: E402
from pulloff.io.scene_file import load_scene  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = json.loads((ROOT / "tests" / "data" / "edge_reference.json").read_text())
SCENES = {
    "separation_elastic": ("separation_elastic", []),
    "separation_kv": ("separation_kv", []),
    "finite_punch_internal": ("finite_punch_internal", []),
    "sls_finite_punch": ("sls_finite_punch", []),
    "prony_external": ("prony_external", []),
    "seed_flat_punch": ("seed_flat_punch", []),
    "separation_kv_v1e-2": ("separation_kv", ["loading.v=1e-2"]),
    "sls_external_v1e-2": ("sls_finite_punch", ["loading.v=1e-2",
                                                "geometry.cohesive_zone=external"]),
    "sls_finite_punch_v1e-4": ("sls_finite_punch", ["loading.v=1e-4"]),
    "sls_finite_punch_v1e-7": ("sls_finite_punch", ["loading.v=1e-7"]),
}
OUTPUTS = {"t_detach": "t_onset", "F_total_detach": "F_onset_total",
           "t_separation": "t_separation", "F_peak_total": "F_peak_total",
           "F_peak_contact": "F_peak_contact"}


def measure(name: str, rtol: float, repeat: int, method: str | None):
    config, overrides = SCENES[name]
    extra = [f"numerics.rtol={rtol}", "model.until=separation"]
    if method:
        extra.append(f"numerics.method={method}")
    scene = load_scene(ROOT / "configs" / f"{config}.yaml", overrides=overrides + extra)
    start = time.perf_counter()
    res = solvers.simulate(scene)
    first = time.perf_counter() - start
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        res = solvers.simulate(scene)
        times.append(time.perf_counter() - start)
    ref = REFERENCE[name]
    error = max(abs(res.summary[ours] / ref[theirs] - 1.0) for ours, theirs in OUTPUTS.items())
    return dict(solver=res.summary["solver"], first=first, median=statistics.median(times),
                spread=(min(times), max(times)), error=error,
                estimate=res.summary["error_estimate"], notes=res.summary["notes"])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rtol", type=float, nargs="+", default=[1e-4, 1e-6])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--stepper", action="store_true")
    ap.add_argument("--only", nargs="*", default=None)
    args = ap.parse_args(argv)
    lines = ["| scene | rtol | solver | warm median (min-max) | first run | worst error | "
             "estimate |", "|---|---|---|---|---|---|---|"]
    for name in args.only or SCENES:
        for rtol in args.rtol:
            for method in ([None, "stepper"] if args.stepper else [None]):
                m = measure(name, rtol, args.repeat, method)
                line = (f"| {name} | {rtol:g} | {m['solver']} | {m['median'] * 1e3:.1f} ms "
                        f"({m['spread'][0] * 1e3:.1f}-{m['spread'][1] * 1e3:.1f}) | "
                        f"{m['first']:.2f} s | {m['error']:.1e} | {m['estimate']:.1e} |")
                print(line, flush=True)
                lines.append(line)
    out = ROOT / "benchmarks" / "results" / "edge_quadrature.txt"
    if not args.only:
        out.write_text("\n".join(lines) + "\n")
        print(f"wrote {out}")


if __name__ == "__main__":
    main()
