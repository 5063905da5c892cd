"""Parameter sweeps: a full grid of scenes, run in parallel, one table row per scene.

A sweep file (HDF5) holds the base scene (YAML text), the axes (JSON) and a ``table`` group with
one dataset per column, each with a ``unit`` attribute. It is rewritten atomically every few
seconds while the sweep runs, so an interruption loses at most the rows of the last few seconds
and never corrupts what was written; running the same command again resumes: rows already in
the file are not recomputed. A scene that fails is a row with ``status = "failed"`` and its
error message; the sweep goes on.

Workers receive :func:`run_point`, a plain function of plain data (base scene text and
overrides), so each process or Dask worker loads numba's disk cache instead of compiling.
"""

from __future__ import annotations

import json
import math
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from itertools import product
from typing import Iterable, Sequence

import numpy as np

from ..io import h5 as h5io
from ..model import outputs
from ..model.scene import unit_of

#: Result columns of the table (beside the axes): every numeric summary and closed-form
#: quantity of the output table (:mod:`pulloff.model.outputs`), name -> unit.
RESULT_COLUMNS = {q.name: q.unit for q in outputs.OUTPUTS
                  if q.group in ("summary", "analytic") and not q.text}
TEXT_COLUMNS = ("status", "message") + tuple(
    q.name for q in outputs.OUTPUTS if q.group in ("summary", "analytic") and q.text
    and q.name != "detached")
#: When a sweep varies one Dugdale parameter, the one held fixed is the first of these that
#: is not varied (so varying sigma_c keeps delta and changes gamma).
_ADHESION_KEEP_ORDER = ("delta", "sigma_c", "gamma")
FLUSH_SECONDS = 2.0
#: Key of a row's history arrays (``--histories``); ``history`` is the model.history column.
ARRAYS = "history_arrays"


class SweepError(ValueError):
    """A sweep that cannot start: bad axis, or an output file holding another sweep."""


@dataclass(frozen=True)
class Axis:
    """One ``--vary`` axis: a dotted scene key and its values."""

    key: str
    values: tuple

    def to_json(self):
        return {"key": self.key, "values": list(self.values)}


def parse_axis(text: str) -> Axis:
    """Parse ``section.key=SPEC`` with SPEC ``lin:a:b:n``, ``log:a:b:n`` or ``v1,v2,...``.

    ``log`` spaces ``n`` values evenly in log10 between ``a`` and ``b`` (both > 0); list values
    are read as YAML scalars (numbers as numbers, ``frozen`` as a string).
    """
    from ..io.scene_file import read_yaml

    key, sep, spec = text.partition("=")
    key = key.strip()
    if not sep or not key or not spec.strip():
        raise SweepError(f"--vary {text!r}: expected SECTION.KEY=lin:a:b:n, log:a:b:n or a "
                         f"comma-separated list")
    spec = spec.strip()
    kind, _, rest = spec.partition(":")
    if kind in ("lin", "log"):
        parts = rest.split(":")
        try:
            if len(parts) != 3:
                raise ValueError
            lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
        except ValueError:
            raise SweepError(f"--vary {text!r}: {kind} needs {kind}:START:STOP:COUNT with "
                             f"numbers and an integer count") from None
        if n < 1 or not (math.isfinite(lo) and math.isfinite(hi)):
            raise SweepError(f"--vary {text!r}: count must be >= 1 and ends finite")
        if kind == "log":
            if lo <= 0 or hi <= 0:
                raise SweepError(f"--vary {text!r}: log spacing needs START, STOP > 0")
            values = np.logspace(math.log10(lo), math.log10(hi), n)
        else:
            values = np.linspace(lo, hi, n)
        return Axis(key, tuple(float(v) for v in values))
    items = [item.strip() for item in spec.strip("[]").split(",") if item.strip()]
    if not items:
        raise SweepError(f"--vary {text!r}: empty list")
    values = []
    for item in items:
        value = read_yaml(item, where=f"--vary {text!r}")
        values.append(float(value) if isinstance(value, int) and not isinstance(value, bool)
                      else value)
    return Axis(key, tuple(values))


def grid(axes: Sequence[Axis]) -> list[tuple]:
    """The full product of the axes' values, first axis slowest."""
    return list(product(*(axis.values for axis in axes)))


def _override(key: str, value) -> str:
    return f"{key}={json.dumps(value)}"


def _adhesion_drops(axes: Sequence[Axis]) -> list[str]:
    """Adhesion keys to remove from the resolved base so that exactly two remain given."""
    varied = [a.key.split(".")[1] for a in axes if a.key.startswith("adhesion.")
              and a.key.split(".")[1] in _ADHESION_KEEP_ORDER]
    if not varied:
        return []
    if len(varied) > 2:
        raise SweepError("--vary: at most two of adhesion.sigma_c, delta, gamma can vary "
                         "(the third follows from gamma = sigma_c delta)")
    keep = list(varied)
    for name in _ADHESION_KEEP_ORDER:
        if len(keep) == 2:
            break
        if name not in keep:
            keep.append(name)
    return [name for name in _ADHESION_KEEP_ORDER if name not in keep]


def run_point(base_yaml: str, overrides: Sequence[str], history: bool = False,
              drop_adhesion: Sequence[str] = ()) -> dict:
    """Run one scene of a sweep; never raises (a failure is a row with its message)."""
    from .. import solvers
    from ..io.scene_file import parse_scene, read_yaml

    row = {"status": "ok", "message": ""}
    try:
        data = read_yaml(base_yaml)
        for name in drop_adhesion:
            data["adhesion"].pop(name, None)
        res = solvers.simulate(parse_scene(data, overrides=overrides))
    except Exception as exc:  # a failed scene is data, not the end of the sweep
        row.update(status="failed", message=f"{type(exc).__name__}: {exc}")
        return row
    if not res.complete:
        # Ctrl-C reached the stepper: a cut-short scene is not a row; stop like the parent.
        raise KeyboardInterrupt
    row.update(res.summary)
    row.update(res.analytic)
    if history:
        row[ARRAYS] = {name: np.asarray(v) for name, v in res.history.items()}
    return row


def _check_axes(base_yaml: str, axes: Sequence[Axis]) -> None:
    """Reject axes naming keys the scene does not have, before any work."""
    from ..io.scene_file import read_yaml

    base = read_yaml(base_yaml)
    seen = set()
    for axis in axes:
        if axis.key in seen:
            raise SweepError(f"--vary {axis.key}: given twice")
        seen.add(axis.key)
        node = base
        for part in axis.key.split("."):
            if not isinstance(node, dict) or part not in node:
                raise SweepError(f"--vary {axis.key}: no such scene key")
            node = node[part]
        if isinstance(node, dict):
            raise SweepError(f"--vary {axis.key}: is a section, not a value")


@dataclass
class SweepResult:
    """A sweep's table as plain numpy arrays, one entry per column, rows in grid order."""

    base_scene: str
    axes: list
    table: dict
    histories: dict

    def column(self, name):
        return self.table[name]


def sweep(scene, axes: Sequence[Axis | str], out=None, workers: int | None = None,
          scheduler: str | None = None, histories: bool = False, progress: bool = False,
          flush_seconds: float = FLUSH_SECONDS) -> SweepResult:
    """Run ``scene`` (a :class:`pulloff.scene.Scene`) over the full product of ``axes``.

    ``workers`` processes on this machine (default: all cores; 1 runs in this process), or a
    Dask distributed cluster at ``scheduler``. With ``out`` the table is kept in that HDF5 file
    and an existing file of the same sweep is resumed.
    """
    axes = [parse_axis(a) if isinstance(a, str) else a for a in axes]
    if not axes:
        raise SweepError("a sweep needs at least one --vary axis")
    return sweep_points(scene, [axis.key for axis in axes], grid(axes), out=out,
                        workers=workers, scheduler=scheduler, histories=histories,
                        progress=progress, flush_seconds=flush_seconds, axes=axes)


def sweep_points(scene, keys: Sequence[str], points: Sequence[tuple], out=None,
                 workers: int | None = None, scheduler: str | None = None,
                 histories: bool = False, progress: bool = False,
                 flush_seconds: float = FLUSH_SECONDS, axes=None) -> SweepResult:
    """Run ``scene`` at explicit ``points``: tuples of values for the dotted ``keys``.

    For sets of scenes that are not a product grid (e.g. a rectangle in ``(alpha, chi)``).
    """
    from ..io.scene_file import scene_to_yaml

    base_yaml = scene_to_yaml(scene)
    keys = list(keys)
    points = [tuple(p) for p in points]
    axes = list(axes) if axes is not None else [
        Axis(key, tuple(p[i] for p in points)) for i, key in enumerate(keys)]
    _check_axes(base_yaml, axes)
    drops = _adhesion_drops(axes)
    layout = _Layout(base_yaml, keys, points, axes)
    rows: dict[int, dict] = {}
    if out is not None and os.path.exists(out):
        rows = _resume(out, layout)
    todo = [i for i in range(len(points)) if i not in rows]
    overrides = {i: [_override(key, value) for key, value in zip(keys, points[i])]
                 for i in todo}

    bar = None
    if progress and todo:
        from tqdm import tqdm

        bar = tqdm(total=len(points), initial=len(points) - len(todo), unit="scene",
                   desc="sweep")
    last_flush = time.monotonic()
    try:
        for index, row in _execute(base_yaml, overrides, todo, workers, scheduler, histories,
                                   drops):
            rows[index] = row
            if bar is not None:
                bar.update(1)
            if out is not None and time.monotonic() - last_flush > flush_seconds:
                _write(out, layout, rows)
                last_flush = time.monotonic()
    finally:
        if bar is not None:
            bar.close()
        if out is not None and (todo or not os.path.exists(out)):
            _write(out, layout, rows)
    return _as_result(layout, rows)


@dataclass(frozen=True)
class _Layout:
    """What identifies a sweep: its base scene and its points (for resuming)."""

    base_yaml: str
    keys: list
    points: list
    axes: list

    def attrs(self) -> dict:
        return {"base_scene": self.base_yaml, "keys": json.dumps(self.keys),
                "points": json.dumps(self.points),
                "axes": json.dumps([axis.to_json() for axis in self.axes])}


def _execute(base_yaml, overrides, todo, workers, scheduler, histories, drops) -> Iterable:
    if not todo:
        return
    if scheduler is not None:
        yield from _execute_dask(base_yaml, overrides, todo, scheduler, histories, drops)
        return
    workers = workers or os.cpu_count() or 1
    if workers == 1 or len(todo) == 1:
        for i in todo:
            yield i, run_point(base_yaml, overrides[i], histories, drops)
        return
    with ProcessPoolExecutor(max_workers=min(workers, len(todo))) as pool:
        futures = {pool.submit(run_point, base_yaml, overrides[i], histories, drops): i
                   for i in todo}
        try:
            for future in as_completed(futures):
                yield futures[future], future.result()
        except BaseException:
            for future in futures:
                future.cancel()
            raise


def run_points(base_yaml: str, batch: Sequence[tuple], history: bool = False,
               drop_adhesion: Sequence[str] = ()) -> list:
    """:func:`run_point` over a batch of ``(index, overrides)``; returns ``(index, row)`` pairs.

    One task per batch keeps a scheduler's per-task overhead (milliseconds) off scenes that
    take about as long.
    """
    return [(i, run_point(base_yaml, ov, history, drop_adhesion)) for i, ov in batch]


def _execute_dask(base_yaml, overrides, todo, scheduler, histories, drops):
    try:
        from distributed import Client, as_completed as dask_completed
    except ImportError:  # the extra is optional
        raise SweepError("--scheduler needs Dask distributed: pip install -e \".[dask]\"") \
            from None
    with Client(scheduler) as client:
        n_workers = max(1, len(client.scheduler_info().get("workers", {})))
        # About eight batches per worker: balanced load, progress that still moves.
        size = max(1, len(todo) // (8 * n_workers))
        batches = [[(i, overrides[i]) for i in todo[j:j + size]]
                   for j in range(0, len(todo), size)]
        futures = [client.submit(run_points, base_yaml, batch, histories, drops, pure=False)
                   for batch in batches]
        for future in dask_completed(futures):
            yield from future.result()


# --- file ----------------------------------------------------------------------------------

def _table(layout: _Layout, rows):
    indices = sorted(rows)
    table = {"index": np.asarray(indices, dtype=np.int64)}
    for a, key in enumerate(layout.keys):
        values = [layout.points[i][a] for i in indices]
        numeric = all(isinstance(v, (int, float)) and not isinstance(v, bool)
                      for v in (p[a] for p in layout.points))
        table[key] = (np.asarray(values, dtype=float) if numeric
                      else np.asarray([str(v) for v in values], dtype=object))
    for name in RESULT_COLUMNS:
        table[name] = np.asarray([rows[i].get(name, math.nan) for i in indices], dtype=float)
    table["detached"] = np.asarray([bool(rows[i].get("detached", False)) for i in indices])
    for name in TEXT_COLUMNS:
        table[name] = np.asarray([str(rows[i].get(name, "")) for i in indices], dtype=object)
    return table


def _write(out, layout: _Layout, rows) -> None:
    import h5py

    table = _table(layout, rows)
    with h5io.atomic_file(out) as f:
        f.attrs["kind"] = "sweep"
        for name, value in layout.attrs().items():
            f.attrs[name] = value
        f.attrs["n_points"] = len(layout.points)
        f.attrs["complete"] = len(rows) == len(layout.points)
        g = f.create_group("table")
        for name, values in table.items():
            if values.dtype == object:
                ds = g.create_dataset(name, data=values.astype(str).astype(object),
                                      dtype=h5py.string_dtype())
            else:
                ds = g.create_dataset(name, data=values)
            ds.attrs["unit"] = RESULT_COLUMNS.get(name) or unit_of(name)
        hist = [i for i in sorted(rows) if ARRAYS in rows[i]]
        if hist:
            h = f.create_group("histories")
            for i in hist:
                gi = h.create_group(f"{i:06d}")
                for name, values in rows[i][ARRAYS].items():
                    ds = gi.create_dataset(name, data=values)
                    ds.attrs["unit"] = h5io.HISTORY_UNITS[name]


def _read_rows(f) -> dict:
    g = f["table"]
    indices = g["index"][()]
    rows = {}
    for r, i in enumerate(indices):
        row = {name: float(g[name][r]) for name in RESULT_COLUMNS if name in g}
        row["detached"] = bool(g["detached"][r])
        for name in (n for n in TEXT_COLUMNS if n in g):
            value = g[name][r]
            row[name] = value.decode() if isinstance(value, bytes) else str(value)
        if "histories" in f and f"{i:06d}" in f["histories"]:
            gi = f["histories"][f"{i:06d}"]
            row[ARRAYS] = {name: gi[name][()] for name in gi}
        rows[int(i)] = row
    return rows


def _layout_of(f) -> _Layout:
    missing = [name for name in ("axes", "points", "base_scene", "keys") if name not in f.attrs]
    if missing:
        # A sweep file of an older layout (or a damaged one): say so instead of a KeyError.
        raise SweepError(f"{f.filename}: a sweep file without {', '.join(missing)} (written by "
                         f"an older pulloff?); choose another -o or remove the file")
    axes = [Axis(a["key"], tuple(a["values"])) for a in json.loads(f.attrs["axes"])]
    points = [tuple(p) for p in json.loads(f.attrs["points"])]
    return _Layout(str(f.attrs["base_scene"]), json.loads(f.attrs["keys"]), points, axes)


def _resume(out, layout: _Layout) -> dict:
    with h5io.open_for_reading(out) as f:
        h5io.check_pulloff_file(out, f)
        if f.attrs.get("kind") != "sweep":
            raise SweepError(f"{out}: exists and is not a sweep file; choose another -o")
        if _layout_of(f).attrs() != layout.attrs():
            raise SweepError(f"{out}: holds a different sweep (base scene or points differ); "
                             f"choose another -o or remove the file")
        return _read_rows(f)


def _as_result(layout: _Layout, rows) -> SweepResult:
    histories = {i: rows[i][ARRAYS] for i in sorted(rows) if ARRAYS in rows[i]}
    return SweepResult(layout.base_yaml, [axis.to_json() for axis in layout.axes],
                       _table(layout, rows), histories)


def load_sweep(path) -> SweepResult:
    """Read a sweep file into plain numpy arrays (rows in point order)."""
    with h5io.open_for_reading(path) as f:
        h5io.check_pulloff_file(path, f)
        if f.attrs.get("kind") != "sweep":
            raise ValueError(f"{path}: not a sweep file")
        layout = _layout_of(f)
        rows = _read_rows(f)
    return _as_result(layout, rows)
