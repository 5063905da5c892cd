"""Sweep throughput: scenes per second on this machine.

    python benchmarks/sweep_throughput.py [--scenes 96]

Runs the same grid (pull speed x work of adhesion around the seed scene, alpha from ~1e-3 to
~1e4) at rtol 1e-4 and 1e-6 with 1 and 2 worker processes and on a local Dask cluster of 2
single-threaded workers. Each timing is of a whole ``sweep`` call, process or cluster start-up
included, after one warm-up sweep that fills numba's disk cache; the start-up cost alone is
also printed (a 2-scene sweep).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from pulloff.io.scene_file import load_scene
from pulloff.studies.sweeps import Axis, sweep

SEED = Path(__file__).resolve().parents[1] / "configs" / "seed_flat_punch.yaml"


def grid(n_scenes: int):
    n_v = max(2, int(round(math.sqrt(n_scenes * 2))))
    n_d = max(1, n_scenes // n_v)
    speeds = tuple(10.0 ** (-5 + 4 * i / (n_v - 1)) for i in range(n_v))
    deltas = tuple(10.0 ** (-9 + 2 * i / max(1, n_d - 1)) for i in range(n_d))
    return [Axis("loading.v", speeds), Axis("adhesion.delta", deltas)]


def timed(fn):
    start = time.perf_counter()
    result = fn()
    return time.perf_counter() - start, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=96)
    args = parser.parse_args()
    axes = grid(args.scenes)
    n = len(axes[0].values) * len(axes[1].values)
    print(f"{n} scenes per sweep (loading.v x adhesion.delta)")
    for rtol in (1e-4, 1e-6):
        scene = load_scene(SEED, overrides=[f"numerics.rtol={rtol}"])
        sweep(scene, axes, workers=1)  # warm-up: compile or load the numba cache
        for workers in (1, 2):
            startup, _ = timed(lambda: sweep(scene, [Axis("loading.v", (1e-3, 2e-3))],
                                             workers=workers))
            elapsed, result = timed(lambda: sweep(scene, axes, workers=workers))
            failed = int((result.table["status"] != "ok").sum())
            print(f"rtol {rtol:g}: {workers} process(es): {n / elapsed:7.1f} scenes/s "
                  f"({elapsed:.2f} s, start-up {startup:.2f} s, {failed} failed)")
        from distributed import LocalCluster

        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                          dashboard_address="127.0.0.1:0") as cluster:
            address = cluster.scheduler_address
            sweep(scene, axes[:1], scheduler=address)  # warm the workers
            elapsed, result = timed(lambda: sweep(scene, axes, scheduler=address))
        print(f"rtol {rtol:g}: Dask, 2 workers:  {n / elapsed:7.1f} scenes/s ({elapsed:.2f} s)")


if __name__ == "__main__":
    main()
