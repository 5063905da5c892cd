"""The seed scene pulled to separation: its peak force against its onset force, converged
(issue 10: "confirming or refuting the 10x"), and what 1e-6 costs (the goal: 1 s).

    python benchmarks/seed_to_separation.py [--levels 16 32 64 128 256] [--rtol 1e-3 1e-6]

``configs/seed_flat_punch.yaml`` with ``model.until = separation``: the moving-edge solver's
single levels at fixed ``n`` and ``simulate`` at each rtol (the extrapolated answer and its
estimate), against the independent moving-edge reference (``tests/data/edge_reference.json``,
a history quadrature converged to ~1e-10). Warm, single-threaded; one run per line (the
slowest take seconds, their spread on this machine is ~20 %). Writes
``benchmarks/results/seed_to_separation.txt``.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from pulloff import solvers  # noqa: E402
from pulloff.io.scene_file import load_scene  # noqa: E402
from pulloff.solvers import contact  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results" / "seed_to_separation.txt"
REFERENCE = json.loads((ROOT / "tests" / "data" / "edge_reference.json").read_text())[
    "seed_flat_punch"]


def scene(rtol=1e-3):
    return load_scene(ROOT / "configs" / "seed_flat_punch.yaml",
                      overrides=["model.until=separation", f"numerics.rtol={rtol}"])


def rel(value, exact):
    return (value - exact) / exact


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", type=int, nargs="+", default=[16, 32, 64, 128, 256])
    ap.add_argument("--rtol", type=float, nargs="+", default=[1e-3, 1e-4, 1e-5, 1e-6])
    args = ap.parse_args(argv)
    ref_ratio = REFERENCE["F_peak_total"] / REFERENCE["F_onset_total"]
    lines = [f"seed_flat_punch to separation; reference: F_peak_total / F_onset_total = "
             f"{ref_ratio:.8f}, t_separation = {REFERENCE['t_separation']:.9g} s, "
             f"F_peak_total = {REFERENCE['F_peak_total']:.9g} N",
             "", "single levels (relative errors against the reference):",
             f"{'n':>5} {'steps':>6} {'time [s]':>9} {'peak/onset':>11} {'ratio err':>10} "
             f"{'t_sep err':>10} {'F_peak err':>10}"]

    def say(line):
        print(line, flush=True)
        lines.append(line)

    for line in lines:
        print(line)
    contact.run_level(scene(), 8)  # compile or load the cache outside the timings
    for n in args.levels:
        start = time.perf_counter()
        level = contact.run_level(scene(), n)
        took = time.perf_counter() - start
        s = level.summary
        ratio = s["F_peak_total"] / s["F_total_detach"]
        say(f"{n:5d} {len(level.rows) - 1:6d} {took:9.2f} {ratio:11.7f} "
            f"{rel(ratio, ref_ratio):+10.2e} {rel(s['t_separation'], REFERENCE['t_separation']):+10.2e} "
            f"{rel(s['F_peak_total'], REFERENCE['F_peak_total']):+10.2e}")
    say("")
    say("simulate (the extrapolated answer; goal: error <= 1e-6 within 1 s):")
    say(f"{'rtol':>6} {'time [s]':>9} {'peak/onset':>11} {'ratio err':>10} {'worst err':>10} "
        f"{'estimate':>9}")
    for rtol in args.rtol:
        start = time.perf_counter()
        r = solvers.simulate(scene(rtol))
        took = time.perf_counter() - start
        ratio = r.F_peak_total / r.F_total_detach
        worst = max(abs(rel(r.t_separation, REFERENCE["t_separation"])),
                    abs(rel(r.F_peak_total, REFERENCE["F_peak_total"])),
                    abs(rel(r.t_detach, REFERENCE["t_onset"])),
                    abs(rel(r.F_total_detach, REFERENCE["F_onset_total"])))
        say(f"{rtol:6.0e} {took:9.2f} {ratio:11.7f} {rel(ratio, ref_ratio):+10.2e} "
            f"{worst:10.1e} {r.error_estimate:9.1e}")
    RESULTS.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
