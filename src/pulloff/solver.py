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

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from . import analytic, kernels

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

    @classmethod
    def from_scene(cls, scene) -> "Problem":
        return cls(G=scene.material.G, eta=scene.material.eta, sigma_c=scene.adhesion.sigma_c,
                   delta=scene.adhesion.delta, a=scene.geometry.radius, v=scene.loading.v,
                   h0=scene.loading.h0)

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


def step_weights(k: float, c: float, dt: float, n_ages: int):
    """All weights of one step size: ``(decay, w_pre_old, w_pre_new, w_on_old, w_on_new,
    ratio, w_young, w_old)`` for :func:`pulloff.kernels.march`, for element ages up to
    ``n_ages`` steps (tables of zeros when ``k = 0``: no element ever enters)."""
    decay, w_pre_old, w_pre_new = kernels.linear_load_weights(k, c, dt)
    if k > 0.0:
        w_on_old, w_on_new = kernels.onset_weights(k, c, dt, n_ages, kernels.TS_NODES,
                                                   kernels.TS_COMPLEMENTS, kernels.TS_WEIGHTS)
        ratio, w_young, w_old = kernels.age_interval_weights(
            k, c, dt, n_ages, kernels.TS_FINE_NODES, kernels.TS_FINE_COMPLEMENTS,
            kernels.TS_FINE_WEIGHTS)
    else:
        w_on_old = w_on_new = np.zeros(n_ages)
        ratio = w_young = w_old = np.zeros(n_ages + 1)
    return decay, w_pre_old, w_pre_new, w_on_old, w_on_new, ratio, w_young, w_old


def run_foundation(problem: Problem, dt: float, n_stop: int, snapshot_times=(),
                   progress=None, n_preloaded: int | None = None) -> FoundationRun:
    """Step the foundation with step ``dt`` until detachment or ``n_stop`` steps.

    Elements entering the zone are placed at ``b`` after every step, so their spacing is set by
    the step; ``n_preloaded`` (default: matched to that spacing) sets the mesh of the part of
    the zone that is loaded from ``t = 0``.
    """
    k, c, h0 = problem.k, problem.c, problem.h0_scaled
    s0 = problem.s_of(0.0)
    # Elements already inside the zone at t = 0: as many as entering elements would fill the
    # same range of sigma.
    s_ref = problem.s_of(n_stop * dt)
    n_pre = n_preloaded or max(8, int(math.ceil(n_stop * s0 / s_ref)))
    sig_pre, offset_pre = preloaded_mesh(s0, n_pre)
    if c == 0.0:
        # An elastic element follows its load at once, also the step lift h0 at t = 0.
        U_pre = np.sqrt(offset_pre * (s0 + sig_pre)) / k
    else:
        U_pre = np.zeros_like(sig_pre)  # a damper cannot move instantly (MODEL.md: u(x,0) = 0)
    capacity = n_stop + 2
    sig_born = np.zeros(capacity)
    U_born = np.zeros(capacity)
    dx_born = np.zeros(capacity)
    sig_born[0] = s0
    nodes_pre = np.append(sig_pre, s0)
    x_pre = np.sqrt(1.0 + nodes_pre * nodes_pre)
    # kernels.interval_width, vectorised: x widths without cancellation for thin zones.
    dx_pre = np.zeros(nodes_pre.size)
    dx_pre[1:] = (np.diff(nodes_pre) * (nodes_pre[1:] + nodes_pre[:-1])
                  / (x_pre[1:] + x_pre[:-1]))
    n_born = 1
    (decay, w_pre_old, w_pre_new, w_on_old, w_on_new, ratio, w_young,
     w_old) = step_weights(k, c, dt, capacity)
    t_out = np.zeros(capacity)
    gap_out = np.zeros(capacity)
    gap_out[0] = frozen_gap(problem, 0.0)  # the frozen and exact states agree at t = 0
    snapshots = []
    if gap_out[0] >= 1.0:
        return FoundationRun(dt, t_out[:1], gap_out[:1], 0.0, sig_pre.size + n_born, 0)

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
    chunk = max(1, n_stop // 50)
    stops = sorted((set(range(chunk, n_stop, chunk)) | capture_steps | {n_stop}) - {0})
    step = 0
    crossed = False
    interrupted = False
    for stop in stops:
        step_before = step
        try:
            step, n_born, crossed = kernels.march(
                sig_pre, offset_pre, U_pre, dx_pre, sig_born, U_born, dx_born, n_born, step,
                stop, k, c, h0, dt, decay, w_pre_old, w_pre_new, w_on_old, w_on_new, ratio,
                w_young, w_old, t_out, gap_out)
        except KeyboardInterrupt:
            # Compiled code does not see signals; Python raises on return, before ``step``
            # is updated, so the arrays hold a consistent state up to ``step``.
            interrupted = True
            break
        if progress is not None:
            progress(step - step_before)
        if step in capture_steps:
            captured[step] = _field(sig_pre, U_pre, sig_born, U_born, n_born)
        if crossed:
            break
    t_detach = _crossing_time(t_out, gap_out, step) if crossed else math.nan
    t_end = t_detach if crossed else step * dt
    for ts in sorted(wanted):
        n0, n1 = wanted[ts]
        # Only times the run reached: none after detachment or past t_max.
        if ts <= t_end and n0 in captured and n1 in captured:
            snapshots.append((ts, *_interpolate_field(problem, captured[n0], captured[n1],
                                                      ts / dt - n0, ts)))
    return FoundationRun(dt, t_out[:step + 1].copy(), gap_out[:step + 1].copy(), t_detach,
                         sig_pre.size + n_born, step, snapshots, interrupted)


def _interpolate_field(problem, field0, field1, weight, t):
    """Field at a time ``weight`` of the way from one step to the next (the newer element,
    placed at the end of the step, is replaced by one at ``b(t)``)."""
    sig0, U0 = field0
    sig1, U1 = field1
    if weight <= 0.0:
        return sig0.copy(), U0.copy()
    n = sig0.size
    U = (1.0 - weight) * U0 + weight * U1[:n]
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


def _n_steps_for(rtol: float) -> int:
    return int(min(_MAX_STEPS, max(_MIN_STEPS, math.ceil(math.sqrt(_STEP_CONSTANT / rtol)))))


def _detach_outputs(problem: Problem, t: float):
    return np.array([t, problem.contact_force(t), problem.total_force(t)], dtype=float)


def simulate(scene, progress: bool = False) -> Result:
    """Run a scene: exact history by time stepping, frozen history in closed form.

    ``numerics.rtol`` is the target relative error of the detachment time and forces. The
    exact model is run at ``N`` and ``2N`` steps per reference time; the second-order stepper's
    error is estimated as a third of their difference (Richardson) and ``N`` doubles until the
    estimate is below ``rtol / 2``. The finer run is reported, with its estimate.
    """
    wall_start = time.perf_counter()
    problem = Problem.from_scene(scene)
    rtol = scene.numerics.rtol
    T = problem.time_scale
    t_limit = math.inf if scene.numerics.t_max is None else scene.numerics.t_max / T
    t_frozen = frozen_detach_time(problem, t_limit)
    snapshot_times = [ts / T for ts in scene.output.snapshots]

    if scene.model.history == "frozen":
        run, error_estimate = _frozen_run(problem, t_frozen, t_limit, scene.output.history_rows,
                                          snapshot_times)
    else:
        run, error_estimate = _exact_run(problem, t_frozen, t_limit, rtol, snapshot_times,
                                         progress)
    notes = []
    if not error_estimate <= rtol and run.t.size > 1 and not run.interrupted:
        notes.append(f"not converged: error estimate {error_estimate:.2g} above rtol {rtol:g} "
                     f"at the step cap ({_MAX_STEPS} steps)")
    t_reached = run.t_detach if not math.isnan(run.t_detach) else run.t[-1]
    for ts in scene.output.snapshots:
        if ts / T > t_reached:
            notes.append(f"snapshot at t = {ts:g} s skipped: after the end of the run")
    return _assemble(scene, problem, run, error_estimate, time.perf_counter() - wall_start,
                     notes)


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
    run = FoundationRun(math.nan, t, gap, t_frozen if detached else math.nan, 0, 0, snapshots)
    # The root is found to rounding; the estimate is that of brentq's tolerance.
    return run, 4e-16 * 8


def _exact_run(problem, t_frozen, t_limit, rtol, snapshot_times, progress):
    t_ref = min(t_frozen, t_limit)
    if t_ref == 0.0:
        return run_foundation(problem, 1.0, 0), 0.0

    def steps_to_cover(n):
        # The frozen time bounds detachment from above, but rounding can put the crossing a
        # hair beyond it; a few spare steps are cheap. A user's t_max is a hard end.
        return n if t_ref >= t_limit else n + max(2, n // 16)

    n = max(_MIN_STEPS // 2, _n_steps_for(rtol) // 2)
    levels = [run_foundation(problem, t_ref / n, steps_to_cover(n))]
    coarse = levels[0]
    # The exact model can detach well before the frozen bound; re-centre the grid on the
    # coarse crossing so that the step count measures the pull that actually happens.
    if coarse.n_steps < n // 2 and math.isfinite(coarse.t_detach) and coarse.t_detach > 0:
        t_ref = min(t_ref, 1.25 * coarse.t_detach * (1.0 + 2.0 / n))
        levels = [run_foundation(problem, t_ref / n, steps_to_cover(n))]
    if levels[-1].interrupted:
        return levels[-1], math.nan
    while True:
        n *= 2
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=steps_to_cover(n), desc=f"{n} steps", unit="step", leave=False)
        try:
            levels.append(run_foundation(problem, t_ref / n, steps_to_cover(n),
                                         snapshot_times, progress=bar.update if bar else None))
        finally:
            if bar is not None:
                bar.close()
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
    m = min(coarse.gap.size, (fine.gap.size + 1) // 2)
    if m < 2:
        return 0.0
    g_c = coarse.gap[:m]
    g_f = fine.gap[: 2 * m - 1: 2]
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
    rows = _decimate(t_hist.size, scene.output.history_rows)
    t_hist, gap_hist = t_hist[rows], gap_hist[rows]
    history = {
        "t": t_hist * T,
        "h": problem.lift(t_hist),
        "b": problem.zone_end(t_hist),
        "gap": gap_hist * problem.delta,
        "F_contact": problem.contact_force(t_hist),
        "F_total": problem.total_force(t_hist),
    }
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


def _zone_ratio(s):
    """``(b - a)/a = sqrt(1 + s^2) - 1`` without cancellation for thin zones."""
    return s * s / (1.0 + np.sqrt(1.0 + s * s))


def analytic_predictions(problem: Problem) -> dict:
    """The closed forms beside the simulation, SI (nan where a formula does not apply)."""
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
    if p.G > 0:
        el = analytic.elastic_mdr_dugdale(p.G, p.sigma_c, p.delta, p.a)
        out["elastic_F_contact"] = el["F_contact"]
        out["elastic_F_total"] = el["F_total"]
        out["elastic_b"] = el["b"]
    else:
        out["elastic_F_contact"] = out["elastic_F_total"] = out["elastic_b"] = math.nan
    return out
