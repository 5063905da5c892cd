"""HDF5 files of a run: written atomically, read back into plain numpy arrays and dicts.

Layout (names are part of the product):

- root attributes ``schema_version``, ``software``, ``software_version``, ``created``,
  ``scene`` (the full resolved scene as YAML text, so a file reproduces itself), ``complete``;
- ``history/``: ``t``, ``h``, ``a``, ``b``, ``gap``, ``F_contact``, ``F_total`` on one time axis
  (``t`` is attached to the others as their dimension scale), each with a ``unit`` attribute;
- ``summary`` attributes: the headline numbers at detachment and the run's bookkeeping;
- ``analytic`` attributes: the closed forms of the seed thesis and the elastic limit;
- ``snapshots/`` (only if requested): one group per time with ``x`` and ``u`` datasets.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import os
import socket
import stat
from pathlib import Path

import h5py
import numpy as np

from .. import __version__
from ..model import outputs
from . import files

SCHEMA_VERSION = 1

HISTORY_UNITS = outputs.units("history")
SUMMARY_UNITS = outputs.units("summary")
ANALYTIC_UNITS = outputs.units("analytic")


def result_to_record(result, scene_yaml: str) -> dict:
    """The plain-dict view of a :class:`pulloff.solvers.result.Result` that files also load
    into."""
    summary = {name: (bool(value) if isinstance(value, (bool, np.bool_)) else
                      int(value) if isinstance(value, (int, np.integer)) else value)
               for name, value in result.summary.items()}
    return {
        "scene": scene_yaml,
        "summary": summary,
        "analytic": dict(result.analytic),
        "history": {name: np.asarray(result.history[name]) for name in HISTORY_UNITS},
        "snapshots": [{"t": t, "x": np.asarray(x), "u": np.asarray(u)}
                      for t, x, u in result.snapshots],
        "complete": bool(result.complete),
    }


class OutputError(ValueError):
    """An output that cannot or must not be written; the message names the key and the path
    the user gave (never a temporary file)."""


_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISLNK, "a symbolic link"),
          (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def check_target(path, key: str) -> Path:
    """Refuse, before any work, an output that could not be written or must not be replaced.

    ``path`` must be a non-empty file name; if it exists it must be a regular file (a
    directory, symbolic link, FIFO, device or socket there is refused: writing would replace
    the node, not write into it); its folder must be a folder (or be creatable) and writable.
    ``key`` names the setting in the message (``-o``, ``output.path``).
    """
    text = os.fspath(path) if not isinstance(path, str) else path
    if not text or not text.strip():
        raise OutputError(f"{key}: empty path; give a file name")
    if "\0" in text:
        raise OutputError(f"{key} = {text!r}: a path cannot hold a NUL character")
    path = Path(text)
    if text.endswith(("/", os.sep)):
        raise OutputError(f"{key} = {text}: is a folder name, not a file name")
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        info = None
    except OSError as exc:
        raise OutputError(f"{key} = {text}: cannot be checked ({exc.strerror})") from None
    if info is not None and not stat.S_ISREG(info.st_mode):
        kind = next((name for test, name in _KINDS if test(info.st_mode)), "not a regular file")
        raise OutputError(f"{key} = {text}: exists and is {kind}, not a regular file; "
                          f"pulloff replaces only regular files: choose another path")
    parent = _existing_parent(path)
    if parent is None or not parent.is_dir():
        raise OutputError(f"{key} = {text}: {parent if parent is not None else path.parent} "
                          f"is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(f"{key} = {text}: no permission to write in {parent}")
    return path


def _existing_parent(path: Path) -> Path | None:
    """The nearest existing ancestor folder of ``path`` (the one a new file or folder is
    made in), or a non-folder that stands in the way."""
    parent = path.parent if str(path.parent) else Path(".")
    while True:
        if parent.exists() or parent.is_symlink():
            return parent
        if parent.parent == parent:
            return None
        parent = parent.parent


def stale_temp_files(path) -> list[Path]:
    """Temporary files an interrupted or killed writer of ``path`` left beside it."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    prefix = files.temp_prefix(path)
    try:
        names = os.listdir(folder)
    except OSError:
        return []
    # mkstemp's names: the prefix, 8 random characters, the suffix.
    return [folder / n for n in names if n.startswith(prefix) and n.endswith(".tmp")
            and len(n) == len(prefix) + 8 + len(".tmp")]


@contextlib.contextmanager
def output_lock(path, key: str = "-o"):
    """Hold the one-writer lock of the output ``path`` while the block runs.

    The lock is a :class:`filelock.FileLock` on ``.NAME.lock`` beside the file (kept there
    after release, as filelock recommends: removing a lock file races with the next writer);
    the holder's pid, host and start time are written to ``.NAME.lock.holder`` while it holds
    it. A second writer is refused at once with an :class:`OutputError` naming the file and
    the holder. Under the lock, temporary files that a killed writer of the same output left
    behind are removed.
    """
    from filelock import FileLock, Timeout

    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    folder.mkdir(parents=True, exist_ok=True)
    lock_path = folder / f".{path.name}.lock"
    holder_path = folder / f".{path.name}.lock.holder"
    lock = FileLock(str(lock_path), timeout=0)
    try:
        lock.acquire()
    except Timeout:
        raise OutputError(f"{key} = {path}: another pulloff process is writing it "
                          f"({_read_holder(holder_path)}); wait for it to finish or choose "
                          f"another path") from None
    except OSError as exc:
        raise OutputError(f"{key} = {path}: cannot lock it for writing ({exc.strerror or exc}; "
                          f"lock file {lock_path})") from None
    try:
        _write_holder(holder_path)
        for stale in stale_temp_files(path):
            stale.unlink(missing_ok=True)
        yield
    finally:
        with contextlib.suppress(OSError):
            holder_path.unlink()
        lock.release()


def _write_holder(holder_path: Path) -> None:
    text = (f"pid {os.getpid()} on host {socket.gethostname()} since "
            f"{_dt.datetime.now().isoformat(timespec='seconds')}\n")
    with contextlib.suppress(OSError):
        holder_path.write_text(text, encoding="utf-8")


def _read_holder(holder_path: Path) -> str:
    try:
        text = holder_path.read_text(encoding="utf-8").strip()
    except OSError:
        text = ""
    return text or "holder unknown"


@contextlib.contextmanager
def atomic_file(path, key: str = "-o"):
    """Open an HDF5 file for writing that appears at ``path`` only once it is complete.

    The file is written under a temporary name in the same folder and renamed at the end; an
    exception or Ctrl-C leaves no file behind (and an older file at ``path`` untouched),
    never a truncated one. A failure to write is an :class:`OutputError` naming ``path``
    (``key`` says which setting gave it), not the temporary file.
    """
    path = Path(path)
    try:
        tmp_name = files.new_temp(path)
    except OSError as exc:
        raise OutputError(f"{key} = {path}: cannot write ({exc.strerror or exc})") from None
    try:
        try:
            with h5py.File(tmp_name, "w") as f:
                stamp(f)
                yield f
            files.publish(tmp_name, path)
        except OSError as exc:
            reason = (exc.strerror or str(exc)).replace(tmp_name, str(path))
            raise OutputError(f"{key} = {path}: cannot write ({reason})") from None
    except BaseException:
        Path(tmp_name).unlink(missing_ok=True)
        raise


def stamp(f: h5py.File) -> None:
    """Root attributes every pulloff file carries."""
    f.attrs["schema_version"] = SCHEMA_VERSION
    f.attrs["software"] = "pulloff"
    f.attrs["software_version"] = __version__
    f.attrs["created"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def check_pulloff_file(path, f: h5py.File) -> None:
    """Raise ``ValueError`` naming ``path`` unless it is a pulloff file of a known schema."""
    if f.attrs.get("software") != "pulloff":
        raise ValueError(f"{path}: not a pulloff result file (no software='pulloff')")
    version = int(f.attrs["schema_version"])
    if version != SCHEMA_VERSION:
        raise ValueError(f"{path}: schema_version {version} is not supported "
                         f"(this pulloff reads {SCHEMA_VERSION})")


def open_for_reading(path) -> h5py.File:
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        raise ValueError(f"{path}: cannot open as HDF5 ({exc})") from None


def write(path, record: dict) -> Path:
    """Write a run ``record`` (see :func:`result_to_record`) atomically to ``path``."""
    with atomic_file(path) as f:
        fill(f, record)
    return Path(path)


class HistoryStream:
    """Appends history rows to ``history/`` of an open file as a run produces them.

    Called with a dict of SI columns (the names of ``HISTORY_UNITS``); the datasets are
    chunked and grow, so a run of any length writes its history with O(chunk) memory.
    :func:`fill` then adds the rest of the run and the dimension scale.
    """

    CHUNK_ROWS = 1 << 15

    def __init__(self, f: h5py.File):
        self.group = f.create_group("history")
        for name, unit in HISTORY_UNITS.items():
            ds = self.group.create_dataset(name, shape=(0,), maxshape=(None,), dtype=float,
                                           chunks=(self.CHUNK_ROWS,))
            ds.attrs["unit"] = unit
        self.rows = 0

    def __call__(self, columns: dict) -> None:
        n = len(columns["t"])
        for name in HISTORY_UNITS:
            ds = self.group[name]
            ds.resize((self.rows + n,))
            ds[self.rows:] = np.asarray(columns[name], dtype=float)
        self.rows += n


def fill(f: h5py.File, record: dict, history_streamed: bool = False) -> None:
    """Write a run ``record`` into an open file; with ``history_streamed`` the history rows
    are already in ``history/`` (see :class:`HistoryStream`) and ``record["history"]``,
    a preview, is not written."""
    f.attrs["scene"] = record["scene"]
    f.attrs["complete"] = bool(record.get("complete", True))

    if history_streamed:
        hist = f["history"]
        axis = hist["t"]
    else:
        hist = f.create_group("history")
        axis = hist.create_dataset("t", data=np.asarray(record["history"]["t"], dtype=float))
        axis.attrs["unit"] = HISTORY_UNITS["t"]
    axis.make_scale("t")
    for name, unit in HISTORY_UNITS.items():
        if name == "t":
            continue
        if history_streamed:
            ds = hist[name]
        else:
            ds = hist.create_dataset(name, data=np.asarray(record["history"][name],
                                                           dtype=float))
            ds.attrs["unit"] = unit
        ds.dims[0].attach_scale(axis)

    summary = f.create_group("summary")
    for name, value in record["summary"].items():
        summary.attrs[name] = value
        summary.attrs[f"{name}__unit"] = SUMMARY_UNITS.get(name, "")

    analytic = f.create_group("analytic")
    for name, value in record["analytic"].items():
        analytic.attrs[name] = value
        analytic.attrs[f"{name}__unit"] = ANALYTIC_UNITS.get(name, "")

    if record.get("snapshots"):
        snaps = f.create_group("snapshots")
        for i, snap in enumerate(record["snapshots"]):
            g = snaps.create_group(f"{i:04d}")
            g.attrs["t"] = snap["t"]
            g.attrs["t__unit"] = "s"
            for name in ("x", "u"):
                ds = g.create_dataset(name, data=np.asarray(snap[name], dtype=float))
                ds.attrs["unit"] = "m"


def _attrs(group) -> dict:
    out = {}
    for name, value in group.attrs.items():
        if name.endswith("__unit"):
            continue
        if isinstance(value, np.generic):
            value = value.item()
        if isinstance(value, bytes):
            value = value.decode()
        out[name] = value
    return out


def _read_rows(ds, history_rows):
    """A dataset, or every n-th row of it plus the last when it is longer than asked."""
    n = ds.shape[0]
    if history_rows is None or n <= history_rows:
        return ds[()]
    stride = -(-n // history_rows)
    return np.append(ds[::stride], ds[n - 1]) if (n - 1) % stride else ds[::stride]


def load(path, history_rows: int | None = None) -> dict:
    """Read a run file into plain Python: the keys of :func:`result_to_record`, plus
    ``units``, ``created`` and ``software_version`` from the file.

    ``history_rows`` caps the history read (every n-th row and the last): a streamed history
    of millions of rows need not be held to draw or show it.

    Raises ``ValueError`` naming the file if it is not a pulloff file of a known schema.
    """
    with open_for_reading(path) as f:
        check_pulloff_file(path, f)
        if "history" not in f:
            raise ValueError(f"{path}: not a single-run file (a sweep? read it with "
                             f"pulloff.sweeps.load_sweep)")
        record = {
            "scene": str(f.attrs["scene"]),
            "software_version": str(f.attrs["software_version"]),
            "created": str(f.attrs["created"]),
            "complete": bool(f.attrs["complete"]),
            "summary": _attrs(f["summary"]),
            "analytic": _attrs(f["analytic"]),
            "history": {name: _read_rows(f["history"][name], history_rows)
                        for name in HISTORY_UNITS if name in f["history"]},
            "history_rows_in_file": int(f["history"]["t"].shape[0]),
            "units": {name: str(f["history"][name].attrs["unit"]) for name in HISTORY_UNITS
                      if name in f["history"]},
            "snapshots": [],
        }
        if "snapshots" in f:
            for key in sorted(f["snapshots"]):
                g = f["snapshots"][key]
                record["snapshots"].append({"t": float(g.attrs["t"]), "x": g["x"][()],
                                            "u": g["u"][()]})
    return record
