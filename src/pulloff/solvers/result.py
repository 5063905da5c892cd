"""The outcome of a run, SI throughout, holding every quantity of the output table."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..model import outputs


@dataclass
class Result:
    """A finished (or interrupted) run.

    ``summary``, ``analytic`` and ``history`` hold every quantity of
    :data:`pulloff.model.outputs.OUTPUTS` of their group (nan or empty text where a scene does
    not have one); summary and analytic values also read as attributes
    (``result.F_total_detach``).
    """

    summary: dict
    analytic: dict
    history: dict  # SI arrays on one time axis
    snapshots: list = field(default_factory=list)  # (t [s], x [m], u [m])
    notes: list = field(default_factory=list)
    complete: bool = True  # False after Ctrl-C: the history holds what was computed until then
    history_streamed: bool = False  # the full history went to a stream; ``history`` previews it
    problem: object = None  # the solver's own reduced description of the scene

    @classmethod
    def build(cls, summary: dict, analytic: dict, history: dict, **rest) -> "Result":
        """A result from the values a solver has; every other declared quantity is filled
        with nan (numbers) or empty text, so no consumer ever meets a missing key."""
        # (from tables made once: building them per result was ~5 us of a 0.3 ms run)
        full = outputs.missing("summary")
        unknown = summary.keys() - full.keys()
        if unknown:
            raise KeyError(f"summary quantities not in the output table: {sorted(unknown)}")
        full.update(summary)  # (in the table's order: every key is already there)
        missing = outputs.missing("analytic")
        an = {name: analytic.get(name, value) for name, value in missing.items()}
        # A pull has one segment: its history may leave that column out.
        history = dict(history)
        history.setdefault("segment", np.zeros(np.shape(history["t"])))
        hist = {name: np.asarray(history[name], dtype=float) for name in outputs.names("history")}
        if not full["notes"]:
            full["notes"] = "; ".join(rest.get("notes", ()))
        return cls(full, an, hist, **rest)

    def __getattr__(self, name):
        # Only called for names that are not attributes: the summary and analytic values.
        for group in ("summary", "analytic"):
            values = self.__dict__.get(group, {})
            if name in values:
                return values[name]
        raise AttributeError(name)

    @property
    def groups(self) -> dict:
        return {name: self.summary[name] for name in ("alpha", "chi", "V")}
