"""Machine spring and force control: the lift at the end of a step is one more unknown, with
the force balance as one more condition; damped Newton on both (a finite-difference Jacobian:
the unknowns are few, each evaluation advances every element)."""

from __future__ import annotations

import math

import numpy as np

from . import contact_phases as phases
from . import contact_state as st


def solve(stepper, step, H_guess, force_residual, H_travel=0.0):
    """The evaluation whose lift balances ``force_residual`` and whose phase conditions hold.

    Where the phase fixes its edges explicitly (bonded, pinned, apart) this is Newton on the
    lift alone. Elsewhere the phase's own root finding runs inside a bracketed search on the
    lift; a flat punch's edge is first tried held (the edge sticks while the gap stays below
    delta), and that lift starts the search if it does not. ``H_travel`` is the lift's
    expected travel over the step (it sizes the search's first trial)."""
    now = step.now
    explicit = {st.BONDED: phases.bonded, st.PINNED: phases.pinned, st.FACE: phases.face,
                st.APART: phases.apart}
    scale = _force_scale(stepper, now)
    # Finite differences on the lift's own scale over the step: a viscous solid's force is
    # nonlinear in the lift on the scale of the rate it implies (a unit-sized difference put
    # the slope 6x off in a 3 ns first step, and Newton stalled).
    H_scale = np.array([max(H_travel, 1e-6 * abs(now.H), 1e-12)])
    if now.phase in explicit:
        build = explicit[now.phase]
        out = _newton(lambda z: _with_force(build(step, z[0]), force_residual),
                      np.array([H_guess]), H_scale, scale)
        if out is None:
            # The phase's own end (a bond past the face's strength) comes first where it is
            # met on the way: the branch ends by it, not by the spring.
            try:
                build(step, H_guess)
            except phases.Lost as lost:
                raise lost from None
            raise phases.Lost("balance")
        return out[0]
    if now.phase == st.CONTACT_PHASE and not stepper.setup.flat:
        both = _smooth_contact(stepper, step, H_guess, H_scale, force_residual, scale)
        if both is not None:
            return both
    if now.phase == st.CONTACT_PHASE and stepper.setup.flat:
        held = _newton(lambda z: _with_force(_stick(step, z[0]), force_residual),
                       np.array([H_guess]), H_scale, scale)
        if held is not None:
            if held[0].gap <= 1.0:
                return held[0]
            H_guess = held[0].H
    return _nested(stepper, step, H_guess, force_residual, H_travel)


def _smooth_contact(stepper, step, H_guess, H_scale, force_residual, scale):
    """A smooth indenter in contact: Newton on the edge and the lift together (the edge
    condition fixes the zone end; ``gap(b) = delta`` and the force balance are the two
    conditions), from the predictor; None where it does not converge, and the nested search
    takes over."""
    now = step.now
    alpha_guess = stepper.guesses(step)[0]
    if alpha_guess <= 0.0:
        return None

    def residual(z):
        alpha, H = z
        if alpha <= 0.0:
            raise phases.Lost("contact")
        ev = step.evaluate(alpha, phases.edge_zone(step, H, alpha), H)
        return ev, np.array([ev.gap - 1.0, force_residual(ev)])

    alpha_scale = max(abs(alpha_guess - now.alpha), 1e-6 * now.alpha, 1e-12)
    out = _newton(residual, np.array([alpha_guess, H_guess]),
                  np.array([alpha_scale, H_scale[0]]), np.array([1.0, scale[0]]))
    if out is None or abs(out[0].alpha - now.alpha) > 0.25 * max(now.alpha, 1.0):
        return None  # no state, or one on another branch
    return out[0]


def _with_force(ev, force_residual):
    return ev, np.array([force_residual(ev)])


def _stick(step, H):
    return step.evaluate(step.now.alpha, phases.edge_zone(step, H, step.now.alpha), H)


def _force_scale(stepper, now):
    machine = stepper.setup.machine or 0.0
    return np.array([max(1.0, abs(now.F_total), machine * abs(now.H))])


def _nested(stepper, step, H_guess, force_residual, H_travel):
    """The phase's root finding inside, the lift outside (bracketed, nearest ``H_guess``);
    a lift at which the phase has no state counts as beyond the search's domain."""
    cache = {}

    def residual(H):
        try:
            cache[H] = ev = stepper._phase(step, H)
        except phases.Lost:
            return math.nan
        return force_residual(ev)

    r0 = residual(H_guess)
    if math.isnan(r0):
        H_guess = step.now.H
        r0 = residual(H_guess)
    if math.isnan(r0):
        raise phases.Lost("balance")
    # The first trial is a small part of the lift's travel over the step: a short step of a
    # viscous solid balances only in a narrow window of lifts.
    probe = max(1e-3 * H_travel, 1e-12 * max(abs(H_guess), 1.0))
    # A jump behind a soft spring moves the indenter too (by F/k): its lift is searched as
    # widely as the jump's edge.
    H = phases.root(residual, H_guess, r0, H_guess + min(probe, 1e-9 * max(abs(H_guess), 1.0)),
                     -math.inf, math.inf, step.jump)
    if H is None:
        raise phases.Lost("balance")
    return cache.get(H) or stepper._phase(step, H)


def _newton(residual, z0, scale, rscale, tol=1e-12, max_iter=30):
    """Damped Newton on ``residual(z) -> (evaluation, vector)``: ``scale`` sizes the unknowns
    (its sign the side of the finite differences), ``rscale`` the residuals; None when it
    fails."""
    z = z0.astype(float)
    try:
        ev, r = residual(z)
    except phases.Lost:
        return None
    for _ in range(max_iter):
        if np.all(np.abs(r) <= tol * rscale):
            return ev, r
        n = z.size
        J = np.empty((n, n))
        for j in range(n):
            h = 1e-7 * scale[j]
            dz = z.copy()
            dz[j] += h
            try:
                J[:, j] = (residual(dz)[1] - r) / h
            except phases.Lost:
                return None
        try:
            dx = np.linalg.solve(J, -r)
        except np.linalg.LinAlgError:
            return None
        norm = np.linalg.norm(r / rscale)
        lam = 1.0
        while lam > 1.0 / 1024:
            try:
                ev_t, r_t = residual(z + lam * dx)
                if np.linalg.norm(r_t / rscale) < (1.0 - 1e-4 * lam) * norm:
                    break
            except phases.Lost:
                pass
            lam *= 0.5
        else:
            return (ev, r) if np.all(np.abs(r) <= 1e-9 * rscale) else None
        z, ev, r = z + lam * dx, ev_t, r_t
    return (ev, r) if np.all(np.abs(r) <= 1e-9 * rscale) else None
