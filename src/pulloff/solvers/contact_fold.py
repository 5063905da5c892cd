"""Where a branch folds inside a step: a smooth indenter's jump out of contact (the edge's
branch ends), the jump into it (a growing zone's branch ends), a force-controlled pull-off
(the force the branch can carry is passed), MODEL.md section 9, and a flat punch's balance
lost behind a spring.

At a fold the state's unknown ``x`` (the edge ``alpha`` in contact, the zone end ``beta`` in the
zone alone) stops being a function of the step length ``d``; but ``d`` stays a smooth function
of ``x``: ``T(x)``, the step after which ``x`` satisfies the phase (and the force balance, where
the lift is not prescribed), has a quadratic maximum at the fold. So the fold is found by
maximising ``T`` (each value a regular root in ``d``), not by bisecting ``d`` towards a double
root, where every failed trial costs a full search for a root that is not there (measured:
1000-2000 evaluations per attempt under a prescribed lift, 20000 under force control, repeated
as the committed steps crept towards the fold).
"""

from __future__ import annotations

import math

from scipy.optimize import brentq, minimize_scalar

from . import contact_phases as phases
from . import contact_state as st

#: The bisection that comes first stops once the step that works is this close to the one
#: that does not: the fold's ``x`` is then within the window searched below.
_BRACKET = 0.02
#: A branch whose longest working step is below this share of the trial step ends at once.
_AT_ONCE = 1e-9
#: The predictor's window reaches this many predicted moves of ``x`` past the last state.
_AHEAD = 4.0
NOW = "now"
#: Secant iterations before a warm-started search for ``T(x)`` gives way to a bracket.
_SECANT_TRIES = 8
#: The rounding of a residual (a gap relative to ``delta`` less 1, or a force balance).
_RESIDUAL_ROUNDING = 8e-15
#: What :func:`_maximise` returns where ``T`` exceeds the lost step over part of its window.
_BEYOND = "beyond"


def foldable(stepper, what) -> bool:
    """Whether a lost branch is one this module locates: a smooth indenter's contact or zone
    alone; a flat punch's zone alone (it recedes and comes off at a fold) and its receding
    edge where the balance behind a machine spring or under force control is lost (the force
    the branch carries has a maximum). A flat branch's end was bisected before, each failed
    probe a full search for a root that is not there: the standard linear solid took 4567
    evaluations at n = 32 under a rigid pull (2106 located) and 30415 behind 100 N/m (6014).
    Not a flat edge's own end (``a`` reaching 0): there locating doubled the evaluations. Nor
    a Kelvin-Voigt bond's balance (its dashpots forbid a fold): compliant_machine.yaml at
    n = 512 then stopped at a spurious maximum at a = 0.067 R and reported an arrest, where
    the bisection creeps on to the bond's vanishing end."""
    phase = stepper.now.phase
    if stepper.setup.flat:
        if stepper.setup.law.c > 0.0 and phase == st.CONTACT_PHASE:
            return False
        return (what == "balance" and phase in (st.CONTACT_PHASE, st.ZONE)
                or what == "zone" and phase == st.ZONE)
    return what in ("contact", "zone", "balance") and phase in (st.CONTACT_PHASE, st.ZONE)


def locate(stepper, dt, what):
    """``(step, evaluation)`` at the fold inside a step of ``dt`` (the state just before the
    branch ends); ``NOW`` where the branch ends at once; None where the fold is not a clean
    maximum of ``T`` (the caller then bisects)."""
    x_now = _unknown(stepper, stepper.now)
    window = _predicted_window(stepper, dt, x_now)
    if window is not None:
        found = _maximise(stepper, window, 1e-9 * dt, dt, 0.0)
        if found is _BEYOND:
            # The lost step missed states that exist: the fold lies a little beyond it.
            found = _maximise(stepper, window, 1e-9 * dt, 2.0 * dt, 0.0)
        if found is not None and found is not _BEYOND:
            return found
    near = _near_fold(stepper, dt)
    if near is None or near == NOW:
        return near
    d_ok, x_ok, d_lost = near
    half = 0.5 * abs(x_ok - x_now)
    if half == 0.0:
        return None
    window = (max(x_ok - half, 0.0), x_ok + half)
    found = _maximise(stepper, window, 1e-9 * d_ok, d_lost, d_ok)
    if found is _BEYOND:
        # As above: the bisection's lost step missed states that exist. Given up here, the
        # branch's end was bisected to 1e-14 and located again from there: the standard
        # linear solid at 1.9e-2 m/s spent 1400 of its 1800 evaluations at n = 16 so, and its
        # separation time moved by 8e-9 (the levels n = 16..256 spread over 1.5e-8 either
        # way).
        found = _maximise(stepper, window, 1e-9 * d_ok, 2.0 * d_lost, d_ok)
    return None if found is _BEYOND else found


def _unknown(stepper, state) -> float:
    return state.alpha if stepper.now.phase == st.CONTACT_PHASE else state.beta


def _predicted_window(stepper, dt, x_now):
    """From the last state to ``_AHEAD`` predicted moves of ``x`` over ``dt`` beyond it (the
    last step's rate), or None without a last step."""
    now, before = stepper.now, stepper.before
    if before is None or now.t <= before.t:
        return None
    move = (x_now - _unknown(stepper, before)) * dt / (now.t - before.t)
    if move == 0.0 or not math.isfinite(move):
        return None
    ends = (x_now, x_now + _AHEAD * move)
    return max(min(ends), 0.0), max(ends)


def _maximise(stepper, window, tiny, d_lost, d_ok):
    """The fold as the maximum of ``T`` over ``window``: ``(step, evaluation)``, or None where
    the maximum lies on the window's edge or below ``d_ok`` (not the fold looked for)."""
    lo, hi = window
    found = []  # (x, T(x)) of every root so far: where the next search starts

    def residual(d, x):
        return _residual(stepper, x, d)[0]

    def steps_to(x):
        """T(x): the step after which ``x`` holds (0 where no step up to ``d_lost`` reaches
        it: beyond the branch)."""
        d = _secant_from(found, x, residual, tiny, d_lost)
        if d is None:
            r_lo = residual(tiny, x)
            r_hi = residual(d_lost, x)
            if (not (math.isfinite(r_lo) and math.isfinite(r_hi))
                    or (r_lo > 0.0) == (r_hi > 0.0)):
                return 0.0
            d = brentq(residual, tiny, d_lost, args=(x,), xtol=1e-15 * d_lost, rtol=1e-15)
        found.append((x, d))
        return d

    best = minimize_scalar(lambda x: -steps_to(x), bounds=(lo, hi), method="bounded",
                           options={"xatol": 1e-12 * max(abs(hi), 1.0)})
    x_fold = float(best.x)
    margin = 1e-3 * (hi - lo)
    if not lo + margin < x_fold < hi - margin:
        return None
    d_fold = steps_to(x_fold)
    if not (d_fold > 0.0 and d_ok * (1.0 - 1e-9) <= d_fold < d_lost):
        return None
    # A maximum beside a stretch where no step up to ``d_lost`` reaches ``x`` is that
    # stretch's edge, not a fold: there T exceeds ``d_lost`` (the lost step missed a state
    # that exists). Taken as the fold, the zone alone of sls_finite_punch.yaml came off
    # 2.7e-4 early at n = 32 (T was 0 over 40 % of the window).
    if steps_to(x_fold - margin) == 0.0 or steps_to(x_fold + margin) == 0.0:
        return _BEYOND
    _, step, ev = _residual(stepper, x_fold, d_fold)
    if ev is None or stepper.crossed(ev) is not None:
        return None  # an event comes first: the caller lands on it
    return step, ev


def _secant_from(found, x, residual, tiny, d_lost):
    """``T(x)`` by the secant method from the roots found at the nearest ``x`` (``T`` is
    smooth in ``x``, so they start it within a hair of the root), or None where there are
    none, an iterate leaves ``(tiny, d_lost)`` or it does not settle within
    :data:`_SECANT_TRIES` (the caller then brackets). A bracketed search from the whole
    ``(tiny, d_lost)`` took 10 evaluations per ``x``, 250 per fold: a fifth of the standard
    linear solid's rate sweep."""
    if not found:
        return None
    x0, d0 = min(found, key=lambda p: abs(p[0] - x))
    d1 = d0 * (1.0 + 1e-7) if d0 > 0.0 else 0.0
    if not tiny < d1 < d_lost:
        return None
    f0, f1 = residual(d0, x), residual(d1, x)
    for _ in range(_SECANT_TRIES):
        if f1 == 0.0:
            return d1
        if not (math.isfinite(f0) and math.isfinite(f1)) or f1 == f0:
            return None
        slope = (f1 - f0) / (d1 - d0)
        d2 = d1 - f1 / slope
        if not tiny < d2 < d_lost:
            return None
        # Converged to brentq's tolerance, or to the band where the residual's rounding
        # (~1e-15, gap - 1 with a gap near 1) decides its sign: no bracket resolves it finer.
        if abs(d2 - d1) <= 1e-15 * d_lost + 1e-14 * abs(d2) + _RESIDUAL_ROUNDING / abs(slope):
            return d2
        d0, f0, d1, f1 = d1, f1, d2, residual(d2, x)
    return None


def _near_fold(stepper, dt):
    """Bisect the step's length until the longest that works and the shortest that does not
    are within ``_BRACKET``: ``(d_ok, x_ok, d_lost)``; ``NOW`` if none longer than a
    billionth of the step works (a zone born unstable); None if an event comes first."""
    try:
        stepper.solve(stepper.make_step(_AT_ONCE * dt))
    except phases.Lost:
        return NOW
    lo, hi, x_lo = 0.0, dt, None
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        try:
            ev = stepper.solve(stepper.make_step(mid))
        except phases.Lost:
            hi = mid
        else:
            if stepper.crossed(ev) is not None:
                return None
            lo, x_lo = mid, _unknown(stepper, ev)
        if x_lo is not None and hi - lo <= _BRACKET * hi:
            return lo, x_lo, hi
    return None


def _residual(stepper, x, d):
    """After a step of ``d`` with the phase's unknown at ``x``: the remaining condition
    (``gap(b)/delta - 1`` under a prescribed lift, the force balance otherwise, with the lift
    from ``gap(b) = delta``), the step and the evaluation (nan, None where no lift fits)."""
    step = stepper.make_step(d)
    if stepper.lift_driven:
        H = stepper.now.H + (stepper.drive.rate * d if stepper.drive.kind == "speed" else 0.0)
        ev = _evaluate(stepper, step, x, H)
        return ev.gap - 1.0, step, ev
    now = stepper.now

    def gap_left(H):
        return _evaluate(stepper, step, x, H).gap - 1.0

    rate = now.Hdot if math.isfinite(now.Hdot) else 0.0
    H = phases.root(gap_left, now.H, gap_left(now.H), now.H + rate * d, -math.inf, math.inf)
    if H is None:
        return math.nan, step, None
    ev = _evaluate(stepper, step, x, H)
    return stepper.force_residual(d)(ev), step, ev


def _evaluate(stepper, step, x, H):
    if stepper.now.phase == st.CONTACT_PHASE:
        return step.evaluate(x, phases.edge_zone(step, H, x), H)
    return step.evaluate(0.0, x, H)
