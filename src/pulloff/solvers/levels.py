"""The one accuracy controller: a ladder of runs, each with half the step of the one before,
judged by a Richardson estimate from the last three.

A solver supplies ``run(n)`` (one pass at resolution ``n``), ``outputs(run)`` (the numbers the
estimate controls; nan where a run has none) and ``can_refine(run)``; the loop doubles ``n``
until the estimate is below ``rtol / 2`` or no further level is allowed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

#: Below this measured order the levels are not (yet) converging: no extrapolation.
DIVERGING_ORDER = 0.5


@dataclass(frozen=True)
class Order:
    """What a solver claims of its error: ``C dt^p`` with ``p`` measured, then clipped to
    ``[low, high]`` (``high`` is the method's order, so a pre-asymptotic accident never shrinks
    the estimate)."""

    low: float = 1.0
    high: float = 2.0


def _scale(v: np.ndarray, floor) -> np.ndarray:
    """What an output's error is relative to: its size, or its ``floor`` where it is smaller
    (an output that is zero in the limit, such as the contact force at a bond's last point,
    is judged against the run's force scale, not against its own rounding)."""
    return np.maximum(np.abs(v), 0.0 if floor is None else np.asarray(floor, dtype=float))


def relative_spread(a: np.ndarray, b: np.ndarray, floor=None) -> float:
    """Largest relative difference of two output vectors where both are finite (``inf`` if one
    run found an event the other did not)."""
    if not np.array_equal(np.isnan(a), np.isnan(b)):
        return math.inf
    scale = _scale(b, floor)
    mask = np.isfinite(a) & np.isfinite(b) & (scale != 0)
    if not np.any(mask):
        return 0.0
    return float(np.max(np.abs(a[mask] - b[mask]) / scale[mask]))


def richardson(values: Sequence[np.ndarray], order: Order, floor=None) -> tuple[float, float]:
    """``(estimate, measured order)`` of the finest of three levels (step ratio 2).

    For the output that changed most between the last two levels: its last difference divided
    by ``2^p - 1``, ``p`` measured from the three levels and clipped to ``order``. Below a
    measured order of 0.5 the levels are not converging and the estimate is the larger of the
    last two differences, with no extrapolation. An event found on one level only gives
    ``inf``. Differences are relative to :func:`_scale`.
    """
    v0, v1, v2 = (np.asarray(v, dtype=float) for v in values)
    if not np.array_equal(np.isnan(v1), np.isnan(v2)):
        return math.inf, math.nan
    scale = _scale(v2, floor)
    mask = np.isfinite(v2) & (scale != 0) & np.isfinite(v1) & np.isfinite(v0)
    if not np.any(mask):
        return 0.0, math.nan
    d_last = np.abs(v2 - v1)[mask] / scale[mask]
    d_prev = np.abs(v1 - v0)[mask] / scale[mask]
    worst = int(np.argmax(d_last))
    if d_last[worst] == 0.0:
        return 0.0, math.nan
    measured = math.log2(d_prev[worst] / d_last[worst]) if d_prev[worst] > 0 else order.high
    if measured < DIVERGING_ORDER:
        return float(max(d_last[worst], d_prev[worst])), measured
    p = min(order.high, max(order.low, measured))
    return float(d_last[worst] / (2.0 ** p - 1.0)), measured


def extrapolate(values: Sequence[np.ndarray], order: Order,
                floor=None) -> tuple[np.ndarray, float]:
    """Richardson-extrapolated outputs of the finest of three levels, and an estimate of their
    relative error: the change between the extrapolations from the last two pairs of levels,
    divided by ``2^p - 1`` (so it assumes the next term of the error is no faster than the
    first). ``p`` is the order :func:`richardson` measures, clipped to ``order``; below the
    diverging order no extrapolation is made (the finest values and an infinite estimate)."""
    v0, v1, v2 = (np.asarray(v, dtype=float) for v in values)
    _, measured = richardson(values, order, floor)
    if not math.isfinite(measured) or measured < DIVERGING_ORDER:
        # No measured order (outputs unchanged between levels) or no convergence.
        same = np.array_equal(v1, v2, equal_nan=True)
        return v2.copy(), (0.0 if same else math.inf)
    p = min(order.high, max(order.low, measured))
    f = 1.0 / (2.0 ** p - 1.0)
    e1 = v1 + (v1 - v0) * f
    e2 = v2 + (v2 - v1) * f
    scale = _scale(e2, floor)
    mask = np.isfinite(e2) & np.isfinite(e1) & (scale != 0)
    if not np.any(mask):
        return e2, 0.0
    return e2, float(np.max(np.abs(e2 - e1)[mask] / scale[mask]) * f)


@dataclass
class Ladder:
    """The outcome of :func:`refine`: every level run, the estimate of what is reported, the
    order measured from the last three (nan before three levels), and the extrapolated outputs
    (None unless asked for and three levels exist)."""

    levels: list
    estimate: float
    order: float
    extrapolated: np.ndarray | None = None

    @property
    def finest(self):
        return self.levels[-1]


def refine(run: Callable[[int], object], outputs: Callable[[object], np.ndarray], rtol: float,
           n_first: int, order: Order, can_refine: Callable[[object, int], bool],
           interrupted: Callable[[object], bool] = lambda r: False,
           extrapolated: bool = False, floor: Callable[[object], np.ndarray] | None = None
           ) -> Ladder:
    """Run ``n_first, 2 n_first, ...`` until the estimate is below ``rtol / 2`` or
    ``can_refine(finest, next_n)`` says no. The estimate is that of the finest level
    (:func:`richardson`), or with ``extrapolated`` that of the extrapolated outputs
    (:func:`extrapolate`), which are then what the ladder reports.

    With only two levels when refinement has to stop, the estimate is a third of their
    difference (the second-order Richardson factor, without a measured order). A level that
    reports ``interrupted`` ends the ladder at once with a nan estimate. ``floor(finest)``
    (optional) gives each output the size below which its error is judged absolutely
    (:func:`_scale`).
    """
    levels = []
    n = n_first
    estimate, measured, values = math.nan, math.nan, None
    while True:
        levels.append(run(n))
        if interrupted(levels[-1]):
            return Ladder(levels, math.nan, math.nan)
        if len(levels) >= 3:
            last = [outputs(r) for r in levels[-3:]]
            lowest = None if floor is None else floor(levels[-1])
            estimate, measured = richardson(last, order, lowest)
            if extrapolated:
                values, estimate = extrapolate(last, order, lowest)
            if estimate <= 0.5 * rtol:
                return Ladder(levels, estimate, measured, values)
        if not can_refine(levels[-1], 2 * n):
            if len(levels) == 2:
                lowest = None if floor is None else floor(levels[-1])
                estimate = relative_spread(outputs(levels[0]), outputs(levels[1]),
                                           lowest) / 3.0
            return Ladder(levels, estimate, measured, values)
        n *= 2
