"""Machine spring and force control: the lift at the end of a step is one more unknown, with
the force balance as one more condition. Broyden iterations from the Jacobian the step
before ended with, else damped Newton with a finite-difference Jacobian (the unknowns are
few, each evaluation advances every element)."""

from __future__ import annotations

import math

import numpy as np

from . import contact_phases as phases
from . import contact_state as st


#: A step this short (of the clock's scale) is an instant: its lift may move by rounding
#: and by its rate over it, not by a finite amount.
_INSTANT = 1e-9
#: The lift's move (relative to its size, at least 1) that an instant cannot make.
_FINITE_MOVE = 1e-4


#: The phases whose edges follow explicitly from the lift: it is their only unknown.
_EXPLICIT = {st.BONDED: phases.bonded, st.PINNED: phases.pinned, st.FACE: phases.face,
             st.APART: phases.apart}


def solve(stepper, step, H_guess, force_residual, H_travel=0.0):
    """:func:`_solve`, where a state a finite lift away from the last in an instant is no
    state of the branch: ``Lost("balance")``. Behind a soft spring past a fold (a tip's knot
    landed on within 1e-11 of the time, behind 1 N/m) the balance was met on the unstable
    side of the branch, three such instants walked the lift from 7.8 to 12.1 (scaled) at
    one time, and the punch was reported off 0.1 % later and 1.5 % below its peak force;
    the branch's end there is a jump out."""
    ev = _solve(stepper, step, H_guess, force_residual, H_travel)
    now = step.now
    if (not step.jump and step.dt <= _INSTANT * max(stepper.t_scale, abs(now.t))
            and abs(ev.H - now.H) > _FINITE_MOVE * max(1.0, abs(now.H))):
        raise phases.Lost("balance")
    return ev


def _solve(stepper, step, H_guess, force_residual, H_travel=0.0):
    """The evaluation whose lift balances ``force_residual`` and whose phase conditions hold.

    Where the phase fixes its edges explicitly (bonded, pinned, apart) the lift is the only
    unknown. In contact the edge and the lift are solved together (a flat punch's edge is
    first tried held: it sticks while the gap stays below delta, and that lift starts the
    receding edge's solve if it does not). Where these fail, the phase's own root finding
    runs inside a bracketed search on the lift. ``H_travel`` is the lift's expected travel
    over the step (it sizes the search's first trial)."""
    now = step.now
    scale = _force_scale(stepper, now)
    # Finite differences on the lift's own scale over the step: a viscous solid's force is
    # nonlinear in the lift on the scale of the rate it implies (a unit-sized difference put
    # the slope 6x off in a 3 ns first step, and Newton stalled).
    H_scale = np.array([max(H_travel, 1e-6 * abs(now.H), 1e-12)])
    if now.phase in _EXPLICIT:
        build = _EXPLICIT[now.phase]
        out = _lift_alone(stepper, now.phase, lambda H: build(step, H), H_guess, H_scale,
                          force_residual, scale)
        if out is None:
            # The phase's own end (a bond past the face's strength) comes first where it is
            # met on the way: the branch ends by it, not by the spring.
            try:
                build(step, H_guess)
            except phases.Lost as lost:
                raise lost from None
            raise phases.Lost("balance")
        return out
    if now.phase == st.CONTACT_PHASE and stepper.setup.flat:
        held = _lift_alone(stepper, "held", lambda H: _stick(step, H), H_guess, H_scale,
                           force_residual, scale)
        if held is not None:
            if held.gap <= 1.0:
                return held
            H_guess = held.H
    if now.phase == st.CONTACT_PHASE:
        # (a flat punch's edge only recedes: the held edge did not hold)
        top = now.alpha if stepper.setup.flat else math.inf
        both = _edge_and_lift(stepper, step, H_guess, H_scale, force_residual, scale, top)
        if both is not None:
            return both
    return _nested(stepper, step, H_guess, force_residual, H_travel)


def _lift_alone(stepper, key, build, H_guess, H_scale, force_residual, scale):
    """The evaluation of ``build(H)`` whose lift balances ``force_residual``, or None: secant
    iterations from the slope the last solve of kind ``key`` ended with, else Newton."""
    def lifted(z):
        return _with_force(build(z[0]), force_residual)

    return _remembered_newton(stepper, key, lifted, np.array([H_guess]), H_scale, scale)


def _remembered_newton(stepper, key, residual, z0, scale, rscale):
    """The evaluation at which ``residual`` vanishes, or None: :func:`_remembered_jacobian`
    from the Jacobian the last solve of kind ``key`` ended with, else :func:`_newton`."""
    jacobians = stepper.balance_jacobians
    out = _remembered_jacobian(residual, z0, jacobians.get(key), scale, rscale)
    if out is not None:
        (ev, _), jacobians[key] = out
        return ev
    tried = []
    out = _newton(residual, z0, scale, rscale, tried)
    if out is None:
        return None
    if tried:
        jacobians[key] = tried[-1]
    return out[0]


def _edge_and_lift(stepper, step, H_guess, H_scale, force_residual, scale, top):
    """In contact: Newton on the edge and the lift together (the edge condition fixes the
    zone end; ``gap(b) = delta`` and the force balance are the two conditions), from the
    predictor, the edge below ``top``; None where it does not converge, and the nested
    search takes over. (A flat punch's receding edge was found by the nested search alone:
    some 30 trial evaluations a step behind a spring, against about 7.)"""
    now = step.now
    alpha_guess = min(stepper.guesses(step)[0], top)
    if alpha_guess <= 0.0:
        return None

    def residual(z):
        alpha, H = z
        if alpha <= 0.0 or alpha > top:
            raise phases.Lost("contact")
        ev = step.evaluate(alpha, phases.edge_zone(step, H, alpha), H)
        return ev, np.array([ev.gap - 1.0, force_residual(ev)])

    alpha_scale = max(abs(alpha_guess - now.alpha), 1e-6 * now.alpha, 1e-12)
    if top < math.inf:
        alpha_scale = -alpha_scale  # (finite differences below the edge's bound)
    ev = _remembered_newton(stepper, "edge", residual, np.array([alpha_guess, H_guess]),
                            np.array([alpha_scale, H_scale[0]]), np.array([1.0, scale[0]]))
    if ev is None or abs(ev.alpha - now.alpha) > 0.25 * max(now.alpha, 1.0):
        return None  # no state, or one on another branch
    return ev


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


#: The most a remembered Jacobian may change (scaled, relative) for its iterations to stand:
#: beyond it the balance may be near a fold (the Jacobian turning singular), where they can
#: step onto another branch; Newton, whose failure there marks the lost balance, decides.
_JACOBIAN_CHANGE = 0.1


#: A Broyden step this many times the unknown's size (or its scale, if larger) is none:
#: a nearly singular remembered Jacobian would send the evaluation to lifts of 1e300, where
#: a trial step does not return (found by a review; not met in any run).
_FAR = 10.0


def _reach(z, scale):
    """The farthest a trial may move each unknown from ``z``: :data:`_FAR` times its size (at
    least 1) or its ``scale``, whichever is larger."""
    return _FAR * np.maximum(np.abs(scale), np.maximum(np.abs(z), 1.0))


def _remembered_jacobian(residual, z0, J, scale, rscale, tol=1e-12, max_iter=8):
    """Broyden iterations (secant iterations for one unknown) from the Jacobian the last
    solve of the same kind ended with: ``((evaluation, residual), Jacobian)``, or None
    where there is none yet or the residual stops falling (Newton takes over). A step's
    balance is nearly linear in its unknowns and its Jacobian changes little from step to
    step: this takes two to four evaluations where Newton with finite differences took
    five to seven. ``scale``, ``rscale``: as for :func:`_newton`."""
    if J is None or not np.all(np.isfinite(J)):
        return None
    unit = np.abs(scale)[None, :] / rscale[:, None]  # (J scaled to unit unknowns, residuals)
    try:
        z = z0.astype(float)
        ev, r = residual(z)
        for _ in range(max_iter):
            if np.all(np.abs(r) <= tol * rscale):
                return (ev, r), J
            dz = np.linalg.solve(J, -r)
            if np.all(z + dz == z) or np.any(np.abs(dz) > _reach(z, scale)):
                return None  # (no move, or one beyond any state of the branch)
            ev1, r1 = residual(z + dz)
            if not np.linalg.norm(r1 / rscale) < np.linalg.norm(r / rscale):
                return None
            J1 = J + np.outer(r1 - r - J @ dz, dz) / (dz @ dz)
            if not (np.linalg.norm((J1 - J) * unit)
                    <= _JACOBIAN_CHANGE * np.linalg.norm(J * unit)):
                return None
            z, ev, r, J = z + dz, ev1, r1, J1
    except (phases.Lost, np.linalg.LinAlgError):
        return None
    return None


def _newton(residual, z0, scale, rscale, jacobians=None, tol=1e-12, max_iter=30):
    """Damped Newton on ``residual(z) -> (evaluation, vector)``: ``scale`` sizes the unknowns
    (its sign the side of the finite differences), ``rscale`` the residuals; None when it
    fails. Each Jacobian is appended to ``jacobians`` where one is given."""
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
        if jacobians is not None:
            jacobians.append(J)
        try:
            dx = np.linalg.solve(J, -r)
        except np.linalg.LinAlgError:
            return None
        norm = np.linalg.norm(r / rscale)
        # (no trial beyond any state of the branch: see _reach)
        lam = min(1.0, float(np.min(_reach(z, scale) / np.maximum(np.abs(dx), 1e-300))))
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
