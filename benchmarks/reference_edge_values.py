"""High-accuracy values of the independent moving-edge reference (pulloff.references.edge).

Runs :func:`pulloff.references.edge.flat_punch_reference` on the shipped scenes that are pulled
to separation (plus the seed scene, also to separation, and three scenes of our own at other
speeds) with a convergence ladder ``N = N0 2^l`` and writes ``tests/data/edge_reference.json``:
scene name -> SI parameters, the scalar outputs of the finest level, the reference's own error
estimate (largest relative change between the two finest levels; a Richardson estimate and the
observed order beside it) and the per-level values.

Usage::

    python benchmarks/reference_edge_values.py [--budget SECONDS] [--only NAME ...]

Progress and timings go to stdout. Single-threaded (numba/BLAS pinned before imports).
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import yaml  # noqa: E402

from pulloff.references.edge import flat_punch_reference  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "tests" / "data" / "edge_reference.json"

SCALARS = ("t_onset", "F_onset_total", "F_onset_contact", "t_separation", "F_peak_total",
           "t_peak_total", "F_peak_contact", "t_peak_contact")


def params_from_config(path):
    """SI parameters of a flat-punch YAML scene for flat_punch_reference."""
    cfg = yaml.safe_load(Path(path).read_text())
    geo, mat, adh, load = cfg["geometry"], cfg["material"], cfg["adhesion"], cfg["loading"]
    p = dict(R=float(geo["radius"]), zone=geo.get("cohesive_zone", "external"),
             v=float(load["v"]), h0=float(load.get("h0", 0.0)),
             machine_stiffness=(None if load.get("machine_stiffness") is None
                                else float(load["machine_stiffness"])))
    kind = mat["kind"]
    if kind == "kelvin_voigt":
        p.update(G_inf=float(mat["G"]), eta=float(mat.get("eta", 0.0)), arms=())
    elif kind == "standard_linear_solid":
        p.update(G_inf=float(mat["G_inf"]), eta=0.0,
                 arms=((float(mat["G_1"]), float(mat["tau_1"])),))
    elif kind == "prony":
        p.update(G_inf=float(mat["G_inf"]), eta=0.0,
                 arms=tuple((float(t["G"]), float(t["tau"])) for t in mat["terms"]))
    else:
        raise ValueError(f"material kind {kind!r}")
    sigma_c = adh.get("sigma_c")
    delta = adh.get("delta")
    gamma = adh.get("gamma")
    if sigma_c is None:
        sigma_c = float(gamma) / float(delta)
    if delta is None:
        delta = float(gamma) / float(sigma_c)
    p.update(sigma_c=float(sigma_c), delta=float(delta))
    return p


def scenes():
    cfg = ROOT / "configs"
    out = {}
    for name in ("separation_kv", "separation_elastic", "finite_punch_internal",
                 "sls_finite_punch", "prony_external", "compliant_machine", "seed_flat_punch"):
        out[name] = params_from_config(cfg / f"{name}.yaml")
    out["separation_kv_v1e-2"] = dict(out["separation_kv"], v=1e-2)
    out["sls_finite_punch_v1e-4"] = dict(out["sls_finite_punch"], v=1e-4)
    # The relaxed limit (the slow end of the rate sweep): the crack leaves its onset slowly,
    # growing faster than linearly, and its timing decides the separation.
    out["sls_finite_punch_v1e-7"] = dict(out["sls_finite_punch"], v=1e-7)
    out["sls_external_v1e-2"] = dict(out["sls_finite_punch"], zone="external", v=1e-2)
    # A Kelvin-Voigt face whose strength limits the bond (chi_R = 0.94), behind 1 kN/m.
    out["finite_punch_spring_kv"] = dict(G_inf=1e6, eta=1e3, arms=(), sigma_c=1e6, delta=3e-6,
                                         R=1e-5, v=1e-3, h0=0.0, zone="internal",
                                         machine_stiffness=1e3)
    # Past the onset behind springs: a Kelvin-Voigt bond behind a soft one (it snaps where
    # a reaches 0), a standard linear solid's finite punch behind 100 N/m (its zone folds).
    out["compliant_machine_k10"] = dict(out["compliant_machine"], machine_stiffness=10.0)
    out["sls_finite_punch_spring"] = dict(out["sls_finite_punch"], machine_stiffness=100.0)
    # Behind 1 N/m the Kelvin-Voigt bond's crack runs through in 5.6 ms at an almost constant
    # force and snaps off where a reaches 0. The pilot run (N = 8, 16, from the 1.4 s onset)
    # steps over it and reports an arrest ("a would grow"), so the scales are given: the
    # onset, the propagation's 5.5 ms, R^2.
    out["compliant_machine_k1"] = dict(out["compliant_machine"], machine_stiffness=1.0,
                                       scales=(1.4376, 5.5e-3, out["compliant_machine"]["R"] ** 2))
    # Faces whose strength limits the bond before the rim's gap reaches delta (the zone alone
    # then holds the whole face until the rim opens): a Kelvin-Voigt face bonded beyond its
    # strength at t = 0 (the viscous force of the start, ell(0) = 4), a Kelvin-Voigt face that
    # collapses after its rim opens, a standard linear solid and a Prony series whose zone
    # folds, and a fast standard linear solid that comes off where its rim opens.
    kv, fpi = out["separation_kv"], out["finite_punch_internal"]
    sls, prony = out["sls_finite_punch"], out["prony_external"]
    out["kv_face_gone_at_start"] = dict(kv, zone="internal", v=2e-2, sigma_c=1e6)
    out["finite_punch_face"] = dict(fpi, v=2e-4, sigma_c=3.5e5)
    out["sls_face_fold"] = dict(sls, zone="internal", v=2.7e-4, sigma_c=1.1e6)
    out["sls_face_released"] = dict(sls, zone="internal", v=2e-2, sigma_c=6e5)
    out["prony_face"] = dict(prony, zone="internal", v=4e-4, sigma_c=1e6)
    return out


def jsonable(x):
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if hasattr(x, "item"):
        return jsonable(x.item())
    return x


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--budget", type=float, default=240.0,
                    help="wall-time budget per scene [s] (levels are not started beyond it)")
    ap.add_argument("--rtol", type=float, default=1e-11, help="stop a ladder below this")
    ap.add_argument("--only", nargs="*", default=None, help="scene names to (re)compute")
    ap.add_argument("--out", default=str(OUT))
    args = ap.parse_args(argv)
    out_path = Path(args.out)
    data = json.loads(out_path.read_text()) if out_path.exists() else {}
    t_all = time.time()
    for name, p in scenes().items():
        if args.only and name not in args.only:
            continue
        print(f"== {name}: {p}", flush=True)
        t0 = time.time()
        p = dict(p)
        scales = p.pop("scales", None)
        res = flat_punch_reference(**p, scales=scales, rtol=args.rtol, N0=16, min_level=1,
                                   max_level=7,
                                   time_budget=args.budget, verbose=True)
        wall = time.time() - t0
        entry = {k: res[k] for k in SCALARS}
        entry.update(
            separation_kind=res["separation_kind"], t_a_zero=res["t_a_zero"],
            error_estimate=res["error_estimate"], error_estimates=res["error_estimates"],
            error_estimate_richardson=res["error_estimate_richardson"],
            observed_order=res["observed_order"], levels=res["levels"], scales=res["scales"],
            params=dict(p, arms=[list(a) for a in p["arms"]]), wall_time=wall,
            n_points_finest=res["n_points"])
        data[name] = jsonable(entry)
        print(f"   {name}: error_estimate={res['error_estimate']:.2e} "
              f"(Richardson {res['error_estimate_richardson']:.2e}, order "
              f"{res['observed_order']:.2f}), {wall:.0f} s", flush=True)
        data["_meta"] = dict(
            generator="benchmarks/reference_edge_values.py",
            solver="pulloff.references.edge.flat_punch_reference",
            units="SI (s, m, N, Pa, Pa s, N/m)",
            error_estimate="max over the scalars of |finest - next finest| / |finest| "
                           "(t_peak_* relative to t_separation)",
            python=sys.version.split()[0], platform=platform.platform())
        out_path.parent.mkdir(parents=True, exist_ok=True)
        out_path.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
    print(f"total {time.time() - t_all:.0f} s -> {out_path}", flush=True)


if __name__ == "__main__":
    main()
