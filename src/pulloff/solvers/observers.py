"""What watches a run: history rows kept, a stream of rows, snapshot times, progress.

Solvers receive an :class:`Observers` and never read ``scene.output`` or draw a progress bar
themselves: the command line and the Python API decide what is kept and shown.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np


@contextlib.contextmanager
def no_progress(desc: str, total: int | None = None):
    """The default progress hook: shows nothing (yields ``None`` instead of an update)."""
    yield None


@dataclass
class Observers:
    """Hooks into a run (SI).

    - ``every``: keep every n-th step of the reported run in the history (None: decimate it
      to ``history_rows`` rows);
    - ``snapshot_times``: times [s] at which the free foundation's ``(x, u)`` is stored;
    - ``stream``: a callable receiving SI history columns as they are computed (fixed-step
      runs, whose history may not fit in memory);
    - ``progress``: ``progress(desc, total)`` -> a context manager yielding ``update(n)`` or
      None.
    """

    every: int | None = None
    history_rows: int = 2000
    snapshot_times: tuple = ()
    stream: Callable | None = None
    progress: Callable = no_progress
    notes: list = field(default_factory=list)

    @classmethod
    def for_scene(cls, scene, progress: Callable | None = None, stream: Callable | None = None):
        """The observers a scene's ``output`` section asks for."""
        return cls(every=scene.output.every, history_rows=scene.output.history_rows,
                   snapshot_times=tuple(scene.output.snapshots), stream=stream,
                   progress=progress or no_progress)

    def kept_rows(self, n_rows: int, steps: np.ndarray | None = None) -> np.ndarray:
        """Indices of the rows of a finished run that go into its history: every
        ``every``-th step (and the last row), or ``history_rows`` evenly spread."""
        if self.every is not None and steps is not None:
            keep = np.nonzero(steps % self.every == 0)[0]
            return keep if keep.size and keep[-1] == n_rows - 1 else np.append(keep, n_rows - 1)
        return decimate(n_rows, self.history_rows)

    def skipped_snapshots(self, t_end: float) -> list[str]:
        """Notes for snapshot times the run did not reach."""
        return [f"snapshot at t = {ts:g} s not stored: after the end of the run "
                f"(t = {t_end:.6g} s)" for ts in self.snapshot_times if ts > t_end]


def decimate(n_rows: int, limit: int) -> np.ndarray:
    """At most ``limit`` row indices evenly spread over ``n_rows``, first and last included."""
    if n_rows <= limit:
        return np.arange(n_rows)
    return np.unique(np.round(np.linspace(0, n_rows - 1, limit)).astype(int))


def stream_every(every: int | None, steps: int, history_rows: int) -> int:
    """Steps between streamed rows of a fixed-step run: ``every``, or a stride that writes
    about ``history_rows`` rows."""
    if every is not None:
        return every
    return max(1, math.ceil(steps / history_rows))
