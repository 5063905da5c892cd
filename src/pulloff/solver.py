"""Orchestration: scales, step selection, error control and detachment location.

The seed scene (MODEL.md section 3) in dimensionless form: lengths along the foundation in units of
``a``, displacements, lift and gap in ``delta``, time in ``T = delta / v``. Then

    s(t) = sqrt(b^2 - 1) = k (h0 + t) + c,   k = 2 G delta / (sigma_c a),  c = 2 eta v / (sigma_c a)
    k U + c dU/dt = sqrt(s^2 - sigma^2)  for an element at sigma = sqrt(x^2 - 1) < s(t)
    gap = (2/pi) [ h atan(s) - int_1^b U / sqrt(b^2 - x^2) dx ]

and detachment is the first ``gap = 1``. ``alpha = (pi/2) k / c^2``, ``chi = (pi/2) k``,
``V = c / 2``. The numerical work lives in :mod:`pulloff.kernels`; this module chooses the step
from ``rtol``, checks it by step doubling, and converts back to SI.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from . import analytic, kernels
from .report import progress_bar

#: Steps per reference time at ``rtol = 1``; the measured error constant of the stepper on the
#: shipped scenes is ~1e-2 (relative error ~ 1e-2 / N^2), so this starts one doubling short.
#: ``_MAX_STEPS`` caps the finest level (its cost grows like the square of the steps).
_STEP_CONSTANT = 0.02
_MIN_STEPS = 16
_MAX_STEPS = 200_000


@dataclass(frozen=True)
class Problem:
    """A seed scene reduced to numbers (SI in the fields, dimensionless through the properties)."""

    G: float  # Pa
    eta: float  # Pa s
    sigma_c: float  # Pa
    delta: float  # m
    a: float  # m
    v: float  # m/s
    h0: float = 0.0  # m
    #: Maxwell arms ``((G_i [Pa], tau_i [s]), ...)`` of a standard linear solid or Prony
    #: series; ``G`` is then the relaxed modulus ``G_inf`` and ``eta`` is 0.
    arms: tuple = ()

    @classmethod
    def from_scene(cls, scene) -> "Problem":
        G, eta, arms = scene.material.relaxation()
        return cls(G=G, eta=eta, sigma_c=scene.adhesion.sigma_c, delta=scene.adhesion.delta,
                   a=scene.geometry.radius, v=scene.loading.v, h0=scene.loading.h0,
                   arms=tuple(arms))

    @property
    def arm_stiffness(self) -> np.ndarray:
        """Dimensionless ``k_i = 2 G_i delta / (sigma_c a)`` of the Maxwell arms."""
        return np.array([2.0 * G * self.delta / (self.sigma_c * self.a) for G, _ in self.arms])

    @property
    def arm_times(self) -> np.ndarray:
        """Dimensionless relaxation times ``tau_i v / delta`` of the Maxwell arms."""
        return np.array([tau / self.time_scale for _, tau in self.arms])

    @property
    def k(self) -> float:
        """Dimensionless foundation stiffness ``2 G delta / (sigma_c a)``."""
        return 2.0 * self.G * self.delta / (self.sigma_c * self.a)

    @property
    def c(self) -> float:
        """Dimensionless foundation damping ``2 eta v / (sigma_c a)``."""
        return 2.0 * self.eta * self.v / (self.sigma_c * self.a)

    @property
    def time_scale(self) -> float:
        """``T = delta / v`` [s]: the time to lift the punch by one Dugdale length."""
        return self.delta / self.v

    @property
    def h0_scaled(self) -> float:
        return self.h0 / self.delta

    def s_of(self, t):
        """``sqrt(b^2 - a^2) / a`` at dimensionless time ``t`` (edge condition)."""
        return self.k * (self.h0_scaled + t) + self.c

    # --- SI views of a dimensionless time -------------------------------------------------
    def lift(self, t):
        """Punch lift ``h`` [m] at dimensionless time ``t``."""
        return self.h0 + self.v * self.time_scale * np.asarray(t, dtype=float)

    def zone_end(self, t):
        """Cohesive-zone end ``b`` [m] at dimensionless time ``t``."""
        s = self.s_of(np.asarray(t, dtype=float))
        return self.a * np.sqrt(1.0 + s * s)

    def contact_force(self, t):
        """``F_contact = 8 a (G h + eta dh/dt)`` [N] (eq. 48)."""
        return 8.0 * self.a * (self.G * self.lift(t) + self.eta * self.v)

    def total_force(self, t):
        """``F_contact`` plus the cohesive zone's own force [N] (MODEL.md section 3)."""
        return self.contact_force(t) + analytic.cohesive_force(self.sigma_c, self.a,
                                                               self.zone_end(t))


# --------------------------------------------------------------------------------------------
# Frozen history (the seed's eq. 31): closed form, nothing to discretise.

def frozen_memory(problem: Problem, t):
    """``U / q`` of the frozen-load model at dimensionless time ``t``: ``(1 - exp(-k t/c)) / k``
    with its exact limits ``1/k`` (``c = 0``) and ``t/c`` (``k = 0``); scalars or arrays."""
    k, c = problem.k, problem.c
    t = np.asarray(t, dtype=float)
    if c == 0.0:
        return np.full_like(t, 1.0 / k)
    if k == 0.0:
        return t / c
    return -np.expm1(-k * t / c) / k


def frozen_gap(problem: Problem, t):
    """Dimensionless gap of the seed's frozen-load model, without linearisation in ``b - a``.

    Every element carries the current load since ``t = 0``: ``U = q`` :func:`frozen_memory`,
    so ``int U / sqrt(b^2 - x^2) dx = (b - 1)`` times that factor. Scalars or arrays.
    """
    s = problem.s_of(np.asarray(t, dtype=float))
    return (2.0 / math.pi) * ((problem.h0_scaled + t) * np.arctan(s)
                              - _zone_ratio(s) * frozen_memory(problem, t))


def frozen_detach_time(problem: Problem, t_limit: float = math.inf) -> float:
    """First dimensionless time with ``frozen_gap = 1`` (``inf`` if none before ``t_limit``).

    It bounds the exact detachment time from above: loads only grow, so the exact displacement
    is never larger than the frozen one and the exact gap reaches 1 no later.
    """
    if frozen_gap(problem, 0.0) >= 1.0:
        return 0.0
    hi = 1.0
    while frozen_gap(problem, hi) < 1.0:
        if hi > t_limit:
            return math.inf
        hi *= 2.0
    lo = hi / 2.0 if hi > 1.0 else 0.0
    return brentq(lambda t: float(frozen_gap(problem, t)) - 1.0, lo, hi, xtol=1e-300,
                  rtol=1e-15, maxiter=400)


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


def _crossing_time(t: np.ndarray, gap: np.ndarray, n: int) -> float:
    """Time where the gap reaches 1 inside step ``n`` (third-order local interpolation).

    A quadratic through the last three points keeps the location error below the stepper's
    second-order error; it falls back to linear when only two points exist.
    """
    t1, t2 = t[n - 1], t[n]
    g1, g2 = gap[n - 1], gap[n]
    t_lin = t1 + (1.0 - g1) * (t2 - t1) / (g2 - g1)
    if n < 2:
        return t_lin
    t0, g0 = t[n - 2], gap[n - 2]
    # Newton form of the quadratic through the three points, solved near the linear guess.
    d1 = (g2 - g1) / (t2 - t1)
    d2 = ((g2 - g1) / (t2 - t1) - (g1 - g0) / (t1 - t0)) / (t2 - t0)

    def residual(tt):
        return g2 + d1 * (tt - t2) + d2 * (tt - t2) * (tt - t1) - 1.0

    if residual(t1) <= 0.0 <= residual(t2):
        return brentq(residual, t1, t2, xtol=1e-300, rtol=1e-15)
    return t_lin


def preloaded_mesh(s0: float, n: int):
    """Nodes ``sigma`` (ascending, from 0) of the zone loaded at ``t = 0`` and ``s0 - sigma``.

    Uniform in angle, ``sigma = s0 cos(theta)``: they cluster toward ``b(0)``, where the load
    of an element is weakest and varies fastest. The offsets ``s0 - sigma`` are exact, so the
    kernels never subtract two nearly equal ``s`` and ``sigma``. No nodes when ``s0 = 0``.
    """
    if s0 <= 0.0:
        return np.zeros(0), np.zeros(0)
    angles = np.arange(n, 0, -1) * (0.5 * np.pi / n)
    sigma = s0 * np.cos(angles)
    sigma[0] = 0.0
    return sigma, 2.0 * s0 * np.sin(0.5 * angles) ** 2


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
    n_tab = max(kernels.ONSET_ASYMPTOTIC_AGE, min(n_ages, _TABLE_AGES))
    decay, w_pre_old, w_pre_new = kernels.linear_load_weights(k, c, dt)
    rule = (kernels.TS_NODES, kernels.TS_COMPLEMENTS, kernels.TS_WEIGHTS)
    if k > 0.0:
        w_on_old, w_on_new = kernels.onset_weights(k, c, dt, n_tab, *rule)
        scale, m_old, m_new = kernels.onset_moments(k, c, dt, *rule)
        ratio, w_young, w_old = kernels.age_interval_weights(
            k, c, dt, n_tab, kernels.TS_FINE_NODES, kernels.TS_FINE_COMPLEMENTS,
            kernels.TS_FINE_WEIGHTS)
    else:
        w_on_old = w_on_new = np.zeros(n_tab)
        scale, m_old, m_new = 0.0, np.zeros(kernels.BINOM_HALF.size), np.zeros(
            kernels.BINOM_HALF.size)
        ratio = np.zeros(n_tab + 1)
        w_young = w_old = np.zeros(n_tab)
    return (decay, w_pre_old, w_pre_new, w_on_old, w_on_new, scale, m_old, m_new, ratio,
            w_young, w_old)


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
        self.tail = np.zeros((0, 2))  # the last three raw rows (time, gap): event location

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
        if t.size >= 3:
            self.tail = np.column_stack([t[-3:], gap[-3:]])
        else:
            self.tail = np.concatenate([self.tail, np.column_stack([t, gap])])[-3:]

    def arrays(self, dt, last_step):
        steps = np.concatenate(self.steps) if self.steps else np.zeros(0, dtype=np.int64)
        gaps = np.concatenate(self.gaps) if self.gaps else np.zeros(0)
        if steps.size == 0 or steps[-1] != last_step:
            # The run's last row always belongs to the history, recorded or not.
            steps = np.append(steps, last_step)
            gaps = np.append(gaps, self.tail[-1, 1])
        return steps, steps * dt, gaps


def si_history(problem: "Problem", t, gap) -> dict:
    """History columns in SI from dimensionless times and gaps (see ``h5io.HISTORY_UNITS``)."""
    return {
        "t": t * problem.time_scale,
        "h": problem.lift(t),
        "a": np.full(np.shape(t), problem.a),
        "b": problem.zone_end(t),
        "gap": gap * problem.delta,
        "F_contact": problem.contact_force(t),
        "F_total": problem.total_force(t),
    }


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
    k, c, h0 = problem.k, problem.c, problem.h0_scaled
    s0 = problem.s_of(0.0)
    # Elements already inside the zone at t = 0: as many as entering elements would fill the
    # same range of sigma.
    s_ref = problem.s_of(n_stop * dt)
    n_pre = n_preloaded or max(8, int(math.ceil(n_stop * s0 / s_ref)))
    if max_elements is not None:
        # A budget bounds this part too (a quarter of it): its mesh then stops refining with
        # the step.
        n_pre = min(n_pre, max(8, int(max_elements) // 4))
    sig_pre, offset_pre = preloaded_mesh(s0, n_pre)
    if c == 0.0:
        # An elastic element follows its load at once, also the step lift h0 at t = 0.
        U_pre = np.sqrt(offset_pre * (s0 + sig_pre)) / k
    else:
        U_pre = np.zeros_like(sig_pre)  # a damper cannot move instantly (MODEL.md: u(x,0) = 0)
    capacity = n_stop + 2
    if max_elements is not None:
        capacity = min(capacity, max(16, int(max_elements) - sig_pre.size))
    born = np.zeros(capacity, dtype=np.int64)
    sig_born = np.zeros(capacity)
    U_born = np.zeros(capacity)
    dx_born = np.zeros(capacity)
    # Quadrature weights of thinned intervals (only ever written by thinning).
    thin_w = np.zeros((capacity if max_elements is not None else 1, 4))
    sig_born[0] = s0
    nodes_pre = np.append(sig_pre, s0)
    x_pre = np.sqrt(1.0 + nodes_pre * nodes_pre)
    # kernels.interval_width, vectorised: x widths without cancellation for thin zones.
    dx_pre = np.zeros(nodes_pre.size)
    dx_pre[1:] = (np.diff(nodes_pre) * (nodes_pre[1:] + nodes_pre[:-1])
                  / (x_pre[1:] + x_pre[:-1]))
    # With a budget the preloaded mesh stops refining with the step: the cubic on v keeps
    # its error far below the trapezoid's (fourth order in its spacing).
    pre_w = (kernels.preloaded_cubic_weights(dx_pre) if max_elements is not None
             and sig_pre.size >= 3 else np.zeros((1, 4)))
    n_born = 1
    weights = step_weights(k, c, dt, n_stop + 2)
    history = _History(problem, record_every, stream, stream_every)
    gap0 = float(frozen_gap(problem, 0.0))  # the frozen and exact states agree at t = 0
    history.add(np.zeros(1, dtype=np.int64), np.zeros(1), np.array([gap0]))
    if gap0 >= 1.0:
        return FoundationRun(dt, np.zeros(1), np.array([gap0]), 0.0, sig_pre.size + n_born, 0,
                             steps=np.zeros(1, dtype=np.int64))

    # Stops for snapshots and progress; the kernel runs uninterrupted between them. A snapshot
    # between two steps interpolates the states at both ends (second order, like the stepper).
    wanted = {}
    for ts in snapshot_times:
        n0 = min(n_stop, max(0, int(math.floor(ts / dt))))
        wanted[ts] = (n0, min(n_stop, n0 + 1))
    capture_steps = {n for pair in wanted.values() for n in pair}
    captured = {}
    if 0 in capture_steps:
        captured[0] = _field(sig_pre, U_pre, sig_born, U_born, n_born)
    # ~50 stops for progress and Ctrl-C (a signal is seen when the kernel returns; the rows
    # of that call are lost); at least _MIN_CHUNK steps each, so small runs pay no overhead.
    chunk = max(_MIN_CHUNK, n_stop // 50)
    stops = sorted((set(range(chunk, n_stop, chunk)) | capture_steps | {n_stop}) - {0})
    buffer = min(n_stop, _CHUNK_STEPS)
    t_buf = np.zeros(buffer + 1)
    gap_buf = np.zeros(buffer + 1)
    step = 0
    crossed = False
    interrupted = False
    n_thinned = 0
    j_consecutive = 0
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
                    n_born = _thin(born, sig_born, U_born, dx_born, thin_w, n_born, step)
                    # The young elements thinning keeps are the consecutive tail.
                    gaps = np.nonzero(np.diff(born[:n_born]) > 1)[0]
                    j_consecutive = int(gaps[-1]) + 1 if gaps.size else 0
                    n_thinned += 1
            if step in capture_steps:
                captured[step] = _field(sig_pre, U_pre, sig_born, U_born, n_born)
            if crossed:
                break
    except KeyboardInterrupt:
        # Compiled code does not see signals; Python raises on return, before ``step`` is
        # updated, so the arrays and the history hold a consistent state up to ``step``.
        interrupted = True
    t_detach = math.nan
    if crossed:
        tail = history.tail
        t_detach = _crossing_time(tail[:, 0], tail[:, 1], tail.shape[0] - 1)
    t_end = t_detach if crossed else step * dt
    snapshots = []
    for ts in sorted(wanted):
        n0, n1 = wanted[ts]
        # Only times the run reached: none after detachment or past t_max.
        if ts <= t_end and n0 in captured and n1 in captured:
            snapshots.append((ts, *_interpolate_field(problem, captured[n0], captured[n1],
                                                      ts / dt - n0, ts)))
    steps, t, gap = history.arrays(dt, step)
    return FoundationRun(dt, t, gap, t_detach, sig_pre.size + n_born, step, snapshots,
                         interrupted, steps=steps, n_thinned=n_thinned)


def _thin(born, sig_born, U_born, dx_born, thin_w, n_born, step) -> int:
    """Thin full element arrays to at most half their size (see ``kernels.thin_entered``)."""
    capacity = sig_born.size
    keep_young = capacity // 4
    # A geometric grading from keep_young to the oldest age in capacity/4 elements.
    oldest = max(step - born[0], keep_young + 1)
    ratio_max = math.exp(math.log(oldest / keep_young) / (capacity // 4))
    n_kept = kernels.thin_entered(born, sig_born, U_born, dx_born, thin_w, n_born, step,
                                  keep_young, ratio_max)
    if n_kept > capacity // 2 + capacity // 4:
        raise RuntimeError(f"thinning kept {n_kept} of {capacity} elements")  # a bug, not input
    return n_kept


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

@dataclass
class Result:
    """Outcome of a simulation, SI units throughout (see :func:`simulate`)."""

    problem: Problem
    history_model: str
    detached: bool
    t_detach: float  # s
    h_detach: float  # m
    b_detach: float  # m
    zone_ratio_detach: float  # (b - a)/a at detachment, from S without cancellation
    F_contact_detach: float  # N
    F_total_detach: float  # N
    error_estimate: float  # relative, of t and F
    complete: bool  # False after Ctrl-C: the history holds what was computed until then
    notes: list  # what the user should know: an unmet rtol, skipped snapshots
    n_elements: int
    n_steps: int
    wall_time: float  # s
    t_end: float  # s, last simulated time
    history: dict  # t, h, b, gap, F_contact, F_total (SI arrays)
    snapshots: list  # (t [s], x [m], u [m])
    groups: dict  # alpha, chi, V
    analytic: dict  # closed forms, SI
    history_streamed: bool = False  # the full history went to a stream; ``history`` previews it
    until: str = "detach"  # model.until
    cohesive_zone: str = "external"  # geometry.cohesive_zone
    t_separation: float = math.nan  # s, b reached 0 (model.until = separation)
    F_peak_contact: float = math.nan  # N, largest F_contact of the run
    F_peak_total: float = math.nan  # N, largest F_total of the run
    t_peak_contact: float = math.nan  # s
    t_peak_total: float = math.nan  # s
    observed_order: float = math.nan  # of the error with the step, from the last three levels


def _n_steps_for(rtol: float) -> int:
    return int(min(_MAX_STEPS, max(_MIN_STEPS, math.ceil(math.sqrt(_STEP_CONSTANT / rtol)))))


def _detach_outputs(problem: Problem, t: float):
    return np.array([t, problem.contact_force(t), problem.total_force(t)], dtype=float)


def simulate(scene, progress: bool = False, stream=None) -> Result:
    """Run a scene: exact history by time stepping, frozen history in closed form.

    ``numerics.rtol`` is the target relative error of the detachment time and forces. The
    exact model is run at ``N`` and ``2N`` steps per reference time; the second-order stepper's
    error is estimated as a third of their difference (Richardson) and ``N`` doubles until the
    estimate is below ``rtol / 2``. The finer run is reported, with its estimate.

    With ``numerics.steps`` the pull is run at that many steps instead, after one run at half
    as many for the error estimate. Its history goes to ``stream`` as it is computed (a
    callable taking :func:`si_history` columns, e.g. :class:`pulloff.h5io.HistoryStream`);
    ``Result.history`` then holds a preview of at most ``output.history_rows`` rows and
    ``Result.history_streamed`` is true.
    """
    wall_start = time.perf_counter()
    problem = Problem.from_scene(scene)
    rtol = scene.numerics.rtol
    T = problem.time_scale
    t_limit = math.inf if scene.numerics.t_max is None else scene.numerics.t_max / T
    t_frozen = frozen_detach_time(problem, t_limit)
    snapshot_times = [ts / T for ts in scene.output.snapshots]

    if (scene.model.until == "separation" or scene.geometry.cohesive_zone == "internal"
            or problem.arms):
        return _simulate_moving_edge(scene, problem, t_frozen, t_limit, progress, wall_start)
    notes = []
    streamed = False
    if scene.model.history == "frozen":
        run, error_estimate = _frozen_run(problem, t_frozen, t_limit, scene.output.history_rows,
                                          snapshot_times)
    elif scene.numerics.steps is not None:
        run, error_estimate = _fixed_run(problem, t_frozen, t_limit, scene, snapshot_times,
                                         progress, stream)
        streamed = stream is not None
        if not error_estimate <= rtol and not run.interrupted and run.t.size > 1:
            notes.append(f"error estimate {error_estimate:.2g} above rtol {rtol:g} at the fixed "
                         f"{scene.numerics.steps} steps")
    else:
        run, error_estimate = _exact_run(problem, t_frozen, t_limit, rtol, snapshot_times,
                                         progress, scene.output.every,
                                         scene.numerics.max_elements)
        if not error_estimate <= rtol and run.t.size > 1 and not run.interrupted:
            notes.append(f"not converged: error estimate {error_estimate:.2g} above rtol "
                         f"{rtol:g} at the step cap ({_MAX_STEPS} steps)")
    if run.n_thinned:
        notes.append(f"element arrays thinned {run.n_thinned} times (numerics.max_elements)")
    t_reached = run.t_detach if not math.isnan(run.t_detach) else run.t[-1]
    for ts in scene.output.snapshots:
        if ts / T > t_reached:
            notes.append(f"snapshot at t = {ts:g} s skipped: after the end of the run")
    if streamed:
        # The stream ends exactly at the event, or at the last step reached.
        if not math.isnan(run.t_detach):
            stream(si_history(problem, np.array([run.t_detach]), np.array([1.0])))
        elif run.steps[-1] % _stream_every(scene) != 0:
            stream(si_history(problem, run.t[-1:], run.gap[-1:]))
    result = _assemble(scene, problem, run, error_estimate, time.perf_counter() - wall_start,
                       notes)
    result.history_streamed = streamed
    return result


#: Steps of the fixed-step mode's default element arrays (``numerics.max_elements``).
_FIXED_MAX_ELEMENTS = 4096


def _stream_every(scene) -> int:
    steps = scene.numerics.steps
    if scene.output.every is not None:
        return scene.output.every
    return max(1, math.ceil(steps / scene.output.history_rows))


def _frozen_run(problem, t_frozen, t_limit, rows, snapshot_times):
    t_end = min(t_frozen, t_limit)
    t = np.linspace(0.0, t_end, max(2, rows)) if t_end > 0 else np.zeros(1)
    gap = frozen_gap(problem, t)
    detached = t_frozen <= t_limit
    snapshots = []
    for ts in snapshot_times:
        if ts <= t_end:
            s = problem.s_of(ts)
            sig = s * np.cos(np.linspace(0.5 * np.pi, 0.0, 65))
            q = np.sqrt(np.maximum((s - sig) * (s + sig), 0.0))
            snapshots.append((ts, sig, q * frozen_memory(problem, ts)))
    run = FoundationRun(math.nan, t, gap, t_frozen if detached else math.nan, 0, 0, snapshots,
                        steps=np.arange(t.size))
    # The root is found to rounding; the estimate is that of brentq's tolerance.
    return run, 4e-16 * 8


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


def _fixed_run(problem, t_frozen, t_limit, scene, snapshot_times, progress, stream):
    """``numerics.steps`` over the pull, checked by a run with half the steps and
    ``1/sqrt(2)`` of the element budget. The step error is second order, the budget's
    (thinned and fixed meshes, fourth-order quadrature) grows 2.8-5.7 times as the budget
    shrinks by ``sqrt(2)`` (measured orders 3-5 in the budget); so a third of the difference
    is within a factor 1/3..2 of the finer run's error whichever dominates."""
    n = scene.numerics.steps
    max_elements = scene.numerics.max_elements or _FIXED_MAX_ELEMENTS
    t_ref = _pull_time(problem, t_frozen, t_limit)
    if t_ref == 0.0:
        return run_foundation(problem, 1.0, 0), 0.0

    preview = max(1, math.ceil(_steps_to_cover(n, t_ref, t_limit) / scene.output.history_rows))
    runs = []
    # The streamed run first: a Ctrl-C during the check leaves its whole history in the file.
    for m, budget, sink in ((n, max_elements, stream),
                            (n // 2, max(64, int(max_elements / math.sqrt(2.0))), None)):
        total = _steps_to_cover(m, t_ref, t_limit)
        with progress_bar(progress, f"{m} steps", total) as update:
            runs.append(run_foundation(problem, t_ref / m, total,
                                       snapshot_times if sink is stream else (),
                                       progress=update, record_every=preview,
                                       max_elements=budget, stream=sink,
                                       stream_every=_stream_every(scene)))
        if runs[-1].interrupted:
            return dataclasses.replace(runs[0], interrupted=True), math.nan
    full, half = runs
    if math.isnan(half.t_detach) or math.isnan(full.t_detach):
        return full, _gap_difference(half, full)
    if full.t_detach == 0.0:
        return full, 0.0
    values = [_detach_outputs(problem, r.t_detach) for r in runs]
    return full, float(np.max(np.abs(values[0] - values[1]) / np.abs(values[0])) / 3.0)


def _steps_to_cover(n: int, t_ref: float, t_limit: float) -> int:
    """Steps for ``n`` steps per ``t_ref``: the frozen time bounds detachment from above, but
    rounding can put the crossing a hair beyond it, and a few spare steps are cheap. A user's
    ``t_max`` is a hard end."""
    return n if t_ref >= t_limit else n + max(2, n // 16)


def _exact_run(problem, t_frozen, t_limit, rtol, snapshot_times, progress, every=None,
               max_elements=None):
    t_ref = min(t_frozen, t_limit)
    if t_ref == 0.0:
        return run_foundation(problem, 1.0, 0), 0.0

    def level(n, snapshots=(), progress=None):
        # In memory: every user-chosen step, or a power of two that keeps ~2000-4000 rows and
        # lands the rows of consecutive levels on common times (for the gap comparison).
        record = every if every is not None else max(1, n // 2048)
        return run_foundation(problem, t_ref / n, _steps_to_cover(n, t_ref, t_limit), snapshots,
                              progress=progress, record_every=record,
                              max_elements=max_elements)

    n = max(_MIN_STEPS // 2, _n_steps_for(rtol) // 2)
    levels = [level(n)]
    coarse = levels[0]
    # The exact model can detach well before the frozen bound; re-centre the grid on the
    # coarse crossing so that the step count measures the pull that actually happens.
    if coarse.n_steps < n // 2 and math.isfinite(coarse.t_detach) and coarse.t_detach > 0:
        t_ref = min(t_ref, 1.25 * coarse.t_detach * (1.0 + 2.0 / n))
        levels = [level(n)]
    if levels[-1].interrupted:
        return levels[-1], math.nan
    while True:
        n *= 2
        with progress_bar(progress, f"{n} steps", _steps_to_cover(n, t_ref, t_limit)) as update:
            levels.append(level(n, snapshot_times, update))
        if levels[-1].interrupted:
            return levels[-1], math.nan
        if len(levels) < 3 and 2 * n <= _MAX_STEPS:
            continue
        estimate = _error_estimate(problem, levels)
        # Measured against the quadrature reference, the estimate tracks the true error to
        # within a factor ~0.6-1 on most scenes, down to 1/12 where the leading error term
        # changes sign (the true error is then far below rtol); half of rtol leaves room.
        if estimate <= 0.5 * rtol or 2 * n > _MAX_STEPS:
            return levels[-1], estimate


def _error_estimate(problem, levels) -> float:
    """Richardson estimate of the finest level's relative error from the last three levels.

    The order is measured from the same levels (clipped to [1, 2]): the stepper is second
    order asymptotically but passes through lower observed orders where the relaxation layer
    ``c/k`` is about one step wide.
    """
    runs = levels[-3:]
    if any(math.isnan(r.t_detach) for r in runs):
        return _gap_difference(runs[-2], runs[-1])
    if runs[-1].t_detach == 0.0:
        return 0.0
    values = [_detach_outputs(problem, r.t_detach) for r in runs]
    scale = np.abs(values[-1])
    d_last = np.abs(values[-1] - values[-2]) / scale
    d_prev = np.abs(values[-2] - values[-1 - 2]) / scale
    worst = int(np.argmax(d_last))
    if d_last[worst] == 0.0:
        return 0.0
    ratio = d_prev[worst] / d_last[worst] if d_prev[worst] > 0 else 4.0
    order = min(2.0, max(1.0, math.log2(ratio)))
    return float(d_last[worst] / (2.0**order - 1.0))


def _gap_difference(coarse: FoundationRun, fine: FoundationRun) -> float:
    """A third of the largest gap difference of two runs (step ratio 2) at their common
    recorded times, relative to the largest gap: the estimate when neither detaches."""
    _, i_c, i_f = np.intersect1d(2 * coarse.steps, fine.steps, return_indices=True)
    if i_c.size < 2:
        return 0.0
    g_c = coarse.gap[i_c]
    g_f = fine.gap[i_f]
    return float(np.max(np.abs(g_f - g_c)) / max(np.max(np.abs(g_f)), 1e-300)) / 3.0


def _decimate(n_rows: int, limit: int) -> np.ndarray:
    if n_rows <= limit:
        return np.arange(n_rows)
    return np.unique(np.round(np.linspace(0, n_rows - 1, limit)).astype(int))


def _assemble(scene, problem: Problem, run: FoundationRun, error_estimate: float, wall: float,
              notes: list):
    T = problem.time_scale
    detached = not math.isnan(run.t_detach)
    t_hist, gap_hist = run.t, run.gap
    if detached and run.t_detach > 0.0:
        # Keep the rows before detachment and end the history exactly at the event.
        keep = t_hist < run.t_detach
        t_hist = np.append(t_hist[keep], run.t_detach)
        gap_hist = np.append(gap_hist[keep], 1.0)
    if scene.output.every is None or scene.numerics.steps is not None:
        # (A fixed-step run's full history is streamed; this is its preview.)
        rows = _decimate(t_hist.size, scene.output.history_rows)
        t_hist, gap_hist = t_hist[rows], gap_hist[rows]
    history = si_history(problem, t_hist, gap_hist)
    td = run.t_detach
    nan = math.nan
    snapshots = [(ts * T, problem.a * np.sqrt(1.0 + sig * sig), problem.delta * U)
                 for ts, sig, U in run.snapshots]
    return Result(
        problem=problem,
        history_model=scene.model.history,
        detached=detached,
        t_detach=td * T if detached else nan,
        h_detach=float(problem.lift(td)) if detached else nan,
        b_detach=float(problem.zone_end(td)) if detached else nan,
        zone_ratio_detach=float(_zone_ratio(problem.s_of(td))) if detached else nan,
        F_contact_detach=float(problem.contact_force(td)) if detached else nan,
        F_total_detach=float(problem.total_force(td)) if detached else nan,
        error_estimate=float(error_estimate),
        complete=not run.interrupted,
        notes=list(notes),
        n_elements=int(run.n_elements),
        n_steps=int(run.n_steps),
        wall_time=wall,
        t_end=float(t_hist[-1] * T),
        history=history,
        snapshots=snapshots,
        groups=analytic.dimensionless_groups(problem.G, problem.eta, problem.sigma_c,
                                             problem.delta, problem.a, problem.v),
        analytic=analytic_predictions(problem),
    )


def _simulate_moving_edge(scene, problem, t_frozen, t_limit, progress, wall_start):
    """A run with a receding contact edge (:mod:`pulloff.propagation`), in SI."""
    from . import propagation

    rtol = scene.numerics.rtol
    internal = scene.geometry.cohesive_zone == "internal"
    until = scene.model.until
    t_scale = t_frozen if math.isfinite(t_frozen) and t_frozen > 0 else 1.0
    if not math.isfinite(t_limit):
        t_limit = propagation.DEFAULT_SPAN * t_scale
    machine = None
    if scene.loading.machine_stiffness is not None:
        # k_m delta / (sigma_c R^2): spring force per unit stretch, in the solver's units.
        machine = (scene.loading.machine_stiffness * problem.delta
                   / (problem.sigma_c * problem.a ** 2))
    run, estimate, order = propagation.simulate_levels(problem, rtol, t_scale, t_limit,
                                                       internal, until, progress, machine)
    T = problem.time_scale
    R = problem.a
    force = problem.sigma_c * R * R
    notes = list(run.notes)
    if not estimate <= rtol and not run.interrupted:
        notes.append(f"not converged: error estimate {estimate:.2g} above rtol {rtol:g} at "
                     f"the step cap ({propagation.MAX_LEVEL_STEPS} steps per level)")
    if (until == "separation" and math.isnan(run.t_separation) and not run.interrupted
            and not run.notes):
        notes.append(f"no separation before t_max = {run.t[-1] * T:.6g} s")
    rows = _decimate(run.t.size, scene.output.history_rows)
    t_hist = run.t[rows]
    history = {
        "t": t_hist * T,
        "h": problem.delta * run.h[rows],  # behind a spring the lift lags the driver
        "a": R * run.a[rows],
        "b": R * run.b[rows],
        "gap": problem.delta * run.gap[rows],
        "F_contact": force * run.F_contact[rows],
        "F_total": force * run.F_total[rows],
    }
    detached = math.isfinite(run.t_onset)
    nan = math.nan
    a_on, b_on, F_c_on, F_t_on = propagation.onset_state(run, internal)
    F_c_on, F_t_on = force * F_c_on, force * F_t_on
    (t_pc, F_pc), (t_pt, F_pt) = propagation.peaks(run, internal)
    t_pc, F_pc, t_pt, F_pt = (float(x) for x in (t_pc * T, F_pc * force, t_pt * T,
                                                 F_pt * force))
    result = Result(
        problem=problem,
        history_model=scene.model.history,
        detached=detached,
        t_detach=run.t_onset * T if detached else nan,
        h_detach=(problem.delta * float(np.interp(run.t_onset, run.t, run.h))
                  if detached else nan),
        b_detach=R * b_on if detached else nan,
        zone_ratio_detach=(b_on - a_on) / a_on if detached and a_on > 0 else nan,
        F_contact_detach=F_c_on if detached else nan,
        F_total_detach=F_t_on if detached else nan,
        error_estimate=float(estimate),
        complete=not run.interrupted,
        notes=notes,
        n_elements=int(run.n_elements),
        n_steps=int(run.n_steps),
        wall_time=time.perf_counter() - wall_start,
        t_end=float(run.t[-1] * T),
        history=history,
        snapshots=[],
        groups=analytic.dimensionless_groups(problem.G, problem.eta, problem.sigma_c,
                                             problem.delta, problem.a, problem.v),
        analytic=analytic_predictions(problem, internal),
        until=until,
        cohesive_zone=scene.geometry.cohesive_zone,
        t_separation=float(run.t_separation * T),
        F_peak_contact=F_pc,
        F_peak_total=F_pt,
        t_peak_contact=t_pc,
        t_peak_total=t_pt,
        observed_order=float(order),
    )
    return result


def _zone_ratio(s):
    """``(b - a)/a = sqrt(1 + s^2) - 1`` without cancellation for thin zones."""
    return s * s / (1.0 + np.sqrt(1.0 + s * s))


def analytic_predictions(problem: Problem, internal: bool = False) -> dict:
    """The closed forms beside the simulation, SI (nan where a formula does not apply).

    With ``internal`` the elastic MDR-Dugdale forces are those of the zone on the punch face
    (:func:`pulloff.analytic.elastic_internal_onset`, ``elastic_b`` is then the radius); the
    seed's forms are for its external zone."""
    p = problem
    out = {}
    lin = analytic.seed_linearised(p.G, p.eta, p.sigma_c, p.delta, p.a, p.v)
    out["seed_linearised_t_detach"] = lin["t_detach"]
    out["seed_linearised_F"] = lin["F"]
    closed = analytic.seed_closed_form(p.G, p.eta, p.sigma_c, p.delta, p.a, p.v)
    out["seed_closed_form_t_detach"] = closed["t_detach"]
    out["seed_closed_form_F"] = closed["F"]
    out["seed_closed_form_branch"] = closed["branch"]
    gamma = p.sigma_c * p.delta
    out["kendall_F"] = analytic.kendall_force(p.G, gamma, p.a) if p.G > 0 else math.nan
    out["viscous_F"] = analytic.viscous_force(p.eta, p.v, p.a)
    if p.G > 0 and internal:
        el = analytic.elastic_internal_onset(p.G, p.sigma_c, p.delta, p.a)
        out["elastic_F_contact"] = el["F_contact"]
        out["elastic_F_total"] = el["F_total"]
        out["elastic_b"] = p.a
    elif p.G > 0:
        el = analytic.elastic_mdr_dugdale(p.G, p.sigma_c, p.delta, p.a)
        out["elastic_F_contact"] = el["F_contact"]
        out["elastic_F_total"] = el["F_total"]
        out["elastic_b"] = el["b"]
    else:
        out["elastic_F_contact"] = out["elastic_F_total"] = out["elastic_b"] = math.nan
    # A standard linear solid or Prony series: the elastic forms are those of the relaxed
    # modulus; beside them, the instantaneous modulus's (a pull much faster than every tau).
    out["elastic_instant_F_contact"] = out["elastic_instant_F_total"] = math.nan
    if p.arms:
        G0 = p.G + sum(G for G, _ in p.arms)
        el = (analytic.elastic_internal_onset(G0, p.sigma_c, p.delta, p.a) if internal
              else analytic.elastic_mdr_dugdale(G0, p.sigma_c, p.delta, p.a))
        out["elastic_instant_F_contact"] = el["F_contact"]
        out["elastic_instant_F_total"] = el["F_total"]
    return out
