"""Recompute the independent reference values of tests/data/smooth_reference.json: the SLS
sphere's cycle with pulloff.references.smooth on a ladder of meshes and steps, with the
observed order and a Richardson estimate of each output (minutes at the finest level).

    python benchmarks/reference_smooth_values.py [--levels 4]
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

from pulloff.references.smooth import sphere_path_reference

DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "smooth_reference.json"
KEYS = ("F_pulloff", "h_pulloff", "F_jump_out", "h_jump_out")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=int, default=4)
    args = parser.parse_args()
    scene = json.loads(DATA.read_text())["scene"]
    arms = tuple(tuple(a) for a in scene.pop("arms"))
    G_inf = scene.pop("G_inf")
    values = []
    for k in range(args.levels):
        n, dh = 3200 * 2 ** k, 5e-10 / 2 ** k
        start = time.perf_counter()
        run = sphere_path_reference(G_inf=G_inf, arms=arms, n_elements=n, dh=dh, **scene)
        values.append([run[key] for key in KEYS])
        print(f"N {n:6d} dh {dh:.2e}: " + "  ".join(f"{key} {run[key]:.8e}" for key in KEYS)
              + f"  ({time.perf_counter() - start:.1f} s)", flush=True)
    for j, key in enumerate(KEYS):
        v0, v1, v2 = (values[-3][j], values[-2][j], values[-1][j])
        ratio = (v1 - v0) / (v2 - v1) if v2 != v1 else math.inf
        p = math.log2(abs(ratio)) if ratio > 0 else math.nan
        est = (v2 - v1) / (2 ** p - 1) if math.isfinite(p) and p > 0 else math.nan
        print(f"{key}: order {p:.2f}, extrapolated {v2 + est:.6e} +- {abs(est):.1e}")


if __name__ == "__main__":
    main()
