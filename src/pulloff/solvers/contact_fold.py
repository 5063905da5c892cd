"""Where a smooth indenter's branch folds inside a step: the jump out of contact (the edge's
branch ends) and the jump into it (a growing zone's branch ends), MODEL.md section 9.

At a fold the state's unknown ``x`` (the edge ``alpha`` in contact, the zone end ``beta`` in the
zone alone) stops being a function of the step length ``d``; but ``d`` stays a smooth function
of ``x``: ``T(x)``, the step after which ``x`` satisfies the phase, has a quadratic maximum at
the fold. So the fold is found by maximising ``T`` (each value a regular root in ``d``), not by
bisecting ``d`` towards a double root, where every failed trial costs a full search for a root
that is not there (measured: 1000-2000 evaluations per attempt, repeated as the committed steps
crept towards the fold; here about 200).
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
NOW = "now"


def foldable(stepper, what) -> bool:
    """Whether a lost branch is one this module locates: a smooth indenter's contact or zone
    under a prescribed lift."""
    phase = stepper.now.phase
    return (not stepper.setup.flat and stepper.lift_driven
            and ((what == "contact" and phase == st.CONTACT_PHASE)
                 or (what == "zone" and phase == st.ZONE)))


def locate(stepper, dt, what):
    """``(step, evaluation)`` at the fold inside a step of ``dt`` (the state just before the
    branch ends); ``NOW`` where the branch ends at once; None where the fold is not a clean
    maximum of ``T`` (the caller then bisects)."""
    near = _near_fold(stepper, dt)
    if near is None or near == NOW:
        return near
    d_ok, x_ok, d_lost = near
    x_now = stepper.now.alpha if what == "contact" else stepper.now.beta
    half = 0.5 * abs(x_ok - x_now)
    if half == 0.0:
        return None
    tiny = 1e-9 * d_ok

    def steps_to(x):
        """T(x): the step length after which ``x`` holds (0 where no step up to the lost one
        reaches it: beyond the branch)."""
        r_lo, r_hi = _residual(stepper, what, x, tiny)[0], _residual(stepper, what, x, d_lost)[0]
        if not (math.isfinite(r_lo) and math.isfinite(r_hi)) or (r_lo > 0.0) == (r_hi > 0.0):
            return 0.0
        return brentq(lambda d: _residual(stepper, what, x, d)[0], tiny, d_lost,
                      xtol=1e-15 * d_lost, rtol=1e-15)

    lo = max(x_ok - half, 0.0)
    best = minimize_scalar(lambda x: -steps_to(x), bounds=(lo, x_ok + half), method="bounded",
                           options={"xatol": 1e-12 * max(abs(x_ok), 1.0)})
    x_fold = float(best.x)
    d_fold = steps_to(x_fold)
    if not d_ok * (1.0 - 1e-9) <= d_fold < d_lost:
        return None  # not the maximum the bisection bracketed: another branch
    _, step, ev = _residual(stepper, what, x_fold, d_fold)
    return step, ev


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
            lo, x_lo = mid, (ev.alpha if stepper.now.phase == st.CONTACT_PHASE else ev.beta)
        if x_lo is not None and hi - lo <= _BRACKET * hi:
            return lo, x_lo, hi
    return None


def _residual(stepper, what, x, d):
    """``gap(b)/delta - 1`` after a step of ``d`` with the phase's unknown at ``x``, and the
    step and evaluation."""
    step = stepper.make_step(d)
    H = stepper.now.H + (stepper.drive.rate * d if stepper.drive.kind == "speed" else 0.0)
    if what == "contact":
        ev = step.evaluate(x, phases.edge_zone(step, H, x), H)
    else:
        ev = step.evaluate(0.0, x, H)
    return ev.gap - 1.0, step, ev
