"""How honest the moving-edge (contact) solver's error estimate is: on the shipped flat-punch
scenes pulled to separation, and on a Kelvin-Voigt finite punch behind a 1 kN/m spring, the
reported ``error_estimate`` beside the true error against the independent moving-edge
reference (``tests/data/edge_reference.json``, itself converged to ~1e-9).

Usage::

    python benchmarks/contact_estimate.py [--rtol 1e-3 1e-4] [--only NAME ...]

One line per scene and rtol: warm wall time [s], the largest relative error over the scalars
the reference gives (onset time and force, separation time, peak forces), the estimate, and
their ratio (above 1: the estimate is honest). The estimate covers more outputs than these
(and judges small forces against a floor), so the ratio is an upper bound of its caution.
Single-threaded.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from pulloff import solvers  # noqa: E402
from pulloff.io.scene_file import load_scene, parse_scene  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = json.loads((ROOT / "tests" / "data" / "edge_reference.json").read_text())
#: (our summary name, the reference's name)
PAIRS = (("t_detach", "t_onset"), ("F_total_detach", "F_onset_total"),
         ("t_separation", "t_separation"), ("F_peak_total", "F_peak_total"),
         ("F_peak_contact", "F_peak_contact"))
SHIPPED = ("separation_kv", "sls_finite_punch", "finite_punch_internal", "prony_external",
           "seed_flat_punch")


def spring_scene(rtol):
    """The reference's ``finite_punch_spring_kv``: a strength-limited face behind 1 kN/m."""
    return parse_scene({
        "schema": 1, "name": "finite_punch_spring_kv",
        "geometry": {"kind": "flat_punch", "radius": 1e-5, "cohesive_zone": "internal"},
        "material": {"kind": "kelvin_voigt", "G": 1e6, "eta": 1e3},
        "adhesion": {"kind": "dugdale", "sigma_c": 1e6, "delta": 3e-6},
        "loading": {"kind": "constant_velocity", "v": 1e-3, "machine_stiffness": 1e3},
        "model": {"until": "detach"}, "numerics": {"rtol": rtol}})


#: The reference's scenes at other speeds: (config, overrides).
VARIANTS = {"separation_kv_v1e-2": ("separation_kv", ["loading.v=1e-2"]),
            "sls_finite_punch_v1e-4": ("sls_finite_punch", ["loading.v=1e-4"]),
            "sls_finite_punch_v1e-7": ("sls_finite_punch", ["loading.v=1e-7"]),
            "sls_external_v1e-2": ("sls_finite_punch", ["loading.v=1e-2",
                                                        "geometry.cohesive_zone=external"]),
            "compliant_machine_k10": ("compliant_machine", ["loading.machine_stiffness=10"]),
            "compliant_machine_k1": ("compliant_machine", ["loading.machine_stiffness=1"]),
            "sls_finite_punch_spring": ("sls_finite_punch",
                                        ["loading.machine_stiffness=100"])}


def scene(name, rtol):
    if name == "finite_punch_spring_kv":
        return spring_scene(rtol)
    config, extra = VARIANTS.get(name, (name, []))
    return load_scene(ROOT / "configs" / f"{config}.yaml",
                      overrides=[f"numerics.rtol={rtol}", "model.until=separation"] + extra)


def worst_error(result, ref):
    """Largest relative error over the scalars both report, its name, and the names the
    reference gives but the run does not (a run that stopped short of the separation once
    passed as exact: only its onset was compared)."""
    errors, missing = {}, []
    for ours, theirs in PAIRS:
        mine, exact = getattr(result, ours, math.nan), ref.get(theirs)
        if exact and mine is not None and math.isfinite(mine):
            errors[ours] = abs(mine - exact) / abs(exact)
        elif exact and math.isfinite(exact):
            missing.append(ours)
    name = max(errors, key=errors.get)
    return errors[name], name, missing


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rtol", type=float, nargs="+", default=[1e-3, 1e-4])
    ap.add_argument("--only", nargs="*", default=None,
                    help=f"scene names (default: {', '.join(SHIPPED)}, finite_punch_spring_kv; "
                         f"also {', '.join(VARIANTS)})")
    args = ap.parse_args(argv)
    names = args.only or list(SHIPPED) + ["finite_punch_spring_kv"]
    solvers.simulate(scene(names[0], 1e-2))  # compile outside the timings
    for rtol in args.rtol:
        for name in names:
            the_scene = scene(name, rtol)
            t0 = time.perf_counter()
            result = solvers.simulate(the_scene)
            wall = time.perf_counter() - t0
            error, worst, missing = worst_error(result, REFERENCE[name])
            if the_scene.model.until == "detach":  # (the spring scene: its onset only)
                missing = [m for m in missing if m.endswith("detach")]
            ratio = result.error_estimate / error if error > 0.0 else math.inf
            short = (f"  MISSING {', '.join(missing)} ({'; '.join(result.notes)})"
                     if missing else "")
            print(f"{name:24s} rtol {rtol:.0e}  {wall:6.2f} s  error {error:.1e} ({worst})  "
                  f"estimate {result.error_estimate:.1e}  ratio {ratio:.2f}{short}", flush=True)


if __name__ == "__main__":
    main()
