"""Recompute the independent reference values of tests/data/smooth_reference.json: the SLS
sphere's cycle with pulloff.references.smooth on a ladder of meshes and steps, with the
observed order and a Richardson estimate of each output (minutes at the finest level).

    python benchmarks/reference_smooth_values.py [--levels 4]

``--force``: the force-controlled retraction of tests/data/smooth_force_reference.json
(approach at v_in to -F_target, then F = -F_target + force_rate (t - t_turn) to the pull-off)
on the ladder N = 800 2^k elements, approach step dh = 1e-9/2^k m, force step
dF = 5e-9/2^k N (k < levels, default 7: ~6 min); ``--write`` stores the estimates there.

    python benchmarks/reference_smooth_values.py --force [--levels 7] [--write]
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
FORCE_DATA = DATA.with_name("smooth_force_reference.json")
FORCE_SCENE = {"G_inf": 1.0e6, "arms": [[9.0e6, 1.0e-3]], "sigma_c": 5.0e6, "delta": 1.0e-8,
               "R": 1.0e-5, "h0": 2.0e-8, "v_in": 1.0e-6, "F_target": 2.0e-6,
               "force_rate": 1.0e-5}
FORCE_KEYS = ("F_pulloff", "h_pulloff", "t_pulloff")


def richardson(v0, v1, v2):
    """Observed order (refinement ratio 2) and the extrapolated value of a three-level ladder."""
    ratio = (v1 - v0) / (v2 - v1) if v2 != v1 else math.inf
    p = math.log2(abs(ratio)) if ratio > 0 else math.nan
    est = (v2 - v1) / (2 ** p - 1) if math.isfinite(p) and p > 0 else math.nan
    return p, v2 + est


def force_ladder(levels: int) -> list:
    """Run the force-control ladder; rows of FORCE_KEYS values, one per level."""
    scene = dict(FORCE_SCENE)
    arms = tuple(tuple(a) for a in scene.pop("arms"))
    values = []
    total = 0.0
    for k in range(levels):
        n, dh, dF = 800 * 2 ** k, 1e-9 / 2 ** k, 5e-9 / 2 ** k
        run = sphere_path_reference(arms=arms, n_elements=n, dh=dh, dF=dF, **scene)
        total += run["wall_time"]
        values.append([run[key] for key in FORCE_KEYS])
        print(f"N {n:6d} dh {dh:.3e} dF {dF:.3e}: "
              + "  ".join(f"{key} {run[key]:.10e}" for key in FORCE_KEYS)
              + f"  steps {run['n_steps']}  ({run['wall_time']:.1f} s)", flush=True)
    print(f"total {total:.0f} s")
    return values


def force_estimates(values: list) -> dict:
    """Richardson over the last three levels (observed order); the error is the larger of the
    change from the previous three-level extrapolation and the spread of the last one over the
    last three observed orders."""
    result = {}
    for j, key in enumerate(FORCE_KEYS):
        col = [v[j] for v in values]
        orders, extrap = [], []
        for i in range(2, len(col)):
            p, x = richardson(col[i - 2], col[i - 1], col[i])
            orders.append(p)
            extrap.append(x)
        print(f"{key}: differences " + " ".join(f"{col[i + 1] - col[i]:+.3e}"
                                            for i in range(len(col) - 1)))
        print(f"{key}: orders " + " ".join(f"{p:.2f}" for p in orders)
              + "; extrapolated " + " ".join(f"{x:.8e}" for x in extrap))
        d = col[-1] - col[-2]
        tail = orders[-3:]
        spread = abs(d / (2 ** min(tail) - 1) - d / (2 ** max(tail) - 1))
        err = max(abs(extrap[-1] - extrap[-2]), spread) if len(extrap) > 1 else math.nan
        print(f"{key}: {extrap[-1]:.8e} +- {err:.1e} ({err / abs(extrap[-1]):.1e} relative)")
        result[key] = extrap[-1]
        result[key + "_error"] = err
        result.setdefault("_orders", []).extend(orders)
    return result


def write_force_reference(result: dict, levels: int) -> None:
    ladder = ", ".join(f"{800 * 2 ** k}" for k in range(levels))
    orders = f"{min(result['_orders']):.1f}-{max(result['_orders']):.1f}"
    doc = {
        "_source": ("pulloff.references.smooth.sphere_path_reference with force_rate (fixed mesh, "
                    "independent of the stepper): displacement-controlled approach to -F_target, "
                    "then F = -F_target + force_rate (t - t_turn) to the fold (the pull-off: the "
                    "root in the last step's length of max_a F(a) - F_prescribed); Richardson "
                    f"estimates (observed orders {orders}) over the last three levels of the joint "
                    f"ladder N = {ladder} elements, dh = 1e-9/2^k m (approach), "
                    f"dF = 5e-9/2^k N (retraction), k = 0..{levels - 1} "
                    "(benchmarks/reference_smooth_values.py --force); error = larger of the "
                    "change from the previous extrapolation and the spread over the last three "
                    "observed orders; t_pulloff from the start of the approach; SI"),
        "scene": FORCE_SCENE,
    }
    lines = [f'  "_source": {json.dumps(doc["_source"])}',
             f'  "scene": {json.dumps(doc["scene"])}']
    for key in FORCE_KEYS:
        value = float(f"{result[key]:.7e}")
        error = float(f"{result[key + '_error']:.1e}")
        lines.append(f'  "{key}": {value!r}, "{key}_error": {error!r}')
    FORCE_DATA.write_text("{\n" + ",\n".join(lines) + "\n}\n")
    print(f"wrote {FORCE_DATA}")


def force_main(levels: int, write: bool) -> None:
    result = force_estimates(force_ladder(levels))
    if write:
        write_force_reference(result, levels)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=int, default=None)
    parser.add_argument("--force", action="store_true",
                        help="the force-controlled retraction (smooth_force_reference.json)")
    parser.add_argument("--write", action="store_true",
                        help="with --force: write the estimates to smooth_force_reference.json")
    args = parser.parse_args()
    if args.force:
        if args.levels is not None and args.levels < 3:
            parser.error("--force needs at least 3 levels (4 for an error estimate)")
        force_main(args.levels or 7, args.write)
        return
    args.levels = args.levels or 4
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
