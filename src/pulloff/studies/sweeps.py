"""Parameter sweeps: a full grid of scenes, run in parallel, one table row per scene.

A sweep file (HDF5) holds the base scene (YAML text), the axes (JSON), the planned size
(``n_points``), whether every row is in (``complete``) and a ``table`` group with one dataset
per column, each with a ``unit`` attribute. It is rewritten atomically every few seconds while
the sweep runs, so an interruption (Ctrl-C, SIGTERM, SIGHUP) loses at most the rows of the last
few seconds and never corrupts what was written; running the same command again resumes: rows
already in the file are not recomputed. A scene that fails is a row with ``status = "failed"``
and its error message; the sweep goes on. One process writes one sweep file at a time (a lock
beside it).

The grid is never built as a list: a point is computed from its index, work is handed to the
workers a few scenes ahead of them, finished rows are kept in compact columns, and the file
is rewritten at a pace that keeps its cost a small part of the run. A grid larger than
:data:`MAX_POINTS` is refused unless ``max_points`` says otherwise.

Workers receive :func:`run_point`, a plain function of plain data (base scene text and
overrides), so each process or Dask worker loads numba's disk cache instead of compiling. They
ignore the signals that stop a sweep (the parent decides, writes the rows and ends them) and
exit when the parent dies.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import sys
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import suppress
from dataclasses import dataclass, field
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
#: The file is rewritten at most once per this many times the duration of its last write.
FLUSH_COST_FACTOR = 20.0
#: Largest grid run without ``max_points`` (``--max-points``) saying more.
MAX_POINTS = 100_000
#: Tasks handed to each worker ahead of the one it runs.
AHEAD = 4
#: Work per task of a worker process once scenes have been timed [s], and its most scenes.
BATCH_SECONDS = 0.05
MAX_BATCH = 64
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


_SPEC_HELP = ("expected SECTION.KEY=lin:START:STOP:COUNT, log:START:STOP:COUNT or a "
              "comma-separated list v1,v2,...")


def parse_axis(text: str, max_points: int | None = MAX_POINTS) -> Axis:
    """Parse ``section.key=SPEC`` with SPEC ``lin:a:b:n``, ``log:a:b:n`` or ``v1,v2,...``.

    ``log`` spaces ``n`` values evenly in log10 between ``a`` and ``b`` (both > 0); list values
    are read as YAML scalars (numbers as numbers, ``frozen`` as a string). A list item is
    addressed by its index (``material.terms.0.G=...``). Every mistake is a
    :class:`SweepError` naming the axis: an unknown spacing (``foo:1:2:3``), an empty list
    item, a count above ``max_points``.
    """
    from ..io.scene_file import read_yaml
    from ..model.scene import SceneError

    if not isinstance(text, str):
        raise SweepError(f"--vary {text!r}: must be a string, {_SPEC_HELP}")
    key, sep, spec = text.partition("=")
    key = key.strip()
    if not sep or not key or not spec.strip():
        raise SweepError(f"--vary {text!r}: {_SPEC_HELP}")
    parts = key.split(".")
    if not all(part.strip() and part == part.strip() for part in parts):
        raise SweepError(f"--vary {text!r}: {key!r} is not a dotted scene key "
                         f"(section.key, e.g. loading.v)")
    spec = spec.strip()
    kind, colon, rest = spec.partition(":")
    if kind in ("lin", "log"):
        pieces = rest.split(":")
        try:
            if len(pieces) != 3:
                raise ValueError
            lo, hi, n = float(pieces[0]), float(pieces[1]), int(pieces[2])
        except ValueError:
            raise SweepError(f"--vary {text!r}: {kind} needs {kind}:START:STOP:COUNT with "
                             f"numbers and an integer count") from None
        if n < 1 or not (math.isfinite(lo) and math.isfinite(hi)):
            raise SweepError(f"--vary {text!r}: count must be >= 1 and ends finite")
        if max_points is not None and n > max_points:
            raise SweepError(f"--vary {text!r}: {n} values, more than --max-points "
                             f"{max_points}; give --max-points {n} to run a grid that large")
        if kind == "log":
            if lo <= 0 or hi <= 0:
                raise SweepError(f"--vary {text!r}: log spacing needs START, STOP > 0")
            values = np.logspace(math.log10(lo), math.log10(hi), n)
        else:
            values = np.linspace(lo, hi, n)
        return Axis(key, tuple(float(v) for v in values))
    if colon:
        # "foo:1:2:3" (or "Log:...") would otherwise be a one-value list holding a string.
        raise SweepError(f"--vary {text!r}: unknown spacing {kind!r} (lin or log); "
                         f"{_SPEC_HELP}")
    body = spec[1:-1] if spec.startswith("[") and spec.endswith("]") else spec
    items = [item.strip() for item in body.split(",")]
    if not any(items):
        raise SweepError(f"--vary {text!r}: empty list")
    if not all(items):
        raise SweepError(f"--vary {text!r}: item {items.index('') + 1} of the list is empty "
                         f"(two commas, or one at an end)")
    if max_points is not None and len(items) > max_points:
        raise SweepError(f"--vary {text!r}: {len(items)} values, more than --max-points "
                         f"{max_points}; give --max-points {len(items)} to run it")
    values = []
    for item in items:
        try:
            value = read_yaml(item, where=f"--vary {text!r}")
        except SceneError as exc:
            raise SweepError(str(exc)) from None
        if value is None or isinstance(value, (list, dict)):
            raise SweepError(f"--vary {text!r}: item {item!r} is not a single value")
        values.append(float(value) if isinstance(value, int) and not isinstance(value, bool)
                      else value)
    return Axis(key, tuple(values))


def grid_size(axes: Sequence[Axis]) -> int:
    """Points of the full product of ``axes``."""
    return math.prod(len(axis.values) for axis in axes)


def check_size(n: int, max_points: int | None) -> None:
    """Refuse a grid above ``max_points`` before any work."""
    if max_points is not None and n > max_points:
        raise SweepError(f"--vary: the grid has {n} points, more than --max-points "
                         f"{max_points}; give --max-points {n} to run a grid that large")


def check_workers(workers) -> None:
    """``workers`` is ``None`` (all cores) or a whole number >= 1."""
    if workers is None:
        return
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1:
        raise SweepError(f"--workers = {workers!r}: must be a whole number >= 1 "
                         f"(default: all cores)")


def grid(axes: Sequence[Axis]) -> list[tuple]:
    """The full product of the axes' values, first axis slowest (a list: small grids only;
    a sweep computes its points from their index)."""
    from itertools import product

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
        scene = parse_scene(data, overrides=overrides)
        # A row without its history keeps only the summary: the run's SI history is then
        # its first and last row, not the hundreds a stored one has (measured: 88 us of a
        # seed scene's ~2 ms at rtol 1e-6 for 300 rows, 46 us for two).
        observers = None if history else solvers.Observers(history_rows=2)
        res = solvers.simulate(scene, observers=observers)
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
        parts = axis.key.split(".")
        for i, part in enumerate(parts):
            where = ".".join(parts[:i]) or "scene"
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise SweepError(f"--vary {axis.key}: {where} has {len(node)} items; "
                                     f"{part!r} is not an index of it")
                node = node[int(part)]
            elif isinstance(node, dict) and part in node:
                node = node[part]
            else:
                raise SweepError(f"--vary {axis.key}: no such scene key")
        if isinstance(node, (dict, list)):
            raise SweepError(f"--vary {axis.key}: is a section, not a value")


@dataclass
class SweepResult:
    """A sweep's table as plain numpy arrays, one entry per column, rows in grid order.

    ``n_points`` is the planned size of the sweep and ``complete`` whether every planned row
    is in the table (an interrupted sweep is resumed by running it again).
    """

    base_scene: str
    axes: list
    table: dict
    histories: dict
    n_points: int | None = None
    complete: bool = True
    keys: list = field(default_factory=list)

    def column(self, name):
        return self.table[name]

    @property
    def name(self) -> str | None:
        """The base scene's name (or None)."""
        from ..io.scene_file import read_yaml

        try:
            data = read_yaml(self.base_scene)
        except ValueError:
            return None
        value = data.get("name") if isinstance(data, dict) else None
        return str(value) if value is not None else None

    def columns(self) -> list[str]:
        """Column names in table order: index, the varied keys, results, text."""
        keys = self.keys or [axis["key"] for axis in self.axes]
        first = ["index"] + [k for k in keys if k in self.table]
        return first + [name for name in self.table if name not in first]

    def unit(self, name: str) -> str:
        """The SI unit of a column ("" for text, flags and counts, "1" dimensionless)."""
        return column_unit(name)

    def to_dataframe(self):
        """The table as a :class:`pandas.DataFrame` (pandas is an optional extra:
        ``pip install "pulloff[pandas]"``), indexed by the grid index."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("SweepResult.to_dataframe needs pandas, an optional extra: "
                              "pip install \"pulloff[pandas]\" (or pip install pandas)") from None
        frame = pd.DataFrame({name: self.table[name] for name in self.columns()})
        frame = frame.set_index("index")
        frame.attrs.update(n_points=self.n_points, complete=self.complete,
                           units={name: column_unit(name) for name in self.table})
        return frame


def column_unit(name: str) -> str:
    """The unit of a sweep table column (empty for text and counts)."""
    return RESULT_COLUMNS.get(name) or unit_of(name)


def sweep(scene, axes: Sequence[Axis | str] | str, out=None, workers: int | None = None,
          scheduler: str | None = None, histories: bool = False, progress: bool = False,
          flush_seconds: float = FLUSH_SECONDS, max_points: int | None = MAX_POINTS,
          replace: bool = False, key: str = "-o") -> SweepResult:
    """Run ``scene`` (a :class:`pulloff.model.scene.Scene`) over the full product of ``axes``.

    ``workers`` processes on this machine (default: all cores; 1 runs in this process), or a
    Dask distributed cluster at ``scheduler``. With ``out`` the table is kept in that HDF5 file
    and an existing file of the same sweep is resumed. A grid of more than ``max_points``
    points is refused (``None``: no limit). Every mistake is raised before any work. With
    ``replace``, see :func:`sweep_points`.
    """
    if isinstance(axes, (str, Axis)):  # one axis, not a list of characters
        axes = [axes]
    axes = [parse_axis(a, max_points) if isinstance(a, str) else a for a in axes]
    if not axes:
        raise SweepError("a sweep needs at least one --vary axis")
    check_size(grid_size(axes), max_points)
    return _sweep(scene, _Layout.product(_base_yaml(scene), axes), out=out, workers=workers,
                  scheduler=scheduler, histories=histories, progress=progress,
                  flush_seconds=flush_seconds, replace=replace, key=key)


def sweep_points(scene, keys: Sequence[str], points: Sequence[tuple], out=None,
                 workers: int | None = None, scheduler: str | None = None,
                 histories: bool = False, progress: bool = False,
                 flush_seconds: float = FLUSH_SECONDS, axes=None, replace: bool = False,
                 key: str = "-o") -> SweepResult:
    """Run ``scene`` at explicit ``points``: tuples of values for the dotted ``keys``.

    For sets of scenes that are not a product grid (e.g. a rectangle in ``(alpha, chi)``).
    With ``replace`` an ``out`` file holding another sweep of the same base scene and keys is
    not refused but replaced, keeping the rows of the points both share (so a changed grid
    recomputes only what differs).
    """
    keys = list(keys)
    points = [tuple(p) for p in points]
    if any(len(p) != len(keys) for p in points):
        raise SweepError(f"sweep_points: every point needs {len(keys)} values ({keys})")
    axes = list(axes) if axes is not None else [
        Axis(k, tuple(dict.fromkeys(p[i] for p in points))) for i, k in enumerate(keys)]
    layout = _Layout(_base_yaml(scene), keys, axes, points)
    return _sweep(scene, layout, out=out, workers=workers, scheduler=scheduler,
                  histories=histories, progress=progress, flush_seconds=flush_seconds,
                  replace=replace, key=key)


def _base_yaml(scene) -> str:
    from ..io.scene_file import scene_to_yaml

    return scene_to_yaml(scene)


def _sweep(scene, layout: _Layout, out, workers, scheduler, histories, progress,
           flush_seconds, replace=False, key="-o") -> SweepResult:
    check_workers(workers)
    _check_axes(layout.base_yaml, layout.axes)
    drops = _adhesion_drops(layout.axes)
    if out is None:
        return _run(layout, _Rows(layout.n), None, workers, scheduler, histories, drops,
                    progress, flush_seconds)
    out = h5io.check_target(out, key)
    if out.exists():
        _resume(out, layout, replace, key)  # refuse a different sweep before taking the lock
    with h5io.output_lock(out, key):
        rows = _resume(out, layout, replace, key) if out.exists() else _Rows(layout.n)
        return _run(layout, rows, out, workers, scheduler, histories, drops, progress,
                    flush_seconds, key)


def _run(layout, rows, out, workers, scheduler, histories, drops, progress, flush_seconds,
         key="-o") -> SweepResult:
    todo = np.flatnonzero(~rows.done)
    bar = None
    if progress and todo.size:
        from tqdm import tqdm

        bar = tqdm(total=layout.n, initial=layout.n - todo.size, unit="scene", desc="sweep")
    last_flush = time.monotonic()
    pause = flush_seconds
    finished = _execute(layout, todo, workers, scheduler, histories, drops)
    try:
        for index, row in finished:
            rows.add(index, row)
            if bar is not None:
                bar.update(1)
            if out is not None and time.monotonic() - last_flush > pause:
                start = time.monotonic()
                _write(out, layout, rows, key)
                last_flush = time.monotonic()
                # Rewriting a large table costs: keep it a small part of the sweep.
                pause = max(flush_seconds, FLUSH_COST_FACTOR * (last_flush - start))
    finally:
        finished.close()  # stops the workers now if the sweep was interrupted
        if bar is not None:
            bar.close()
        if out is not None and (todo.size or not os.path.exists(out)):
            _write(out, layout, rows, key)
    return _as_result(layout, rows)


class _Layout:
    """What identifies a sweep: its base scene, keys and points (for resuming). A product grid
    keeps only its axes; a point is computed from its index, first axis slowest."""

    def __init__(self, base_yaml: str, keys, axes, points=None):
        self.base_yaml = base_yaml
        self.keys = list(keys)
        self.axes = list(axes)
        self.points = points  # None: the full product of the axes
        self.n = grid_size(self.axes) if points is None else len(points)
        sizes = [len(axis.values) for axis in self.axes]
        self._strides = [math.prod(sizes[a + 1:]) for a in range(len(sizes))]

    @classmethod
    def product(cls, base_yaml, axes):
        return cls(base_yaml, [axis.key for axis in axes], axes)

    def point(self, i: int) -> tuple:
        if self.points is not None:
            return self.points[i]
        return tuple(axis.values[(i // stride) % len(axis.values)]
                     for axis, stride in zip(self.axes, self._strides))

    def column(self, a: int, indices: np.ndarray) -> list:
        """The values of key ``a`` at the grid ``indices``."""
        if self.points is not None:
            return [self.points[i][a] for i in indices]
        axis = self.axes[a]
        positions = (np.asarray(indices, dtype=np.int64) // self._strides[a]) % len(axis.values)
        return [axis.values[j] for j in positions]

    def numeric(self, a: int) -> bool:
        values = self.axes[a].values if self.points is None else (p[a] for p in self.points)
        return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)

    def attrs(self) -> dict:
        out = {"base_scene": self.base_yaml, "keys": json.dumps(self.keys),
               "axes": json.dumps([axis.to_json() for axis in self.axes])}
        if self.points is None:
            out["grid"] = "product"
        else:
            out["points"] = json.dumps(self.points)
        return out

    def index_of(self) -> dict:
        """Point -> index, to carry rows over from another layout."""
        return {tuple(self.point(i)): i for i in range(self.n)}


class _Rows:
    """The finished rows of a sweep in compact columns that grow as rows arrive."""

    def __init__(self, n: int):
        self.done = np.zeros(n, dtype=bool)
        self.count = 0
        self._index = np.empty(16, dtype=np.int64)
        self._numbers = np.empty((16, len(RESULT_COLUMNS)))
        self._detached = np.empty(16, dtype=bool)
        self._text = {name: [] for name in TEXT_COLUMNS}
        self.histories = {}

    def _grow(self, need: int) -> None:
        size = self._index.size
        if need <= size:
            return
        size = max(need, 2 * size)
        self._index = np.resize(self._index, size)
        self._numbers = np.resize(self._numbers, (size, len(RESULT_COLUMNS)))
        self._detached = np.resize(self._detached, size)

    def add(self, index: int, row: dict) -> None:
        if self.done[index]:
            return
        self._grow(self.count + 1)
        k = self.count
        self._index[k] = index
        self._numbers[k] = [_as_float(row.get(name, math.nan)) for name in RESULT_COLUMNS]
        self._detached[k] = bool(row.get("detached", False))
        for name in TEXT_COLUMNS:
            self._text[name].append(str(row.get(name, "")))
        if ARRAYS in row:
            self.histories[int(index)] = row[ARRAYS]
        self.done[index] = True
        self.count += 1

    def add_columns(self, indices, numbers: dict, detached, text: dict, histories) -> None:
        """Rows read back from a file (vectorised); rows already present are skipped."""
        indices = np.asarray(indices, dtype=np.int64)
        keep = ~self.done[indices]
        _, first = np.unique(indices, return_index=True)
        once = np.zeros(indices.size, dtype=bool)
        once[first] = True
        keep &= once
        indices = indices[keep]
        m = indices.size
        self._grow(self.count + m)
        k = self.count
        self._index[k:k + m] = indices
        for c, name in enumerate(RESULT_COLUMNS):
            column = numbers.get(name)
            self._numbers[k:k + m, c] = math.nan if column is None else np.asarray(column)[keep]
        self._detached[k:k + m] = np.asarray(detached, dtype=bool)[keep]
        for name in TEXT_COLUMNS:
            column = text.get(name)
            self._text[name].extend([""] * m if column is None else
                                    [column[j] for j in np.flatnonzero(keep)])
        for i, arrays in histories.items():
            if not self.done[i]:
                self.histories[int(i)] = arrays
        self.done[indices] = True
        self.count += m

    def table(self, layout: _Layout) -> dict:
        order = np.argsort(self._index[:self.count], kind="stable")
        indices = self._index[:self.count][order]
        table = {"index": indices.copy()}
        for a, key in enumerate(layout.keys):
            values = layout.column(a, indices)
            table[key] = (np.asarray(values, dtype=float) if layout.numeric(a)
                          else np.asarray([str(v) for v in values], dtype=object))
        numbers = self._numbers[:self.count][order]
        for c, name in enumerate(RESULT_COLUMNS):
            table[name] = numbers[:, c].copy()
        table["detached"] = self._detached[:self.count][order].copy()
        for name in TEXT_COLUMNS:
            column = self._text[name]
            table[name] = np.asarray([column[j] for j in order], dtype=object)
        return table


def _as_float(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def _execute(layout: _Layout, todo: np.ndarray, workers, scheduler, histories,
             drops) -> Iterable:
    """``(index, row)`` of each scene of ``todo`` as it finishes."""
    if not todo.size:
        return
    base_yaml = layout.base_yaml

    def overrides(i):
        return [_override(k, v) for k, v in zip(layout.keys, layout.point(int(i)))]

    if scheduler is not None:
        yield from _execute_dask(base_yaml, overrides, todo, scheduler, histories, drops)
        return
    workers = workers or os.cpu_count() or 1
    if workers == 1 or todo.size == 1:
        for i in todo:
            yield int(i), run_point(base_yaml, overrides(i), histories, drops)
        return
    n_workers = min(workers, int(todo.size))
    pool = ProcessPoolExecutor(max_workers=n_workers, initializer=_worker_init,
                               initargs=(os.getpid(), _start_method()))
    pending = set()
    queue = iter(todo)
    size = 1  # scenes per task, until scenes have been timed

    def submit():
        batch = [(int(i), overrides(i)) for i in itertools.islice(queue, size)]
        if batch:
            pending.add(pool.submit(run_points, base_yaml, batch, histories, drops))

    try:
        # A few tasks ahead of each worker: the grid is never submitted as a whole.
        for _ in range(AHEAD * n_workers):
            submit()
        while pending:
            finished, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in finished:
                pending.discard(future)
                rows = future.result()
                yield from rows
                size = _batch_size(rows, size)
                submit()
    except BrokenProcessPool:
        _stop_pool(pool)
        raise SweepError("a worker process died (killed, or out of memory); the finished "
                         "rows are kept: run the same command to resume") from None
    except BaseException:
        # Ctrl-C, SIGTERM, a failed worker or a caller that stopped iterating: the workers
        # end now, not after the scenes they are running.
        _stop_pool(pool)
        raise
    pool.shutdown(wait=True)


def _batch_size(rows: list, size: int) -> int:
    """Scenes per task for about ``BATCH_SECONDS`` of work, from the run times of a finished
    batch (unchanged while none ran): each task costs the parent and the worker ~0.3 ms of
    pickling and queues, as much as a seed scene at rtol 1e-6 (one scene per task, two
    workers ran 470 scenes/s where one process ran 360)."""
    times = [row.get("wall_time", math.nan) for _, row in rows]
    times = [t for t in times if isinstance(t, float) and t > 0.0]
    if not times:
        return size
    # By the slowest scene, growing at most 2x a batch: the grid's order often follows the
    # cost, and a batch's rows arrive (and survive a Ctrl-C) only when all of it is done.
    return int(min(MAX_BATCH, 2 * size, max(1, BATCH_SECONDS / max(times))))


def _start_method() -> str:
    import multiprocessing

    return multiprocessing.get_start_method()


def _stop_pool(pool: ProcessPoolExecutor) -> None:
    processes = list((getattr(pool, "_processes", None) or {}).values())
    for process in processes:
        with suppress(Exception):
            process.kill()
    with suppress(Exception):
        pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        with suppress(Exception):
            process.join(2.0)


def _worker_init(parent_pid: int, start_method: str) -> None:
    """A sweep worker: leaves stopping to its parent and dies with it."""
    import signal

    for name in ("SIGINT", "SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_IGN)
    # Only a forked or spawned worker is the parent's child (a forkserver's is not).
    expected = parent_pid if start_method in ("fork", "spawn") else None
    die_with_parent(expected)


def die_with_parent(expected_parent: int | None = None) -> None:
    """Make this process exit when its parent dies: ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` on
    Linux, else a thread that polls ``os.getppid()``. With ``expected_parent``, a parent that
    died before this call (the process was re-parented) ends the process at once."""
    import signal

    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            armed = libc.prctl(1, int(signal.SIGKILL), 0, 0, 0) == 0  # PR_SET_PDEATHSIG = 1
        except (OSError, AttributeError):
            armed = False
        if armed:
            if expected_parent is not None and os.getppid() != expected_parent:
                os._exit(1)
            return
    import threading

    parent = os.getppid() if expected_parent is None else expected_parent

    def watch():
        while True:
            if os.getppid() != parent:
                os._exit(1)
            time.sleep(0.5)

    threading.Thread(target=watch, name="pulloff-parent-watch", daemon=True).start()


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
        batches = [[(int(i), overrides(i)) for i in todo[j:j + size]]
                   for j in range(0, len(todo), size)]
        futures = [client.submit(run_points, base_yaml, batch, histories, drops, pure=False)
                   for batch in batches]
        for future in dask_completed(futures):
            yield from future.result()


# --- file ----------------------------------------------------------------------------------

def _write(out, layout: _Layout, rows: _Rows, key: str = "-o") -> None:
    import h5py

    table = rows.table(layout)
    with h5io.atomic_file(out, key) as f:
        f.attrs["kind"] = "sweep"
        for name, value in layout.attrs().items():
            f.attrs[name] = value
        f.attrs["n_points"] = layout.n
        f.attrs["complete"] = bool(rows.count == layout.n)
        g = f.create_group("table")
        for name, values in table.items():
            if values.dtype == object:
                ds = g.create_dataset(name, data=values.astype(str).astype(object),
                                      dtype=h5py.string_dtype())
            else:
                ds = g.create_dataset(name, data=values)
            ds.attrs["unit"] = column_unit(name)
        if rows.histories:
            h = f.create_group("histories")
            for i in sorted(rows.histories):
                gi = h.create_group(f"{i:06d}")
                for name, values in rows.histories[i].items():
                    ds = gi.create_dataset(name, data=values)
                    ds.attrs["unit"] = h5io.HISTORY_UNITS[name]


def _read_into(f, rows: _Rows, mapping=None) -> None:
    """Add the rows of an open sweep file to ``rows``; ``mapping`` (file index -> index in
    ``rows``, or -1 where a point is not in the new sweep) carries rows to another layout."""
    g = f["table"]
    indices = g["index"][()].astype(np.int64)
    keep = np.ones(indices.size, dtype=bool)
    if mapping is not None:
        indices = np.asarray([mapping.get(int(i), -1) for i in indices], dtype=np.int64)
        keep = indices >= 0
    numbers = {name: g[name][()][keep] for name in RESULT_COLUMNS if name in g}
    text = {}
    for name in (n for n in TEXT_COLUMNS if n in g):
        values = g[name].asstr()[()] if g[name].dtype.kind == "O" else g[name][()]
        text[name] = [str(v) for v in np.asarray(values, dtype=object)[keep]]
    detached = g["detached"][()][keep] if "detached" in g else np.zeros(int(keep.sum()), bool)
    histories = {}
    if "histories" in f:
        old = g["index"][()]
        for r in np.flatnonzero(keep):
            name = f"{int(old[r]):06d}"
            if name in f["histories"]:
                gi = f["histories"][name]
                histories[int(indices[r])] = {k: gi[k][()] for k in gi}
    rows.add_columns(indices[keep], numbers, detached, text, histories)


def _layout_of(f) -> _Layout:
    product = f.attrs.get("grid") == "product"
    needed = ("axes",) + (() if product else ("points",)) + ("base_scene", "keys")
    missing = [name for name in needed if name not in f.attrs]
    if missing:
        # A sweep file of an older layout (or a damaged one): say so instead of a KeyError.
        raise SweepError(f"{f.filename}: a sweep file without {', '.join(missing)} (written by "
                         f"an older pulloff?); choose another -o or remove the file")
    axes = [Axis(a["key"], tuple(a["values"])) for a in json.loads(f.attrs["axes"])]
    keys = json.loads(f.attrs["keys"])
    points = None if product else [tuple(p) for p in json.loads(f.attrs["points"])]
    return _Layout(str(f.attrs["base_scene"]), keys, axes, points)


def _same(a: _Layout, b: _Layout) -> bool:
    if (a.base_yaml, a.keys, a.n) != (b.base_yaml, b.keys, b.n):
        return False
    if a.points is None and b.points is None:
        return [x.to_json() for x in a.axes] == [x.to_json() for x in b.axes]
    return all(tuple(a.point(i)) == tuple(b.point(i)) for i in range(a.n))


def _resume(out, layout: _Layout, replace: bool = False, key: str = "-o") -> _Rows:
    rows = _Rows(layout.n)
    with h5io.open_for_reading(out) as f:
        h5io.check_pulloff_file(out, f)
        if f.attrs.get("kind") != "sweep":
            raise SweepError(f"{key} = {out}: exists and is not a sweep file; choose another "
                             f"-o")
        try:
            old = _layout_of(f)
        except SweepError:
            if replace:
                return rows
            raise
        if _same(old, layout):
            _read_into(f, rows)
            return rows
        if not replace:
            raise SweepError(f"{key} = {out}: holds a different sweep (base scene or points "
                             f"differ); choose another -o or remove the file")
        if (old.base_yaml, old.keys) == (layout.base_yaml, layout.keys):
            # The same scene on another grid: keep the rows of the points both have.
            new_index = layout.index_of()
            mapping = {i: new_index.get(tuple(old.point(i)), -1) for i in range(old.n)}
            _read_into(f, rows, mapping)
        return rows


def _as_result(layout: _Layout, rows: _Rows) -> SweepResult:
    return SweepResult(layout.base_yaml, [axis.to_json() for axis in layout.axes],
                       rows.table(layout), dict(sorted(rows.histories.items())),
                       n_points=layout.n, complete=bool(rows.count == layout.n),
                       keys=list(layout.keys))


def load_sweep(path) -> SweepResult:
    """Read a sweep file into plain numpy arrays (rows in point order), with its planned size
    ``n_points`` and whether it is ``complete``."""
    with h5io.open_for_reading(path) as f:
        h5io.check_pulloff_file(path, f)
        if f.attrs.get("kind") != "sweep":
            raise ValueError(f"{path}: not a sweep file")
        layout = _layout_of(f)
        rows = _Rows(layout.n)
        _read_into(f, rows)
    return _as_result(layout, rows)
