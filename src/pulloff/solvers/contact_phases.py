"""The conditions that fix the edges at the end of a step, phase by phase (MODEL.md 3, 6, 9).

Each function takes a :class:`pulloff.solvers.contact_step.Step` and the lift at its end and
returns the :class:`Evaluation` that satisfies the phase's conditions, continuing the branch the
solution is on; it raises :class:`Lost` when that branch ends inside the step (the edge reaches
the centre, the zone vanishes or jumps, the bond reaches the strength limit).
"""

from __future__ import annotations

import math

from . import contact_state as st


class Lost(Exception):
    """The phase's branch ends inside the trial step; ``what`` says how."""

    def __init__(self, what: str):
        super().__init__(what)
        self.what = what


_XTOL = 1e-14
#: A Newton correction below this share of the root ends the search without a bracket once
#: the residual is below ``_SMALL_RESIDUAL`` (measured: the gap's rounding floor is
#: 1e-13..1e-11, where the last iterates repeat without changing sign).
_STALL = 1e-13
_SMALL_RESIDUAL = 1e-9
#: How far a jump's search looks, in the larger of the last state, the predictor and the unit
#: of length: a state ten thousand times further is no state of the scene (measured: without
#: a bound, a tabulated tip's searches ran to 1e27 at 400 evaluations each).
WIDE_REACH = 1e4


def _secant(f, x_held, f_held, x_guess, lo, hi, reach):
    """Secant iterations from the last state and the predictor, bracketed once a sign change
    is seen: a few evaluations where the predictor is good; None if they wander off."""
    x0, f0 = x_held, f_held
    x1 = min(max(x_guess, lo), hi)
    if x1 == x0:
        return None
    f1 = f(x1)
    bracket = None
    slope = math.nan
    for _ in range(40):
        if math.isnan(f1):
            return None
        if abs(x1 - x0) > 1e-9 * max(abs(x1), 1e-300):  # a chord rounding does not decide
            slope = _chord(x0, f0, x1, f1)
        if f1 == 0.0 or abs(f1) <= 1e-14:
            return x1
        if (f1 > 0.0) != (f0 > 0.0):
            bracket = (min(x0, x1), max(x0, x1))
        elif bracket is not None and not bracket[0] <= x1 <= bracket[1]:
            return None
        if abs(x1 - x0) <= _XTOL * max(abs(x1), 1e-300) and bracket is not None:
            return x1
        x2 = x1 - f1 * (x1 - x0) / (f1 - f0) if f1 != f0 else math.nan
        if (abs(f1) <= _SMALL_RESIDUAL and abs(f1) <= abs(slope) * _STALL * max(abs(x1), 1e-300)):
            # The residual's rounding floor (~1e-12 of delta) hides the sign change: a
            # Newton correction this small (on a chord wide enough to trust) is convergence.
            return x1
        if bracket is not None and not bracket[0] < x2 < bracket[1]:
            x2 = 0.5 * (bracket[0] + bracket[1])
        if not (lo <= x2 <= hi) or abs(x2 - x_held) > reach:
            return None
        f2 = f(x2)
        if bracket is not None and not math.isnan(f2):
            a, b = bracket
            # keep the sign change between the newest point and the side it pairs with
            if (f2 > 0.0) != (f1 > 0.0):
                bracket = (min(x1, x2), max(x1, x2))
            else:
                keep = x0 if (f0 > 0.0) != (f2 > 0.0) else (a if x2 > 0.5 * (a + b) else b)
                bracket = (min(keep, x2), max(keep, x2))
        x0, f0, x1, f1 = x1, f1, x2, f2
    return None


def _chord(x0, f0, x1, f1):
    return (f1 - f0) / (x1 - x0) if x1 != x0 else math.nan


def _bracketed(f, a, fa, b, fb):
    """A root of ``f`` between ``a`` and ``b`` (a sign change), Illinois regula falsi with
    bisection where it stalls; None if ``f`` turns nan inside."""
    for _ in range(200):
        if abs(b - a) <= _XTOL * max(abs(a), abs(b), 1e-300):
            return b if abs(fb) <= abs(fa) else a
        x = b - fb * (b - a) / (fb - fa)
        if not min(a, b) < x < max(a, b):
            x = 0.5 * (a + b)
        fx = f(x)
        if math.isnan(fx):
            return None
        if fx == 0.0 or abs(fx) <= 1e-15:
            return x
        if (fx > 0.0) != (fb > 0.0):
            a, fa = b, fb
        else:
            fa *= 0.5  # Illinois: the kept end's value is halved so it cannot stall
        b, fb = x, fx
    return b


def root(f, x_held, f_held, x_guess, lo, hi, wide=False, secant=None):
    """The root of ``f`` nearest ``x_held`` inside ``[lo, hi]`` (the branch the solution is
    on): secant iterations from the predictor ``x_guess`` first (``secant``, if given, runs
    them on a compiled ``f``); where they give up, brackets grow from ``x_held``
    geometrically, the side of ``x_guess`` first, until ``f`` changes sign; None if it does
    not within a reach of a quarter of ``x_held`` (or of the length unit) or four predicted
    steps: a root further away is another branch."""
    if f_held == 0.0:
        return x_held
    first = 1.0 if x_guess >= x_held else -1.0
    reach = max(4.0 * abs(x_guess - x_held), 0.25 * max(abs(x_held), 1.0))
    if wide:  # a jump: the new state may be far, but not beyond every scale of the scene
        reach = WIDE_REACH * max(abs(x_held), abs(x_guess), 1.0)
    lo, hi = max(lo, x_held - reach), min(hi, x_held + reach)
    if x_guess != x_held:
        if secant is None:
            quick = _secant(f, x_held, f_held, x_guess, lo, hi, reach)
        else:
            quick = secant(x_held, f_held, x_guess, lo, hi, reach)
        if quick is not None:
            return quick
    step = max(abs(x_guess - x_held), 1e-7 * max(abs(x_held), 1.0))
    ends = {first: (x_held, f_held), -first: (x_held, f_held)}
    for _ in range(200 if wide else 80):
        for direction in (first, -first):
            a, fa = ends[direction]
            b = min(max(x_held + direction * step, lo), hi)
            if b == a:
                continue
            fb = f(b)
            if math.isnan(fb):  # beyond the branch's domain: look no further this way
                if direction > 0:
                    hi = a
                else:
                    lo = a
                continue
            if fb == 0.0:
                return b
            if (fb > 0.0) != (fa > 0.0):
                return _bracketed(f, a, fa, b, fb)
            ends[direction] = (b, fb)
        if ends[1.0][0] >= hi and ends[-1.0][0] <= lo:
            return None
        step *= 2.0
    return None


def bonded(step, H):
    """Flat punch, zone outside: the edge held at the rim, the zone end from the edge
    condition (the gap at ``b`` is an output until it reaches ``delta``: the onset)."""
    Q = step.contact_load(1.0, H, step.lift_rate(H), _Hf(step, H))
    return step.evaluate(1.0, math.hypot(1.0, max(Q, 0.0)), H)


def pinned(step, H):
    """Flat punch, zone on the face: the zone end held at the rim, the edge from the edge
    condition; the bond is gone once the bonded load needs more than the face."""
    Q = step.contact_load(step.now.alpha, H, step.lift_rate(H), _Hf(step, H))
    if Q >= 1.0:
        raise Lost("strength")
    return step.evaluate(math.sqrt(1.0 - max(Q, 0.0) ** 2), 1.0, H)


def _Hf(step, H):
    law = step.s.setup.law
    return step.filtered_lift(H) if law.maxwell else step.now.Hf


def edge_zone(step, H, alpha):
    """The zone end the edge condition puts with the edge at ``alpha``."""
    Q = max(step.contact_load(alpha, H, step.lift_rate(H), _Hf(step, H)), 0.0)
    return math.sqrt(alpha * alpha + Q * Q)  # (kernels.contact.edge_zone: the same sum)


def receding(step, H, guess_alpha):
    """Edge condition and ``gap(b) = delta`` with the edge receding from where it was."""
    now = step.now

    def residual(alpha):
        return step.evaluate(alpha, edge_zone(step, H, alpha), H).gap - 1.0

    r_held = residual(now.alpha)
    alpha = root(residual, now.alpha, r_held, min(guess_alpha, now.alpha), 0.0, now.alpha,
                 step.jump, step.compiled_secant(H))
    if alpha is None or alpha <= 0.0:
        raise Lost("contact")
    return step.evaluate(alpha, edge_zone(step, H, alpha), H)


def flat_contact(step, H, guess_alpha):
    """A flat punch after the onset: the edge sticks while the gap stays below ``delta`` (the
    edge condition fixes ``b``), else it recedes; it never advances."""
    now = step.now
    held = step.evaluate(now.alpha, edge_zone(step, H, now.alpha), H)
    if held.gap <= 1.0:
        return held
    return receding(step, H, guess_alpha)


def zone_end(step, H, alpha, guess_beta, top=math.inf, wide=False):
    """``gap(b) = delta`` with the edge at ``alpha``, on the branch of the last zone end (and
    below ``top``); ``wide``: the nearest root however far."""
    now = step.now

    def residual(beta):
        return step.evaluate(alpha, beta, H).gap - 1.0

    start = min(max(now.beta, alpha * (1.0 + 1e-12), 1e-12), top)
    beta = root(residual, start, residual(start), min(max(guess_beta, alpha), top), alpha, top,
                 step.jump or wide, step.compiled_secant(H, alpha))
    if beta is None:
        raise Lost("zone")
    return step.evaluate(alpha, beta, H)


#: How far [delta] the solid may pass through the indenter before a zone-only state counts
#: as none. The landing on ``a = 0`` leaves the centre up to ~4e-6 delta through the face
#: (prony_external.yaml at n = 32, where ``1e-9 max(H, 1)`` made the zone alone "none" at
#: once and the level separated at a = 0, skipping the zone's 0.084 time units).
_THROUGH = 1e-4


def zone_only(step, H, guess_beta):
    """No contact: the zone alone pulls the surface; it ends (separation) once the gap at
    the centre exceeds ``delta``, and the surfaces touch once it reaches zero. Behind a flat
    punch the zone only recedes: its broken bonds do not re-form during the pull (so an
    elastic punch, whose zone would have to grow, comes off at once; MODEL.md section 6)."""
    flat = step.s.setup.flat
    born = not flat and step.now.beta <= 1e-9  # a zone just born grows like sqrt(t)
    ev = zone_end(step, H, 0.0, guess_beta, step.now.beta if flat else math.inf, wide=born)
    if ev.H - ev.centre_u < -_THROUGH and (flat or step.jump or born):
        # A zone-only state with the solid passing through the indenter is none: a flat
        # punch comes off, a smooth indenter's jump (or a zone born unstable) lands in
        # contact instead.
        raise Lost("zone")
    return ev


def smooth_contact(step, H, guess_alpha):
    """A smooth indenter in contact, on a solid with an instantaneous modulus (elastic, or
    Maxwell arms; a Kelvin-Voigt solid is refused upstream): the line load is continuous at
    the edge whichever way it moves (MODEL.md 9), so the edge condition fixes the zone end and
    ``gap(b) = delta`` the edge, on the branch of the last edge. (A rule that let the edge
    stick while the contact pulled less than the zone held a near-elastic standard linear
    solid's contact 10x too long.)"""
    now = step.now

    def residual(alpha):
        return step.evaluate(alpha, edge_zone(step, H, alpha), H).gap - 1.0

    start = max(now.alpha, 1e-12)
    alpha = root(residual, start, residual(start), max(guess_alpha, 1e-12), 0.0, math.inf,
                 step.jump, step.compiled_secant(H))
    if alpha is None or alpha <= 0.0:
        raise Lost("contact")
    return step.evaluate(alpha, edge_zone(step, H, alpha), H)


def apart(step, H):
    """No zone: the centre element relaxes; the zone is born when the centre gap reaches
    ``delta``."""
    return step.evaluate(0.0, 0.0, H)


def face(step, H):
    """Flat punch, zone on the face past its strength: the zone alone holds the whole face
    (the bond is gone, ``a = 0``, ``b`` at the rim) until the rim's gap reaches ``delta``."""
    return step.evaluate(0.0, step.now.beta, H)


PHASES = {st.BONDED, st.PINNED, st.CONTACT_PHASE, st.ZONE, st.FACE, st.APART}
