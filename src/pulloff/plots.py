"""Figures of a run, drawn from a record dict (a fresh result or a loaded file)."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; a run on a headless machine must not need a display
import matplotlib.pyplot as plt  # noqa: E402


def plot_history(record: dict, path, title: str | None = None) -> Path:
    """Force and gap histories with the closed-form forces marked; saves a PNG at ``path``."""
    h = record["history"]
    s = record["summary"]
    an = record["analytic"]
    t_ms = h["t"] * 1e3
    fig, (ax_f, ax_g) = plt.subplots(2, 1, figsize=(7.0, 6.4), sharex=True,
                                     constrained_layout=True)
    ax_f.plot(t_ms, h["F_contact"], label="F_contact (simulation)", color="C0")
    ax_f.plot(t_ms, h["F_total"], label="F_total (simulation)", color="C1", ls="--")
    for key, label, style in (("seed_closed_form_F", "seed closed form", ":"),
                              ("seed_linearised_F", "seed eq. 53 + 48", "-."),
                              ("kendall_F", "Kendall", (0, (1, 3)))):
        value = an.get(key)
        if isinstance(value, float) and math.isfinite(value):
            ax_f.axhline(value, color="0.4", ls=style, lw=1.0, label=label)
    if s["detached"]:
        ax_f.plot([s["t_detach"] * 1e3], [s["F_contact_detach"]], "ko", ms=4,
                  label="detachment")
    ax_f.set_ylabel("force [N]")
    ax_f.legend(fontsize=8, loc="upper left")
    ax_f.grid(alpha=0.3)

    ax_g.plot(t_ms, h["gap"] * 1e9, color="C2", label="gap at r = b")
    delta = _delta(record)
    if delta is not None:
        ax_g.axhline(delta * 1e9, color="0.4", ls=":", lw=1.0, label="delta")
    ax_g.set_xlabel("time [ms]")
    ax_g.set_ylabel("gap [nm]")
    ax_g.legend(fontsize=8, loc="upper left")
    ax_g.grid(alpha=0.3)
    if title:
        fig.suptitle(title, fontsize=10)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _delta(record) -> float | None:
    import yaml

    try:
        return float(yaml.safe_load(record["scene"])["adhesion"]["delta"])
    except Exception:  # the figure is still useful without the reference line
        return None
