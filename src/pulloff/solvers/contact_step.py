"""One step of the contact stepper: the paths over the step, the element states at its end for
trial edges and lift, and what they give (gap, edge loads, forces).

A step goes from the instant ``now`` to ``now.t + dt``. Over it the zone end, the contact edge
and the lift follow quadratics in the step fraction ``s`` through the step's two ends and the
point before (linear after an event, where they may kink). :meth:`Step.evaluate` advances
every free element exactly for its rheology under that load (:mod:`pulloff.kernels.contact`)
and returns an :class:`Evaluation`; the phase logic in :mod:`pulloff.solvers.contact` chooses
the trial values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..kernels import contact as K
from .contact_state import CONTACT, FREE

_TINY = 1e-13


def quadratic_path(prev, now, new, r):
    """``(p0, p1, p2)`` of the quadratic through ``(-r, prev)``, ``(0, now)``, ``(1, new)``;
    linear through the last two when ``r`` is None."""
    if r is None or r <= 0.0 or prev is None or not math.isfinite(prev):
        return now, new - now, 0.0
    p2 = (prev - now + r * (new - now)) / (r * (r + 1.0))
    return now, new - now - p2, p2


def filter_poly(mu, h0, h1, h2):
    """``int_0^1 mu e^{-mu (1-s)} (h0 + h1 s + h2 s^2) ds``: what a dashpot of relaxation
    ``1/mu`` steps gains from a lift polynomial in the step."""
    m0, m1, m2 = K.exp_moments(mu)
    return mu * (h0 * m0 + h1 * m1 + h2 * m2)


@dataclass
class Evaluation:
    """The end of a trial step (dimensionless)."""

    alpha: float
    beta: float
    H: float
    Hdot: float
    gap: float  # at the zone end (or at the centre when there is no zone)
    edge_load: float  # the contact element's line load at alpha
    edge_free_u: float  # a free element's displacement at alpha (as if it stayed free)
    F_contact: float
    F_total: float
    centre_u: float  # displacement of the element at the centre, nan if none
    lo: int  # the elements advanced: lo..hi-1
    hi: int
    Y: np.ndarray  # their modes at the end of the step
    U: np.ndarray  # their displacements at the end of the step
    Hf: np.ndarray  # the arms' filtered lift at the end of the step


class Step:
    """A trial step of length ``dt`` from ``now``; ``before`` is the instant one step earlier
    on the same smooth stretch (None after an event)."""

    def __init__(self, stepper, now, dt, before):
        self.s = stepper
        self.now = now
        self.dt = dt
        law = stepper.setup.law
        self.mus = -law.lam * dt
        self.decay = np.exp(-self.mus)
        self.zdt = law.z * dt
        self.w3 = np.zeros((max(law.n_modes, 1), 3))
        for k, mu in enumerate(self.mus):
            K.fitted_radau3(mu, self.w3[k])
        self.r = (now.t - before.t) / dt if before is not None else None
        self.before = before
        self.arm_mus = dt / law.tau_arms if law.maxwell else np.zeros(0)

    # --- paths over the step -------------------------------------------------------------
    def path(self, name, new):
        prev = getattr(self.before, name) if self.before is not None else None
        return quadratic_path(prev, getattr(self.now, name), new, self.r)

    def lift_path(self, H_new):
        """The lift over the step: exact (linear) under a driven lift, else the quadratic."""
        drive = self.s.drive
        if self.s.lift_driven:
            return self.now.H, drive.rate * self.dt if drive.kind == "speed" else 0.0, 0.0
        return self.path("H", H_new)

    def lift_rate(self, H_new):
        """``dH/dt`` at the end of the step (the Kelvin-Voigt contact load needs it)."""
        h0, h1, h2 = self.lift_path(H_new)
        return (h1 + 2.0 * h2) / self.dt

    def filtered_lift(self, H_new, s=1.0):
        """The arms' filtered lift ``Hf`` (``tau dHf/dt = H - Hf``) at fraction ``s``."""
        h0, h1, h2 = self.lift_path(H_new)
        mus = self.arm_mus * s
        out = np.exp(-mus) * self.now.Hf
        for i, mu in enumerate(mus):
            out[i] += filter_poly(mu, h0, h1 * s, h2 * s * s)
        return out

    # --- the contact side ----------------------------------------------------------------
    def contact_load(self, xi, H_new, Hdot, Hf):
        """Line load of a contact element at ``xi`` at the end of the step."""
        law = self.s.setup.law
        G = self.s.setup.indenter.g(xi)
        if law.maxwell:
            memory = self.s.contact_memory(xi, self.now.t + self.dt)
            return (law.kappa_inf * (H_new + G) + float(np.dot(law.kappa_arms, H_new - Hf))
                    - memory)
        return law.kappa_inf * (H_new + G) + law.c * Hdot

    def released_modes(self, x, s_c, H_new):
        """Modes of a contact element at ``x`` released at fraction ``s_c``: its dashpots from
        the contact formula, in the eigenbasis (Kelvin-Voigt: its displacement)."""
        law = self.s.setup.law
        G = self.s.setup.indenter.g(x)
        h0, h1, h2 = self.lift_path(H_new)
        if not law.maxwell:
            return np.array([h0 + s_c * (h1 + s_c * h2) + G])
        t = self.now.t + s_c * self.dt
        E = self.filtered_lift(H_new, s_c) + G + self.s.contact_memory_arms(x, t)
        return law.V_inv @ E

    # --- the free side -------------------------------------------------------------------
    def evaluate(self, alpha, beta, H_new) -> Evaluation:
        """The end of the step for trial edges and lift."""
        s = self.s
        nodes = s.nodes
        law = s.setup.law
        now = self.now
        Hdot = self.lift_rate(H_new)
        Hf = self.filtered_lift(H_new) if law.maxwell else now.Hf
        bp = self.path("beta", beta)
        zone = beta > 0.0
        b_top = max(now.beta, beta, K.path_value(*bp, 0.5)) if zone else 0.0
        lo = nodes.below(min(now.alpha, alpha) - _TINY)
        if zone:
            hi = max(nodes.below(b_top * (1.0 + 1e-12) + _TINY), lo)
        else:  # no zone: only the element at the centre matters (its gap)
            hi = lo + 1 if nodes.n and nodes.xi[0] == 0.0 and lo == 0 else lo
        xi, Y0, s0, virtual = self._elements(lo, hi, alpha, beta, H_new)
        nm = law.n_modes
        Y = np.zeros((xi.size, max(nm, 1)))
        U = np.zeros(xi.size)
        K.free_field(xi, Y0, s0, 0, xi.size, bp[0], bp[1], bp[2], self.mus, self.zdt,
                     law.ctil, law.d, nm, self.w3, Y, U)
        stays = np.zeros(xi.size, dtype=bool)
        stays[:hi - lo] = (nodes.status[lo:hi] == CONTACT) & (nodes.xi[lo:hi] <= alpha)
        U[stays] = H_new + s.setup.indenter.g(xi[stays])
        order = np.argsort(xi, kind="stable")
        ev = Evaluation(alpha, beta, H_new, Hdot, math.nan, math.nan, math.nan, 0.0, 0.0,
                        math.nan, lo, hi, Y[order], U[order], Hf)
        ev.xi, ev.virtual, ev.stays = xi[order], virtual[order], stays[order]
        ev.dt = self.dt
        s.finish_evaluation(self, ev, bp)
        return ev

    def _elements(self, lo, hi, alpha, beta, H_new):
        """The elements a step advances: the existing ones ``lo..hi-1`` and the new ones it
        places where the receding edge releases the solid or the zone end enters virgin
        solid. Returns positions, modes at the start of each one's free stretch, where that
        stretch starts (0, or the fraction at which the edge releases it), and which are new."""
        nodes = self.s.nodes
        law = self.s.setup.law
        nm = law.n_modes
        width = max(nm, 1)
        Y0 = nodes.Y[lo:hi, :width].copy()
        if nm:
            lag = (self.now.t - nodes.t_last[lo:hi]) / self.dt  # elements beyond the zone
            if np.any(lag > 0.0):
                Y0 *= np.exp(-np.outer(lag, self.mus))
        s0 = np.zeros(hi - lo)
        ap = self.path("alpha", alpha)
        released = np.nonzero((nodes.status[lo:hi] == CONTACT) & (nodes.xi[lo:hi] > alpha))[0]
        for j in released:
            s0[j] = _crossing(ap, nodes.xi[lo + j])
            if nm:
                Y0[j] = self.released_modes(nodes.xi[lo + j], s0[j], H_new)
        new_x = self.s.new_elements(self, alpha, beta)
        new_s0 = np.array([_crossing(ap, x) if x < self.now.alpha else 0.0 for x in new_x])
        new_Y = np.zeros((new_x.size, width))
        for j, x in enumerate(new_x):
            if x < self.now.alpha and nm:
                new_Y[j] = self.released_modes(x, new_s0[j], H_new)
        virtual = np.concatenate([np.zeros(hi - lo, dtype=bool), np.ones(new_x.size, dtype=bool)])
        return (np.concatenate([nodes.xi[lo:hi], new_x]), np.vstack([Y0, new_Y]),
                np.concatenate([s0, new_s0]), virtual)


def _crossing(p, x):
    """The fraction where the path ``p`` passes ``x`` (nearest to the step, clamped to it)."""
    roots = np.empty(2)
    n = K.path_roots(p[0], p[1], p[2], x, -1e-12, 1.0 + 1e-12, roots)
    if n == 0:
        return 1.0 if abs(K.path_value(*p, 1.0) - x) < abs(p[0] - x) else 0.0
    return min(max(roots[0], 0.0), 1.0)
