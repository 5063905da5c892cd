"""What changes against the seed's model: the pull past the onset, the finite punch, a real solid.

    python benchmarks/beyond_seed.py      # ~20 s

Writes results/beyond_seed.txt (peak against onset force for Kelvin-Voigt and the standard
linear solid at three speeds, both cohesive-zone geometries; and the standard linear solid
over eight decades of speed) and results/beyond_seed.png (left: the Kelvin-Voigt pull of
configs/separation_kv.yaml, force, contact edge and zone end; right: onset and peak force of
the standard linear solid against speed, with the elastic limits).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from pulloff import solvers  # noqa: E402
from pulloff.model import analytic  # noqa: E402
from pulloff.io.scene_file import load_scene, parse_scene  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
G_INF, G_1, TAU_1, SIGMA_C, DELTA, R = 1e6, 9e6, 1e-3, 1e7, 3e-6, 1e-5
KV = {"kind": "kelvin_voigt", "G": 1e6, "eta": 1e3}  # tau = 1 ms, as the SLS arm
SLS = {"kind": "standard_linear_solid", "G_inf": G_INF, "G_1": G_1, "tau_1": TAU_1}


def scene(material, v, zone):
    return parse_scene({
        "schema": 1, "name": "beyond_seed",
        "geometry": {"kind": "flat_punch", "radius": R, "cohesive_zone": zone},
        "material": material,
        "adhesion": {"kind": "dugdale", "sigma_c": SIGMA_C, "delta": DELTA},
        "loading": {"kind": "constant_velocity", "v": v},
        "model": {"until": "separation"}, "numerics": {"rtol": 1e-3}})


def elastic(G, zone):
    if zone == "internal":
        return analytic.elastic_internal_onset(G, SIGMA_C, DELTA, R)["F_total"]
    return analytic.elastic_mdr_dugdale(G, SIGMA_C, DELTA, R)["F_total"]


def main() -> None:
    lines = ["== peak against onset force (F_total), run to separation, rtol 1e-3",
             f"   punch R = {R:g} m, sigma_c = {SIGMA_C:g} Pa, delta = {DELTA:g} m; "
             f"KV: G = 1e6 Pa, eta = 1e3 Pa s; "
             f"SLS: G_inf = {G_INF:g}, G_1 = {G_1:g} Pa, tau_1 = {TAU_1:g} s",
             f"{'material':<6} {'zone':<9} {'v m/s':>7} {'onset N':>11} {'peak N':>11} "
             f"{'peak/onset':>10} {'t_sep/t_on':>10} {'estimate':>9} {'order':>6}"]
    for name, material in (("KV", KV), ("SLS", SLS)):
        for zone in ("external", "internal"):
            for v in (1e-5, 1e-3, 1e-1):
                res = solvers.simulate(scene(material, v, zone))
                # (t_sep/t_on is undefined when the bond is gone at t = 0.)
                ratio = (f"{res.t_separation / res.t_detach:>10.4f}" if res.t_detach > 0
                         else f"{'-':>10}")
                lines.append(f"{name:<6} {zone:<9} {v:>7.0e} {res.F_total_detach:>11.5e} "
                             f"{res.F_peak_total:>11.5e} "
                             f"{res.F_peak_total / res.F_total_detach:>10.4f} {ratio} "
                             f"{res.error_estimate:>9.1e} {res.observed_order:>6.2f}")
    speeds = [10.0 ** e for e in range(-7, 2)]
    lines.append("")
    lines.append("== standard linear solid against speed: onset and peak F_total [N]")
    lines.append(f"{'v m/s':>7} {'ext onset':>11} {'ext peak':>11} {'int onset':>11} "
                 f"{'int peak':>11}")
    curves = {zone: ([], []) for zone in ("external", "internal")}
    for v in speeds:
        row = f"{v:>7.0e}"
        for zone in ("external", "internal"):
            res = solvers.simulate(scene(SLS, v, zone))
            curves[zone][0].append(res.F_total_detach)
            curves[zone][1].append(res.F_peak_total)
            row += f" {res.F_total_detach:>11.5e} {res.F_peak_total:>11.5e}"
        lines.append(row)
    for zone in ("external", "internal"):
        lines.append(f"  {zone}: elastic with G_inf {elastic(G_INF, zone):.5e} N, with "
                     f"G_inf + G_1 {elastic(G_INF + G_1, zone):.5e} N"
                     + (f", strength limit {math.pi * R * R * SIGMA_C:.5e} N"
                        if zone == "internal" else ""))
    text = "\n".join(lines)
    print(text)
    out = ROOT / "benchmarks" / "results"
    out.mkdir(exist_ok=True)
    (out / "beyond_seed.txt").write_text(text + "\n")

    kv = solvers.simulate(load_scene(ROOT / "configs" / "separation_kv.yaml"))
    h = kv.history
    fig, (ax_h, ax_v) = plt.subplots(1, 2, figsize=(11.0, 4.2), constrained_layout=True)
    t_ms = h["t"] * 1e3
    ax_h.plot(t_ms, h["F_total"] * 1e3, color="C1", label="F_total")
    ax_h.plot(t_ms, h["F_contact"] * 1e3, color="C0", label="F_contact")
    ax_h.axvline(kv.t_detach * 1e3, color="0.5", ls=":", label="onset (the seed stops here)")
    ax_h.plot([kv.t_peak_total * 1e3], [kv.F_peak_total * 1e3], "kv", label="peak")
    ax_h.set_xlabel("time [ms]")
    ax_h.set_ylabel("force [mN]")
    ax_r = ax_h.twinx()
    ax_r.plot(t_ms, h["a"] * 1e6, color="C3", ls="--", label="a")
    ax_r.plot(t_ms, h["b"] * 1e6, color="C4", ls="-.", label="b")
    ax_r.set_ylabel("radius [um]")
    handles = ax_h.get_legend_handles_labels()
    more = ax_r.get_legend_handles_labels()
    ax_h.legend(handles[0] + more[0], handles[1] + more[1], fontsize=8, loc="lower left")
    ax_h.set_title("Kelvin-Voigt, external zone: past the onset to separation", fontsize=9)
    for zone, color in (("external", "C0"), ("internal", "C1")):
        onset, peak = curves[zone]
        ax_v.semilogx(speeds, [F * 1e3 for F in peak], "o-", color=color,
                      label=f"{zone}: peak")
        ax_v.semilogx(speeds, [F * 1e3 for F in onset], "x:", color=color,
                      label=f"{zone}: onset")
        ax_v.axhline(elastic(G_INF, zone) * 1e3, color=color, lw=0.8, ls="--")
    ax_v.axhline(math.pi * R * R * SIGMA_C * 1e3, color="k", lw=0.8, ls="-.",
                 label="strength limit (internal)")
    ax_v.set_xlabel("lift speed v [m/s]")
    ax_v.set_ylabel("F_total [mN]")
    ax_v.set_title("standard linear solid: dashed, elastic with G_inf", fontsize=9)
    ax_v.legend(fontsize=8)
    fig.savefig(out / "beyond_seed.png", dpi=120)
    plt.close(fig)
    print(f"wrote {out / 'beyond_seed.txt'} and {out / 'beyond_seed.png'}")


if __name__ == "__main__":
    main()
