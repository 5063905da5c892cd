"""What Maxwell arms cost: each shipped solid with arms against its Kelvin-Voigt counterpart
(issue 10: "rheologies with arms cost at most 3x Kelvin-Voigt at the same rtol").

    python benchmarks/arms_vs_kelvin_voigt.py [--rtol 1e-4 1e-6] [--repeat 3]

The counterpart keeps the scene and replaces the solid by the Kelvin-Voigt one with the same
relaxed modulus and the arms' low-frequency viscosity, ``G = G_inf``, ``eta = sum_i G_i
tau_i``: the same long-time response, without memory. Both run to separation through
``simulate`` at each rtol; warm medians of ``--repeat`` runs, single thread, and the ratio.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
from pathlib import Path  # noqa: E402

from common import machine_summary, time_call  # noqa: E402
from pulloff import solvers  # noqa: E402
from pulloff.io.scene_file import load_scene  # noqa: E402

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
WITH_ARMS = ("sls_finite_punch", "prony_external")


def kelvin_voigt_counterpart(scene) -> str:
    """The override that swaps the solid for ``G = G_inf``, ``eta = sum G_i tau_i``."""
    spectrum = scene.material.spectrum()
    eta = sum(G * tau for G, tau in spectrum.arms)
    return f"material={{kind: kelvin_voigt, G: {spectrum.G_inf!r}, eta: {eta!r}}}"


def timed(scene, repeat):
    """``(median seconds, result)`` of warm runs (:func:`common.time_call`)."""
    solvers.simulate(scene)  # warm: compile or load numba's cache
    timing, result = time_call(lambda: solvers.simulate(scene), min_repeats=repeat,
                               min_total=0.0)
    return timing.median, result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rtol", type=float, nargs="+", default=[1e-4, 1e-6])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(machine_summary())
    print("(equal rtol, not equal achieved accuracy: the estimates are printed beside)")
    print(f"{'config':<18} {'rtol':>6} {'arms [s]':>9} {'estimate':>9} {'KV [s]':>8} "
          f"{'estimate':>9} {'ratio':>6}  counterpart")
    for name in WITH_ARMS:
        path = CONFIGS / f"{name}.yaml"
        swap = kelvin_voigt_counterpart(load_scene(path))
        for rtol in args.rtol:
            arms, with_arms = timed(load_scene(path, overrides=[f"numerics.rtol={rtol}"]),
                                    args.repeat)
            kv, without = timed(load_scene(path, overrides=[f"numerics.rtol={rtol}", swap]),
                                args.repeat)
            if not (with_arms.t_separation > 0.0 and without.t_separation > 0.0):
                raise SystemExit(f"{name} at rtol {rtol:g}: a run did not separate")
            print(f"{name:<18} {rtol:6.0e} {arms:9.3f} {with_arms.error_estimate:9.1e} "
                  f"{kv:8.3f} {without.error_estimate:9.1e} {arms / kv:6.2f}  {swap}",
                  flush=True)


if __name__ == "__main__":
    main()
