"""Figures of a run, drawn from a record dict (a fresh result or a loaded file)."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; a run on a headless machine must not need a display
import matplotlib.pyplot as plt  # noqa: E402


#: Closed forms drawn on the force panel: key of ``record["analytic"]``, label, colour, style.
_CLOSED_FORMS = (
    ("seed_closed_form_F", "seed closed form (eqs. 64/89)", "C2", ":"),
    ("seed_linearised_F", "seed eq. 53 + 48", "C8", "-."),
    ("kendall_F", "Kendall (eq. 95)", "C3", (0, (6, 2))),
    ("elastic_F_contact", "elastic MDR-Dugdale F_contact", "C5", (0, (1, 1.5))),
)


def _finite(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and \
        math.isfinite(value)


def _legend(ax) -> None:
    """A legend beside the panel, never over the curves or the closed-form lines."""
    ax.legend(fontsize=7.5, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0,
              frameon=False)


def plot_history(record: dict, path, title: str | None = None) -> Path:
    """Force (with the closed forms, the onset and the peak), cohesive-zone width
    ``(b - a)/a`` with the contact edge, and gap histories; a driver/spring panel for a
    compliant machine; a loading path's force-displacement loop instead (:func:`plot_path`).
    Saves a PNG at ``path``."""
    scene = _scene(record)
    if _get(scene, "loading", "kind") == "path":
        return plot_path(record, path, title)
    stiffness = _get(scene, "loading", "machine_stiffness")
    n_panels = 4 if _finite(stiffness) else 3
    fig, axes = plt.subplots(n_panels, 1, figsize=(9.0, 2.6 * n_panels + 0.6), sharex=True,
                             constrained_layout=True)
    _force_panel(axes[0], record)
    _zone_panel(axes[1], record, scene)
    _gap_panel(axes[2], record, scene)
    if n_panels == 4:
        _machine_panel(axes[3], record, scene, stiffness)
    axes[-1].set_xlabel("time [ms]")
    if title:
        fig.suptitle(title, fontsize=10)
    return _save(fig, path)


def _time_ms(record):
    import numpy as np

    return np.asarray(record["history"]["t"]) * 1e3


def _force_panel(ax_f, record) -> None:
    """Both forces, the closed forms as levels (or named in the legend when off scale), the
    onset and the peak."""
    import numpy as np

    h, s, an = record["history"], record["summary"], record["analytic"]
    t_ms = _time_ms(record)
    ax_f.plot(t_ms, h["F_contact"], label="F_contact (simulation)", color="C0")
    ax_f.plot(t_ms, h["F_total"], label="F_total (simulation)", color="C1", ls="--")
    scale = np.nanmax(np.abs(np.concatenate([np.asarray(h["F_contact"], float),
                                             np.asarray(h["F_total"], float), [0.0]])))
    for key, label, colour, style in _CLOSED_FORMS:
        value = an.get(key)
        if not _finite(value):
            continue
        if scale > 0 and not 0.1 <= abs(value) / scale <= 10.0:
            # Far off the simulated forces: a line there would only squash the curves.
            ax_f.plot([], [], ls="none", label=f"{label}: {value:.3g} N (off scale)")
            continue
        # Dotted lines wider, so one lying on another closed form still shows.
        ax_f.axhline(value, color=colour, ls=style, lw=2.0 if style == ":" or
                     isinstance(style, tuple) and style[1][0] < 2 else 1.2,
                     label=f"{label}: {value:.3g} N")
    if s.get("detached"):
        ax_f.plot([s["t_detach"] * 1e3], [s["F_contact_detach"]], "ko", ms=4,
                  label="onset of detachment")
    if s.get("until") == "separation" and _finite(s.get("F_peak_total", math.nan)):
        ax_f.plot([s["t_peak_total"] * 1e3], [s["F_peak_total"]], "kv", ms=5,
                  label="peak F_total")
    ax_f.set_ylabel("force [N]")
    _legend(ax_f)
    ax_f.grid(alpha=0.3)


def _zone_panel(ax_r, record, scene) -> None:
    """The zone width relative to the contact radius, the quantity that matters (a and b
    themselves differ in the sixth digit for a thin zone), with the contact edge."""
    import numpy as np

    h = record["history"]
    t_ms = _time_ms(record)
    b = np.asarray(h["b"], dtype=float)
    a = np.asarray(h["a"], dtype=float) if "a" in h else None
    ref = a if a is not None else np.full_like(b, _get(scene, "geometry", "radius") or np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where((ref > 0) & (b > 0), (b - ref) / ref, np.nan)
    ax_r.plot(t_ms, ratio, color="C4", label="(b - a)/a, cohesive-zone width")
    positive = ratio[np.isfinite(ratio) & (ratio > 0)]
    if positive.size > 1 and positive.max() / positive.min() > 100:
        ax_r.set_yscale("log")
    else:
        ax_r.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3), useOffset=False)
    ax_r.set_ylabel("(b - a)/a")
    ax_r.grid(alpha=0.3)
    handles, labels = ax_r.get_legend_handles_labels()
    if a is not None:
        ax_a = ax_r.twinx()
        ax_a.plot(t_ms, a * 1e6, color="C3", lw=1.0, ls="--", label="contact edge a (right)")
        ax_a.set_ylabel("a [um]")
        ax_a.ticklabel_format(axis="y", useOffset=False, style="plain")
        more_h, more_l = ax_a.get_legend_handles_labels()
        handles, labels = handles + more_h, labels + more_l
    ax_r.legend(handles, labels, fontsize=7.5, loc="upper left", bbox_to_anchor=(1.1, 1.0),
                borderaxespad=0.0, frameon=False)


def _gap_panel(ax_g, record, scene) -> None:
    import numpy as np

    ax_g.plot(_time_ms(record), np.asarray(record["history"]["gap"]) * 1e9, color="C2",
              label="gap at r = b")
    delta = _get(scene, "adhesion", "delta")
    if _finite(delta):
        ax_g.axhline(delta * 1e9, color="0.4", ls=":", lw=1.0, label="delta (onset)")
    ax_g.set_ylabel("gap [nm]")
    _legend(ax_g)
    ax_g.grid(alpha=0.3)


def _machine_panel(ax_m, record, scene, stiffness) -> None:
    """The driver, the punch and the spring's stretch between them."""
    import numpy as np

    h = record["history"]
    t_ms = _time_ms(record)
    lift = np.asarray(h["h"], dtype=float)
    v = _get(scene, "loading", "v")
    if _get(scene, "loading", "kind") == "constant_velocity" and _finite(v):
        driver = (_get(scene, "loading", "h0") or 0.0) + v * np.asarray(h["t"])
        driver_label = "driver h0 + v t"
    else:
        driver = lift + np.asarray(h["F_total"], dtype=float) / stiffness
        driver_label = "driver (h + F_total / k)"
    ax_m.plot(t_ms, driver * 1e6, color="0.3", label=driver_label)
    ax_m.plot(t_ms, lift * 1e6, color="C0", ls="--", label="punch lift h")
    ax_m.fill_between(t_ms, lift * 1e6, driver * 1e6, color="C0", alpha=0.12,
                      label=f"spring stretch (k = {stiffness:.3g} N/m)")
    ax_m.set_ylabel("machine [um]")
    _legend(ax_m)
    ax_m.grid(alpha=0.3)


#: Closed forms of a path drawn as levels on the loop: key, label, colour, style.
_PATH_FORMS = (
    ("mdr_dugdale_F_pulloff_load", "MDR-Dugdale pull-off, load control", "C3", ":"),
    ("mdr_dugdale_F_pulloff_displacement", "MDR-Dugdale pull-off, displacement control",
     "C5", "-."),
    ("jkr_F_pulloff_load", "JKR pull-off, load control", "C7", (0, (6, 2))),
    ("relaxed_F_pulloff", "elastic pull-off, relaxed modulus", "C8", ":"),
    ("instant_F_pulloff", "elastic pull-off, instantaneous modulus", "C9", "-."),
)


def plot_path(record: dict, path, title: str | None = None) -> Path:
    """A loading path: force against lift (the loop, one colour per segment, the pull-off and
    the elastic closed forms marked), and the contact edge ``a`` and zone end ``b`` against
    time."""
    import numpy as np

    h, s, an = record["history"], record["summary"], record["analytic"]
    fig, (ax_l, ax_e) = plt.subplots(2, 1, figsize=(9.0, 7.2), constrained_layout=True)
    lift_nm = np.asarray(h["h"], float) * 1e9
    force_uN = np.asarray(h["F_total"], float) * 1e6
    segment = np.asarray(h.get("segment", np.zeros(lift_nm.size)), int)
    for k in np.unique(segment):
        rows = np.nonzero(segment == k)[0]
        # Share the row where one segment hands over, so the loop has no holes.
        rows = np.append(rows, rows[-1] + 1) if rows[-1] + 1 < lift_nm.size else rows
        ax_l.plot(lift_nm[rows], force_uN[rows], color=f"C{k % 10}", label=f"segment {k}")
    if _finite(s.get("F_pulloff")):
        ax_l.plot([s["h_pulloff"] * 1e9], [s["F_pulloff"] * 1e6], "v", color="k",
                  label="pull-off (simulation)")
    for key, label, colour, style in _PATH_FORMS:
        if _finite(an.get(key)):
            ax_l.axhline(an[key] * 1e6, color=colour, ls=style, lw=1.0, label=label)
    ax_l.set_xlabel("lift h [nm] (negative: pressed in)")
    ax_l.set_ylabel("F_total [uN] (tension > 0)")
    ax_l.grid(alpha=0.3)
    _legend(ax_l)
    t_ms = np.asarray(h["t"], float) * 1e3
    ax_e.plot(t_ms, np.asarray(h["a"], float) * 1e6, color="C0", label="contact edge a")
    ax_e.plot(t_ms, np.asarray(h["b"], float) * 1e6, color="C1", ls="--", label="zone end b")
    ax_e.set_xlabel("time [ms]")
    ax_e.set_ylabel("radius [um]")
    ax_e.grid(alpha=0.3)
    _legend(ax_e)
    fig.suptitle(title or s.get("name", "") or "loading path", fontsize=11)
    return _save(fig, path)


def _scene(record) -> dict:
    """The stored scene as plain data ({} where it cannot be read)."""
    from .scene_file import read_yaml

    try:
        data = read_yaml(str(record.get("scene", "")))
    except Exception:  # the figure is still useful without the scene's reference lines
        return {}
    return data if isinstance(data, dict) else {}


def _get(scene: dict, section: str, key: str):
    part = scene.get(section)
    value = part.get(key) if isinstance(part, dict) else None
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) \
        else value


# --- validation figures ---------------------------------------------------------------------

def plot_alpha_tstar(curves: dict, path) -> Path:
    """The seed's Figs. 8/10: alpha against t*, eq. 53 and its approximations vs simulation."""
    import numpy as np

    from ..model import analytic

    t = np.logspace(-3, 2.5, 400)
    fig, (ax, ax_dev) = plt.subplots(1, 2, figsize=(11.0, 4.6), constrained_layout=True)
    ax.loglog(t, analytic.seed_rhs(t), "k-", lw=1.5, label="eq. 53 (seed, numerical root)")
    big = t > 1.0
    ax.loglog(t[big], 0.5 * t[big] ** 2 - 0.5, "k--", lw=1.0, label="parabolic, eq. 56")
    ax.loglog(t, 0.5 * t + 0.25 * t**2, "k:", lw=1.0, label="Taylor T2, eq. 79")
    ax.axhline(analytic.ALPHA_SWITCH, color="0.6", lw=0.8)
    exact = curves["history"] == "exact"
    for i, chi in enumerate(np.unique(curves["chi"][exact])):
        sel = exact & (curves["chi"] == chi)
        ax.loglog(curves["t_star"][sel], curves["alpha"][sel], "o-", ms=3.5, lw=0.8,
                  color=f"C{i}", label=f"exact simulation, chi = {chi:.0e}")
    frozen = curves["history"] == "frozen"
    if frozen.any():
        chi = curves["chi"][frozen][0]
        ax.loglog(curves["t_star"][frozen], curves["alpha"][frozen], "kx", ms=6,
                  label=f"frozen history (eq. 31), chi = {chi:.0e}")
    ax.set_xlabel("t* = t G / eta at detachment")
    ax.set_ylabel("alpha")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")

    root = np.array([analytic.seed_t_star(a) for a in curves["alpha"]])
    for i, chi in enumerate(np.unique(curves["chi"][exact])):
        sel = exact & (curves["chi"] == chi)
        ax_dev.semilogx(curves["alpha"][sel], curves["t_star"][sel] / root[sel], "o-",
                        ms=3.5, lw=0.8, color=f"C{i}", label=f"exact, chi = {chi:.0e}")
    if frozen.any():
        ax_dev.semilogx(curves["alpha"][frozen], curves["t_star"][frozen] / root[frozen], "kx",
                        label="frozen history")
    ax_dev.axhline(1.0, color="k", lw=0.8)
    ax_dev.set_xlabel("alpha")
    ax_dev.set_ylabel("t* simulated / t* of eq. 53")
    ax_dev.legend(fontsize=7)
    ax_dev.grid(alpha=0.3, which="both")
    return _save(fig, path)


def plot_taylor(path) -> Path:
    """The seed's Fig. 9: Taylor polynomials T1-T5 of eq. 53's right side."""
    import numpy as np

    from ..model import analytic

    t = np.linspace(0.0, 3.0, 300)
    fig, ax = plt.subplots(figsize=(6.0, 4.4), constrained_layout=True)
    ax.plot(t, analytic.seed_rhs(t), "k-", lw=2.0, label="eq. 53")
    for degree in range(1, 6):
        ax.plot(t, analytic.taylor_poly(t, degree), lw=1.0, label=f"T{degree}")
    ax.set_ylim(-0.5, 6.0)
    ax.set_xlabel("t*")
    ax.set_ylabel("alpha")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def plot_force_speed(speeds, material: dict, path) -> Path:
    """Pull-off force against speed: simulation, the seed's closed form, the two limits."""
    import numpy as np

    from ..model import analytic

    t = speeds.table
    v = t["loading.v"]
    e = material
    elastic = analytic.elastic_mdr_dugdale(e["G"], e["sigma_c"], e["delta"], e["a"])
    fig, ax = plt.subplots(figsize=(6.8, 4.8), constrained_layout=True)
    ax.loglog(v, t["F_contact_detach"], "o-", ms=4, label="simulation F_contact")
    ax.loglog(v, t["F_total_detach"], "s--", ms=3, label="simulation F_total")
    ax.loglog(v, t["seed_closed_form_F"], "k-", lw=1.0, label="seed closed form (64/89)")
    vv = np.logspace(np.log10(v.min()), np.log10(v.max()), 200)
    ax.loglog(vv, 8 * e["eta"] * vv * e["a"], "k:", lw=1.0, label="8 eta v a (eq. 96)")
    ax.axhline(analytic.kendall_force(e["G"], e["sigma_c"] * e["delta"], e["a"]), color="C3",
               lw=1.0, ls="-.", label="Kendall (eq. 95)")
    ax.axhline(elastic["F_total"], color="C2", lw=0.8, ls=":", label="elastic MDR F_total")
    # The range of the simulated forces: the viscous line would otherwise spend decades on
    # speeds where it is far below them and squeeze the transition.
    simulated = np.concatenate([t["F_contact_detach"], t["F_total_detach"]])
    simulated = simulated[np.isfinite(simulated) & (simulated > 0)]
    if simulated.size:
        ax.set_ylim(simulated.min() / 2.0, simulated.max() * 2.0)
    ax.set_xlabel("pull speed v [m/s]")
    ax.set_ylabel("pull-off force [N]")
    ax.set_title(f"G = {e['G']:.2g} Pa, eta = {e['eta']:.2g} Pa s, sigma_c = "
                 f"{e['sigma_c']:.2g} Pa, delta = {e['delta']:.2g} m, a = {e['a']:.2g} m",
                 fontsize=8)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


def plot_error_map(emap: dict, grid: dict, claim: float, path) -> Path:
    """Relative error of the seed's closed form against the exact simulation, (alpha, chi)."""
    import numpy as np
    from matplotlib.colors import TwoSlopeNorm

    alphas, chis = np.asarray(grid["map_alpha"]), np.asarray(grid["map_chi"])
    err = np.full((chis.size, alphas.size), np.nan)
    for a, c, F, Fc in zip(emap["alpha"], emap["chi"], emap["F"], emap["F_closed"]):
        i = int(np.argmin(np.abs(np.log(chis / c))))
        j = int(np.argmin(np.abs(np.log(alphas / a))))
        err[i, j] = 100.0 * (Fc - F) / F
    fig, ax = plt.subplots(figsize=(7.2, 4.8), constrained_layout=True)
    limit = max(np.nanmax(np.abs(err)), 100 * claim * 1.2)
    mesh = ax.pcolormesh(alphas, chis, err, shading="nearest", cmap="RdBu_r",
                         norm=TwoSlopeNorm(0.0, -limit, limit))
    fig.colorbar(mesh, ax=ax, label="(closed form - exact) / exact of F_contact [%]")
    if np.nanmax(np.abs(err)) > 100 * claim:
        ax.contour(alphas, chis, np.abs(err), levels=[100 * claim], colors="k",
                   linewidths=1.2)
    ax.plot([], [], "k-", label=f"|error| = {100 * claim:.2f} % (the seed's claim)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("alpha")
    ax.set_ylabel("chi = pi G delta / (sigma_c a)")
    ax.legend(fontsize=8, loc="lower left")
    return _save(fig, path)


def _save(fig, path) -> Path:
    """Save a figure atomically: written beside ``path`` under a temporary name and renamed,
    so an existing figure is replaced whole or not at all."""
    from .files import replaced_whole

    path = Path(path)
    fmt = path.suffix[1:].lower() or "png"
    try:
        if fmt not in fig.canvas.get_supported_filetypes():
            raise ValueError(f"{path}: cannot draw a .{fmt} figure (use .png, .pdf or .svg)")
        with replaced_whole(path) as tmp:
            fig.savefig(tmp, dpi=120, format=fmt)
    finally:
        plt.close(fig)
    return path


#: What a sweep plots: (simulated, closed forms as (column, label, style)), by kind of scene.
_SWEEP_Y = {
    "pull": ("F_contact_detach", "F_contact at detachment [N]",
             (("seed_closed_form_F", "seed closed form (eqs. 64/89)", "--"),)),
    "path": ("F_pulloff", "pull-off force F_pulloff [N]",
             (("relaxed_F_pulloff", "elastic, relaxed modulus", ":"),
              ("instant_F_pulloff", "elastic, instantaneous modulus", "-."))),
}


def plot_sweep(result, path, title: str | None = None) -> Path:
    """The pull-off force against the first numeric axis of a sweep, one line per value of the
    other axes (at most eight), simulation solid and the closed forms beside it: the seed's for
    a pull, the elastic limits (relaxed and instantaneous modulus) for a loading path -- over
    a retraction speed, the master curve."""
    import numpy as np

    t = result.table
    keys = [axis["key"] for axis in result.axes]
    numeric = [k for k in keys if t[k].dtype.kind == "f"]
    if not numeric:
        raise ValueError("a sweep needs a numeric axis to be plotted")
    x_key = numeric[0]
    others = [k for k in keys if k != x_key]
    ok_all = t["status"] == "ok"
    kind = "path" if np.any(np.isfinite(t["F_pulloff"][ok_all])) else "pull"
    y_key, y_label, forms = _SWEEP_Y[kind]
    groups = {}
    for r in range(t["index"].size):
        groups.setdefault(tuple(t[k][r] for k in others), []).append(r)
    fig, ax = plt.subplots(figsize=(7.0, 4.8), constrained_layout=True)
    for i, (label, rows) in enumerate(list(groups.items())[:8]):
        rows = np.asarray(rows)[np.argsort(t[x_key][rows])]
        name = ", ".join(f"{k} = {v:.3g}" if isinstance(v, float) else f"{k} = {v}"
                         for k, v in zip(others, label)) or "simulation"
        ok = t["status"][rows] == "ok"
        ax.plot(t[x_key][rows][ok], t[y_key][rows][ok], "o-", ms=3.5, color=f"C{i}",
                label=name)
        for column, _, style in forms:
            ax.plot(t[x_key][rows][ok], t[column][rows][ok], ls=style, lw=1.0, color=f"C{i}")
    x = t[x_key][ok_all]
    if x.size and np.all(x > 0) and x.max() / x.min() > 20:
        ax.set_xscale("log")
    positive = t[y_key][ok_all]
    if positive.size and np.all(positive > 0) and positive.max() / positive.min() > 20:
        ax.set_yscale("log")
    for column, label, style in forms:
        if np.any(np.isfinite(t[column][ok_all])):
            ax.plot([], [], "k", ls=style, lw=1.0, label=label)
    from ..model.scene import unit_of

    ax.set_xlabel(f"{x_key} [{unit_of(x_key) or '-'}]")
    ax.set_ylabel(y_label)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    if title:
        ax.set_title(title, fontsize=9)
    return _save(fig, path)
