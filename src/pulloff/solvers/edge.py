"""Pull-off past the onset: the contact edge recedes until full separation (MODEL.md section 6).

Same scales as :mod:`pulloff.solver` (lengths in the punch radius ``R``, displacements, lift
and gap in ``delta``, time in ``delta / v``; ``k``, ``c`` as there), but the foundation lives on
fixed positions in ``x`` because the contact edge ``a`` moves. Each step:

1. the bonded line load gives ``ell = sqrt(b^2 - a^2)`` (edge condition; ``k h + c`` for a
   Kelvin-Voigt solid lifted at constant speed, from the shared state of the bonded elements
   for a Maxwell solid);
2. the contact edge is tried where it was (external zone) or where the edge condition puts it
   with ``b = R`` (internal zone, the zone on the punch face);
3. if the gap at ``b`` then exceeds ``delta``, the edge recedes: ``a`` solves ``gap(b(a)) =
   delta`` (a root in ``[0, a_old]``: ``a`` never grows). Elements released at the edge keep
   ``u = h`` and continue as free elements. Once ``a = 0`` the zone alone holds the punch:
   ``b`` solves ``gap(b) = delta``, until the gap at the centre reaches ``delta`` (separation).

Free elements advance by the exact step of their rheology for a load linear over the step
(Kelvin-Voigt: an exponential; a standard linear solid or Prony series: the matrix exponential
of its arms). The gap integral integrates the field, linear in ``sqrt(b^2 - x^2)`` between
nodes, exactly against ``1/sqrt(b^2 - x^2)``. A new element is placed at ``a`` and at ``b``
whenever they move, so both edges are resolved between the old nodes, not snapped to them.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from ..kernels import edge as kernels
from ..kernels.onset import linear_load_weights
from ..model import analytic
from . import levels as ladder
from .base import Solver, flat_punch_pull, problem as problem_line
from .frozen import frozen_detach_time
from .problem import Problem
from .result import Result

PHASE_BONDED, PHASE_RECEDING, PHASE_ZONE_ONLY, PHASE_SEPARATED = 0, 1, 2, 3


@dataclass
class PropagationRun:
    """One pass at a fixed step (dimensionless; see the module docstring)."""

    dt: float
    t: np.ndarray
    h: np.ndarray
    a: np.ndarray  # contact radius / R
    b: np.ndarray  # zone end / R
    gap: np.ndarray  # gap at b / delta
    F_contact: np.ndarray  # / (sigma_c R^2)
    F_total: np.ndarray  # / (sigma_c R^2)
    t_onset: float  # first gap(b) = 1 (nan if none)
    t_separation: float  # b reached 0 (nan if not)
    n_elements: int
    n_steps: int
    interrupted: bool = False
    notes: list = field(default_factory=list)
    ell_onset: float = math.nan  # sqrt(b^2 - a^2) / R at the onset (bonded line load)


def edge_zone_end(xi_a: float, ell: float) -> float:
    """``xi_b = b - 1`` with ``b^2 = a^2 + ell^2`` and ``a = 1 + xi_a``, without cancellation."""
    a = 1.0 + xi_a
    b = math.sqrt(a * a + ell * ell)
    return (xi_a * (2.0 + xi_a) + ell * ell) / (1.0 + b)


def edge_contact_for_face(ell: float) -> float:
    """``xi_a`` of the contact edge when the zone reaches the punch rim (``b = 1``):
    ``a = sqrt(1 - ell^2)``; ``-1`` (``a = 0``) once ``ell >= 1``."""
    if ell >= 1.0:
        return -1.0
    return -ell * ell / (1.0 + math.sqrt(1.0 - ell * ell))


def forces(a: float, b: float, ell: float):
    """``(F_contact, F_total) / (sigma_c R^2)``: ``2 a L`` and the whole line load."""
    if b <= 0.0:
        return 0.0, 0.0
    if a <= 0.0:
        return 0.0, math.pi * b * b
    F_contact = 4.0 * a * ell
    return F_contact, 2.0 * a * ell + 2.0 * b * b * math.atan2(ell, a)


class _KelvinVoigt:
    """``k U + c dU/dt = q`` per element; bonded elements carry ``ell = k h + c dh/dt``.

    The punch speed (in units of ``v``) is 1 under a rigid machine. Behind a spring it follows
    from the force balance; at the end of a step it is the variable-step BDF2 difference of
    the lifts (backward Euler on the first step). BDF2 is second order and damps: the
    trapezoidal rule, tried first, let a start from rest ring as 0, 2, 0, 2, ... for ever.
    """

    def __init__(self, problem, capacity):
        self.k, self.c = problem.k, problem.c

    def start(self, h0, rigid):
        self.rigid = rigid
        self.h_prev = None  # the lift one step before the current one
        self.dt_prev = math.nan
        # Behind a relaxed spring the punch starts at rest.
        self.ell = self.k * h0 + (self.c if rigid else 0.0)
        return self.ell

    def initial_displacement(self, q):
        # A damper cannot move at once (MODEL.md: u(x, 0) = 0); a spring alone follows q.
        return q / self.k if self.c == 0.0 else np.zeros_like(q)

    def prepare(self, dt):
        self.dt = dt
        self.decay, self.w_old, self.w_new = linear_load_weights(self.k, self.c, dt)

    def _speed(self, h_old, h_new):
        if self.rigid:
            return 1.0
        if self.h_prev is None:
            return (h_new - h_old) / self.dt
        w = self.dt / self.dt_prev
        return ((1.0 + 2.0 * w) / (1.0 + w) * h_new - (1.0 + w) * h_old
                + w * w / (1.0 + w) * self.h_prev) / self.dt

    def bonded_trial(self, h_old, h_new):
        """Bonded line load at the end of the step for a trial lift (no state changes)."""
        if self.c == 0.0:
            return self.k * h_new
        return self.k * h_new + self.c * self._speed(h_old, h_new)

    def advance_bonded(self, h_old, h_new):
        self.ell = self.bonded_trial(h_old, h_new)
        self.h_prev, self.dt_prev = h_old, self.dt

    def base(self, U, E, q_old, lo, hi, out):
        kernels.kv_base(U, q_old, lo, hi, self.decay, self.w_old, out)

    def commit(self, E, q_new, lo, hi):
        pass  # U is the whole state

    def released_at_start(self, h_old):
        """``(base, E)`` of an element released at the start of the step (u = h then);
        a Kelvin-Voigt element has no state besides U."""
        return self.decay * h_old + self.w_old * self.ell, np.zeros(0)

    def released_now(self):
        return np.zeros(0)  # the state of an element released at the end of the step

    def with_load(self, E_pred, q):
        return E_pred


class _Maxwell:
    """Generalised Maxwell solid ``G(t) = G_inf + sum G_i exp(-t/tau_i)`` (a standard linear
    solid has one arm): element state = the arms' dashpot displacements ``E_i``.

    Bonded elements all follow the punch, so they share one state; free ones obey
    ``q = k_inf U + sum k_i (U - E_i)``, ``tau_i dE_i/dt = U - E_i``, a linear system in ``E``
    driven by ``q``. Its step for ``q`` linear over the step is exact (matrix exponential of
    the system augmented by the load and its slope), with no stability limit however short
    the relaxation times.
    """

    def __init__(self, problem, capacity):
        from scipy.linalg import expm

        self.expm = expm
        self.k_inf = problem.k
        self.k_arms = problem.arm_stiffness
        self.taus = problem.arm_times
        self.k_total = self.k_inf + float(np.sum(self.k_arms))
        m = self.k_arms.size
        self.E_pred = np.zeros((capacity, m))
        self.A = (np.outer(1.0 / self.taus, self.k_arms) / self.k_total
                  - np.diag(1.0 / self.taus))
        self.B = 1.0 / (self.k_total * self.taus)

    def start(self, h0, rigid):
        self.E_bond = np.zeros(self.k_arms.size)  # the dashpots have not moved at t = 0
        self.ell = self.k_inf * h0 + float(np.dot(self.k_arms, h0 - self.E_bond))
        return self.ell

    def initial_displacement(self, q):
        return q / self.k_total  # the instantaneous (glassy) response

    def prepare(self, dt):
        m = self.k_arms.size
        M = np.zeros((m + 2, m + 2))
        M[:m, :m] = self.A * dt
        M[:m, m] = self.B * dt
        M[m, m + 1] = 1.0  # q(t + s dt) = q_old + s (q_new - q_old), s in [0, 1]
        X = self.expm(M)
        self.phi = np.ascontiguousarray(X[:m, :m])
        self.gamma_new = X[:m, m + 1].copy()
        self.gamma_old = X[:m, m] - self.gamma_new
        self.w_new = (1.0 + float(np.dot(self.k_arms, self.gamma_new))) / self.k_total
        # Bonded dashpots under a lift linear over the step: E + tau dE/dt = h.
        self.bond_weights = np.array([linear_load_weights(1.0, tau, dt)
                                      for tau in self.taus])

    def _bond_after(self, h_old, h_new):
        w = self.bond_weights
        return w[:, 0] * self.E_bond + w[:, 1] * h_old + w[:, 2] * h_new

    def bonded_trial(self, h_old, h_new):
        E = self._bond_after(h_old, h_new)
        return self.k_inf * h_new + float(np.dot(self.k_arms, h_new - E))

    def advance_bonded(self, h_old, h_new):
        self.ell = self.bonded_trial(h_old, h_new)
        self.E_bond = self._bond_after(h_old, h_new)

    def base(self, U, E, q_old, lo, hi, out):
        kernels.maxwell_base(E, q_old, lo, hi, self.phi, self.gamma_old, self.k_arms,
                             self.k_total, self.E_pred, out)

    def commit(self, E, q_new, lo, hi):
        E[lo:hi] = self.E_pred[lo:hi] + np.outer(q_new[lo:hi], self.gamma_new)

    def released_at_start(self, h_old):
        E_pred = self.phi @ self.E_bond + self.gamma_old * self.ell
        return float(np.dot(self.k_arms, E_pred)) / self.k_total, E_pred

    def released_now(self):
        return self.E_bond.copy()

    def with_load(self, E_pred, q):
        return E_pred + self.gamma_new * q


@dataclass
class _Attempt:
    """The edges, forces and events of one step for a trial lift (nothing committed)."""

    h: float
    ell: float
    phase: int
    new_a: float
    new_b: float
    released: bool
    gap: float
    F_contact: float
    F_total: float
    onset_frac: float = math.nan  # where in the step the onset falls (nan: not in this step)
    ell_onset: float = math.nan
    sep_time: float = math.nan
    centre_base: float = math.nan
    centre_E: object = None
    centre_gap: float = math.nan
    stop: bool = False  # the onset, and the run ends there (until = detach)
    valid: bool = True  # False: no zone end satisfies gap(b) = delta at this lift


def run_propagation(problem, n: int, t_scale: float, t_limit: float = math.inf,
                    internal: bool = False, until: str = "separation",
                    max_steps: int = 200_000, progress=None,
                    machine: float | None = None) -> PropagationRun:
    """Step the foundation until separation (or the onset, ``until = 'detach'``), ``t_limit``
    or ``max_steps``. ``problem`` is a :class:`pulloff.solver.Problem` whose ``a`` is the
    punch radius ``R``. ``machine`` is the dimensionless stiffness ``k_m delta / (sigma_c
    R^2)`` of a spring between the driver (at ``h0 + t``) and the punch; ``None``: rigid.

    The step follows the physics: each step advances ``1/n`` of a measure that adds the time
    in units of ``t_scale`` (the onset time, say) to the distances the contact edge and the
    zone end travel (in ``R`` and in the initial zone end) and to the change of the spring's
    stretch (in ``t_scale`` lifts), predicted from the last step's rates. Doubling ``n``
    halves every step of the same solution, so the levels of :func:`simulate_levels` can be
    compared as with a fixed step.
    """
    h0 = problem.h0_scaled
    n_stop = max_steps
    dt = t_scale / n
    n_pre = max(8, n // 4)
    capacity = n_pre + 2 * (n_stop + 2)
    law = (_Maxwell if problem.arms else _KelvinVoigt)(problem, capacity)
    ell = law.start(h0, machine is None)
    if internal:
        xi_a = edge_contact_for_face(ell)
        xi_b = 0.0
    else:
        xi_a = 0.0
        xi_b = edge_zone_end(xi_a, ell)
    # Elements in the zone at t = 0, graded toward b where the load varies fastest.
    theta = np.linspace(0.0, 0.5 * math.pi, n_pre)
    xi_pre = xi_a + (xi_b - xi_a) * np.sin(theta)
    xi_pre[-1] = xi_b
    lo = n_stop + 2
    hi = lo + n_pre
    xi = np.zeros(capacity)
    U = np.zeros(capacity)
    E = np.zeros((capacity, len(problem.arms)))
    q_old = np.zeros(capacity)
    base = np.zeros(capacity)
    scratch = np.zeros(capacity)
    xi[lo:hi] = xi_pre
    kernels.zone_loads(xi, lo, hi, xi_b, q_old)
    U[lo:hi] = law.initial_displacement(q_old[lo:hi])
    h = h0
    phase = PHASE_ZONE_ONLY if xi_a <= -1.0 else PHASE_BONDED

    def gap_for(xi_a_t, xi_b_t, ell_t, h_t, released, u_edge=None):
        # A node released at the edge holds u = h at its release, the end of the step.
        u_a = h_t if u_edge is None else u_edge
        return kernels.trial_gap(base, lo, hi, xi, xi_a_t, released, u_a, xi_b_t, h_t,
                                 ell_t, law.w_new, scratch)

    a0 = 1.0 + xi_a
    F_c, F_t = forces(a0, 1.0 + xi_b, ell)
    g0 = kernels.trial_gap(U, lo, hi, xi, xi_a, False, h, xi_b, h, ell, 0.0, scratch)
    rows = {"t": [0.0], "h": [h], "a": [a0], "b": [1.0 + xi_b], "gap": [g0],
            "F_contact": [F_c], "F_total": [F_t]}
    t_onset = math.nan
    ell_onset = math.nan
    t_sep = math.nan
    notes = []
    centre_gap_prev = math.nan
    interrupted = False
    step = 0
    if phase == PHASE_ZONE_ONLY:
        # The bonded load needs more than the face at once (internal zone): the bond is gone
        # at t = 0, the punch hangs on the zone at the strength limit.
        t_onset = 0.0
        ell_onset = ell
        if until == "detach":
            return _finish(rows, dt, t_onset, t_sep, hi - lo, 0, False, notes, ell_onset)
    elif g0 >= 1.0:
        t_onset = 0.0
        ell_onset = ell
        if until == "detach":
            return _finish(rows, dt, t_onset, t_sep, hi - lo, 0, False, notes, ell_onset)
        phase = PHASE_RECEDING
    t_now = 0.0

    def attempt(h_new, t_new):
        """Edges after this step for a trial lift ``h_new``; changes no state."""
        ell_start = law.ell
        ell_new = law.bonded_trial(h, h_new)
        ph = phase
        xa = xi_a
        released = False
        onset_frac = ell_on = math.nan
        g = math.nan
        new_a, new_b = xa, xi_b
        if internal and ell_new >= 1.0 and ph in (PHASE_BONDED, PHASE_RECEDING):
            # The bonded line load needs a zone wider than the face: the bond is gone.
            if ph == PHASE_BONDED:
                # The strength limit: the bonded load reaches the rim inside this step.
                onset_frac = (1.0 - ell_start) / (ell_new - ell_start)
                ell_on = 1.0
                if until == "detach":
                    return _Attempt(h_new, ell_new, ph, xa, xi_b, False, g, 0.0, 0.0,
                                    onset_frac, ell_on, stop=True)
            ph = PHASE_ZONE_ONLY
            released = xa > -1.0
            xa = -1.0
        if ph in (PHASE_BONDED, PHASE_RECEDING):
            xa_try = min(xa, edge_contact_for_face(ell_new)) if internal else xa
            xb_try = edge_zone_end(xa_try, ell_new)
            released_try = xa_try < xa
            g = gap_for(xa_try, xb_try, ell_new, h_new, released_try)
            if g <= 1.0 and xa_try > -1.0:
                new_a, new_b, released = xa_try, xb_try, released_try
            else:
                if ph == PHASE_BONDED:
                    # Onset inside this step: the gap crosses 1 between the last two rows.
                    g_prev = rows["gap"][-1]
                    onset_frac = (1.0 - g_prev) / (g - g_prev) if g != g_prev else 1.0
                    ell_on = ell_start + onset_frac * (ell_new - ell_start)
                    if (machine is not None and getattr(law, "c", 0.0) > 0.0
                            and h_new - h > 100.0 * (t_new - t_now)):
                        # The punch is thrown in this step (a damper's load follows its
                        # speed): the onset is the state it leaves, not an interpolation.
                        ell_on = ell_start
                    if until == "detach":
                        return _Attempt(h_new, ell_new, ph, xa, xi_b, False, g, 0.0, 0.0,
                                        onset_frac, ell_on, stop=True)
                    ph = PHASE_RECEDING

                def f_a(x_a):
                    return gap_for(x_a, edge_zone_end(x_a, ell_new), ell_new, h_new,
                                   True) - 1.0

                released = True
                if f_a(-1.0) > 0.0:
                    ph = PHASE_ZONE_ONLY
                    xa = -1.0
                else:
                    new_a = brentq(f_a, -1.0, xa_try, xtol=1e-15, rtol=1e-15)
                    new_b = edge_zone_end(new_a, ell_new)
        centre_base, centre_E, centre = math.nan, None, math.nan
        sep_time = math.nan
        valid = True
        if ph == PHASE_ZONE_ONLY:
            new_a = -1.0
            # The contact vanished inside this step: the node at the centre is taken as
            # released at the step's start (u = h then) and loaded since; for an elastic
            # solid that is its load over k, as it must be.
            centre_released = released
            centre_base, centre_E = (law.released_at_start(h) if centre_released
                                     else (base[lo], None))
            centre = h_new - centre_base - 1.0  # gap at the centre as the zone vanishes

            def f_b(x_b):
                if x_b <= -1.0:
                    return centre
                u_c = centre_base + law.w_new * kernels.zone_load(-1.0, x_b)
                # atan2(ell, a) with a = 0 is pi/2 for any ell > 0.
                return gap_for(-1.0, x_b, 1.0, h_new, centre_released, u_c) - 1.0

            if centre >= 0.0:
                # Separation inside this step: the centre gap crossed 1.
                onset_here = not math.isnan(onset_frac)
                if math.isnan(centre_gap_prev) and (onset_here or t_onset >= t_now):
                    # Onset, loss of contact and separation in one step: an unstable
                    # crack, which comes off at the onset.
                    sep_time = t_now + onset_frac * (t_new - t_now) if onset_here else t_onset
                else:
                    frac = 1.0
                    if not math.isnan(centre_gap_prev) and centre != centre_gap_prev:
                        frac = -centre_gap_prev / (centre - centre_gap_prev)
                    sep_time = t_now + min(1.0, max(0.0, frac)) * (t_new - t_now)
                ph = PHASE_SEPARATED
                new_b = -1.0
            else:
                if internal and f_b(0.0) <= 0.0:
                    new_b = 0.0  # the zone covers the whole face (the strength limit)
                else:
                    hi_b = 0.0 if internal else max(xi_b, -1.0 + 1e-12)
                    bracketed = f_b(hi_b) >= 0.0
                    for _ in range(60):
                        if bracketed:
                            break
                        hi_b = -1.0 + 1.5 * (1.0 + hi_b)
                        bracketed = f_b(hi_b) >= 0.0
                    # No end found: a trial lift far below the punch's (the machine's search
                    # tries such); the zone as wide as searched, its force only too large.
                    new_b = (brentq(f_b, -1.0, hi_b, xtol=1e-15, rtol=1e-15) if bracketed
                             else hi_b)
                    valid = bracketed
            ell_new = 0.0
        a_now = 1.0 + new_a
        b_now = 1.0 + new_b if ph != PHASE_SEPARATED else 0.0
        F_c, F_t = forces(a_now, b_now, ell_new)
        return _Attempt(h_new, ell_new, ph, new_a, new_b, released, g, F_c, F_t, onset_frac,
                        ell_on, sep_time, centre_base, centre_E, centre, valid=valid)

    def balanced(t_new):
        """The attempt whose lift balances the spring: ``kappa (d - h) = F_total``. The root
        nearest the last lift is taken (the branch the punch is on); when that branch ends,
        the next root is a jump, which the history shows."""
        d_new = h0 + t_new

        def residual(h_try):
            trial = attempt(h_try, t_new)
            if not trial.valid:
                return -1e300  # no equilibrium of the zone: as if the force were unbounded
            return machine * (d_new - h_try) - trial.F_total

        r_here = residual(h)
        width = max(d_new - h, 1e-12 * max(1.0, abs(h)))
        lo_h, r_lo = h, r_here
        if r_here < 0.0:
            # The punch moves down (the force grew faster than the spring): search below.
            step_h = 0.05 * width
            for _ in range(200):
                hi_h, r_hi = lo_h, r_lo
                lo_h = lo_h - step_h
                r_lo = residual(lo_h)
                if r_lo >= 0.0:
                    break
                step_h *= 2.0
            if r_lo < 0.0:
                # No lift below balances it either: no equilibrium behind this machine.
                stuck = attempt(h, t_new)
                stuck.valid = False
                return stuck
            h_root = brentq(residual, lo_h, hi_h, xtol=1e-14 * max(1.0, abs(h)), rtol=1e-15)
            return attempt(h_root, t_new)
        # Scan upward from the last lift so the first sign change is found, not a far one.
        step_h = 0.05 * width
        hi_h = h
        for _ in range(200):
            prev_h = hi_h
            hi_h = min(d_new, hi_h + step_h)
            r_hi = residual(hi_h)
            if r_hi <= 0.0 or hi_h >= d_new:
                break
            step_h *= 2.0
        if r_hi > 0.0:
            return attempt(d_new, t_new)  # no force at all: the punch follows the driver
        h_root = brentq(residual, prev_h, hi_h, xtol=1e-14 * max(1.0, abs(h)), rtol=1e-15)
        return attempt(h_root, t_new)

    rate = 0.0  # |da/dt| + |db/dt| / b_ref + |d(stretch)/dt| / t_scale of the last step
    b_ref = max(1.0, 1.0 + xi_b)
    try:
        while step < n_stop and phase != PHASE_SEPARATED and t_now < t_limit:
            # At most doubling per step: the rates come from the step before.
            dt_next = 1.0 / (n * (1.0 / t_scale + rate))
            dt = min(dt_next, 2.0 * dt, t_limit - t_now) if step else min(dt_next, t_limit)
            t_new = t_now + dt
            law.prepare(dt)
            law.base(U, E, q_old, lo, hi, base)
            att = attempt(h0 + t_new, t_new) if machine is None else balanced(t_new)
            if (machine is not None and abs((t_new - att.h) - (t_now - h)) > 2.0 * t_scale / n
                    and dt > 1e-9 * t_scale / n):
                # The punch jumped further than the step measure allows (the rates came from
                # the step before): redo the step shorter, so that the jump is resolved.
                dt_redo = 0.25 * dt
                rate = max(rate, 1.0 / (n * dt_redo))
                dt = 2.0 * dt_redo  # the controller halves it back to dt_redo
                continue
            if not att.valid:
                notes.append(f"stopped at t = {t_now:.6g} delta/v: no lift balances the "
                             "machine with a zone end where gap(b) = delta (once the contact "
                             "is gone the punch would fall back onto the surface, which the "
                             "model does not cover)")
                break
            if not math.isnan(att.onset_frac):
                t_onset = t_now + att.onset_frac * dt
                ell_onset = att.ell_onset
            if att.stop:
                break
            if att.phase == PHASE_SEPARATED:
                t_sep = att.sep_time
            if att.phase == PHASE_ZONE_ONLY:
                centre_gap_prev = att.centre_gap
            new_a, new_b = att.new_a, att.new_b
            # Commit the step with the chosen lift, edge and zone end.
            kernels.zone_loads(xi, lo, hi, new_b, q_old)
            kernels.trial_displacements(base, lo, hi, xi, max(new_b, -1.0), law.w_new, U)
            law.commit(E, q_old, lo, hi)
            released_at_edge = False
            if att.released and new_a < xi[lo]:
                lo -= 1
                xi[lo] = new_a
                q_old[lo] = kernels.zone_load(new_a, new_b)
                if att.phase >= PHASE_ZONE_ONLY:
                    U[lo] = att.centre_base + law.w_new * q_old[lo]
                    E[lo] = law.with_load(att.centre_E, q_old[lo])
                else:
                    U[lo] = att.h  # bonded until now: it follows the punch
                    released_at_edge = True
            if new_b > xi[hi - 1]:
                xi[hi] = new_b
                U[hi] = 0.0  # enters now, unloaded: its dashpots have not moved either
                q_old[hi] = 0.0
                E[hi] = 0.0
                hi += 1
            stretch_change = abs((t_new - att.h) - (t_now - h))
            law.advance_bonded(h, att.h)
            if released_at_edge:
                E[lo] = law.released_now()  # the bonded state, advanced to the release
            rate = (abs(new_a - xi_a) + abs(max(new_b, -1.0) - xi_b) / b_ref
                    + stretch_change / t_scale) / dt
            xi_a, xi_b, phase, h = new_a, new_b, att.phase, att.h
            t_now = t_new
            step += 1
            rows["t"].append(t_new)
            rows["h"].append(att.h)
            rows["a"].append(1.0 + xi_a)
            rows["b"].append(1.0 + xi_b if phase != PHASE_SEPARATED else 0.0)
            rows["gap"].append(min(att.gap, 1.0) if phase == PHASE_BONDED else 1.0)
            rows["F_contact"].append(att.F_contact)
            rows["F_total"].append(att.F_total)
            if progress is not None:
                progress(1)
    except KeyboardInterrupt:
        interrupted = True
    return _finish(rows, dt, t_onset, t_sep, hi - lo, step, interrupted, notes, ell_onset)


def _finish(rows, dt, t_onset, t_sep, n_elements, n_steps, interrupted, notes, ell_onset):
    arrays = {name: np.asarray(values, dtype=float) for name, values in rows.items()}
    return PropagationRun(dt, arrays["t"], arrays["h"], arrays["a"], arrays["b"], arrays["gap"],
                          arrays["F_contact"], arrays["F_total"], t_onset, t_sep, n_elements,
                          n_steps, interrupted, notes, ell_onset)


# --------------------------------------------------------------------------------------------
# Accuracy control.

#: Cap on the steps of one level: a level costs ~steps^2 element updates per root evaluation.
MAX_LEVEL_STEPS = 20_000
#: Default end, in frozen onset times, when the scene gives no t_max.
DEFAULT_SPAN = 100.0


def peak(t: np.ndarray, F: np.ndarray):
    """``(t_peak, F_peak)`` of a sampled history: the largest sample, refined by the parabola
    through it and its neighbours (an interior maximum is then second order in the step)."""
    i = int(np.argmax(F))
    # Only a smooth maximum is refined: not one the force falls from at once (an unstable
    # crack), where a parabola would overshoot.
    if 0 < i < F.size - 1 and min(F[i - 1], F[i + 1]) > 0.9 * F[i]:
        t0, t1, t2 = t[i - 1], t[i], t[i + 1]
        f0, f1, f2 = F[i - 1], F[i], F[i + 1]
        d1 = (f1 - f0) / (t1 - t0)
        d2 = (f2 - f1) / (t2 - t1)
        curv = (d2 - d1) / (t2 - t0)
        if curv < 0.0:
            # f(t) = f1 + d1 (t - t1) + curv (t - t1)(t - t0); vertex where f' = 0.
            t_v = 0.5 * (t1 + t0) - d1 / (2.0 * curv)
            if t0 <= t_v <= t2:
                return t_v, f1 + d1 * (t_v - t1) + curv * (t_v - t1) * (t_v - t0)
    return float(t[i]), float(F[i])


def onset_state(run: PropagationRun, internal: bool):
    """``(a, b, F_contact, F_total)`` at the onset time (the edge condition with the bonded
    load at the onset and the contact radius of the step it falls in); nans without one."""
    if not math.isfinite(run.t_onset):
        return (math.nan,) * 4
    ell = run.ell_onset
    if internal:
        a = 1.0 + edge_contact_for_face(ell)
        b = 1.0
    else:
        i = max(0, int(np.searchsorted(run.t, run.t_onset, side="right")) - 1)
        a = float(run.a[i])
        b = math.sqrt(a * a + ell * ell)
    return (a, b, *forces(a, b, ell))


def peaks(run: PropagationRun, internal: bool):
    """``((t, F_contact), (t, F_total))`` of the largest forces, the onset included (an
    unstable crack's largest force is at the onset, between two samples)."""
    _, _, Fc_on, Ft_on = onset_state(run, internal)
    out = []
    for F, F_on in ((run.F_contact, Fc_on), (run.F_total, Ft_on)):
        t_p, F_p = peak(run.t, F)
        if math.isfinite(F_on) and F_on >= F_p:
            t_p, F_p = run.t_onset, F_on
        out.append((t_p, F_p))
    return out


def outputs(run: PropagationRun, internal: bool) -> np.ndarray:
    """The numbers a level is judged by: onset and separation times, onset and peak forces."""
    _, _, Fc_on, Ft_on = onset_state(run, internal)
    (_, Fc), (_, Ft) = peaks(run, internal)
    return np.array([run.t_onset, run.t_separation, Fc_on, Ft_on, Fc, Ft], dtype=float)


#: The load's sqrt at the moving zone ends limits the step to order 1.5: a higher measured
#: order is a pre-asymptotic accident and must not shrink the estimate.
ORDER = ladder.Order(1.0, 1.5)


def simulate_levels(problem, rtol: float, t_scale: float, t_limit: float, internal: bool,
                    until: str, progress, machine: float | None = None):
    """Runs at ``n = 50, 100, 200, ...`` (:func:`pulloff.solvers.levels.refine`) until the
    Richardson estimate of the finest level's relative error is below ``rtol / 2`` or a level
    would exceed ``MAX_LEVEL_STEPS``. Returns ``(finest run, estimate, observed order)``."""

    def level(n):
        with progress(f"n = {n}", None) as update:
            return run_propagation(problem, n, t_scale, t_limit, internal, until,
                                   max_steps=MAX_LEVEL_STEPS, progress=update, machine=machine)

    result = ladder.refine(
        level, lambda run: outputs(run, internal), rtol, 50, ORDER,
        # The next level takes about twice the steps of this one.
        can_refine=lambda run, n: 2 * run.n_steps <= MAX_LEVEL_STEPS
        and run.n_steps < MAX_LEVEL_STEPS, interrupted=lambda run: run.interrupted)
    return result.finest, result.estimate, result.order


class EdgeSolver(Solver):
    """The moving contact edge: separation, the finite punch, Maxwell solids, a compliant
    machine (MODEL.md section 6)."""

    name = "edge"
    summary = "moving-edge stepper (receding contact edge, any rheology, machine spring)"

    def unsupported(self, scene) -> list[str]:
        out = flat_punch_pull(scene, "moving-edge", zones=("external", "internal"), machine=True)
        if scene.model.history != "exact":
            out.append(problem_line(
                "model.history", scene.model.history, "the seed's frozen load history (eq. 31) "
                "is a Kelvin-Voigt onset closed form; the moving-edge solver steps the exact "
                "history" + (f" of a {scene.material.kind}" if scene.material.kind not in
                             ("kelvin_voigt", "elastic") else "")))
        if scene.numerics.steps is not None:
            out.append(problem_line(
                "numerics.steps", scene.numerics.steps, "fixed-step runs cover the seed's onset "
                "only; a moving contact edge is refined from numerics.rtol"))
        if scene.output.snapshots:
            out.append(problem_line(
                "output.snapshots", list(scene.output.snapshots), "the moving-edge solver "
                "stores no displacement profiles"))
        return out

    def solve(self, scene, observers) -> Result:
        return _solve(scene, observers)


def _solve(scene, observers) -> Result:
    """A run with a receding contact edge, in SI."""
    wall_start = time.perf_counter()
    problem = Problem.from_scene(scene)
    T = problem.time_scale
    t_limit = math.inf if scene.numerics.t_max is None else scene.numerics.t_max / T
    t_frozen = frozen_detach_time(problem, t_limit)
    rtol = scene.numerics.rtol
    internal = scene.geometry.cohesive_zone == "internal"
    until = scene.model.until
    t_scale = t_frozen if math.isfinite(t_frozen) and t_frozen > 0 else 1.0
    if not math.isfinite(t_limit):
        t_limit = DEFAULT_SPAN * t_scale
    machine = None
    if scene.loading.machine_stiffness is not None:
        # k_m delta / (sigma_c R^2): spring force per unit stretch, in the solver's units.
        machine = (scene.loading.machine_stiffness * problem.delta
                   / (problem.sigma_c * problem.a ** 2))
    run, estimate, order = simulate_levels(problem, rtol, t_scale, t_limit, internal, until,
                                           observers.progress, machine)
    notes = list(run.notes)
    if not estimate <= rtol and not run.interrupted:
        notes.append(f"not converged: error estimate {estimate:.2g} above rtol {rtol:g} at "
                     f"the step cap ({MAX_LEVEL_STEPS} steps per level)")
    if (until == "separation" and math.isnan(run.t_separation) and not run.interrupted
            and not run.notes):
        notes.append(f"no separation before t_max = {run.t[-1] * T:.6g} s")
    summary = _summary(scene, problem, run, internal)
    summary.update(error_estimate=float(estimate), observed_order=float(order),
                   wall_time=time.perf_counter() - wall_start)
    return Result.build(summary, analytic.predictions(scene),
                        _history(problem, run, observers), notes=notes,
                        complete=not run.interrupted, problem=problem)


def _history(problem, run, observers) -> dict:
    rows = observers.kept_rows(run.t.size, np.arange(run.t.size))
    R, force = problem.a, problem.sigma_c * problem.a ** 2
    return {"t": run.t[rows] * problem.time_scale,
            "h": problem.delta * run.h[rows],  # behind a spring the lift lags the driver
            "a": R * run.a[rows], "b": R * run.b[rows], "gap": problem.delta * run.gap[rows],
            "F_contact": force * run.F_contact[rows], "F_total": force * run.F_total[rows]}


def _summary(scene, problem, run, internal) -> dict:
    T, R, force = problem.time_scale, problem.a, problem.sigma_c * problem.a ** 2
    a_on, b_on, F_c_on, F_t_on = onset_state(run, internal)
    (t_pc, F_pc), (t_pt, F_pt) = peaks(run, internal)
    detached = math.isfinite(run.t_onset)
    out = {"detached": detached, "solver": "edge", "history": scene.model.history,
           "until": scene.model.until, "cohesive_zone": scene.geometry.cohesive_zone,
           "n_elements": int(run.n_elements), "n_steps": int(run.n_steps),
           "t_end": float(run.t[-1] * T), "t_separation": float(run.t_separation * T),
           "F_peak_contact": float(F_pc * force), "F_peak_total": float(F_pt * force),
           "t_peak_contact": float(t_pc * T), "t_peak_total": float(t_pt * T),
           **problem.groups}
    if detached:
        out.update(t_detach=run.t_onset * T,
                   h_detach=problem.delta * float(np.interp(run.t_onset, run.t, run.h)),
                   b_detach=R * b_on,
                   zone_ratio_detach=(b_on - a_on) / a_on if a_on > 0 else math.nan,
                   F_contact_detach=force * F_c_on, F_total_detach=force * F_t_on)
    return out
