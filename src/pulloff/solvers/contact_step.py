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



def quadratic_path(prev, now, new, r):
    """``(p0, p1, p2)`` of the quadratic through ``(-r, prev)``, ``(0, now)``, ``(1, new)``;
    linear through the last two when ``r`` is None."""
    if r is None or r <= 0.0 or prev is None or not math.isfinite(prev):
        return now, new - now, 0.0
    p2 = (prev - now + r * (new - now)) / (r * (r + 1.0))
    return now, new - now - p2, p2


@dataclass
class Evaluation:
    """The end of a trial step (dimensionless)."""

    alpha: float
    beta: float
    H: float
    Hdot: float
    gap: float  # at the zone end (or at the centre when there is no zone)
    edge_load: float  # the contact element's line load at alpha
    F_contact: float
    F_total: float
    centre_u: float  # displacement of the element at the centre, nan if none
    lo: int  # the elements advanced: lo..hi-1
    hi: int
    Y: np.ndarray  # their modes at the end of the step
    U: np.ndarray  # their displacements at the end of the step
    Hf: np.ndarray  # the arms' filtered lift at the end of the step

    # (``xi`` and ``flags`` of the rows ``Y``, ``U`` are set by :meth:`Step._evaluate`; most
    # evaluations are trials nobody commits, so the masks are made when asked for)
    @property
    def virtual(self) -> np.ndarray:
        """The rows of elements the step places (new ones)."""
        return self.flags == 1

    @property
    def stays(self) -> np.ndarray:
        """The rows of contact elements that stay in contact."""
        return self.flags == 2


def is_fresh(setup) -> bool:
    """Whether each evaluation places its own elements: an elastic smooth contact has no
    history."""
    return not setup.flat and setup.law.c == 0.0 and not setup.law.maxwell


def step_constants(setup) -> np.ndarray:
    """The constants ``sc`` (:func:`pulloff.kernels.contact.evaluate_step`) every step of
    ``setup`` shares, the law's and the indenter's; a step copies them and adds its own."""
    law, ind = setup.law, setup.indenter
    sc = np.zeros(K.S_N)
    sc[[K.S_KAPPA, K.S_C, K.S_D, K.S_FLAT, K.S_AF, K.S_C_G, K.S_N_G, K.S_FRESH]] = (
        law.kappa_inf, law.c, law.d, 1.0 if setup.flat else 0.0, ind.A_f, ind.C, ind.n,
        1.0 if is_fresh(setup) else 0.0)
    return sc


#: The contact view of a law without arms (never read).
_NO_CONTACTS = (np.zeros(0, dtype=np.int64), np.zeros((2, 0)), np.zeros(1, dtype=np.int64))


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
        K.fitted_radau3_rows(self.mus, self.w3)
        self.r = (now.t - before.t) / dt if before is not None else None
        self.before = before
        self.arm_mus = dt / law.tau_arms if law.maxwell else np.zeros(0)
        self.jump = False  # a zero-time transition: the phase's root is searched widely
        self.k_alpha = self.k_beta = 0  # new elements per step (set by the stepper)
        self.law = (law.ctil, law.kappa_arms, law.tau_arms, law.V_inv, law.V_kernel)
        # A step's trials share their lift (a driven one, or the balance's few): its path,
        # rate and the arms' filtered lift at the end are computed once per lift.
        self._driven = None
        if stepper.lift_driven:
            drive = stepper.drive
            self._driven = (now.H, drive.rate * dt if drive.kind == "speed" else 0.0, 0.0)
        self._at_end = {}
        self._edges = None
        # The phase searches come back to points they have evaluated (the held edge, the
        # root they end on): a step answers those from its memo.
        self._memo = {}
        self.fresh = stepper.fresh
        self._contacts = None  # (view, element count): see `contacts`
        sc = stepper.step_constants.copy()
        sc[K.S_T0], sc[K.S_DT], sc[K.S_ALPHA0], sc[K.S_BETA0] = now.t, dt, now.alpha, now.beta
        sc[K.S_XIMAX], sc[K.S_KINK] = stepper.nodes.xi_max, stepper.first_edge
        sc[K.S_LIVE_END] = stepper.nodes.live_end
        self._constants = sc

    @property
    def contacts(self):
        """The contact elements and their memory at the step's end
        (:func:`pulloff.kernels.contact.contact_view`), gathered once per step (again where
        archived elements came back): every trial reads them."""
        nodes = self.s.nodes
        if self._contacts is None or self._contacts[1] != nodes.n:
            if self.s.setup.law.maxwell:
                law = self.s.setup.law
                view = K.contact_view(nodes.xi, nodes.status, nodes.D, nodes.tj, nodes.n,
                                      law.kappa_arms, law.tau_arms, self._constants)
            else:  # no arms, no memory: never read
                view = _NO_CONTACTS
            self._contacts = (view, nodes.n)
        return self._contacts[0]

    @property
    def edges(self) -> np.ndarray:
        """The edges now and one step earlier, the steps' ratio, the released elements'
        spacing and their largest count (inf where the step places its own):
        ``kernels.contact.trial_ranges``'s."""
        if self._edges is None:
            now, before, nan = self.now, self.before, math.nan
            self._edges = np.array([
                now.alpha, now.beta, before.alpha if before is not None else nan,
                before.beta if before is not None else nan, nan if self.r is None else self.r,
                math.inf if self.fresh else self.s.spacing(now),
                math.inf if self.fresh else self.s.most_released])
        return self._edges

    @property
    def constants(self):
        sc = self._constants
        k_beta = max(self.k_beta, int(4 * self.s.per_zone)) if self.fresh else self.k_beta
        sc[K.S_K_ALPHA], sc[K.S_K_BETA] = self.k_alpha, k_beta
        sc[K.S_JUMP] = 1.0 if self.jump else 0.0
        return sc

    # --- paths over the step -------------------------------------------------------------
    def path(self, name, new):
        prev = getattr(self.before, name) if self.before is not None else None
        return quadratic_path(prev, getattr(self.now, name), new, self.r)

    def lift_path(self, H_new):
        """The lift over the step: exact (linear) under a driven lift, else the quadratic."""
        if self._driven is not None:
            return self._driven
        return self.path("H", H_new)

    def _end_of(self, H_new):
        """``(lift path as an array, dH/dt at the end, Hf at the end)`` for the lift
        ``H_new``, computed once per lift (the array ``Hf`` is shared: not to be changed)."""
        got = self._at_end.get(H_new)
        if got is None:
            path = np.array(self.lift_path(H_new), float)
            Hf = self.now.Hf
            if self.arm_mus.size:
                Hf = np.empty(self.now.Hf.size)
                K._filtered_lift(self.now.Hf, self.arm_mus, path, 1.0, Hf)
            got = self._at_end[H_new] = (path, (path[1] + 2.0 * path[2]) / self.dt, Hf)
        return got

    def lift_rate(self, H_new):
        """``dH/dt`` at the end of the step (the Kelvin-Voigt contact load needs it)."""
        return self._end_of(H_new)[1]

    def filtered_lift(self, H_new, s=1.0):
        """The arms' filtered lift ``Hf`` (``tau dHf/dt = H - Hf``) at fraction ``s`` (at the
        end: shared between the step's trials, not to be changed)."""
        if s == 1.0:
            return self._end_of(H_new)[2]
        out = np.empty(self.now.Hf.size)
        K._filtered_lift(self.now.Hf, self.arm_mus, self._end_of(H_new)[0], s, out)
        return out

    # --- the contact side ----------------------------------------------------------------
    def contact_load(self, xi, H_new, Hdot, Hf):
        """Line load of a contact element at ``xi`` at the end of the step."""
        law = self.s.setup.law
        if law.maxwell and not self.s.setup.flat:
            # A smooth edge: the compiled formulas (kernels.contact.edge_load, which the
            # compiled edge search evaluates too). In a jump the dashpots do not move: an
            # element the contact reaches keeps the free state it had (virgin: none) and
            # meets the indenter with the glassy modulus; beyond the contact the edge reaches
            # a free element whose dashpots relax toward the indenter from the step's start.
            nodes = self.s.nodes
            return K.edge_load(float(xi), nodes.mesh, self.law, self._stepw(Hf),
                               self.s.setup.indenter.table, self._constants_at(H_new, Hdot),
                               nodes.n)
        G = self.s.setup.indenter.g(xi)
        if law.maxwell:
            memory = self.s.contact_memory(xi, self.now.t + self.dt, self.contacts[0])
            arms = 0.0
            for kappa, lag in zip(law.kappa_arms.tolist(), (H_new - Hf).tolist()):
                arms += kappa * lag  # in order, as the compiled edge search sums them
            return law.kappa_inf * (H_new + G) + arms - memory
        return law.kappa_inf * (H_new + G) + law.c * Hdot

    def _constants_at(self, H_new, Hdot):
        """A copy of the step's constants with the lift ``H_new`` and its rate at the end."""
        sc = self.constants.copy()
        sc[K.S_H1], sc[K.S_HDOT] = H_new, Hdot
        return sc

    def _stepw(self, Hf1):
        """The step's arrays the kernels take (``stepw``), with the arms' filtered lift
        ``Hf1`` at the end."""
        return (self.mus, self.decay, self.zdt, self.w3, self.arm_mus, self.now.Hf, Hf1,
                *self.contacts)

    def released_modes(self, x, s_c, H_new):
        """Modes of a contact element at ``x`` released at fraction ``s_c``: its dashpots from
        the contact formula, in the eigenbasis (Kelvin-Voigt: its displacement)."""
        law = self.s.setup.law
        G = self.s.setup.indenter.g(x)
        h0, h1, h2 = self.lift_path(H_new)
        if not law.maxwell:
            return np.array([h0 + s_c * (h1 + s_c * h2) + G])
        t = self.now.t + s_c * self.dt
        E = self.filtered_lift(H_new, s_c) + G + self.s.contact_memory_arms(x, t,
                                                                           self.contacts[0])
        return law.V_inv @ E

    def compiled_secant(self, H_new, alpha=None):
        """``contact_phases._secant`` compiled with its residual at the lift ``H_new``
        (:func:`pulloff.kernels.contact.edge_secant`: the same iterates, without Python
        between them): for an edge (``alpha`` None: the unknown is the edge, the zone end from
        the edge condition: a flat punch's receding edge, a smooth one on a solid with arms)
        or for the zone end with the edge held at ``alpha``. ``(x_held, f_held, x_guess, lo,
        hi, reach) -> root or None``. None (the Python search then) where the step places
        its own elements (an elastic smooth contact: its evaluations are not the compiled
        ones)."""
        if self.fresh or (alpha is None and not self.s.setup.flat
                          and not self.s.setup.law.maxwell):
            return None
        s, now = self.s, self.now
        nodes, law = s.nodes, s.setup.law
        lift, Hdot, Hf = self._end_of(H_new)
        sc = self._constants_at(H_new, Hdot)
        edges = self.edges
        Hf1 = Hf if law.maxwell else now.Hf
        table = s.setup.indenter.table
        held = math.nan if alpha is None else float(alpha)

        def secant(x_held, f_held, x_guess, lo, hi, reach):
            # (the mesh as it is now: a Python evaluation may have brought archived elements
            # back since)
            mesh = nodes.mesh
            stepw = self._stepw(Hf1)
            sc[K.S_LIVE_END] = nodes.live_end
            x, last = K.edge_secant(x_held, f_held, x_guess, lo, hi, reach, held, mesh,
                                    self.law, stepw, table, sc, edges, lift, nodes.n)
            if math.isnan(x):
                return None
            # The phase evaluates its root next: the search's last evaluation is that one.
            a, b, lo_e, hi_e, m, out, res = last
            self._memo[self._key(a, b, H_new)] = self._evaluation(
                a, b, H_new, Hdot, Hf if law.maxwell else now.Hf, lo_e, hi_e, m, out, res)
            return x
        return secant

    # --- the free side -------------------------------------------------------------------
    def evaluate(self, alpha, beta, H_new) -> Evaluation:
        """The end of the step for trial edges and lift (:func:`pulloff.kernels.contact.
        evaluate_step` advances every element); a repeated trial is answered from the memo."""
        key = self._key(alpha, beta, H_new)
        ev = self._memo.get(key)
        if ev is None:
            ev = self._memo[key] = self._evaluate(alpha, beta, H_new)
        return ev

    def _key(self, alpha, beta, H_new):
        return (alpha, beta, H_new, self.k_alpha, self.k_beta, self.jump, self.s.nodes.n)

    def _evaluation(self, alpha, beta, H_new, Hdot, Hf, lo, hi, m, out, res) -> Evaluation:
        """An :class:`Evaluation` of what :func:`pulloff.kernels.contact.evaluate_step` wrote
        (``m`` rows of ``out``, and ``res``)."""
        ev = Evaluation(alpha, beta, H_new, Hdot, res[K.R_GAP], res[K.R_EDGE_LOAD],
                        res[K.R_F_CONTACT], res[K.R_F_TOTAL],
                        res[K.R_CENTRE_U], lo, hi, out[1][:m], out[2][:m], Hf)
        ev.xi, ev.flags = out[0][:m], out[3][:m]
        ev.dt = self.dt
        return ev

    def _evaluate(self, alpha, beta, H_new) -> Evaluation:
        s = self.s
        nodes = s.nodes
        law = s.setup.law
        now = self.now
        lift, Hdot, Hf = self._end_of(H_new)
        if not law.maxwell:
            Hf = now.Hf
        sc = self._constants_at(H_new, Hdot)
        while True:
            stepw = self._stepw(Hf)
            mesh = nodes.mesh
            _, lo, hi, m, out, res = K.trial_state(alpha, beta, mesh, self.law, stepw,
                                                   s.setup.indenter.table, sc, self.edges,
                                                   lift, nodes.n)
            if hi >= 0:
                break
            # The trial reaches the archived elements: every element is live again.
            nodes.restore()
            self._constants[K.S_LIVE_END] = sc[K.S_LIVE_END] = nodes.live_end
        return self._evaluation(alpha, beta, H_new, Hdot, Hf, lo, hi, m, out, res)
