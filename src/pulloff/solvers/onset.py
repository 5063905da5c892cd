"""The seed's onset stepper: the flat punch with its zone outside, pulled to the onset.

The seed scene (MODEL.md section 3) in dimensionless form (see :mod:`.problem`): lengths along
the foundation in units of ``a``, displacements, lift and gap in ``delta``, time in
``T = delta / v``. Then

    s(t) = sqrt(b^2 - 1) = k (h0 + t) + c,   k = 2 G delta / (sigma_c a),  c = 2 eta v / (sigma_c a)
    k U + c dU/dt = sqrt(s^2 - sigma^2)  for an element at sigma = sqrt(x^2 - 1) < s(t)
    gap = (2/pi) [ h atan(s) - int_1^b U / sqrt(b^2 - x^2) dx ]

and detachment is the first ``gap = 1``. ``alpha = (pi/2) k / c^2``, ``chi = (pi/2) k``,
``V = c / 2``. The numerical work lives in :mod:`pulloff.kernels.onset`; this module chooses the
step from ``rtol``, checks it by step doubling (:mod:`.levels`), and converts back to SI.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..kernels import onset as kernels
from . import levels as ladder
from .base import Solver, flat_punch_pull, problem as problem_line, stepper_settings
from .frozen import frozen_detach_time, frozen_gap, zone_ratio
from .observers import decimate, no_progress, stream_every
from .problem import Problem, predictions, si_history
from .result import Result

#: The ladder reports the Richardson extrapolation of its last two levels, whose error falls
#: like ``C / N^3`` (measured on the work-precision scenes: C = 0.06-0.3) and whose estimate is
#: 1-30x that. ``_STEP_CONSTANT`` puts the finest of the first four levels (the ladder's least)
#: at ``N = (_STEP_CONSTANT / rtol)^(1/3)``; of 0.3, 1 and 3 (and 10), 1 was fastest over the
#: four scenes at rtol 1e-6 and 1e-8. ``_MAX_STEPS`` caps the finest level (its cost grows
#: like the square of the steps).
_STEP_CONSTANT = 1.0
_MIN_STEPS = 16
_MAX_STEPS = 200_000
#: The stepper is second order; pre-asymptotically it passes through lower observed orders
#: where the relaxation layer ``c/k`` is about one step wide.
ORDER = ladder.Order(1.0, 2.0)


# --------------------------------------------------------------------------------------------
# Time stepping of the foundation.

@dataclass
class FoundationRun:
    """One time-stepped pass at a fixed step (all dimensionless)."""

    dt: float
    t: np.ndarray  # times of steps 0..n
    gap: np.ndarray
    t_detach: float  # nan if no crossing
    n_elements: int
    n_steps: int
    snapshots: list = field(default_factory=list)  # (t, sigma, U)
    interrupted: bool = False  # Ctrl-C arrived: the run holds what was computed until then
    steps: np.ndarray | None = None  # step numbers of the recorded rows
    n_thinned: int = 0  # times the element arrays were full and thinned


def preloaded_mesh(s0: float, n: int):
    """Nodes ``sigma`` (ascending, from 0) of the zone loaded at ``t = 0`` and ``s0 - sigma``.

    Uniform in angle, ``sigma = s0 cos(theta)``: they cluster toward ``b(0)``, where the load
    of an element is weakest and varies fastest. The offsets ``s0 - sigma`` are exact, so the
    kernels never subtract two nearly equal ``s`` and ``sigma``. No nodes when ``s0 = 0``.
    """
    sigma, offset, _, _ = kernels.preloaded_state(float(s0), int(n), 1.0, 1.0)
    return sigma, offset


#: Ages with tabulated weights, so the tables stay small however long the run. Older elements
#: use :func:`pulloff.kernels.onset_weight_pair`'s expansion (equal to the tables to rounding)
#: and, in the gap, the trapezoid on ``v`` (accurate: ``U/q`` has long relaxed). rtol runs
#: never reach this age.
_TABLE_AGES = 1 << 16
#: Rows of one ``march`` call's history buffer: the history in memory never grows with the run
#: beyond what is recorded.
_CHUNK_STEPS = 1 << 16
_MIN_CHUNK = 2048


def step_weights(k: float, c: float, dt: float, n_ages: int):
    """All weights of one step size, in the order :func:`pulloff.kernels.march` takes them:
    ``(decay, w_pre_old, w_pre_new, w_on_old, w_on_new, onset_scale, onset_m_old, onset_m_new,
    ratio, w_young, w_old)``, tabulated for element ages up to ``min(n_ages, _TABLE_AGES)``
    steps (tables of zeros when ``k = 0``: no element ever enters)."""
    # A run shorter than the expansion's first age never needs it: its tables cover every age.
    n_tab = (n_ages if n_ages <= kernels.ONSET_ASYMPTOTIC_AGE
             else max(kernels.ONSET_ASYMPTOTIC_AGE, min(n_ages, _TABLE_AGES)))
    decay, w_pre_old, w_pre_new = kernels.linear_load_weights(k, c, dt)
    if not k > 0.0:
        zeros = np.zeros(n_tab)
        return (decay, w_pre_old, w_pre_new, zeros, zeros, 0.0, _NO_MOMENTS, _NO_MOMENTS,
                np.zeros(n_tab + 1), zeros, zeros)
    rule = (kernels.TS_NODES, kernels.TS_COMPLEMENTS, kernels.TS_WEIGHTS)
    w_on_old, w_on_new = kernels.onset_weights(k, c, dt, n_tab, *rule)
    # The expansion beyond the tables, only where elements grow older than them.
    scale, m_old, m_new = (kernels.onset_moments(k, c, dt, *rule) if n_tab < n_ages
                           else (0.0, _NO_MOMENTS, _NO_MOMENTS))
    return (decay, w_pre_old, w_pre_new, w_on_old, w_on_new, scale, m_old, m_new,
            *kernels.age_interval_weights(k, c, dt, n_tab))


#: The moments of a run whose tables reach every age (never read, never written).
_NO_MOMENTS = np.zeros(kernels.BINOM_HALF.size)


class _History:
    """Rows of one run kept as they arrive: every ``every``-th step in memory, and every
    ``stream_every``-th step handed to ``stream`` (SI columns, see :func:`si_history`), so
    neither memory nor the kernel's buffer grows with the number of steps."""

    def __init__(self, problem, every, stream=None, stream_every=1):
        self.problem = problem
        self.every = max(1, int(every))
        self.stream = stream
        self.stream_every = max(1, int(stream_every))
        self.steps, self.gaps = [], []
        # The last four raw rows (times, gaps): event location.
        self.tail = (np.zeros(0), np.zeros(0))

    def add(self, steps: np.ndarray, t: np.ndarray, gap: np.ndarray) -> None:
        if self.every == 1:
            self.steps.append(steps)
            self.gaps.append(gap)
        else:
            keep = steps % self.every == 0
            self.steps.append(steps[keep])
            self.gaps.append(gap[keep])
        if self.stream is not None:
            # The crossing row lies past the event; the caller appends the event itself.
            send = (steps % self.stream_every == 0) & (gap < 1.0)
            if np.any(send):
                self.stream(si_history(self.problem, t[send], gap[send]))
        if t.size >= 4:
            self.tail = (t[-4:], gap[-4:])
        else:
            self.tail = (np.concatenate([self.tail[0], t])[-4:],
                         np.concatenate([self.tail[1], gap])[-4:])

    def arrays(self, dt, last_step):
        steps = np.concatenate(self.steps) if self.steps else np.zeros(0, dtype=np.int64)
        gaps = np.concatenate(self.gaps) if self.gaps else np.zeros(0)
        if steps.size == 0 or steps[-1] != last_step:
            # The run's last row always belongs to the history, recorded or not.
            steps = np.append(steps, last_step)
            gaps = np.append(gaps, self.tail[1][-1])
        return steps, steps * dt, gaps


def run_foundation(problem: Problem, dt: float, n_stop: int, snapshot_times=(),
                   progress=None, n_preloaded: int | None = None, record_every: int = 1,
                   max_elements: int | None = None, stream=None,
                   stream_every: int = 1) -> FoundationRun:
    """Step the foundation with step ``dt`` until detachment or ``n_stop`` steps.

    Elements entering the zone are placed at ``b`` after every step, so their spacing is set by
    the step; ``n_preloaded`` (default: matched to that spacing) sets the mesh of the part of
    the zone that is loaded from ``t = 0``. With ``max_elements`` the entered elements live in
    arrays of that size: when they are full the old ones are thinned to a geometric grading
    in age (:func:`pulloff.kernels.thin_entered`), so a run of any length keeps O(max_elements)
    state. The history keeps every ``record_every``-th step in memory and hands every
    ``stream_every``-th to ``stream`` (a callable taking :func:`si_history` columns).
    """
    if (not snapshot_times and progress is None and record_every == 1
            and max_elements is None and stream is None and 0 < n_stop <= _MIN_CHUNK
            and _start_gap(problem) < 1.0):
        return _ladder_level(problem, dt, n_stop, n_preloaded)
    k, c, h0 = problem.k, problem.c, problem.h0_scaled
    s0 = problem.s_of(0.0)
    sig_pre, offset_pre, U_pre, dx_pre, pre_w = _preloaded(problem, dt, n_stop, n_preloaded,
                                                           max_elements)
    capacity = n_stop + 2
    if max_elements is not None:
        capacity = min(capacity, max(16, int(max_elements) - sig_pre.size))
    born, sig_born, U_born, dx_born, thin_w = _entered_arrays(capacity, max_elements)
    sig_born[0] = s0
    n_born = 1
    weights = step_weights(k, c, dt, n_stop + 2)
    history = _History(problem, record_every, stream, stream_every)
    gap0 = _start_gap(problem)
    history.add(np.zeros(1, dtype=np.int64), np.zeros(1), np.array([gap0]))
    if gap0 >= 1.0:
        return FoundationRun(dt, np.zeros(1), np.array([gap0]), 0.0, sig_pre.size + n_born, 0,
                             steps=np.zeros(1, dtype=np.int64))

    wanted, capture_steps, stops = _stops(snapshot_times, dt, n_stop)
    captured = {}
    if 0 in capture_steps:
        captured[0] = _field(sig_pre, U_pre, sig_born, U_born, n_born)
    buffer = min(n_stop, _CHUNK_STEPS)
    t_buf, gap_buf = np.zeros(buffer + 1), np.zeros(buffer + 1)
    step = n_thinned = j_consecutive = 0
    crossed = interrupted = False
    try:
        for stop in stops:
            while step < stop:
                row0 = step
                step_new, n_born, code = kernels.march(
                    sig_pre, offset_pre, U_pre, dx_pre, pre_w, born, sig_born, U_born,
                    dx_born, thin_w, n_born, j_consecutive, step, min(stop, row0 + buffer), k,
                    c, h0, dt, *weights, t_buf, gap_buf, row0)
                rows = step_new - row0
                history.add(np.arange(row0 + 1, step_new + 1), t_buf[1:rows + 1].copy(),
                            gap_buf[1:rows + 1].copy())
                step = step_new
                if progress is not None:
                    progress(rows)
                if code == kernels.MARCH_CROSSED:
                    crossed = True
                    break
                if code == kernels.MARCH_FULL:
                    n_born, j_consecutive = _thin(born, sig_born, U_born, dx_born, thin_w,
                                                  n_born, step)
                    n_thinned += 1
            if step in capture_steps:
                captured[step] = _field(sig_pre, U_pre, sig_born, U_born, n_born)
            if crossed:
                break
    except KeyboardInterrupt:
        # Compiled code does not see signals; Python raises on return, before ``step`` is
        # updated, so the arrays and the history hold a consistent state up to ``step``.
        interrupted = True
    t_tail, gap_tail = history.tail
    t_detach = kernels.crossing_time(t_tail, gap_tail) if crossed else math.nan
    t_end = t_detach if crossed else step * dt
    snapshots = _snapshots(problem, wanted, captured, dt, t_end)
    steps, t, gap = history.arrays(dt, step)
    return FoundationRun(dt, t, gap, t_detach, sig_pre.size + n_born, step, snapshots,
                         interrupted, steps=steps, n_thinned=n_thinned)


def _ladder_level(problem: Problem, dt: float, n_stop: int, n_preloaded) -> FoundationRun:
    """:func:`run_foundation` of a ladder's level (one kernel call, every row kept, nothing
    observed): the same kernels, rows and crossing, without the chunks, history and
    snapshots that cost ~40 us of Python per level (a third of a run at rtol 1e-6 went to the
    Python around its five levels). Kernels called one by one from here: one compiled call
    nesting them (and one for the weights) took numba's first compile from 8 to 15 s here,
    since a caller re-optimises its callees' code."""
    k, c, h0 = problem.k, problem.c, problem.h0_scaled
    sig_pre, offset_pre, U_pre, dx_pre, pre_w = _preloaded(problem, dt, n_stop, n_preloaded,
                                                           None)
    born, sig_born, U_born, dx_born, thin_w = _entered_arrays(n_stop + 2, None)
    sig_born[0] = problem.s_of(0.0)
    t_rows, gap_rows = np.zeros(n_stop + 1), np.zeros(n_stop + 1)
    gap_rows[0] = _start_gap(problem)
    try:
        step, n_born, code = kernels.march(
            sig_pre, offset_pre, U_pre, dx_pre, pre_w, born, sig_born, U_born, dx_born,
            thin_w, 1, 0, 0, n_stop, k, c, h0, dt, *step_weights(k, c, dt, n_stop + 2),
            t_rows, gap_rows, 0)
    except KeyboardInterrupt:
        # As run_foundation: the rows of the interrupted kernel call are lost, the run ends
        # at its first row and says so.
        return FoundationRun(dt, np.zeros(1), gap_rows[:1].copy(), math.nan,
                             sig_pre.size + 1, 0, interrupted=True,
                             steps=np.zeros(1, dtype=np.int64))
    steps = np.arange(step + 1)
    t_detach = (kernels.crossing_time(t_rows[:step + 1], gap_rows[:step + 1])
                if code == kernels.MARCH_CROSSED else math.nan)
    return FoundationRun(dt, steps * dt, gap_rows[:step + 1], t_detach,
                         sig_pre.size + n_born, step, steps=steps)


@functools.lru_cache(maxsize=256)
def _start_gap(problem: Problem) -> float:
    """The gap at ``t = 0``, where the frozen and exact states agree (once per problem: every
    level of a ladder starts there)."""
    return float(frozen_gap(problem, 0.0))


def _entered_arrays(capacity: int, max_elements):
    """Arrays of the elements entering the zone: step born, sigma, U, width, and the
    quadrature weights of thinned intervals (only ever written by thinning)."""
    return (np.zeros(capacity, dtype=np.int64), np.zeros(capacity), np.zeros(capacity),
            np.zeros(capacity), np.zeros((capacity if max_elements is not None else 1, 4)))


def _stops(snapshot_times, dt: float, n_stop: int):
    """Where the kernel pauses: the steps around each snapshot time (a snapshot between two
    steps interpolates the states at both ends, second order like the stepper) and ~50 stops
    for progress and Ctrl-C (a signal is seen when the kernel returns; the rows of that call
    are lost), at least _MIN_CHUNK steps apart so small runs pay no overhead. Returns
    ``(wanted, capture_steps, stops)``."""
    chunk = max(_MIN_CHUNK, n_stop // 50)
    if not snapshot_times and 0 < n_stop <= chunk:
        return {}, set(), [n_stop]  # a ladder's level: one call of the kernel
    wanted = {}
    for ts in snapshot_times:
        n0 = min(n_stop, max(0, int(math.floor(ts / dt))))
        wanted[ts] = (n0, min(n_stop, n0 + 1))
    capture_steps = {n for pair in wanted.values() for n in pair}
    stops = sorted((set(range(chunk, n_stop, chunk)) | capture_steps | {n_stop}) - {0})
    return wanted, capture_steps, stops


def _preloaded(problem: Problem, dt: float, n_stop: int, n_preloaded, max_elements):
    """The elements already inside the zone at ``t = 0``: ``(sigma, offset, U, dx, cubic
    weights)``, as many as entering elements would fill the same range of sigma (a budget
    bounds them to a quarter of it: the mesh then stops refining with the step)."""
    k, c = problem.k, problem.c
    s0 = problem.s_of(0.0)
    n_pre = n_preloaded or _matched_preloaded(problem, dt, n_stop)
    if max_elements is not None:
        n_pre = min(n_pre, max(8, int(max_elements) // 4))
    # An elastic element follows its load at once, also the step lift h0 at t = 0; a damper
    # cannot move instantly (MODEL.md: u(x,0) = 0).
    sig_pre, offset_pre, U_pre, dx_pre = kernels.preloaded_state(float(s0), n_pre, k, c)
    # With a budget the preloaded mesh stops refining with the step: the cubic on v keeps
    # its error far below the trapezoid's (fourth order in its spacing).
    pre_w = (kernels.preloaded_cubic_weights(dx_pre) if max_elements is not None
             and sig_pre.size >= 3 else np.zeros((1, 4)))
    return sig_pre, offset_pre, U_pre, dx_pre, pre_w


def _matched_preloaded(problem: Problem, dt: float, n_stop: int) -> int:
    """Elements of the zone loaded at ``t = 0`` with the spacing that entering elements get
    over ``n_stop`` steps of ``dt`` (at least 8)."""
    return max(8, int(math.ceil(n_stop * problem.s_of(0.0) / problem.s_of(n_stop * dt))))


def _snapshots(problem: Problem, wanted: dict, captured: dict, dt: float, t_end: float):
    """The requested fields, each interpolated between the two steps around its time; only
    times the run reached (none after detachment or past t_max)."""
    out = []
    for ts in sorted(wanted):
        n0, n1 = wanted[ts]
        if ts <= t_end and n0 in captured and n1 in captured:
            out.append((ts, *_interpolate_field(problem, captured[n0], captured[n1],
                                                ts / dt - n0, ts)))
    return out


def _thin(born, sig_born, U_born, dx_born, thin_w, n_born, step) -> tuple[int, int]:
    """Thin full element arrays to at most half their size (see ``kernels.thin_entered``);
    returns how many are kept and where their consecutive young tail starts."""
    capacity = sig_born.size
    keep_young = capacity // 4
    # A geometric grading from keep_young to the oldest age in capacity/4 elements.
    oldest = max(step - born[0], keep_young + 1)
    ratio_max = math.exp(math.log(oldest / keep_young) / (capacity // 4))
    n_kept = kernels.thin_entered(born, sig_born, U_born, dx_born, thin_w, n_born, step,
                                  keep_young, ratio_max)
    if n_kept > capacity // 2 + capacity // 4:
        raise RuntimeError(f"thinning kept {n_kept} of {capacity} elements")  # a bug, not input
    # The young elements thinning keeps are the consecutive tail.
    gaps = np.nonzero(np.diff(born[:n_kept]) > 1)[0]
    return n_kept, (int(gaps[-1]) + 1 if gaps.size else 0)


def _interpolate_field(problem, field0, field1, weight, t):
    """Field at a time ``weight`` of the way from one step to the next (the newer element,
    placed at the end of the step, is replaced by one at ``b(t)``)."""
    sig0, U0 = field0
    sig1, U1 = field1
    if weight <= 0.0:
        return sig0.copy(), U0.copy()
    n = sig0.size
    if sig1.size >= n and np.array_equal(sig1[:n], sig0):
        U1_at_0 = U1[:n]
    else:
        # Old elements were thinned in between: the newer field, interpolated to the older nodes.
        U1_at_0 = np.interp(sig0, sig1, U1)
    U = (1.0 - weight) * U0 + weight * U1_at_0
    s_t = problem.s_of(t)
    if s_t > sig0[-1]:
        return np.append(sig0, s_t), np.append(U, 0.0)
    return sig0.copy(), U


def _field(sig_pre, U_pre, sig_born, U_born, n_born):
    return (np.concatenate([sig_pre, sig_born[:n_born]]),
            np.concatenate([U_pre, U_born[:n_born]]))


# --------------------------------------------------------------------------------------------
# Accuracy control and the SI result.

def seed_onset_problems(scene, solver: str, machine: bool = False) -> list[str]:
    """Problems of a scene for a solver of the seed's onset (Kelvin-Voigt or elastic, exact
    history, to the onset; ``machine``: behind a machine spring too)."""
    out = flat_punch_pull(scene, solver, machine=machine)
    if scene.material.kind not in ("kelvin_voigt", "elastic"):
        out.append(problem_line("material.kind", scene.material.kind,
                                f"the {solver} solver takes Kelvin-Voigt and elastic solids"))
    if scene.model.history != "exact":
        out.append(problem_line("model.history", scene.model.history,
                                f"the {solver} solver solves the exact load history"))
    if scene.model.until != "detach":
        out.append(problem_line("model.until", scene.model.until,
                                f"the {solver} solver stops at the onset of detachment"))
    return out


class OnsetSolver(Solver):
    """The seed scene to its onset: a flat punch with its zone outside, a Kelvin-Voigt (or
    elastic) solid, a rigid machine pulling at constant speed; exact load history."""

    name = "onset"
    method = "stepper"
    kernel = "onset.march"
    summary = "seed onset stepper (flat punch, external zone, Kelvin-Voigt, rigid pull)"

    def unsupported(self, scene) -> list[str]:
        return seed_onset_problems(scene, "onset") + stepper_settings(scene, "onset")

    def solve(self, scene, observers) -> Result:
        wall_start = time.perf_counter()
        problem = Problem.from_scene(scene)
        T = problem.time_scale
        t_limit = math.inf if scene.numerics.t_max is None else scene.numerics.t_max / T
        t_frozen = frozen_detach_time(problem, t_limit)
        notes = []
        if scene.numerics.steps is not None:
            run, estimate = _fixed_run(problem, t_frozen, t_limit, scene.numerics, observers)
            if not estimate <= scene.numerics.rtol and not run.interrupted and run.t.size > 1:
                notes.append(f"error estimate {estimate:.2g} above rtol "
                             f"{scene.numerics.rtol:g} at the fixed {scene.numerics.steps} steps")
            order = math.nan
        else:
            run, estimate, order = _exact_run(problem, t_frozen, t_limit, scene.numerics.rtol,
                                              observers)
            if not estimate <= scene.numerics.rtol and run.t.size > 1 and not run.interrupted:
                notes.append(f"not converged: error estimate {estimate:.2g} above rtol "
                             f"{scene.numerics.rtol:g} at the step cap ({_MAX_STEPS} steps)")
        if run.n_thinned:
            notes.append(f"element arrays thinned {run.n_thinned} times (numerics.max_elements)")
        t_reached = run.t_detach if not math.isnan(run.t_detach) else run.t[-1]
        notes += observers.skipped_snapshots(t_reached * T)
        streamed = observers.stream is not None and scene.numerics.steps is not None
        if streamed:
            _end_stream(problem, run, observers, scene.numerics.steps)
        return assemble(scene, problem, run, estimate, order, observers,
                         time.perf_counter() - wall_start, notes, streamed)


def _end_stream(problem, run, observers, steps):
    """The stream ends exactly at the event, or at the last step reached."""
    if not math.isnan(run.t_detach):
        observers.stream(si_history(problem, np.array([run.t_detach]), np.array([1.0])))
    elif run.steps[-1] % stream_every(observers.every, steps, observers.history_rows) != 0:
        observers.stream(si_history(problem, run.t[-1:], run.gap[-1:]))


def _n_steps_for(rtol: float) -> int:
    """Steps of the finest of the first four levels for ``rtol`` (see ``_STEP_CONSTANT``)."""
    return int(min(_MAX_STEPS, max(_MIN_STEPS, math.ceil((_STEP_CONSTANT / rtol) ** (1 / 3)))))


def detach_outputs(problem: Problem, t: float, *more):
    return np.array([t, problem.contact_force(t), problem.total_force(t), *more], dtype=float)


def _outputs(problem: Problem, run: FoundationRun) -> np.ndarray:
    """What the ladder controls: time and forces at the onset, or the gap at the end of a run
    that does not detach (all levels end at the same time then)."""
    if math.isnan(run.t_detach):
        return np.array([math.nan, math.nan, math.nan, run.gap[-1]])
    return detach_outputs(problem, run.t_detach, math.nan)


#: Steps of the fixed-step mode's default element arrays (``numerics.max_elements``).
_FIXED_MAX_ELEMENTS = 4096


def _pull_time(problem, t_frozen, t_limit):
    """Time span for a fixed step count: the detachment time of a cheap pilot run (64 steps
    over the frozen bound, which bounds it from above) with a small margin, or ``t_max``."""
    t_ref = min(t_frozen, t_limit)
    if t_ref == 0.0 or not math.isfinite(t_ref):
        return t_ref
    pilot = run_foundation(problem, t_ref / 64, 68)
    if math.isfinite(pilot.t_detach) and pilot.t_detach > 0:
        # The pilot's error is ~1e-2/64^2: 2 % keeps the event inside the span.
        t_ref = min(t_ref, 1.02 * pilot.t_detach)
    return t_ref


def _fixed_run(problem, t_frozen, t_limit, numerics, observers):
    """``numerics.steps`` over the pull, checked by a run with half the steps and
    ``1/sqrt(2)`` of the element budget. The step error is second order, the budget's
    (thinned and fixed meshes, fourth-order quadrature) grows 2.8-5.7 times as the budget
    shrinks by ``sqrt(2)`` (measured orders 3-5 in the budget); so a third of the difference
    is within a factor 1/3..2 of the finer run's error whichever dominates."""
    n = numerics.steps
    max_elements = numerics.max_elements or _FIXED_MAX_ELEMENTS
    t_ref = _pull_time(problem, t_frozen, t_limit)
    if t_ref == 0.0:
        return run_foundation(problem, 1.0, 0), 0.0

    preview = max(1, math.ceil(_steps_to_cover(n, t_ref, t_limit) / observers.history_rows))
    every = stream_every(observers.every, n, observers.history_rows)
    runs = []
    # The streamed run first: a Ctrl-C during the check leaves its whole history in the file.
    for m, budget, sink in ((n, max_elements, observers.stream),
                            (n // 2, max(64, int(max_elements / math.sqrt(2.0))), None)):
        total = _steps_to_cover(m, t_ref, t_limit)
        first = not runs
        with observers.progress(f"{m} steps", total) as update:
            runs.append(run_foundation(
                problem, t_ref / m, total, [ts / problem.time_scale for ts in observers.snapshot_times] if first else (),
                progress=update, record_every=preview, max_elements=budget, stream=sink,
                stream_every=every))
        if runs[-1].interrupted:
            return dataclasses.replace(runs[0], interrupted=True), math.nan
    full, half = runs
    if math.isnan(half.t_detach) or math.isnan(full.t_detach):
        return full, _gap_difference(half, full)
    if full.t_detach == 0.0:
        return full, 0.0
    values = [detach_outputs(problem, r.t_detach) for r in runs]
    return full, float(np.max(np.abs(values[0] - values[1]) / np.abs(values[0])) / 3.0)


def _steps_to_cover(n: int, t_ref: float, t_limit: float) -> int:
    """Steps for ``n`` steps per ``t_ref``: the frozen time bounds detachment from above, but
    rounding can put the crossing a hair beyond it, and a few spare steps are cheap. A user's
    ``t_max`` is a hard end."""
    return n if t_ref >= t_limit else n + max(2, n // 16)


def level_mesh(problem: Problem, n: int, n_first: int, t_ref: float, t_limit: float):
    """``(dt, steps, preloaded elements)`` of the ladder's level with ``n`` steps per
    ``t_ref`` (``n = n_first 2^j``). The preloaded mesh is matched to the first level and
    doubles exactly with the steps: matched to each level's own rounded step count, its
    spacing's ratio to the step wandered by up to a few percent from level to level, an
    ``h^2`` error that the extrapolation turned into a staircase (its changes shrank 0.1x,
    then 50x, on the thin zone with alpha 0.1), and the estimate asked for a level more."""
    n_pre = _matched_preloaded(problem, t_ref / n_first,
                               _steps_to_cover(n_first, t_ref, t_limit)) * (n // n_first)
    return t_ref / n, _steps_to_cover(n, t_ref, t_limit), n_pre


def _exact_run(problem, t_frozen, t_limit, rtol, observers):
    """The ladder of step-doubled runs (:func:`pulloff.solvers.levels.refine`); returns the
    finest run, its estimate and the measured order."""
    t_ref = min(t_frozen, t_limit)
    if t_ref == 0.0:
        return run_foundation(problem, 1.0, 0), 0.0, math.nan
    snapshots = [ts / problem.time_scale for ts in observers.snapshot_times]
    n_first = max(_MIN_STEPS // 2, _n_steps_for(rtol) // 8)

    def level(n, t_ref):
        # In memory: every user-chosen step, or a power of two that keeps ~2000-4000 rows and
        # lands the rows of consecutive levels on common times.
        record = observers.every if observers.every is not None else max(1, n // 2048)
        dt, total, n_pre = level_mesh(problem, n, n_first, t_ref, t_limit)
        show = observers.progress if n > n_first else no_progress
        with show(f"{n} steps", total) as update:
            return run_foundation(problem, dt, total, snapshots if n > n_first else (),
                                  progress=update, record_every=record, n_preloaded=n_pre)

    coarse = level(n_first, t_ref)
    # The exact model can detach well before the frozen bound; re-centre the grid on the
    # coarse crossing so that the step count measures the pull that actually happens.
    if coarse.n_steps < n_first // 2 and math.isfinite(coarse.t_detach) and coarse.t_detach > 0:
        t_ref = min(t_ref, 1.25 * coarse.t_detach * (1.0 + 2.0 / n_first))
        coarse = level(n_first, t_ref)
    ladder_result = ladder.refine(
        lambda n: coarse if n == n_first else level(n, t_ref),
        lambda run: _outputs(problem, run), rtol, n_first, ORDER,
        can_refine=lambda run, n: n <= _MAX_STEPS, interrupted=lambda run: run.interrupted,
        extrapolated="method")
    finest = ladder_result.finest
    values = ladder_result.extrapolated
    if values is not None and math.isfinite(values[0]) and math.isfinite(finest.t_detach):
        # The forces are functions of the time alone: only the time is extrapolated.
        finest = dataclasses.replace(finest, t_detach=float(values[0]))
    return finest, ladder_result.estimate, ladder_result.order


def _gap_difference(coarse: FoundationRun, fine: FoundationRun) -> float:
    """A third of the largest gap difference of two runs (step ratio 2) at their common
    recorded times, relative to the largest gap: the estimate when neither detaches."""
    _, i_c, i_f = np.intersect1d(2 * coarse.steps, fine.steps, return_indices=True)
    if i_c.size < 2:
        return 0.0
    g_c = coarse.gap[i_c]
    g_f = fine.gap[i_f]
    return float(np.max(np.abs(g_f - g_c)) / max(np.max(np.abs(g_f)), 1e-300)) / 3.0


def assemble(scene, problem: Problem, run: FoundationRun, estimate: float, order: float,
             observers, wall: float, notes: list, streamed: bool, solver: str = "onset",
             extra: dict | None = None) -> Result:
    """The SI result of an onset run (``solver``: its name in the summary; ``extra``: more
    summary values)."""
    T = problem.time_scale
    detached = not math.isnan(run.t_detach)
    t_hist, gap_hist = run.t, run.gap
    if detached and run.t_detach > 0.0:
        # Keep the rows before detachment and end the history exactly at the event.
        keep = t_hist < run.t_detach
        t_hist = np.concatenate((t_hist[keep], (run.t_detach,)))
        gap_hist = np.concatenate((gap_hist[keep], (1.0,)))
    if (observers.every is None or streamed) and t_hist.size > observers.history_rows:
        # (A fixed-step run's full history is streamed; this is its preview. Rows within
        # the limit are all kept: decimate's indices would be every row.)
        rows = decimate(t_hist.size, observers.history_rows)
        t_hist, gap_hist = t_hist[rows], gap_hist[rows]
    td = run.t_detach
    summary = {"detached": detached, "error_estimate": float(estimate),
               "observed_order": float(order), "n_elements": int(run.n_elements),
               "n_steps": int(run.n_steps), "wall_time": wall, "t_end": float(t_hist[-1] * T),
               "solver": solver, "history": scene.model.history, "until": scene.model.until,
               "cohesive_zone": scene.geometry.cohesive_zone, **problem.groups}
    if detached:
        F_contact, F_total = problem.forces(td)
        summary.update(
            t_detach=td * T, h_detach=float(problem.lift(td)),
            b_detach=float(problem.zone_end(td)),
            zone_ratio_detach=float(zone_ratio(problem.s_of(td))),
            F_contact_detach=float(F_contact), F_total_detach=float(F_total))
    summary.update(extra or {})
    snapshots = [(ts * T, problem.a * np.sqrt(1.0 + sig * sig), problem.delta * U)
                 for ts, sig, U in run.snapshots]
    return Result.build(summary, predictions(scene), si_history(problem, t_hist, gap_hist),
                        snapshots=snapshots, notes=notes, complete=not run.interrupted,
                        history_streamed=streamed, problem=problem)
