"""The console table of a run: simulation beside the seed's closed forms (from a record dict)."""

from __future__ import annotations

import contextlib
import math

import numpy as np


@contextlib.contextmanager
def progress_bar(enabled: bool, desc: str, total: int | None = None, unit: str = "step"):
    """A tqdm bar on the terminal while the block runs: yields its ``update`` (or ``None``
    when ``enabled`` is false), and closes it however the block ends."""
    if not enabled:
        yield None
        return
    from tqdm import tqdm

    bar = tqdm(total=total, desc=desc, unit=unit, leave=False)
    try:
        yield bar.update
    finally:
        bar.close()


def _fmt(value, unit=""):
    if isinstance(value, str):
        return value
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    text = f"{value:.6g}"
    return f"{text} {unit}".rstrip()


def _rel(model, reference):
    """``(model - reference)/|reference|`` as a percentage, or the ratio where they are more
    than a factor 10 apart (a closed form outside its range says nothing in percent)."""
    if not all(isinstance(x, (int, float)) and math.isfinite(x) for x in (model, reference)):
        return "n/a"
    if reference == 0:
        return "n/a"
    ratio = model / reference
    if not 0.1 <= ratio <= 10.0:
        return f"x{ratio:.3g}"
    return f"{(model - reference) / abs(reference):+.2%}"


def format_table(record: dict, title: str | None = None) -> str:
    """A short plain-text table: detachment, forces, closed forms and their differences.

    The differences are ``(closed form - simulation) / simulation`` against the simulated
    ``F_contact`` (the seed's own definition of the pull-off force, eq. 48).
    """
    s = record["summary"]
    lines = []
    if title:
        lines.append(title)
    lines.append(f"  model: history={s.get('history', 'exact')}   alpha = {_fmt(s['alpha'])}   "
                 f"chi = {_fmt(s['chi'])}   V = {_fmt(s['V'])}   solver: {s.get('solver', '?')}")
    if "F_pulloff" in s and isinstance(s["F_pulloff"], float) and math.isfinite(s["F_pulloff"]):
        lines[-1] = f"  model: path   solver: {s.get('solver', '?')}"
        lines.extend(_path_lines(record))
    elif not record.get("complete", True):
        lines.append(f"  INCOMPLETE: interrupted at t = {_fmt(s['t_end'], 's')}; the history "
                     f"holds what was computed until then")
    elif not s["detached"]:
        lines.append(f"  no detachment before t_max = {_fmt(s['t_end'], 's')} "
                     f"(last simulated time); raise numerics.t_max to continue")
    else:
        lines.extend(_onset_lines(s, record["analytic"]))
    if (s.get("until") == "separation" and record.get("complete", True)
            and not math.isfinite(s.get("F_pulloff", math.nan))):
        lines.extend(_separation_lines(s))
    for note in filter(None, str(s.get("notes", "")).split("; ")):
        lines.append(f"  note: {note}")
    rows = record.get("history_rows_in_file", len(record["history"]["t"]))
    work = (f"Gauss nodes {s['n_elements']}, gap evaluations {s['n_steps']}"
            if s.get("solver") == "onset_quadrature"
            else f"elements {s['n_elements']}, steps {s['n_steps']}")
    lines.append(f"  {work}, history rows {rows}, wall time {s['wall_time'] * 1e3:.1f} ms")
    return "\n".join(lines)


def _onset_lines(s: dict, an: dict) -> list[str]:
    """The onset's values and the closed forms against them."""
    rows = [
        ("detachment time t", s["t_detach"], "s"),
        ("lift h", s["h_detach"], "m"),
        ("cohesive-zone end b", s["b_detach"], "m"),
        ("(b - a)/a", s.get("zone_ratio_detach"), ""),
        ("F_contact (eq. 48)", s["F_contact_detach"], "N"),
        ("F_total (with zone)", s["F_total_detach"], "N"),
    ]
    lines = ["  simulation"]
    for label, value, unit in rows:
        lines.append(f"    {label:<28} {_fmt(value, unit):>16}")
    lines.append(f"    {'error estimate (relative)':<28} {_fmt(s['error_estimate']):>16}")
    F = s["F_contact_detach"]
    t = s["t_detach"]
    lines.append("  closed forms                           value   vs simulation")
    compare = [
        ("seed linearised t (eq. 53)", an.get("seed_linearised_t_detach"), "s", t),
        ("seed linearised F (eq. 48)", an.get("seed_linearised_F"), "N", F),
        (f"seed closed form F ({an.get('seed_closed_form_branch', '?')})",
         an.get("seed_closed_form_F"), "N", F),
        ("Kendall F (eq. 95)", an.get("kendall_F"), "N", F),
        ("viscous F = 8 eta v a (eq. 96)", an.get("viscous_F"), "N", F),
        ("elastic MDR-Dugdale F_contact", an.get("elastic_F_contact"), "N", F),
        ("elastic MDR-Dugdale F_total", an.get("elastic_F_total"), "N", s["F_total_detach"]),
    ]
    instant = an.get("elastic_instant_F_total")
    if isinstance(instant, float) and math.isfinite(instant):
        compare.append(("elastic, instantaneous modulus F_total", instant, "N",
                        s["F_total_detach"]))
    for label, value, unit, ref in compare:
        lines.append(f"    {label:<34} {_fmt(value, unit):>14}   {_rel(value, ref):>10}")
    return lines


def _separation_lines(s: dict) -> list[str]:
    """A run past the onset: separation, peaks, and the ladder's order."""
    F_on = s["F_total_detach"]
    rows = [
        ("separation time", _fmt(s.get("t_separation"), "s")),
        ("peak F_contact", f"{_fmt(s.get('F_peak_contact'), 'N')} at "
                           f"{_fmt(s.get('t_peak_contact'), 's')}"),
        ("peak F_total", f"{_fmt(s.get('F_peak_total'), 'N')} at "
                         f"{_fmt(s.get('t_peak_total'), 's')}"),
        ("peak / onset F_total", _rel(s.get("F_peak_total"), F_on)),
    ]
    order = s.get("observed_order")
    if isinstance(order, float) and math.isfinite(order):
        # A number only where the last three levels converge; elsewhere it would mislead.
        rows.append(("observed order (step)", _fmt(order) if order >= 0.5 else
                     "none: levels not converging"))
    return ["  past the onset (model.until = separation)"] + [
        f"    {label:<28} {text:>30}" for label, text in rows]


def _path_lines(record) -> list[str]:
    """The summary of a loading path: pull-off, jumps, energy, and the closed forms (elastic
    solids) beside them."""
    s, an = record["summary"], record["analytic"]
    lines = []
    if not record.get("complete", True):
        lines.append(f"  INCOMPLETE: interrupted at t = {_fmt(s['t_end'], 's')}")
    rows = [
        ("pull-off F_pulloff", f"{_fmt(s.get('F_pulloff'), 'N')} at h = "
                               f"{_fmt(s.get('h_pulloff'), 'm')}"),
        ("most compressive F_total", _fmt(s.get("F_max_compressive"), "N")),
        ("jump in: F, h", f"{_fmt(s.get('F_jump_in'), 'N')}, {_fmt(s.get('h_jump_in'), 'm')}"),
        ("jump out: F, h", f"{_fmt(s.get('F_jump_out'), 'N')}, "
                           f"{_fmt(s.get('h_jump_out'), 'm')}"),
        ("energy dissipated", _fmt(s.get("energy_dissipated"), "J")),
        ("work of separation", _fmt(s.get("work_separation"), "J")),
        ("Maugis lambda", _fmt(s.get("maugis_lambda"))),
        ("error estimate (relative)", _fmt(s.get("error_estimate"))),
    ]
    lines.append("  simulation")
    for label, text in rows:
        lines.append(f"    {label:<28} {text:>34}")
    compare = [
        ("MDR-Dugdale F, load control", "mdr_dugdale_F_pulloff_load", "F_pulloff"),
        ("MDR-Dugdale F, displ. control", "mdr_dugdale_F_pulloff_displacement", "F_jump_out"),
        ("Maugis-Dugdale F, load control", "maugis_F_pulloff_load", "F_pulloff"),
        ("Maugis-Dugdale F, displ. control", "maugis_F_pulloff_displacement", "F_jump_out"),
        ("JKR F, load control", "jkr_F_pulloff_load", "F_pulloff"),
        ("elastic, relaxed modulus", "relaxed_F_pulloff", "F_pulloff"),
        ("elastic, instantaneous modulus", "instant_F_pulloff", "F_pulloff"),
    ]
    shown = [(label, an.get(key), s.get(ref), ref) for label, key, ref in compare
             if isinstance(an.get(key), float) and math.isfinite(an.get(key))]
    if shown:
        lines.append("  closed forms (elastic)                 value   vs simulation")
        for label, value, ref, name in shown:
            lines.append(f"    {label:<34} {_fmt(value, 'N'):>14}   {_rel(value, ref):>10}"
                         f" ({name})")
    return lines


def _short(value) -> str:
    if isinstance(value, (float, np.floating)):
        return "n/a" if math.isnan(value) else f"{value:.4g}"
    return str(value)


def format_sweep(result, max_rows: int = 40, title: str | None = None) -> str:
    """One line per scene: the varied values, the groups (alpha/chi of a pull, lambda and the
    speed in relaxation times of a path), the simulated force and its closed forms;
    an interrupted sweep is marked INCOMPLETE with how many of its planned rows it holds."""
    table = result.table
    keys = [axis["key"] for axis in result.axes]
    n = table["index"].size
    failed = int(np.sum(table["status"] != "ok"))
    planned = getattr(result, "n_points", None)
    lines = [title] if title else []
    lines.append(f"sweep over {' x '.join(keys)}: {n} rows, {failed} failed")
    if not getattr(result, "complete", True):
        lines.append(f"  INCOMPLETE: {n} of {planned if planned is not None else '?'} planned "
                     f"rows (interrupted; run the same sweep command to resume)")
    ok = table["status"] == "ok"
    path = bool(np.any(np.isfinite(np.asarray(table["F_pulloff"], dtype=float)[ok])))
    # A pull: the seed's groups and closed form; a loading path: the elastic limits.
    groups, (force, *forms) = ((("maugis_lambda", "speed_relaxation"),
                                ("F_pulloff", "relaxed_F_pulloff", "instant_F_pulloff"))
                               if path else (("alpha", "chi"),
                                             ("F_contact_detach", "seed_closed_form_F")))
    heads = (["lambda", "v tau / delta", "F_pulloff [N]", "relaxed", "instant"] if path else
             ["alpha", "chi", "F_contact [N]", "closed form"])
    columns = keys + heads + ["estimate", "status"]
    widths = [max(12, len(c)) for c in columns]
    lines.append("  " + " ".join(f"{c:>{w}}" for c, w in zip(columns, widths)))
    shown = range(n) if n <= max_rows else list(range(max_rows // 2)) + list(
        range(n - max_rows // 2, n))
    previous = -1
    for r in shown:
        if r != previous + 1:
            lines.append(f"  ... {n - max_rows} rows not shown ...")
        previous = r
        F = table[force][r]
        cells = ([_short(table[k][r]) for k in keys] + [_short(table[g][r]) for g in groups]
                 + [_short(F)] + [_rel(float(table[c][r]), float(F)) for c in forms]
                 + [_short(table["error_estimate"][r]), str(table["status"][r])])
        line = "  " + " ".join(f"{c:>{w}}" for c, w in zip(cells, widths))
        if table["status"][r] != "ok":
            line += f"  ({table['message'][r]})"
        lines.append(line)
    return "\n".join(lines)


def scene_name(record: dict) -> str | None:
    """The ``name`` of the scene stored in a run record (None if it has none)."""
    from .scene_file import read_yaml

    try:
        data = read_yaml(str(record.get("scene", "")))
    except ValueError:
        return None
    name = data.get("name") if isinstance(data, dict) else None
    return str(name) if name is not None else None


def _csv_value(value) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (float, np.floating)):
        return "" if math.isnan(value) else repr(float(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    return str(value)


def write_sweep_csv(result, stream) -> None:
    """A sweep's table as CSV (header: column names with their units in brackets; empty
    cells for nan), rows in grid order: for spreadsheets, pandas, R."""
    import csv

    column_unit = result.unit
    names = result.columns()
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow([f"{n} [{column_unit(n)}]" if column_unit(n) not in ("", "1") else n
                     for n in names])
    columns = [result.table[n] for n in names]
    for r in range(result.table["index"].size):
        writer.writerow([_csv_value(column[r]) for column in columns])


def write_history_csv(record: dict, stream) -> None:
    """A run's history as CSV, one row per stored time, SI units in the header."""
    import csv

    from .h5 import HISTORY_UNITS

    names = [n for n in HISTORY_UNITS if n in record["history"]]
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow([f"{n} [{HISTORY_UNITS[n]}]" for n in names])
    columns = [record["history"][n] for n in names]
    for r in range(len(columns[0]) if columns else 0):
        writer.writerow([_csv_value(column[r]) for column in columns])
