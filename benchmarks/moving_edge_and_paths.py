"""Warm run time and accuracy of the shipped configs that move the contact edge: flat punches
run to separation (against the independent reference of pulloff.references.edge, its values in
tests/data/edge_reference.json) and smooth indenters on loading paths (against the elastic
closed forms beside every run).

    python benchmarks/moving_edge_and_paths.py [--repeat 3] [--skip compliant_machine ...]

The first call of each config (numba compile or cache load included) is reported apart; then
the median and the spread (min-max) of ``--repeat`` warm runs. Single-threaded.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time
from pathlib import Path

from pulloff.io.scene_file import load_scene
from pulloff.solvers import simulate

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = json.loads((ROOT / "tests" / "data" / "edge_reference.json").read_text())
#: (output, reference key) for a flat punch run to separation.
FLAT = (("t_detach", "t_onset"), ("F_total_detach", "F_onset_total"),
        ("t_separation", "t_separation"), ("F_peak_total", "F_peak_total"))
#: (output, closed form) for an elastic smooth indenter on a path.
PATH = (("F_pulloff", "mdr_dugdale_F_pulloff_load"),
        ("F_jump_out", "mdr_dugdale_F_pulloff_displacement"))


def errors(name, res) -> dict:
    if name in REFERENCE:
        ref = REFERENCE[name]
        return {out: getattr(res, out) / ref[key] - 1.0 for out, key in FLAT}
    if math.isfinite(getattr(res, "F_pulloff", math.nan)):
        pairs = dict(PATH)
        if res.scene_control == "force":  # a force ramp comes off at the load-controlled fold
            pairs["F_jump_out"] = "mdr_dugdale_F_pulloff_load"
        return {out: getattr(res, out) / res.analytic[key] - 1.0 for out, key in pairs.items()
                if math.isfinite(res.analytic.get(key, math.nan))}
    return {}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--skip", nargs="*", default=[])
    args = parser.parse_args()
    for path in sorted((ROOT / "configs").glob("*.yaml")):
        scene = load_scene(path)
        moving = (scene.loading.kind == "path" or scene.model.until == "separation"
                  or getattr(scene.geometry, "cohesive_zone", "") == "internal")
        if not moving or path.stem in args.skip:
            continue
        start = time.perf_counter()
        res = simulate(scene)
        first = time.perf_counter() - start
        res.scene_control = getattr(scene.loading, "control", "displacement")
        times = []
        for _ in range(args.repeat):
            start = time.perf_counter()
            res = simulate(scene)
            times.append(time.perf_counter() - start)
        res.scene_control = getattr(scene.loading, "control", "displacement")
        errs = " ".join(f"{k}={v:+.1e}" for k, v in errors(path.stem, res).items())
        print(f"{path.stem:<22} first {first:6.2f} s  warm median {statistics.median(times):7.3f}"
              f" s (min {min(times):.3f}, max {max(times):.3f})  estimate "
              f"{res.error_estimate:.1e}  vs reference: {errs or 'n/a'}", flush=True)


if __name__ == "__main__":
    main()
