"""The flat punch to separation by quadrature (the default for rigid pulls since the
eighteenth session) against the moving-edge reference and the contact stepper, warm, one
thread.

    python benchmarks/edge_quadrature.py [--rtol 1e-4 1e-6] [--repeat 3] [--stepper]
    python benchmarks/edge_quadrature.py --work-precision

``--work-precision``: single marches (no check run) at tolerances 1e-3 .. 1e-7 on the five
shipped pulls to separation and the compliant machine's: error against the reference and
warm time, the figure
``results/work_precision_edge.png`` with the fitted ``time ~ error^x`` and cost against the
history's node count (``time ~ nodes^y``; the memory makes every step integrate the whole
history, so y near 2 is expected).

For each scene of ``tests/data/edge_reference.json`` (the shipped moving-edge configs, four at
other speeds, and the compliant machine's to separation behind 100, 10 and 1 N/m): the solver
that ran it, the median warm time
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
    # through machine springs (since the nineteenth session)
    "compliant_machine": ("compliant_machine", []),
    "compliant_machine_k10": ("compliant_machine", ["loading.machine_stiffness=10"]),
    "compliant_machine_k1": ("compliant_machine", ["loading.machine_stiffness=1"]),
    # faces at their strength limit before the rim opens (since the twenty-second session)
    "kv_face_gone_at_start": ("separation_kv", ["geometry.cohesive_zone=internal",
                                                "loading.v=2e-2", "adhesion.sigma_c=1e6"]),
    "finite_punch_face": ("finite_punch_internal", ["loading.v=2e-4", "adhesion.sigma_c=3.5e5"]),
    "sls_face_fold": ("sls_finite_punch", ["geometry.cohesive_zone=internal", "loading.v=2.7e-4",
                                           "adhesion.sigma_c=1.1e6"]),
    "sls_face_released": ("sls_finite_punch", ["geometry.cohesive_zone=internal",
                                               "loading.v=2e-2", "adhesion.sigma_c=6e5"]),
    "prony_face": ("prony_external", ["geometry.cohesive_zone=internal", "loading.v=4e-4",
                                      "adhesion.sigma_c=1e6"]),
}
OUTPUTS = {"t_detach": "t_onset", "F_total_detach": "F_onset_total",
           "t_separation": "t_separation", "F_peak_total": "F_peak_total",
           "F_peak_contact": "F_peak_contact"}


def relative_error(value: float, ref: dict, name: str) -> float:
    """Against the reference's value, or where that is 0 (a face bonded beyond its strength
    at t = 0 detaches then, with no contact force) against its separation time or peak force."""
    scale = ref[name] or ref["t_separation" if name.startswith("t_") else "F_peak_total"]
    return abs(value - ref[name]) / abs(scale)


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
    error = max(relative_error(res.summary[ours], ref, theirs) for ours, theirs in OUTPUTS.items())
    return dict(solver=res.summary["solver"], first=first, median=statistics.median(times),
                spread=(min(times), max(times)), error=error,
                estimate=res.summary["error_estimate"], notes=res.summary["notes"])


def work_precision(repeat: int):
    import math

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from pulloff.solvers import edge_quadrature as edge

    names = ["separation_kv", "finite_punch_internal", "sls_finite_punch", "prony_external",
             "seed_flat_punch", "compliant_machine"]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    lines = ["| scene | tol | nodes | warm time | worst error |", "|---|---|---|---|---|"]
    fits = []
    for name in names:
        config, overrides = SCENES[name]
        scene = load_scene(ROOT / "configs" / f"{config}.yaml",
                           overrides=overrides + ["model.until=separation"])
        model = edge.EdgeModel.from_scene(scene)
        ref = REFERENCE[name]
        rows = []
        for tol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7):
            edge.run_near(model, tol, math.inf)
            times = []
            for _ in range(repeat):
                start = time.perf_counter()
                run = edge.run_near(model, tol, math.inf)
                times.append(time.perf_counter() - start)
            summary = edge.summarise(run)
            error = max(relative_error(summary[ours], ref, theirs)
                        for ours, theirs in OUTPUTS.items())
            rows.append((run.n, statistics.median(times), error))
            lines.append(f"| {name} | {run.tol:g} | {run.n} | {rows[-1][1] * 1e3:.1f} ms | "
                         f"{error:.1e} |")
            print(lines[-1], flush=True)
        nodes, times, errors = (np.array(c) for c in zip(*rows))
        x = np.polyfit(np.log(errors), np.log(times), 1)[0]
        y = np.polyfit(np.log(nodes), np.log(times), 1)[0]
        fits.append(f"{name}: time ~ error^{x:.2f}, time ~ nodes^{y:.2f}")
        ax.loglog(times, errors, "o-", label=f"{name} (time ~ error^{x:.2f})")
    ax.set_xlabel("warm time of one march [s]")
    ax.set_ylabel("worst relative error vs reference")
    ax.set_title("pull to separation by quadrature")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(ROOT / "benchmarks" / "results" / "work_precision_edge.png", dpi=110)
    text = "\n".join(lines + [""] + fits) + "\n"
    (ROOT / "benchmarks" / "results" / "work_precision_edge.txt").write_text(text)
    print("\n".join(fits))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rtol", type=float, nargs="+", default=[1e-4, 1e-6])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--stepper", action="store_true")
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--work-precision", action="store_true")
    args = ap.parse_args(argv)
    if args.work_precision:
        work_precision(args.repeat)
        return
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
