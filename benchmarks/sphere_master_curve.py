"""The pull-off master curve of a viscoelastic sphere: ``configs/sphere_sls_cycle.yaml``
(approach to 2 uN, dwell, retract) retracted at speeds from 1e-8 to 1e-2 m/s, its pull-off
force beside the elastic limits with the relaxed and the instantaneous modulus; the energy
dissipated over each cycle; the warm time of each run and of the whole curve.

    python benchmarks/sphere_master_curve.py [--rtol 1e-3] [--points 13]

Writes ``benchmarks/results/sphere_master_curve.{png,txt}``. Single-threaded; the first run
(numba compile or cache load) is reported apart.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import yaml

from pulloff.io.scene_file import parse_scene
from pulloff.solvers import simulate

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "sphere_sls_cycle.yaml"
OUT = ROOT / "benchmarks" / "results"


def run(speed: float, rtol: float):
    data = yaml.safe_load(CONFIG.read_text())
    data["loading"]["segments"][2]["speed"] = speed
    data["numerics"]["rtol"] = rtol
    data.pop("output", None)
    scene = parse_scene(data)
    start = time.perf_counter()
    result = simulate(scene)
    return result, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rtol", type=float, default=1e-3)
    parser.add_argument("--points", type=int, default=13)
    args = parser.parse_args()
    _, first = run(1e-6, args.rtol)
    speeds = np.logspace(-8, -2, args.points)
    rows, total = [], 0.0
    for v in speeds:
        res, wall = run(float(v), args.rtol)
        total += wall
        rows.append((v, res.F_pulloff, res.energy_dissipated, res.error_estimate, wall))
        print(f"v {v:9.3e} m/s  F_pulloff {res.F_pulloff:.5e} N  dissipated "
              f"{res.energy_dissipated:.4e} J  estimate {res.error_estimate:.1e}  {wall:6.2f} s",
              flush=True)
    relaxed, instant = res.relaxed_F_pulloff, res.instant_F_pulloff
    lines = [f"# {CONFIG.name}, rtol {args.rtol}: first run {first:.2f} s (compile/cache "
             f"included); {len(speeds)} warm runs {total:.1f} s in all",
             f"# elastic limits: relaxed {relaxed:.5e} N, instantaneous {instant:.5e} N",
             "speed_m_s,F_pulloff_N,energy_dissipated_J,error_estimate,wall_s"]
    lines += [",".join(f"{x:.6e}" for x in row) for row in rows]
    OUT.mkdir(exist_ok=True)
    (OUT / "sphere_master_curve.txt").write_text("\n".join(lines) + "\n")
    _figure(np.array(rows), relaxed, instant)
    print("\n".join(lines[:2]))


def _figure(rows, relaxed, instant) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, ax_e) = plt.subplots(1, 2, figsize=(10, 4))
    ax.semilogx(rows[:, 0], rows[:, 1] * 1e6, "o-", label="simulation (SLS, tau = 10 ms)")
    ax.axhline(relaxed * 1e6, color="C2", ls=":", label="elastic, relaxed modulus")
    ax.axhline(instant * 1e6, color="C3", ls="-.", label="elastic, instantaneous modulus")
    ax.set_xlabel("retraction speed [m/s]")
    ax.set_ylabel("pull-off force [uN]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    ax_e.semilogx(rows[:, 0], rows[:, 2] * 1e12, "s-", color="C1")
    ax_e.set_xlabel("retraction speed [m/s]")
    ax_e.set_ylabel("energy dissipated over the cycle [pJ]")
    ax_e.grid(alpha=0.3)
    fig.suptitle("sphere_sls_cycle.yaml: pull-off master curve")
    fig.tight_layout()
    fig.savefig(OUT / "sphere_master_curve.png", dpi=110)


if __name__ == "__main__":
    main()
