"""The conditions that fix the edges at the end of a step, phase by phase (MODEL.md 3, 6, 9).

Each function takes a :class:`pulloff.solvers.contact_step.Step` and the lift at its end and
returns the :class:`Evaluation` that satisfies the phase's conditions, continuing the branch the
solution is on; it raises :class:`Lost` when that branch ends inside the step (the edge reaches
the centre, the zone vanishes or jumps, the bond reaches the strength limit).
"""

from __future__ import annotations

import math

from scipy.optimize import brentq

from . import contact_state as st


class Lost(Exception):
    """The phase's branch ends inside the trial step; ``what`` says how."""

    def __init__(self, what: str):
        super().__init__(what)
        self.what = what


_XTOL = 1e-14


def _root(f, x_held, f_held, x_guess, lo, hi):
    """The root of ``f`` nearest ``x_held`` inside ``[lo, hi]`` (the branch the solution is
    on): brackets grow from ``x_held`` geometrically, the side of ``x_guess`` first, until
    ``f`` changes sign; None if it does not within a reach of a quarter of ``x_held`` (or of
    the length unit) or four predicted steps: a root further away is another branch."""
    if f_held == 0.0:
        return x_held
    first = 1.0 if x_guess >= x_held else -1.0
    reach = max(4.0 * abs(x_guess - x_held), 0.25 * max(abs(x_held), 1.0))
    lo, hi = max(lo, x_held - reach), min(hi, x_held + reach)
    step = max(abs(x_guess - x_held), 1e-7 * max(abs(x_held), 1.0))
    ends = {first: (x_held, f_held), -first: (x_held, f_held)}
    for _ in range(80):
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
                return brentq(f, min(a, b), max(a, b), xtol=_XTOL * max(abs(b), 1e-300),
                              rtol=1e-15, maxiter=200)
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


def _edge_zone(step, H, alpha):
    """The zone end the edge condition puts with the edge at ``alpha``."""
    Q = step.contact_load(alpha, H, step.lift_rate(H), _Hf(step, H))
    return math.hypot(alpha, max(Q, 0.0))


def receding(step, H, guess_alpha):
    """Edge condition and ``gap(b) = delta`` with the edge receding from where it was."""
    now = step.now

    def residual(alpha):
        return step.evaluate(alpha, _edge_zone(step, H, alpha), H).gap - 1.0

    r_held = residual(now.alpha)
    alpha = _root(residual, now.alpha, r_held, min(guess_alpha, now.alpha), 0.0, now.alpha)
    if alpha is None or alpha <= 0.0:
        raise Lost("contact")
    return step.evaluate(alpha, _edge_zone(step, H, alpha), H)


def flat_contact(step, H, guess_alpha):
    """A flat punch after the onset: the edge sticks while the gap stays below ``delta`` (the
    edge condition fixes ``b``), else it recedes; it never advances."""
    now = step.now
    held = step.evaluate(now.alpha, _edge_zone(step, H, now.alpha), H)
    if held.gap <= 1.0:
        return held
    return receding(step, H, guess_alpha)


def zone_end(step, H, alpha, guess_beta, top=math.inf):
    """``gap(b) = delta`` with the edge at ``alpha``, on the branch of the last zone end (and
    below ``top``)."""
    now = step.now

    def residual(beta):
        return step.evaluate(alpha, beta, H).gap - 1.0

    start = min(max(now.beta, alpha * (1.0 + 1e-12), 1e-12), top)
    beta = _root(residual, start, residual(start), min(max(guess_beta, alpha), top), alpha, top)
    if beta is None:
        raise Lost("zone")
    return step.evaluate(alpha, beta, H)


def zone_only(step, H, guess_beta):
    """No contact: the zone alone pulls the surface; it ends (separation) once the gap at
    the centre exceeds ``delta``, and the surfaces touch once it reaches zero. Behind a flat
    punch the zone only recedes: its broken bonds do not re-form during the pull (so an
    elastic punch, whose zone would have to grow, comes off at once; MODEL.md section 6)."""
    flat = step.s.setup.flat
    ev = zone_end(step, H, 0.0, guess_beta, step.now.beta if flat else math.inf)
    if flat and ev.H - ev.centre_u < -1e-12 * max(abs(ev.H), 1.0):
        # The zone could hold the punch only with the solid passing through its face:
        # there is no zone-only state, the punch comes off.
        raise Lost("zone")
    return ev


def smooth_contact(step, H, guess_alpha, guess_beta):
    """A smooth indenter in contact: ``gap(b) = delta`` always; the edge recedes where the
    contact element would pull harder than the zone (a tensile singularity), advances where a
    free element would pass through the indenter, and sticks otherwise."""
    now = step.now
    ind = step.s.setup.indenter
    held = zone_end(step, H, now.alpha, guess_beta)
    ell = math.sqrt(max((held.beta - now.alpha) * (held.beta + now.alpha), 0.0))
    if held.edge_load > ell:
        return receding(step, H, guess_alpha)
    if held.edge_free_u > H + ind.g(now.alpha):
        return advancing(step, H, guess_alpha, guess_beta)
    return held


def advancing(step, H, guess_alpha, guess_beta):
    """The edge advances to where a free element meets the indenter (the zone end from the
    gap at each trial edge)."""
    now = step.now
    ind = step.s.setup.indenter
    cache = {}

    def residual(alpha):
        ev = zone_end(step, H, alpha, cache.get("beta", guess_beta))
        cache["beta"] = ev.beta
        return ev.edge_free_u - H - ind.g(alpha)

    r_held = residual(now.alpha)
    hi = max(guess_alpha, now.alpha) * 4.0 + 1.0
    alpha = _root(residual, now.alpha, r_held, max(guess_alpha, now.alpha * (1 + 1e-9) + 1e-12),
                  now.alpha, hi)
    if alpha is None:
        raise Lost("advance")
    return zone_end(step, H, alpha, cache.get("beta", guess_beta))


def apart(step, H):
    """No zone: the centre element relaxes; the zone is born when the centre gap reaches
    ``delta``."""
    return step.evaluate(0.0, 0.0, H)


PHASES = {st.BONDED, st.PINNED, st.CONTACT_PHASE, st.ZONE, st.APART}
