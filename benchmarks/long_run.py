"""Long fixed-step runs: peak memory, time, the streamed history and the element budget's error.

    python benchmarks/long_run.py             # 1e7 steps of the seed scene (~3-4 min)
    python benchmarks/long_run.py --steps 1e6 # a quicker look
    python benchmarks/long_run.py --study     # budget error against the reference (~30 s)

The long run is ``pulloff run configs/seed_flat_punch.yaml`` with ``numerics.steps``,
``numerics.max_elements = 1024`` and ``output.every = 1`` (every step streamed to the file),
in a child process that reports its own peak resident memory; the same command at 1000 steps
gives the baseline (interpreter, numpy, numba, scipy, h5py, matplotlib). The study runs
scenes at 40000 steps through budgets of 128 to 2048 elements against the independent
quadrature reference (``pulloff.references.onset``), with the observed order in the budget.
Single thread. Writes results/long_run.txt.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

ROOT = Path(__file__).resolve().parents[1]
SEED = ROOT / "configs" / "seed_flat_punch.yaml"
STUDY_SCENES = ("seed_flat_punch", "wide_zone", "hard/alpha_1e6", "hard/thin_zone_1e-8",
                "hard/near_viscous")
BUDGETS = (128, 256, 512, 1024, 2048)


def child(args) -> None:
    """Run the CLI in this process and print its peak memory (the last line, JSON)."""
    import resource
    import time

    from pulloff.cli import main

    start = time.perf_counter()
    code = main(args)
    wall = time.perf_counter() - start
    peak_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # kB on Linux
    print(json.dumps({"code": code, "wall": wall, "peak_MB": peak_kb / 1024}))


def run_child(steps: int, out: Path) -> dict:
    cmd = [sys.executable, __file__, "--child", "run", str(SEED), "-o", str(out), "-q",
           "--set", f"numerics.steps={steps}", "--set", "numerics.max_elements=1024",
           "--set", "output.every=1"]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=True)
    lines = proc.stdout.strip().splitlines()
    info = json.loads(lines[-1])
    info["table"] = "\n".join(lines[:-1])
    return info


def long_run(steps: int, lines: list) -> None:
    import h5py

    from pulloff.io import h5 as h5io
    from pulloff.references.onset import reference_detachment
    from pulloff.io.scene_file import load_scene
    from pulloff.solvers.onset import Problem

    with tempfile.TemporaryDirectory() as tmp:
        base = run_child(1000, Path(tmp) / "base.h5")
        out = Path(tmp) / "long.h5"
        info = run_child(steps, out)
        record = h5io.load(out, history_rows=10)
        size_MB = out.stat().st_size / 2**20
        with h5py.File(out) as f:
            rows = f["history"]["t"].shape[0]
    s = record["summary"]
    p = Problem.from_scene(load_scene(SEED))
    ref = reference_detachment(p.G, p.eta, p.sigma_c, p.delta, p.a, p.v, p.h0, rtol=1e-12)
    err = max(abs(s["t_detach"] / ref["t_detach"] - 1),
              abs(s["F_total_detach"] / ref["F_total"] - 1))
    lines += [
        f"== long run: seed_flat_punch, numerics.steps = {steps:.3g}, max_elements = 1024, "
        f"output.every = 1",
        f"  steps run              {s['n_steps']} (+ a check run at half the steps)",
        f"  elements at the end    {s['n_elements']}",
        f"  history rows in file   {rows} ({size_MB:.0f} MB, streamed in chunks)",
        f"  wall time              {info['wall']:.1f} s (whole command, both runs)",
        f"  peak resident memory   {info['peak_MB']:.0f} MB; the same command at 1000 steps: "
        f"{base['peak_MB']:.0f} MB; the run adds {info['peak_MB'] - base['peak_MB']:.0f} MB",
        f"  error of t and F_total {err:.2e} against the reference; estimate "
        f"{s['error_estimate']:.2e}",
        f"  notes: {s['notes']}",
    ]


def study(lines: list) -> None:
    import time

    from pulloff.references.onset import reference_detachment
    from pulloff.io.scene_file import load_scene, override
    from pulloff.solvers import simulate
    from pulloff.solvers.problem import Problem

    steps = 40000
    lines.append(f"== element budget against the reference, {steps} steps "
                 f"(error of t and F_total, the larger)")
    lines.append(f"{'scene':<22} {'budget':>6} {'elements':>8} {'error':>9} {'estimate':>9} "
                 f"{'est/err':>7} {'order':>6} {'time s':>7}")
    simulate(load_scene(SEED, overrides=["numerics.steps=100"]))  # compile / load the cache
    for name in STUDY_SCENES:
        scene = load_scene(ROOT / "configs" / f"{name}.yaml",
                           overrides=[f"numerics.steps={steps}"])
        p = Problem.from_scene(scene)
        ref = reference_detachment(p.G, p.eta, p.sigma_c, p.delta, p.a, p.v, p.h0, rtol=1e-12)
        prev = None
        for budget in BUDGETS:
            start = time.perf_counter()
            res = simulate(override(scene, [f"numerics.max_elements={budget}"]))
            wall = time.perf_counter() - start
            err = max(abs(res.t_detach / ref["t_detach"] - 1),
                      abs(res.F_total_detach / ref["F_total"] - 1))
            order = f"{math.log2(prev / err):6.2f}" if prev else f"{'':>6}"
            lines.append(f"{name:<22} {budget:>6} {res.n_elements:>8} {err:>9.2e} "
                         f"{res.error_estimate:>9.2e} {res.error_estimate / err:>7.2f} {order} "
                         f"{wall:>7.2f}")
            prev = err


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        child(sys.argv[2:])
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=float, default=1e7)
    parser.add_argument("--study", action="store_true", help="the budget study only")
    args = parser.parse_args()
    lines: list = []
    if args.study:
        study(lines)
        name = "long_run_study.txt"
    else:
        long_run(int(args.steps), lines)
        name = "long_run.txt"
    text = "\n".join(lines)
    print(text)
    results = ROOT / "benchmarks" / "results"
    results.mkdir(exist_ok=True)
    (results / name).write_text(text + "\n")


if __name__ == "__main__":
    main()
