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


class _Floats(list):
    """A list known to hold Python floats only (what :func:`_floats` returns): the ladder
    converts each level's outputs once, and its every later look at them costs one type
    check instead of one per element."""


def _floats(v) -> list:
    """An output vector as Python floats. A level has a handful of outputs, and the ladder's
    arithmetic on them runs after every level of every run: float operations are the same
    IEEE ones as numpy's, without ~1 us per array call (a fifth of a ~1 ms onset run went to
    the ladder's array calls)."""
    if type(v) is _Floats:
        return v
    return _Floats(np.asarray(v, dtype=float).tolist())


def _scale_floats(v: list, floor) -> list:
    """:func:`_scale` over Python floats (nan wherever numpy's maximum gives nan)."""
    if floor is None:
        return _Floats(abs(x) for x in v)
    floors = np.broadcast_to(np.asarray(floor, dtype=float), (len(v),)).tolist()
    return _Floats(a if (a != a or a >= f) else f for a, f in zip((abs(x) for x in v), floors))


def same_events(values: Sequence[np.ndarray]) -> bool:
    """Whether every level found the same events: its outputs are nan in the same places. An
    event found on some levels only is not converged, whichever level lacks it."""
    rows = [[x != x for x in _floats(v)] for v in values]
    return all(row == rows[-1] for row in rows)


def relative_spread(a: np.ndarray, b: np.ndarray, floor=None) -> float:
    """Largest relative difference of two output vectors where both are finite (``inf`` if one
    run found an event the other did not)."""
    if not same_events([a, b]):
        return math.inf
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    scale = _scale(b, floor)
    mask = np.isfinite(a) & np.isfinite(b) & (scale != 0)
    if not np.any(mask):
        return 0.0
    return float(np.max(np.abs(a[mask] - b[mask]) / scale[mask]))


def _worst_change(v0, v1, v2, scale) -> tuple[float, float]:
    """``(|v2 - v1|, |v1 - v0|)`` relative to ``scale`` for the output whose last change is
    the largest (the first such), over the outputs finite on every level with a nonzero
    scale; ``(-1, -1)`` with none (see :func:`_floats`)."""
    worst_last = worst_prev = -1.0
    for a, b, c, sc in zip(_floats(v0), _floats(v1), _floats(v2), _floats(scale)):
        if not (math.isfinite(a) and math.isfinite(b) and math.isfinite(c)) or sc == 0:
            continue
        d_last = abs(c - b) / sc
        if d_last > worst_last:
            worst_last, worst_prev = d_last, abs(b - a) / sc
    return worst_last, worst_prev


def richardson(values: Sequence[np.ndarray], order: Order, floor=None) -> tuple[float, float]:
    """``(estimate, measured order)`` of the finest of three levels (step ratio 2).

    For the output that changed most between the last two levels: its last difference divided
    by ``2^p - 1``, ``p`` measured from the three levels and clipped to ``order``. Below a
    measured order of 0.5 the levels are not converging and the estimate is the larger of the
    last two differences, with no extrapolation. An event found on some of the three levels
    only gives ``inf`` (once only the last two were compared: an output missing on the
    coarsest level dropped out of the estimate unseen). Differences are relative to :func:`_scale`.
    """
    v0, v1, v2 = (_floats(v) for v in values)
    if not same_events([v0, v1, v2]):
        return math.inf, math.nan
    worst_last, worst_prev = _worst_change(v0, v1, v2, _scale_floats(v2, floor))
    if worst_last <= 0.0:  # no output to judge, or none changed
        return 0.0, math.nan
    measured = math.log2(worst_prev / worst_last) if worst_prev > 0 else order.high
    if measured < DIVERGING_ORDER:
        return float(max(worst_last, worst_prev)), measured
    p = min(order.high, max(order.low, measured))
    return float(worst_last / (2.0 ** p - 1.0)), measured


def extrapolate(values: Sequence[np.ndarray], order: Order, floor=None,
                raw: tuple[float, float] | None = None) -> tuple[np.ndarray, float]:
    """Richardson-extrapolated outputs of the finest of three or four levels, and an estimate
    of their relative error.

    Each pair of consecutive levels is extrapolated with the method's order ``p = order.high``
    (not with the order measured from the same levels: with that order the extrapolations from
    the last two pairs agree by construction and their change says nothing). The finest
    extrapolation ``e`` is reported. Its estimate:

    * from three levels (two extrapolations), their change ``|e2 - e1|`` itself: that is
      ``2^q - 1`` times the error of ``e2`` if the remaining error falls like ``dt^q``
      (cautious once asymptotic, ``q >= p + 1``) and ``(2^p - 1)/2^p`` of it where the levels
      still converge at the lowest order ``order.low = 1`` (pre-asymptotic); but two higher
      terms can cancel in that change, so :func:`refine` stops on it only where it cannot
      refine further;
    * from four levels (three extrapolations), their last change divided by ``2^q - 1`` with
      ``q`` measured from the three extrapolations for the output that changed most and
      clipped to ``[order.low, p]`` (not to ``p + 1``, the order an extrapolation has once
      asymptotic: pre-asymptotic levels whose own order is off ``p`` leave extrapolations that
      converge irregularly, and measured on the seed's scenes ``p + 1`` put the estimate up to
      5x below the error), and never below the previous change divided by ``2^q (2^q - 1)``
      (what it predicts at that order: a sudden drop can be two error terms cancelling, which
      measured 47x below the error on a viscous scene); below the diverging order the larger
      of their last two changes.

    Below the diverging order of the levels themselves no extrapolation is made: the finest
    values, with :func:`richardson`'s estimate (the larger of the last two changes; rounding
    alone on a scene the levels solve exactly). ``raw`` is :func:`richardson`'s result on the
    last three levels where the caller has it already.
    """
    v = [_floats(x) for x in values[-4:]]
    if not same_events(v):
        # An event (detachment) found on some levels only: not converged.
        return np.array(v[-1]), math.inf
    raw_estimate, measured = raw or richardson(v[-3:], order, floor)
    if not math.isfinite(measured) or measured < DIVERGING_ORDER:
        # Outputs unchanged, levels not converging, or (an exact scene) differing by rounding
        # alone: the finest level, with the larger of its last two changes as the estimate.
        return np.array(v[-1]), raw_estimate
    e = _pairwise(v, order.high)
    finest = np.array(e[-1])
    scale = _scale_floats(e[-1], floor)
    # (over three extrapolations the first is only compared; with two, a copy of it)
    d_last, d_prev = _worst_change(e[-3] if len(e) == 3 else e[-2], e[-2], e[-1], scale)
    if d_last < 0.0:  # no output finite on every extrapolation
        return finest, 0.0
    if len(e) == 2:
        return finest, float(d_last)
    if d_last == 0.0 and d_prev == 0.0:
        return finest, 0.0
    q = math.log2(d_prev / d_last) if d_prev > 0 and d_last > 0 else math.inf
    if q < DIVERGING_ORDER:
        return finest, float(max(d_last, d_prev))
    q = min(order.high, max(order.low, q))
    # A last change far smaller than the one before is as likely two error terms cancelling
    # as convergence: the estimate is never below what the previous change predicts at q.
    return finest, float(max(d_last, d_prev / 2.0 ** q) / (2.0 ** q - 1.0))


def extrapolate_measured(values: Sequence[np.ndarray], order: Order, floor=None,
                         raw: tuple[float, float] | None = None) -> tuple[np.ndarray, float]:
    """The contact solver's extrapolation: the finest of three levels extrapolated with the
    order :func:`richardson` measures (clipped to ``order``). Its estimate, per output, is
    the larger of the change between the extrapolations from the last two pairs of levels
    divided by ``2^p - 1`` and the extrapolation's own correction ``|e - finest|``.

    The change alone was too small: for the output that changed most the two extrapolations
    agree by construction (the order is measured from that output), so it came from the other
    outputs only (measured 11x below the error on the seed's separation time, 50x on a
    finite punch behind a spring at rtol 1e-5). The fixed-order :func:`extrapolate` does not
    have the weakness, but on the contact solver it costs one to three more levels per run
    (measured: the test suite 1.5x slower, 232 s against 154 s warm). With the correction the
    estimate is 1.6-34x the error against the moving-edge reference on its scenes at rtol 1e-3
    to 1e-6 (``benchmarks/contact_estimate.py``); 0.92x on ``separation_kv`` at 1e-2 m/s and
    rtol 1e-6, whose levels converge at a falling order (25x below before the gap integral
    stopped crossing the punch's first bond edge). ``raw`` as for :func:`extrapolate`.
    """
    v0, v1, v2 = (np.asarray(v, dtype=float) for v in values[-3:])
    raw_estimate, measured = raw or richardson(values[-3:], order, floor)
    if not math.isfinite(measured) or measured < DIVERGING_ORDER:
        # Events found on some levels only (richardson's estimate is then inf), outputs
        # unchanged, or levels not (yet) converging regularly: the finest level, with
        # the larger of its last two changes as the estimate (as :func:`extrapolate`). Once
        # this was infinite, and a Prony punch behind a spring at rtol 1e-2 (levels 8e-6 and
        # 7e-6 apart) refined to n = 128, three times the time.
        return v2.copy(), raw_estimate
    p = min(order.high, max(order.low, measured))
    e1, e2 = (np.array(e) for e in _pairwise([_floats(x) for x in values[-3:]], p))
    scale = _scale(e2, floor)
    mask = np.isfinite(e2) & np.isfinite(e1) & (scale != 0)
    if not np.any(mask):
        return e2, 0.0
    spread = np.abs(e2 - e1)[mask] / (2.0 ** p - 1.0)
    # Three levels fit the order and cannot check it: the extrapolation is trusted no further
    # than its own correction (the seed's separation time: error 5.6e-6, spread 5.1e-7).
    correction = np.abs(e2 - v2)[mask]
    return e2, float(np.max(np.maximum(spread, correction) / scale[mask]))


def _pairwise(v: Sequence[list], p: float) -> list[list]:
    """The Richardson extrapolation at order ``p`` of each pair of consecutive levels (step
    ratio 2, outputs as Python floats), coarsest pair first."""
    f = 1.0 / (2.0 ** p - 1.0)
    return [_Floats(b + (b - a) * f for a, b in zip(coarse, fine))
            for coarse, fine in zip(v[:-1], v[1:])]


_EXTRAPOLATIONS = {"method": extrapolate, "measured": extrapolate_measured}
#: Levels before a ladder may stop on its estimate. The fixed-order extrapolation needs four:
#: from three, an ``h^3`` and an ``h^4`` term can cancel in the change of the two
#: extrapolations while the error stays (the estimate is then unboundedly low); from four the
#: previous change bounds it (tests/test_levels.py).
_MIN_LEVELS = {None: 3, "measured": 3, "method": 4}


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
           extrapolated: str | None = None,
           floor: Callable[[object], np.ndarray] | None = None,
           first_order_max: float = math.inf) -> Ladder:
    """Run ``n_first, 2 n_first, ...`` until the estimate is below ``rtol / 2`` (from three
    levels on, four with ``extrapolated="method"``) or ``can_refine(finest, next_n)`` says no. The estimate is that of the finest level
    (:func:`richardson`), or with ``extrapolated`` (``"method"``: :func:`extrapolate`,
    ``"measured"``: :func:`extrapolate_measured`) that of the extrapolated outputs, which are
    then what the ladder reports.

    With only two levels when refinement has to stop, the estimate is a third of their
    difference (the second-order Richardson factor, without a measured order). A level that
    reports ``interrupted`` ends the ladder at once with a nan estimate. ``floor(finest)``
    (optional) gives each output the size below which its error is judged absolutely
    (:func:`_scale`). The first three levels are not stopped on where the order they measure
    exceeds ``first_order_max``: a first level too coarse for the asymptotic range (its
    error far larger than the order predicts) leaves an extrapolation whose estimate is
    honest but far too cautious, and the next level is cheaper than the work it would ask
    of a run that trusts it.
    """
    levels, outs = [], []
    n = n_first
    estimate, measured, values = math.nan, math.nan, None
    while True:
        levels.append(run(n))
        if interrupted(levels[-1]):
            return Ladder(levels, math.nan, math.nan)
        outs.append(_floats(outputs(levels[-1])))
        if len(levels) >= 3:
            last = outs[-4 if extrapolated else -3:]
            lowest = None if floor is None else floor(levels[-1])
            estimate, measured = richardson(last[-3:], order, lowest)
            if extrapolated:
                values, estimate = _EXTRAPOLATIONS[extrapolated](last, order, lowest,
                                                                 raw=(estimate, measured))
            regular = len(levels) > 3 or not measured > first_order_max
            if (estimate <= 0.5 * rtol and len(levels) >= _MIN_LEVELS[extrapolated]
                    and regular):
                return Ladder(levels, estimate, measured, values)
        if not can_refine(levels[-1], 2 * n):
            if len(levels) == 2:
                lowest = None if floor is None else floor(levels[-1])
                estimate = relative_spread(outs[0], outs[1], lowest) / 3.0
            return Ladder(levels, estimate, measured, values)
        n *= 2
