"""A flat punch pulled to separation by quadrature over its history: no foundation mesh.

Elements do not interact, so the gap at the zone end is one integral over the history of the
two radii (:func:`pulloff.kernels.quadrature.edge_gap_split`: the spatial part in closed
form). The history is what is solved for:

- **onset** (``a`` pinned at ``R`` with the zone outside, or ``b`` pinned at ``R`` with the
  zone on the face, and there from the face's strength limit on ``a = 0``: the zone alone on
  the whole face): explicit, the onset is the root of ``gap = delta`` in time;
- **receding** (both move, the edge condition ``b^2 = a^2 + ell^2`` holds): unknown ``a(t)``;
- **zone alone** (``a = 0``): unknown ``b(t)``, until it collapses (``b -> 0``) or the branch
  turns back in time (a fold: the punch snaps off).

The two unknown phases are marched in a parameter ``sigma = t / t_onset + q`` (or
``(t - t_onset) / t_unit + q`` with ``t_unit`` 100 creep times where the onset comes later:
:data:`_CREEP_TIMES`), where ``q`` is
a phase's own measure of progress (``asinh`` of the receded area over the onset zone's, then
``1 - b^2 / b_0^2``): both ``t`` and ``q`` are smooth in ``sigma``, also through a fold, where
``t`` turns back. Each step solves ``gap = delta`` for ``q`` at the next ``sigma`` (secants
from a degree-5 predictor; the old memory is linearised over a step, only its newest part
recomputed), and the predictor's miss, against the zone's width and the time, sets the next
step. The history is the degree-5 interpolant of the nodes in ``sigma``, never across a piece
boundary: the onset, ``a = 0``, and the instant the zone end passes the onset's bond radius
(where the openings of elements released before and after the onset meet in a kink, a weak
singularity of the solution; the march lands on it).

A run at tolerance ``tol`` is checked by one at ``tol / 4``; the finer one is reported and the
largest relative change of the controlled outputs is the estimate (cautious: the error falls
about in proportion to ``tol``). The moving-edge stepper (:mod:`.contact`) solves the same
model on an element mesh; the reference (:mod:`pulloff.references.edge`) integrates over the
elements adaptively.
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from ..kernels import quadrature as kernels
from ..model import analytic
from .base import Solver, flat_punch_pull, problem as problem_line
from . import edge_machine
from .edge_machine import Machine
from .onset_quadrature import _MAX_SPRING_TO_SOLID
from .problem import Problem
from .result import Result

#: Gauss points and panels graded toward a singular point, by the march's tolerance.
_RULES = ((1e-3, (6, 4)), (1e-5, (8, 6)), (1e-7, (12, 10)), (0.0, (16, 14)))
#: Degree of the history's and the predictor's interpolants.
DEGREE = 5
#: The check run's tolerance against the reported one's.
_CHECK = 4.0
#: The first run's tolerance over rtol: the outputs' errors came out 0.002-0.06 times the
#: march's tolerance on the shipped configs (rtol 1e-4 to 1e-8, against the reference).
_TOL_PER_RTOL = 8.0
#: Steps in one run at most (a run at rtol 1e-8 takes ~300-1100).
MAX_NODES = 20000
#: The first step, in sigma, of a phase (doubled until the predictor has its stencil).
_FIRST_STEP = 1e-6
#: The same where the time unit is capped (:data:`_CREEP_TIMES`) under a rigid pull of a
#: solid without instantaneous compliance (Kelvin-Voigt): 1e-2 creep times. There the gap
#: is a Volterra equation of the first kind in the history, and from 1e-4 creep times its
#: march oscillated node to node and turned back (finite_punch_internal at 1e-7 m/s, 2e5
#: creep times into the pull, at tolerances 8e-4 to 8e-5; the stepper then took 11
#: minutes); with this it runs through at 8e-4 to 2e-6. Standard linear solids and springs
#: keep the small first step: from this one they turned back at 2e-7, from it they do not.
_FIRST_STEP_CAPPED = 1e-4
#: Secants without a smaller residual after which a step's root is the best point met
#: (:func:`secant`). The gap's rounding in ``q`` is the time's (``T`` quantised to ~1e-15 of
#: the clock since ``t = 0``, times the memory's fastest rate): ~1e-12 on slow pulls, where
#: secants to 1e-14 ran into their cap of 40.
_PATIENCE = 4
_SECANTS_BEFORE_PATIENCE = 8
_RESIDUAL_NOISE = 1e-10
#: The smallest step, relative to sigma (where the predictor's miss is rounding).
_SMALLEST_STEP = 1e-11
#: Where the zone alone would land on its collapse (``b = 0``) from a node farther than this
#: in ``q = 1 - b^2 / b_0^2``, its branch is first solved at a few points between
#: (:func:`_turns_before_the_end`). It may turn back just before the collapse (a fold at
#: ``b^2`` ~ 1e-2 ``b_0^2``): marches of rtol 1e-4 that had landed from ``b^2 = 0.1 b_0^2`` on
#: standard linear solid and Prony faces (1.2e-4, 1.8e-5 m/s) came out 1e-4 and 3.9e-4
#: early, with estimates 8x below that (a review).
_LANDING_GAP = 1e-3
_LANDING_CHECKS = 4
#: The zone alone's ``1 - q`` (its ``b^2`` over the phase's first) within which a collapse
#: whose landing fails is taken at the last node's time, extrapolated.
_COLLAPSED = 1e-5
#: A landing on the collapse later than the last node by this many of the last step's (or
#: the predictor's) time is taken for a root on another branch (see _land_on_end).
_LANDING_JUMP = 8.0
#: Within this of the collapse in ``q``, a turn back after the zone alone passed the onset's
#: bond radius is a fold (farther, a lost branch: see march).
_NEAR_COLLAPSE = 0.05
#: Quartered steps before a step back in time is taken for a fold.
_FOLD_RETRIES = 6
#: The march's time unit in creep times at most (:func:`_time_unit`). With the onset time
#: as the unit, a crack that runs for a few creep times long after its onset (a standard
#: linear solid pulled at 1e-7 m/s, t_onset = 2e4 creep times; a Kelvin-Voigt bond behind
#: 0.1 N/m) moved in ``q`` while ``t`` stood still in ``sigma``: the time miss asked for
#: steps of 1e-11 after five doublings, and the march turned back (a false fold). Measured on
#: those two and the shipped pulls (rtol 1e-6) and a 15-speed sweep (rtol 1e-4): 3
#: oscillates, 10 still turns back (the standard linear solid at tolerance 8e-6), 30 leaves
#: the Prony pull 3x less accurate, 100 runs through everywhere within the reference's
#: values.
_CREEP_TIMES = 100.0
#: The smallest rtol: below it a run takes seconds to minutes.
RTOL_FLOOR = 1e-9
#: The outputs whose change between the two runs is the estimate.
CONTROLLED = ("t_detach", "F_total_detach", "t_separation", "F_peak_total",
              "F_peak_contact")


def _rule(tol: float):
    n, graded = next(rule for limit, rule in _RULES if tol >= limit)
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w, graded


#: The smaller Gauss rules of a history interval far from every singular point of its
#: integrand (:func:`kernels._rule_at`), and the errors each is chosen for. An ``n``-point
#: rule's error on a function analytic inside the Bernstein ellipse ``rho`` is ~``rho^-2n``
#: (a constant apart: :data:`_FAR_ERROR`), and a singular point ``d`` interval widths away
#: leaves ``rho = x + sqrt(x^2 - 1)``, ``x = 1 + 2 d``; on ``exp(beta u)`` over [0, 1] it is
#: ``2^(2n+1) (n!)^4 / ((2n+1) ((2n)!)^3) (beta / 2)^(2n)`` of the integral (:data:`_FAR_EXP_ERROR`).
_FAR_POINTS = (3, 4, 5, 6, 8)
_FAR_ERROR = 1e-20
_FAR_EXP_ERROR = 1e-17


def _rule_table(gx: np.ndarray, gw: np.ndarray, rate: float) -> np.ndarray:
    """``[points, column, distance, width, x..., weights...]`` rows: the far rules smaller
    than the run's own (``gx, gw``, the last row, whose states come first in a row of
    ``March.states``), with the least distance (interval widths) to a singular point and the
    longest interval (the kernel's time unit; ``rate`` the fastest exponential's) each keeps."""
    sizes = [p for p in _FAR_POINTS if p < gx.size] + [gx.size]
    table = np.zeros((len(sizes), 4 + 2 * gx.size))
    col = 1 + 5 * gx.size
    for i, points in enumerate(sizes):
        if points == gx.size:
            x, w, column, distance, width = gx, gw, 0, 0.0, math.inf
        else:
            x, w = np.polynomial.legendre.leggauss(points)
            x, w = 0.5 * (x + 1.0), 0.5 * w
            rho = _FAR_ERROR ** (-0.5 / points)
            distance = 0.25 * (rho + 1.0 / rho) - 0.5
            coefficient = (2.0 ** (2 * points + 1) * math.factorial(points) ** 4
                           / ((2 * points + 1) * math.factorial(2 * points) ** 3))
            beta = 2.0 * (_FAR_EXP_ERROR / coefficient) ** (0.5 / points)
            width = beta / rate if rate > 0.0 else math.inf
            column, col = col, col + 1 + 5 * points
        table[i, :4] = points, column, distance, width
        table[i, 4:4 + points], table[i, 4 + points:4 + 2 * points] = x, w
    return table


@dataclass
class EdgeModel:
    """A rigid pull of a flat punch in the kernels' units (their module's header): SI
    scales, the lift's and the rheology's arrays."""

    R: float  # m, punch radius
    sigma_c: float  # Pa
    delta: float  # m
    v: float  # m/s
    h0: float  # m
    zone: int  # 0 external, 1 internal
    time_scale: float  # s
    rh: np.ndarray  # the bonded load's law (kernels.ell_of)
    cr: np.ndarray  # the creep compliance (kernels.creep_rate)
    machine: Machine | None = None  # a machine spring's (None: a rigid pull)
    t_strength: float = math.inf  # when a zone on the face reaches its strength limit

    @classmethod
    def from_scene(cls, scene, t_limit: float = math.inf) -> "EdgeModel":
        """The scene's pull; behind a machine spring with the lift path to past its onset
        (``t_limit`` in ``delta / v``; ``ValueError`` where there is none)."""
        spectrum = scene.material.spectrum()
        sigma_c, delta = scene.adhesion.sigma_c, scene.adhesion.delta
        R, v, h0 = scene.geometry.radius, scene.loading.v, scene.loading.h0
        ts = delta / v
        rh = [2.0 * h0 / (sigma_c * R), 2.0 * v * ts / (sigma_c * R), spectrum.G_inf,
              spectrum.eta / ts]
        for G, tau in spectrum.arms:
            rh += [G, tau / ts]
        compliance = sigma_c * R / (math.pi * delta)  # J in these units is J * compliance
        J0, rates, weights = spectrum.creep()
        cr = [J0 * compliance, 2.0 * spectrum.eta * h0 / (sigma_c * R * ts)]
        for rate, weight in zip(rates, weights):
            cr += [rate * ts, weight * compliance * ts]
        machine = None
        if scene.loading.machine_stiffness is not None:
            machine = Machine.from_scene(scene, t_limit)
            rh = machine.law_array()
        model = cls(R, sigma_c, delta, v, h0, 0 if scene.geometry.cohesive_zone == "external"
                    else 1, ts, np.array(rh, float), np.array(cr, float), machine)
        model.t_strength = strength_time(model)
        return model

    @property
    def fastest_rate(self) -> float:
        """The fastest exponential of the creep's kernel and of a rigid pull's bonded load
        (1 / kernel time unit; 0 for none)."""
        rates = list(self.cr[2::2])
        if self.rh[0] == self.rh[0]:
            rates += [1.0 / tau for tau in self.rh[5::2]]
        return max(rates, default=0.0)

    @property
    def fastest_creep(self) -> float:
        """The shortest creep time (inf for an elastic solid), in the time scale."""
        rates = self.cr[2::2]
        return 1.0 / rates.max() if rates.size and rates.max() > 0.0 else math.inf

    def ell(self, t: float) -> float:
        """The bonded load while the bond radius is pinned (a rigid pull's at any time)."""
        return kernels.ell_of(t, self.rh)

    def lift(self, t: float) -> float:
        """The lift [delta] while the bond radius is pinned (a rigid pull's at any time)."""
        if self.machine is not None:
            return self.machine.lift_before(t)
        return self.h0 / self.delta + t

    def state(self, t: float, p: float, phase: int, ell: float | None = None):
        """``(ell, r, P)`` at ``t``: phase 1 pinned, 2 receding (``p = r``), 3 alone
        (``p = b^2``); ``ell`` given past the onset behind a machine spring."""
        ell = self.ell(t) if ell is None else ell
        if phase == 1:  # (as kernels._pinned_state)
            if self.zone == 0:
                return ell, 0.0, ell * ell
            return (ell, 1.0, 1.0) if t >= self.t_strength else (ell, ell * ell, ell * ell)
        return (ell, p, ell * ell) if phase == 2 else (ell, 1.0, p)

    def radii(self, t: float, p: float, phase: int, ell: float | None = None):
        """``(a, b)`` in R."""
        ell, r, P = self.state(t, p, phase, ell)
        a = math.sqrt(max(1.0 - r, 0.0))
        return a, math.sqrt(a * a + P)

    def forces(self, t: float, p: float, phase: int, ell: float | None = None):
        """``(F_contact, F_total)`` [N]: ``2 a L`` and the whole line load's."""
        ell, r, P = self.state(t, p, phase, ell)
        a, b = self.radii(t, p, phase, ell)
        unit = 2.0 * self.sigma_c * self.R ** 2
        total = a * ell + b * b * math.atan2(math.sqrt(P), a) if b > 0.0 else 0.0
        return unit * 2.0 * a * ell, unit * total


class _Phase:
    """A marched phase's progress measure ``q(p)`` and its end."""

    def __init__(self, phase: int, p0: float, width: float):
        self.phase, self.p0, self.width = phase, p0, width
        self.p_end = 1.0 if phase == 2 else 0.0
        self.q_end = self.q(self.p_end)

    def p(self, q: float) -> float:
        if self.phase == 2:
            return self.p0 + self.width * math.sinh(q)
        return self.p0 * (1.0 - q)

    def q(self, p: float) -> float:
        if self.phase == 2:
            return math.asinh((p - self.p0) / self.width)
        return 1.0 - p / self.p0


@dataclass
class March:
    """One run at one tolerance: the onset, the nodes of the history, how it ended."""

    model: EdgeModel
    tol: float
    t_limit: float = math.inf
    t_on: float = math.inf
    t_unit: float = math.nan  # the time unit of sigma, and its origin (see sigma_of)
    t_origin: float = 0.0
    first_step: float = _FIRST_STEP
    t_zero: float = math.nan  # when a reached 0
    refusal: list = field(default_factory=list)  # the stepper's lines, where it refuses
    released: bool = False  # the zone alone from a face at its strength limit: its first piece
    smallest: float = math.inf  # the smallest step taken (in sigma)
    max_nodes: int = MAX_NODES
    end: str = ""  # collapse | fold | snap | unstable_onset | t_max | no_onset | steps
    fold: tuple = ()  # (t, sigma) of a fold
    evaluations: int = 0
    n: int = 0
    hist: np.ndarray = field(default=None)
    segs: np.ndarray = field(default=None)
    qs: np.ndarray = field(default=None)

    def __post_init__(self):
        self.gx, self.gw, self.graded = _rule(self.tol)
        # behind a machine spring a fourth row: the bonded load (edge_machine)
        self.machine = self.model.machine
        self.hist = np.zeros((3 if self.machine is None else 4, MAX_NODES + 2))
        self.qs = np.zeros(MAX_NODES + 2)
        self.lifts = np.zeros(MAX_NODES + 2)  # behind a machine spring: H at the nodes
        self.zero = ()  # behind a machine spring: (t, H, ell) where a reached 0
        self.segs = np.zeros((0, 2), dtype=np.int64)
        self.ctx = np.zeros(7)
        self.ctx[1], self.ctx[6] = self.model.zone, self.model.t_strength
        # the history's intervals' Gauss states (kernels.history_integral), grown with it
        self.rules = _rule_table(self.gx, self.gw, self.model.fastest_rate)
        # (and the last three columns each node's (flag, r, P): kernels._node_rp)
        self.states = np.zeros((256, int(max(col + 1 + 5 * points
                                             for points, col in self.rules[:, :2])) + 3))

    def sigma_of(self, t: float, q: float) -> float:
        """The march's parameter at time ``t`` and progress ``q``: ``t / t_onset + q``, or
        where the unit is shorter than the onset time ``(t - t_onset) / t_unit + q`` (the
        first steps then keep their digits: ``t_onset / t_unit`` is up to 2e2 on the
        scenes met)."""
        return (t - self.t_origin) / self.t_unit + q

    def t_of(self, sigma: float, q: float) -> float:
        return self.t_origin + self.t_unit * (sigma - q)

    def rounding(self, sigma: float) -> float:
        """The scale of ``sigma``'s rounding: its own, or the onset time's in sigma."""
        return max(abs(sigma), self.t_on / self.t_unit)

    def from_release(self, piece: int) -> bool:
        """Whether ``piece`` is a zone alone's first, released from a face at its strength
        limit (the march's first piece then)."""
        return self.released and piece == 0

    def node_ell(self, i: int) -> float:
        """The bonded load at node ``i``: the history's behind a machine spring, a rigid
        pull's at the node's time."""
        return self.model.ell(self.hist[0, i]) if self.machine is None else self.hist[3, i]

    # -- the gap -----------------------------------------------------------------------------
    def _context(self, t, p, phase, ell=None):
        c = self.ctx
        c[0], c[2] = self.t_on, t
        c[3], c[4], c[5] = self.model.state(t, p, phase, ell)
        return c

    def onset_gap(self, t: float) -> float:
        self.evaluations += 1
        return kernels.edge_gap_split(self._context(t, 0.0, 1), self.model.rh,
                                      self.model.cr, self.hist, 0, self.segs, DEGREE, self.gx,
                                      self.gw, self.graded, -math.inf, 1, self.states,
                                      self.rules)

    def _trial(self, t, p, sigma, phase):
        """The history with a trial node after the accepted ones: ``(hist, n)``. A trial
        beyond a fold (earlier than the last node) sees the history before it only. Behind
        a machine spring the node's bonded load and lift (``self.trial_lift``) are solved."""
        i, hist = self.n, self.hist
        if i > 0 and hist[0, i - 1] >= t:
            hist = hist[:, :i + 1].copy()
            first = self.segs[-1, 0] + 1
            while i > first and hist[0, i - 1] >= t:
                i -= 1
        hist[0, i], hist[1, i], hist[2, i] = t, p, sigma
        if self.machine is not None:
            hist[3, i], self.trial_lift = self._lift(hist, i, phase)
        return hist, i + 1

    def _lift(self, hist, i, phase):
        """``(ell, H)`` at node ``i`` behind the machine spring (its rows 0-2 set)."""
        if phase == 3:
            return self.zero[2], self.machine.lift_alone(hist[0, i], hist[1, i])
        return self.machine.receding(hist, self.lifts, self.segs[-1, 0], i)

    def ell_at(self, t, p, sigma, phase):
        """The bonded load at a point of the branch (the trial node's behind a spring)."""
        if self.machine is None:
            return self.model.ell(t)
        hist, n = self._trial(t, p, sigma, phase)
        return hist[3, n - 1]

    def gap(self, t, p, phase, sigma, part=-1, split=0.0):
        """``gap / delta`` with a trial node; ``part`` 0 / 1: the memory before / after
        ``split`` (:func:`kernels.edge_gap_split`), -1 all of it."""
        hist, n = self._trial(t, p, sigma, phase)
        self.evaluations += 1
        m = self.model
        args = (self._context(t, p, phase, hist[3, n - 1] if self.machine else None),
                m.rh, m.cr, hist, n, self.segs, DEGREE, self.gx, self.gw, self.graded)
        alone = 0.0
        if self.machine is not None and phase == 3 and part != 0:
            # the punch moves with the zone; the virtual element crept (edge_machine)
            alone = self.trial_lift - self.machine.virtual_lift(t, *self.zero)
        if part < 0:
            split, part = -math.inf, 1
        return kernels.edge_gap_split(*args, split, part, self.states, self.rules) + alone

    def push(self, t, p, sigma, q, new_piece=None):
        """A node; behind a machine spring with its bonded load and lift (a piece's first
        node: the one before it at the same time, or the path's before the onset)."""
        i = self.n
        if i >= self.max_nodes:
            raise _Steps()
        if new_piece is not None:
            self.segs = np.vstack([self.segs, [[i, new_piece]]]).astype(np.int64)
        self.hist[:3, i] = t, p, sigma
        if i == 0:  # (a history begun again: see _unstable_onset)
            self.states[:, self.rules[:, 1].astype(np.int64)] = 0.0
            self.states[:, -3] = 0.0
        elif i >= self.states.shape[0]:
            self.states = np.concatenate([self.states, np.zeros_like(self.states)])
        self.states[i, -3] = 0.0  # (a node popped and pushed again: kernels._node_rp)
        if self.machine is not None:
            if new_piece is None:
                self.hist[3, i], self.lifts[i] = self._lift(self.hist, i, self.segs[-1, 1])
            elif i > 0 and self.hist[0, i - 1] == t:
                self.hist[3, i], self.lifts[i] = self.hist[3, i - 1], self.lifts[i - 1]
            else:
                self.hist[3, i], self.lifts[i] = self.model.ell(t), self.model.lift(t)
        self.qs[i] = q
        self.n = i + 1


class _Steps(Exception):
    """The step cap was reached."""


def secant(f, x0: float, h: float, xtol: float = 1e-14, patience: int = 0) -> float:
    """A root of ``f`` near ``x0`` by secants (first step ``h``), to ``xtol`` relative to
    ``max(|x|, 1)``. With ``patience``: from secant :data:`_SECANTS_BEFORE_PATIENCE` + 1 on,
    where ``|f|`` (at most :data:`_RESIDUAL_NOISE`) has not fallen below its smallest value
    for that many in a row, ``f`` is at its rounding and the point of the smallest ``|f|`` is
    the root (before, a march's roots are
    those of plain secants: which steps turn back near a vertical tangent of ``t(sigma)`` moved
    with them, sls_finite_punch at tolerance 2e-6 falsely)."""
    f0 = f(x0)
    x1 = x0 + h
    f1 = f(x1)
    (best, f_best), stalled = ((x1, f1) if abs(f1) < abs(f0) else (x0, f0)), 0
    for iteration in range(40):
        if f1 == f0 or f1 == 0.0:
            break
        x0, x1, f0 = x1, x1 - f1 * (x1 - x0) / (f1 - f0), f1
        if abs(x1 - x0) <= xtol * max(abs(x1), 1.0):
            break
        f1 = f(x1)
        if abs(f1) < abs(f_best):
            best, f_best, stalled = x1, f1, 0
        else:
            stalled += 1
            if (patience and stalled >= patience and iteration >= _SECANTS_BEFORE_PATIENCE
                    and abs(f_best) <= _RESIDUAL_NOISE):
                return best
    return x1


def illinois(f, lo: float, hi: float, f_lo: float, f_hi: float, xtol: float,
             ftol: float = 0.0) -> float:
    """The root of ``f`` in ``[lo, hi]`` (``f_lo``, ``f_hi`` of opposite signs): to ``xtol``,
    or where ``|f| <= ftol`` (its rounding)."""
    side, x = 0, hi
    for _ in range(100):
        if hi - lo <= xtol:
            break
        x = hi - f_hi * (hi - lo) / (f_hi - f_lo)
        if not lo < x < hi:
            x = 0.5 * (lo + hi)
        fx = f(x)
        if abs(fx) <= ftol:
            return x
        if (fx < 0.0) == (f_lo < 0.0):
            lo, f_lo = x, fx
            f_hi *= 0.5 if side == -1 else 1.0
            side = -1
        else:
            hi, f_hi = x, fx
            f_lo *= 0.5 if side == 1 else 1.0
            side = 1
    return x


def find_onset(run: March) -> None:
    """The first root of ``gap = delta`` while the bond is pinned (``run.t_on``), or
    ``run.end = "no_onset"`` before ``run.t_limit``."""
    g0 = run.onset_gap(0.0) - 1.0
    if g0 >= 0.0:
        run.t_on = 0.0
        return
    lo, g_lo, t = 0.0, g0, 1e-3
    while True:
        t = min(t, run.t_limit)
        g = run.onset_gap(t) - 1.0
        if g >= 0.0:
            break
        if t >= run.t_limit:
            run.end = "no_onset"
            return
        lo, g_lo, t = t, g, 2.0 * t
    run.t_on = illinois(lambda s: run.onset_gap(s) - 1.0, lo, t, g_lo, g, 4e-16 * t)


def strength_time(model: EdgeModel) -> float:
    """When the bonded load of a zone on the face first reaches ``2 sigma_c R`` (inf if never):
    the bond would then need more than the whole face can hold. 0 where it needs that at
    ``t = 0`` already (a lift ``h0`` or a Kelvin-Voigt solid's dampers), also where ``ell``
    then relaxes below 1 for a while (a lifted standard linear solid): the bond is gone at
    once. (``ell`` of a rigid pull falls, if at all, only from ``t = 0`` to one minimum, so
    from ``ell(0) < 1`` the first crossing is on its rise, which doubling brackets.)"""
    if model.zone == 0 or model.machine is not None:
        return math.inf
    if model.ell(0.0) >= 1.0:
        return 0.0
    if model.ell(1e300) < 1.0:
        return math.inf
    lo, hi = 0.0, 1e-3
    while model.ell(hi) < 1.0:
        lo, hi = hi, 2.0 * hi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if model.ell(mid) < 1.0 else (lo, mid)
        if hi - lo <= 4e-16 * hi:
            break
    return lo


#: A step's root is taken once a secant moves it by less than this times the march's
#: tolerance (relative to ``max(|q|, 1)``), and the first secant is this small a part of
#: ``q``: the last secant, not evaluated, is then within ~1e-15 of the root (the secants
#: converge superlinearly from the predictor's miss), and a step takes 3 evaluations of
#: the newest memory where it took 4 (with 1e-14 and a first secant of 1e-5 of ``q``). The
#: shipped pulls' results moved by at most 2e-6 at rtol 1e-4 and 3e-9 at 1e-6, none farther
#: from the reference by more than those; runs took 5-50 % less time. Of ten random pulls
#: checked against the reference by a review, one (a standard linear solid, zone outside,
#: 1.7e-5 m/s) moved at rtol 1e-4 from 1.8e-7 to 3.2e-5, its estimate 1.7e-5: the march at
#: tolerance 2e-4 gives the same value with 1e-7 and 1e-8 here, so that is its own error
#: (the one before was lucky); at rtol 1e-6 all ten agree with before to two digits.
#: 1e-4 of the tolerance sent a standard linear solid at 1e-7 m/s to the stepper (a false
#: fold at tolerance 8e-4).
_STEP_XTOL = 1e-6
_FIRST_SECANT = 1e-7


def _step(run: March, ph: _Phase, sigma: float, q_guess: float, piece: int) -> tuple:
    """``(q, t)`` on the branch at ``sigma`` (``t = March.t_of(sigma, q)``). The memory older than
    the last ``DEGREE + 2`` nodes is linear in ``q`` over a step (two evaluations, again at
    the root while it moved by more than the linearisation allows), only the rest is
    evaluated at every secant; where four linearisations do not settle, the whole gap is
    solved from the predictor."""
    def t_of(q):
        return run.t_of(sigma, q)

    def whole(q0):
        q = secant(lambda q: run.gap(t_of(q), ph.p(q), ph.phase, sigma) - 1.0, q0,
                   1e-7 * max(abs(q0), 1e-3), xtol, patience=_PATIENCE)
        return q, t_of(q)

    xtol = _STEP_XTOL * run.tol
    if run.n - piece <= DEGREE + 3:
        return whole(q_guess)
    split = run.hist[0, run.n - 2 - DEGREE]
    predicted = q_guess
    for _ in range(4):
        h = 1e-6 * max(abs(q_guess), 1e-2)
        old = run.gap(t_of(q_guess), ph.p(q_guess), ph.phase, sigma, 0, split)
        slope = (run.gap(t_of(q_guess + h), ph.p(q_guess + h), ph.phase, sigma, 0, split)
                 - old) / h

        def residual(q, q0=q_guess, old=old, slope=slope):
            return (run.gap(t_of(q), ph.p(q), ph.phase, sigma, 1, split) + old
                    + (q - q0) * slope - 1.0)

        q = secant(residual, q_guess, _FIRST_SECANT * max(abs(q_guess), 1e-2), xtol,
                   patience=_PATIENCE)
        # the linearisation's error, ~ (q - q_guess)^2, far below the step's tolerance
        if (q - q_guess) ** 2 <= 1e-3 * run.tol * max(abs(q), 1e-2):
            return q, t_of(q)
        q_guess = q
    # (the old memory was not linear over the step after four tries: a kink of the openings
    # in it; the root had been taken from the last linearisation as it was)
    return whole(predicted)


def _predict(run: March, piece: int, sigma: float, values: np.ndarray) -> float:
    # (a zone alone released from the face leaves its first node like e log e: that node is
    # left out once two others are there, see _RELEASE_GROWTH)
    first = piece + 1 if run.from_release(piece) and run.n > 2 else piece
    m = min(run.n - first, DEGREE + 1)
    return kernels.lagrange(run.hist[2], values, run.n - m, m, sigma)


def _miss(run: March, ph: _Phase, q: float, q_guess: float, t: float) -> float:
    """The predictor's miss: in the bond radius against the zone's width, in time against
    ``t``."""
    dq = abs(q - q_guess)
    # in time against the time since the onset (but at least the fastest creep time): a
    # slow pull's crack grows in e-folds of its memory, not of the pull's clock
    miss_t = dq * run.t_unit / max(t - run.t_on, min(run.model.fastest_creep, t))
    if ph.phase == 2:
        ell = run.model.ell(t) if run.machine is None else run.hist[3, run.n - 1]
        return max(abs(ph.p(q) - ph.p(q_guess)) / (ell * ell), miss_t)
    return max(dq, miss_t)


def _zone_past_bond(p: float, phase: int, ell: float, a_on2: float) -> float:
    """``b^2 - a_onset^2`` (``ell`` the bonded load there, unused for the zone alone): its
    sign change is a kink of the openings (see the module)."""
    return (1.0 - p + ell * ell if phase == 2 else p) - a_on2


def _turns_before_the_end(run: March, ph: _Phase, t_end: float) -> bool:
    """Whether the branch between the last node and the collapse found at ``t_end`` reaches
    a later time than that somewhere (a fold first): its time solved at fixed ``b`` where
    ``1 - q`` is halved from the last node's, :data:`_LANDING_CHECKS` times (landings from
    within :data:`_LANDING_GAP` are not checked)."""
    n = run.n
    left = ph.q_end - run.qs[n - 1]
    if left <= _LANDING_GAP:
        return False
    t0 = run.hist[0, n - 1]
    for k in range(1, _LANDING_CHECKS + 1):
        q = ph.q_end - left * 0.5 ** k
        t = secant(lambda s: run.gap(s, ph.p(q), ph.phase, run.sigma_of(s, q)) - 1.0, t0,
                   1e-9 * t0, 1e-11)
        if not math.isfinite(t):
            return False
        if t > t_end:
            return True
        t0 = t
    return False


def _land_on_end(run: March, ph: _Phase, piece: int, sigma: float) -> tuple:
    """``(t, sigma)`` where the phase's measure reaches its end (``a = 0`` or ``b = 0``):
    ``t`` solved at the end's ``p``, from the predictor's ``t`` there."""
    n = run.n
    lo, hi = run.hist[2, n - 1], sigma
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _predict(run, piece, mid, run.qs) < ph.q_end else (lo, mid)
    t0 = _predict(run, piece, lo, run.hist[0]) if n - piece > 1 else run.hist[0, n - 1]
    t = secant(lambda s: run.gap(s, ph.p_end, ph.phase, run.sigma_of(s, ph.q_end)) - 1.0,
               t0, t0 * 1e-9, 1e-15)
    if ph.phase == 3 and n - piece > 1:
        # a root far past the predictor's is on another branch: the march's turned back
        # before (a lifted Kelvin-Voigt face at 4.3e-3 m/s folds at 1 - q ~ 7e-6 and
        # landed 1.6 % later with an estimate of 6e-5; a review): no end from this step
        scale = max(abs(t0 - run.hist[0, n - 1]), run.hist[0, n - 1] - run.hist[0, n - 2])
        if t - run.hist[0, n - 1] > _LANDING_JUMP * scale:
            t = math.nan
    return t, run.sigma_of(t, ph.q_end)


def _land_on_kink(run: March, ph: _Phase, piece: int, sigma: float, before: float,
                  after: float, a_on2: float) -> tuple:
    """``(q, t, sigma)`` of the branch where the zone end passes the onset's bond radius."""
    found = {}

    def residual(s):
        q, t = _step(run, ph, s, _predict(run, piece, s, run.qs), piece)
        found[s] = (q, t)
        p = ph.p(q)
        return _zone_past_bond(p, ph.phase, run.ell_at(t, p, s, ph.phase), a_on2)

    # (to the residual's rounding: its last bits had taken ~20 more steps on separation_kv
    # at tolerance 8e-6, the Illinois rule halving one side's value each time)
    s = illinois(residual, run.hist[2, run.n - 1], sigma, before, after,
                 1e-15 * run.rounding(sigma), 4.0 * sys.float_info.epsilon * max(a_on2, 1.0))
    q, t = found[s] if s in found else _step(run, ph, s, _predict(run, piece, s, run.qs),
                                             piece)
    return q, t, s


def _unstable_onset(run: March, ph: "_Phase") -> bool:
    """Whether the first phase's edge moving on would open the gap further at the onset (an
    elastic solid's crack runs at once): the gap's slope in the phase's measure at the
    onset's time; from a face released at its rim, :func:`_lets_go_at_release`."""
    if ph.phase == 3:
        return _lets_go_at_release(run)
    dr = 1e-6 * ph.width
    run.push(run.t_on, ph.p0, 0.0, 0.0, new_piece=2)
    g = run.gap(run.t_on, ph.p0 + dr, 2, 1e-9 * dr / ph.width)
    run.n, run.segs = 0, run.segs[:0]
    return g > 1.0 + 1e-12


#: The growth of the first steps of a zone alone released from a face at its strength limit
#: (2 elsewhere): it leaves the release like ``t - t_release ~ e (A - c1 log e)`` in its shrunk
#: area ``e = 1 - b^2 / R^2`` (:func:`_lets_go_at_release`), and the degree-5 interpolants
#: through first nodes a factor 2 apart (a stencil spanning 32x in ``e``) did not hold that
#: log: the first predicted step missed its slope by O(1), the steps fell to the rounding and
#: the march turned back falsely within 1e-5 of the time (tolerances 1e-8, 1e-9 on Kelvin-Voigt
#: and Prony faces, 1e-7 on a Kelvin-Voigt face at 2.2e-5 m/s; marches agreeing). With 1.1, and
#: the release's node left out of the predictor, five faces of the reference and the
#: Kelvin-Voigt face at 2.2e-4 and 2.2e-5 m/s run through at tolerances 1e-5 to 1e-8 (errors
#: 5e-12 to 1.4e-7 against the reference), at 1e-9 all but one (/tmp study, 22nd session).
_RELEASE_GROWTH = 1.1
#: Within its first nodes after such a release a turn back in time after steps below this
#: fraction of the first step is no fold but a lost branch (handed over): with the first
#: steps' growth 1.1 a Kelvin-Voigt face at 2.2e-5 m/s still turned back at its 10th node at
#: tolerance 1e-9 (the first predicted step's slope 2e-3 off, the steps cut to 1e-7 of the
#: first by then, to the gap's rounding), 2 % before the collapse the coarser marches and
#: the reference find; real folds there (fast standard linear solids and Prony series, 25-42
#: nodes after the release) come with steps near the first (a fold within the dip of the
#: release itself is found apart, :func:`_lets_go_at_release`).
_RELEASE_NODES = 60
_RELEASE_NOISE = 1e-4


def _noise_turn(run: March, piece: int) -> bool:
    """Whether a turn back in time is the rounding's after a face's release (see above)."""
    return (run.from_release(piece) and run.n - piece <= _RELEASE_NODES
            and run.smallest < _RELEASE_NOISE * run.first_step)


#: The zone alone released from a face at its strength limit: the decades of ``1 - b^2``
#: sampled for the gap's dip below delta (:func:`_lets_go_at_release`), the first the
#: largest shrinkage at which the gap must have opened for the fold to lie within the dip.
_RELEASE_DECADES = range(3, 15)


def _lets_go_at_release(run: March) -> bool:
    """Whether a zone alone on the whole face comes off right where its rim opens (``b = R``,
    ``gap = delta`` at ``run.t_on``); then ``run.fold`` = ``(t, nan)`` of the fold. The gap
    of a smaller zone goes like ``e (c0 + c1 log e)`` in ``e = 1 - b^2`` (the elements at the
    rim carried sigma_c since the strength limit: the ``d log d`` of the zone's opening), so
    it first dips below delta, by ~1e-9 on a standard linear solid at 2e-2 m/s, before it
    opens. Where it has opened by ``e = 1e-3``, the branch turns back within the dip: the
    fold comes when the rim's gap has risen by the dip's depth, ``depth / (d gap / dt)``
    after the release (to first order in the dip's width: the rate is that of ``e = 0``)."""
    t = run.t_on
    run.push(t, 1.0, 0.0, 0.0, new_piece=3)
    try:
        def excess(log_e):
            return run.gap(t, 1.0 - 10.0 ** log_e, 3, 1e-12) - 1.0

        if not excess(-_RELEASE_DECADES[0]) > 0.0:
            return False
        samples = [(excess(-k), -k) for k in _RELEASE_DECADES]
        depth, k = min(samples)
        if depth < 0.0:
            lo, hi = k - 1.0, min(k + 1.0, -float(_RELEASE_DECADES[0]))
            depth = min(depth, excess(_largest(lambda x: -excess(x), lo, hi, 1e-3)))
        dt = 1e-9 * max(t, run.t_unit)
        rate = (run.gap(t + dt, 1.0, 3, 1e-12) - 1.0) / dt
        if not rate > 0.0:
            return False
        run.fold = (t + max(-depth, 0.0) / rate, math.nan)
        return True
    finally:
        run.n, run.segs = 0, run.segs[:0]


#: Samples of each phase's measure in the search for the state a bond lifted past its onset
#: at t = 0 jumps to (:func:`_jump_at_zero`).
_JUMP_SAMPLES = 32


def _jump_at_zero(run: March, r_on: float):
    """Lifted past its onset at ``t = 0`` (``gap > delta`` with the bond pinned): the state it
    jumps to at once, ``(phase, p)``, the first on the receding path from the pinned bond
    (the bond radius down to 0, then the zone end down to 0) where the gap is back at
    ``delta``; None where there is none (the punch comes off at once). Without instantaneous
    compliance the elements keep their displacements through the jump (MODEL.md 6: free
    elements start at ``u = 0``, the bonded ones at ``h0``), so a smaller bond, or the zone
    alone, closes the gap: a Kelvin-Voigt punch lifted by ``2 delta`` keeps ``a = 0.2 R``;
    an elastic solid follows at once and opens further (off at once, as the reference)."""
    run.push(0.0, r_on, 0.0, 0.0, new_piece=2)
    b0 = run.model.state(0.0, 0.0, 1)[2]  # (b^2 where a reaches 0: the face's at most)
    try:
        for phase, start, end in ((2, r_on, 1.0), (3, b0, 0.0)):
            if start == end:  # (a face at its strength limit: no bond to recede)
                continue
            def excess(p, phase=phase):
                return run.gap(0.0, p, phase, 0.0) - 1.0

            lo, g_lo = start, excess(start)
            for k in range(1, _JUMP_SAMPLES + 1):
                hi = start + (end - start) * k / _JUMP_SAMPLES
                g_hi = excess(hi)
                if g_hi <= 0.0:
                    (left, g_left), (right, g_right) = sorted(((lo, g_lo), (hi, g_hi)))
                    return phase, illinois(excess, left, right, g_left, g_right, 1e-15)
                lo, g_lo = hi, g_hi
        return None
    finally:
        run.n, run.segs = 0, run.segs[:0]


def _snaps_at_a_zero(run: March, t: float, b0: float) -> bool:
    """Behind a machine spring, whether the zone alone cannot hold the punch where ``a``
    reaches 0: the gap's slope in ``b^2`` at that time, the punch moving with the zone (the
    moving-edge reference's criterion: a smaller zone must close the gap)."""
    eps = 1e-4 * b0
    sigma = run.hist[2, run.n - 1]
    near = run.gap(t, b0 - 1e-3 * eps, 3, sigma + 1e-12 * run.rounding(sigma))
    far = run.gap(t, b0 - eps, 3, sigma + 2e-12 * run.rounding(sigma))
    return not (near - far) / (0.999 * eps) > 0.0


def _advance(run: March, ph: _Phase, piece: int, step: float):
    """One step's try: ``(q, t, sigma, at_end, next step, accepted)``, or None where the
    march has lost the branch (``run.end = "lost"``). The predictor's miss against the
    tolerance sets the next step and rejects a step that missed by more than three times."""
    n = run.n
    sigma = run.hist[2, n - 1] + step
    floor = _SMALLEST_STEP * run.rounding(sigma)
    q_guess = _predict(run, piece, sigma, run.qs)
    if q_guess >= ph.q_end:
        t, sigma_end = _land_on_end(run, ph, piece, sigma)
        if math.isfinite(t) and ph.phase == 3 and step > floor and _turns_before_the_end(
                run, ph, t):
            return q_guess, t, sigma, False, 0.5 * step, False
        if math.isfinite(t):
            return ph.q_end, t, sigma_end, True, step, True
        collapsed = _collapsed(run, ph, piece, step)
        if collapsed:
            return collapsed
        # (no end found from this step's prediction: the landing's secant met a NaN gap;
        # it had pushed a NaN time and reported a collapse without a time)
        return _shorter(run, step, floor)
    q, t = _step(run, ph, sigma, q_guess, piece)
    if not (math.isfinite(t) and math.isfinite(q) and q <= ph.q_end):
        # the secants went past a = 0 (or b = 0): land there, or take a shorter step
        t, sigma = _land_on_end(run, ph, piece, sigma)
        if math.isfinite(t) and t > run.hist[0, n - 1]:
            return ph.q_end, t, sigma, True, step, True
        collapsed = _collapsed(run, ph, piece, step)
        if collapsed:
            return collapsed
        return _shorter(run, step, floor)
    if n - piece <= DEGREE:
        growth = _RELEASE_GROWTH if run.from_release(piece) else 2.0
        return q, t, sigma, False, growth * step, True
    if run.from_release(piece) and run.model.zone == 1 and ph.p(q) > 1.0:
        # (a zone on the face larger than the face: the steps overshot the release's dip)
        return _shorter(run, step, floor)
    miss = _miss(run, ph, q, q_guess, t)
    if (run.from_release(piece) and run.model.cr[0] > 0.0 and step > floor
            and abs(q - q_guess) > 0.5 * abs(q - run.qs[n - 1])):
        # (the predictor missed by more than half the step's own progress: see
        # _RELEASE_GROWTH; a standard linear solid's nodes oscillated into a zone larger
        # than the face. Not for a solid without instantaneous compliance, whose gap is
        # a Volterra equation of the first kind: steps cut to 1e-4 creep times made a
        # near-elastic Kelvin-Voigt face's nodes oscillate, see _FIRST_STEP_CAPPED)
        return q, t, sigma, False, 0.5 * step, False
    factor = min(2.0, max(0.2, 0.8 * (run.tol / max(miss, 1e-300)) ** (1.0 / (DEGREE + 1))))
    accepted = not (miss > 3.0 * run.tol and step > floor)
    return q, t, sigma, False, max(step * factor, floor), accepted


def _shorter(run: March, step: float, floor: float):
    """A rejected try that asks for a quarter of the step, or None (``run.end = "lost"``)
    where the step is at its floor already."""
    if step <= floor:
        run.end = "lost"
        return None
    return math.nan, math.nan, math.nan, False, 0.25 * step, False


def _collapsed(run: March, ph: _Phase, piece: int, step: float):
    """A zone alone within :data:`_COLLAPSED` of its collapse whose landing failed (its gap
    nan this close: the interpolant through the last nodes dips below ``b = 0``; a lifted
    Kelvin-Voigt face at 7.6e-2 m/s crept to ``b^2 = 1e-12 b_0^2`` and was lost): the
    collapse at the time extrapolated from the last two nodes (an attempt's tuple), or None."""
    n, hs, qs = run.n, run.hist[0], run.qs
    if not (ph.phase == 3 and ph.q_end - qs[n - 1] <= _COLLAPSED and n - piece > 1
            and qs[n - 1] > qs[n - 2]):
        return None
    t = hs[n - 1] + (hs[n - 1] - hs[n - 2]) / (qs[n - 1] - qs[n - 2]) * (ph.q_end - qs[n - 1])
    return ph.q_end, t, run.sigma_of(t, ph.q_end), True, step, True


def _first_phase(run: March, r_on: float):
    """The phase the march starts in at the onset (its first node pushed), or None where the
    punch comes off at once (``run.end = "unstable_onset"``); lifted past the onset at
    ``t = 0``, after the jump (:func:`_jump_at_zero`); from a face held at its strength limit
    (``a = 0`` at the onset), the zone alone from ``b = R``."""
    ell_on = run.model.ell(run.t_on)
    if r_on >= 1.0:
        ph = _Phase(3, 1.0, 0.0)
    else:
        ph = _Phase(2, r_on, max(ell_on ** 2, 1e-300))
    if run.t_on == 0.0 and run.machine is None and run.onset_gap(0.0) > 1.0 + 1e-12:
        jump = _jump_at_zero(run, r_on)
        if jump is None:
            run.end = "unstable_onset"
            return None
        ph = _Phase(2, jump[1], ph.width) if jump[0] == 2 else _Phase(3, jump[1], 0.0)
        run.t_zero = 0.0 if jump[0] == 3 else run.t_zero
    elif _unstable_onset(run, ph):
        run.end = "unstable_onset"
        return None
    if ph.phase == 3 and math.isnan(run.t_zero):
        run.t_zero = min(run.t_on, run.model.t_strength)
    run.released = ph.phase == 3 and r_on >= 1.0
    run.push(run.t_on, ph.p0, run.sigma_of(run.t_on, 0.0), 0.0, new_piece=ph.phase)
    return ph


def _turned_back(run: March, ph: _Phase, piece: int, crossed: bool, node: tuple) -> None:
    """A step that came back earlier than the last node (``node = (t, p, sigma, q)``, past
    the fold retries): a fold of the branch (``run.fold``), or a lost branch."""
    n = run.n
    t, p, sigma, q = node
    if (n - piece <= DEGREE or _noise_turn(run, piece)
            or (ph.phase == 3 and crossed and ph.q_end - q > _NEAR_COLLAPSE)):
        # Turned back within a phase's first steps (the seed scene's zone alone at
        # tolerance 1e-7, where finer and coarser marches collapse), or after the
        # zone alone passed the onset's bond radius (separation_kv lifted by 1.5e-6 m
        # at 1e-2 m/s, at tolerance 1e-6 only, 1.6 % before the reference's collapse;
        # every real fold met so far, the zone's on the face and outside, came
        # before any such crossing of the zone alone), or within a zone alone's
        # first steps after the face released it (_RELEASE_NODES): no fold this
        # march can place. (Folds within _NEAR_COLLAPSE of the collapse after the
        # crossing are real: standard linear solids and Prony series with the zone
        # outside at 2.5e-7 .. 9e-4 m/s, within 2.3e-6 .. 1.4e-5 of the stepper.)
        run.end = "lost"
        return
    run.push(t, p, sigma, q)
    run.fold = _fold(run, piece)
    run.end = "fold" if ph.phase == 3 else "bond_fold"


def march(run: March) -> None:
    """The receding and zone-alone phases from the onset to separation (``run.end``)."""
    r_on = run.model.state(run.t_on, 0.0, 1)[1]
    a_on2 = 1.0 - r_on
    ph = _first_phase(run, r_on)
    if ph is None:
        return
    piece, step = 0, run.first_step
    retries, crossed, end_retries = 0, False, 0
    while True:
        n = run.n
        attempt = _advance(run, ph, piece, step)
        if attempt is None:
            return
        q, t, sigma, at_end, step, accepted = attempt
        if not accepted:
            continue
        p = ph.p_end if at_end else ph.p(q)
        if (t < run.hist[0, n - 1] and retries < _FOLD_RETRIES
                and step > _SMALLEST_STEP * run.rounding(sigma)):
            # A fold persists under smaller steps; a step that overshot the branch does not;
            # nor does a landing on the zone's collapse that came earlier than the last node
            # (the branch turned back in between: a standard linear solid's face at 1.2e-4
            # m/s folded 3.4e-4 after the interpolant through such a landing, both marches
            # of rtol 1e-4 agreeing).
            step *= 0.25
            retries += 1
            continue
        if t < run.hist[0, n - 1]:
            _turned_back(run, ph, piece, crossed, (t, p, sigma, q))
            return
        if t > run.t_limit:
            run.end = "t_max"
            return
        before = _zone_past_bond(run.hist[1, n - 1], ph.phase, run.node_ell(n - 1), a_on2)
        after = _zone_past_bond(p, ph.phase, run.ell_at(t, p, sigma, ph.phase), a_on2)
        kink = before > 0.0 and after < 0.0 and not crossed
        if kink and at_end and step > _SMALLEST_STEP * run.rounding(sigma):
            # A step onto the collapse across the kink: shorter, to land on the kink first.
            # Coarse marches that jumped it agreed with each other 2.9e-4 from the answer
            # (separation_kv lifted by 1.36e-7 m at 9.2e-2 m/s, rtol 1e-4: estimate 3.2e-5;
            # found by a review).
            step *= 0.25
            continue
        if kink and not at_end:
            q, t, sigma = _land_on_kink(run, ph, piece, sigma, before, after, a_on2)
            run.push(t, ph.p(q), sigma, q)
            piece = run.n
            run.push(t, ph.p(q), sigma, q, new_piece=ph.phase)
            step = 100.0 * run.first_step
            crossed = True  # (once a phase: the landing's own rounding is no second crossing)
            continue
        run.smallest = min(run.smallest, sigma - run.hist[2, n - 1])
        run.push(t, p, sigma, q)
        retries = 0
        if not at_end:
            continue
        if ph.phase == 3:
            if _fold_before_the_end(run, piece) and end_retries < _FOLD_RETRIES:
                run.n -= 1  # (the landing: the branch turns back before it; smaller steps)
                step, end_retries = 0.25 * step, end_retries + 1
                continue
            run.end = "collapse"
            return
        run.t_zero = t
        b0 = run.node_ell(run.n - 1) ** 2
        ph = _Phase(3, b0, 0.0)
        piece, crossed = run.n, False
        if run.machine is not None:
            run.zero = (t, run.lifts[run.n - 1], run.hist[3, run.n - 1])
        run.push(t, b0, run.sigma_of(t, 0.0), 0.0, new_piece=3)
        if run.machine is not None and _snaps_at_a_zero(run, t, b0):
            run.end = "snap"
            return
        step = run.first_step


def _largest(f, lo: float, hi: float, xtol: float = 0.0) -> float:
    """The argument of the largest ``f`` in ``[lo, hi]`` (golden section; ``f`` unimodal
    there), to ``xtol`` (or the rounding of ``hi``)."""
    golden = 0.5 * (math.sqrt(5.0) - 1.0)
    a, b = lo + (1 - golden) * (hi - lo), lo + golden * (hi - lo)
    fa, fb = f(a), f(b)
    for _ in range(200):
        if hi - lo <= max(1e-15 * abs(hi), xtol):
            break
        if fa > fb:
            hi, b, fb = b, a, fa
            a = lo + (1 - golden) * (hi - lo)
            fa = f(a)
        else:
            lo, a, fa = a, b, fb
            b = lo + golden * (hi - lo)
            fb = f(b)
    return 0.5 * (lo + hi)


def _fold(run: March, piece: int) -> tuple:
    """``(t, sigma)`` of the largest ``t`` of the interpolant through the last nodes (the
    last one past the fold)."""
    n = run.n
    m = min(n - piece, DEGREE + 1)
    hs, ht = run.hist[2], run.hist[0]

    def t_at(s):
        return kernels.lagrange(hs, ht, n - m, m, s)

    s = _largest(t_at, hs[max(n - 3, n - m)], hs[n - 1])
    return max((t_at(s), s), (ht[n - 2], hs[n - 2]))


def _fold_before_the_end(run: March, piece: int) -> bool:
    """Whether a march that landed on the zone's collapse (``b = 0``, its last node) came from
    a node before a fold: the interpolant through its last nodes rises above the landing's
    time in between (by more than a tenth of the tolerance over the phase's duration). Both
    marches of a standard linear solid's face at rtol 1e-3 had landed so in one step from
    ``b^2 = 0.13 R^2``, 1.8e-3 before the reference's fold, and agreed (estimate 7e-6)."""
    t_end = run.hist[0, run.n - 1]
    return _fold(run, piece)[0] - t_end > 1e-12 * abs(t_end)


def _piece_of(run: March, i: int) -> tuple:
    """``(first, last)`` node of the piece holding node ``i`` (its own piece if a boundary)."""
    starts = list(run.segs[:, 0]) + [run.n]
    j = max(k for k in range(len(starts) - 1) if starts[k] <= i)
    return starts[j], starts[j + 1] - 1


def _phases(run: March) -> np.ndarray:
    """The phase (2 receding, 3 zone alone) of each node."""
    phases = np.empty(run.n, dtype=np.int64)
    for start, phase in run.segs:
        phases[start:] = phase
    return phases


def _peak(run: March, which: int) -> tuple:
    """``(t, F)`` of the largest force (0: contact, 1: total) after the onset: the largest
    node, refined on its piece's interpolant in sigma."""
    model, hist, n = run.model, run.hist, run.n
    phases = _phases(run)
    forces = np.array([model.forces(hist[0, i], hist[1, i], phases[i], run.node_ell(i))[which]
                       for i in range(n)])
    if run.end == "fold":
        forces[-1] = -math.inf  # past the fold
    i = int(np.argmax(forces))
    first, last = _piece_of(run, i)
    if not first < i < last:
        return hist[0, i], forces[i]
    m = min(last - first + 1, DEGREE + 1)
    i0 = min(max(i - m // 2, first), last - m + 1)
    sigmas, values = hist[2, i0:i0 + m], forces[i0:i0 + m]

    def force_at(s):
        return kernels.lagrange(sigmas, values, 0, m, s)

    s = _largest(force_at, hist[2, i - 1], hist[2, i + 1])
    F = force_at(s)
    if F <= forces[i]:
        return hist[0, i], forces[i]
    return kernels.lagrange(sigmas, hist[0, i0:i0 + m], 0, m, s), F


def _onset_contact_peak(run: March) -> tuple:
    """``(t, F_contact)`` of the largest contact force while the bond is pinned (to the onset,
    the face's strength limit or ``t_max``): at its end with the zone outside; on the face the
    bond shrinks (``a^2 = 1 - ell^2``) and ``2 a ell`` peaks where ``ell^2`` first reaches 1/2
    (``ell`` falls, if at all, from ``t = 0`` to one minimum: a lifted standard linear
    solid's may pass 1/2 on its way down), or else at ``t = 0``."""
    model = run.model
    t = min(run.t_on, model.t_strength, run.t_limit)
    half = math.sqrt(0.5)
    if model.zone == 1 and model.ell(0.0) >= half:
        low = _largest(lambda s: -model.ell(s), 0.0, t) if t > 0.0 else 0.0
        if model.ell(low) < half:
            t = _first_at(model.ell, half, 0.0, low)
        else:  # (above 1/sqrt 2 throughout: 2 a ell is largest where ell is smallest)
            t = low if model.ell(low) < model.ell(0.0) else 0.0
    elif model.zone == 1 and model.ell(t) > half:
        t = _first_at(model.ell, half, 0.0, t)
    return t, model.forces(t, 0.0, 1)[0]


def _first_at(f, level: float, lo: float, hi: float) -> float:
    """Where ``f`` crosses ``level`` in ``[lo, hi]`` (one crossing; bisection)."""
    rising = f(lo) < level
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if (f(mid) < level) == rising else (lo, mid)
    return 0.5 * (lo + hi)


def summarise(run: March) -> dict:
    """The summary quantities of one run (SI)."""
    model, ts = run.model, run.model.time_scale
    # the bond lets go at the onset, or where the face's strength limit comes first (the
    # zone alone then holds the face until its rim opens, at run.t_on; or t_max comes first)
    t = min(run.t_on, model.t_strength)
    out = {"detached": t <= run.t_limit}
    if not out["detached"]:
        return out
    a, b = model.radii(t, 0.0, 1)
    Fc, Ft = model.forces(t, 0.0, 1)
    h_on = (model.h0 + model.v * t * ts if model.machine is None
            else model.lift(t) * model.delta)
    out.update(t_detach=t * ts, h_detach=h_on, b_detach=b * model.R,
               zone_ratio_detach=(b - a) / a if a > 0.0 else math.nan, F_contact_detach=Fc,
               F_total_detach=Ft)
    if run.end == "unstable_onset":
        tc, Fcp = _onset_contact_peak(run)
        t_off = run.fold[0] if run.fold else run.t_on  # (a zone alone's fold in its dip)
        out.update(t_separation=t_off * ts, F_peak_total=Ft, t_peak_total=t * ts,
                   F_peak_contact=Fcp, t_peak_contact=tc * ts)
        return out
    if run.end in ("collapse", "fold", "snap"):
        out["t_separation"] = (run.fold[0] if run.end == "fold" else run.hist[0, run.n - 1]) * ts
    contact, total = [_onset_contact_peak(run)], [(t, Ft)]
    if run.n:  # (no nodes where t_max came before the rim of a face opened)
        contact.append(_peak(run, 0))
        total.append(_peak(run, 1))
    tc, Fcp = max(contact, key=lambda x: x[1])
    tt, Ftp = max(total, key=lambda x: x[1])
    out.update(F_peak_total=Ftp, t_peak_total=tt * ts, F_peak_contact=Fcp,
               t_peak_contact=tc * ts)
    return out


#: Rows of the history before the onset (uniform in time; the gap evaluated at each).
ONSET_ROWS = 64


def history(run: March) -> dict:
    """SI history: rows before the onset (the gap computed), then the march's nodes (the gap
    is delta there) and the fold."""
    model, ts = run.model, run.model.time_scale
    t_first = run.t_on if math.isfinite(run.t_on) else run.t_limit
    rigid = model.machine is None
    rows = []
    # (one row where the onset is at t = 0: the pinned state, before a jump)
    times = np.linspace(0.0, t_first, ONSET_ROWS + 1)[:-1 if run.n else None] if t_first > 0.0 \
        else np.zeros(1)
    if 0.0 < model.t_strength < t_first:  # (the row where the bond is gone)
        times = np.sort(np.append(times, model.t_strength))
    for t in times:
        rows.append((t, 0.0, 1, run.onset_gap(t), None, None if rigid else model.lift(t)))
    phases = _phases(run)
    last = run.n - 1 if run.end == "fold" else run.n
    for i in range(last):
        if i and run.hist[0, i] == run.hist[0, i - 1] and phases[i] == phases[i - 1]:
            continue  # a piece boundary's second copy
        rows.append((run.hist[0, i], run.hist[1, i], phases[i], 1.0, run.node_ell(i),
                     None if rigid else run.lifts[i]))
    out = {name: [] for name in ("t", "h", "a", "b", "gap", "F_contact", "F_total")}
    for t, p, phase, gap, ell, lift in rows:
        a, b = model.radii(t, p, phase, ell)
        Fc, Ft = model.forces(t, p, phase, ell)
        h = model.h0 + model.v * t * ts if rigid else lift * model.delta
        for name, value in zip(out, (t * ts, h, a * model.R, b * model.R, gap * model.delta,
                                     Fc, Ft)):
            out[name].append(value)
    if run.end == "fold":
        for name in out:
            out[name].append(out[name][-1])
        out["t"][-1] = run.fold[0] * ts
        # (behind a spring the lift that balances the row's force: the force and radii are
        # the last node's, the time the fold's)
        out["h"][-1] = (model.h0 + model.v * run.fold[0] * ts if rigid else
                        model.v * run.fold[0] * ts - out["F_total"][-1]
                        / model.machine.stiffness)
    return {name: np.array(values) for name, values in out.items()}


def _changes(coarse: dict, fine: dict) -> float:
    """The largest relative change of the controlled outputs (inf where one run has an output
    the other lacks)."""
    worst = 0.0
    for name in CONTROLLED:
        a, b = coarse.get(name, math.nan), fine.get(name, math.nan)
        if math.isnan(a) and math.isnan(b):
            continue
        if not (math.isfinite(a) and math.isfinite(b)):
            return math.inf
        worst = max(worst, abs(a - b) / max(abs(b), 1e-300))
    return worst


def run_near(model: EdgeModel, tol: float, t_limit: float,
             max_nodes: int = MAX_NODES) -> March:
    """:func:`run_at` at ``tol``, or a little below where that march lost its branch (the
    seed scene's at 1e-7 only, of the tolerances 1e-3 .. 1e-7 tried: its neighbours at
    5e-8 and 3e-7 ran through)."""
    for factor in (1.0, 0.7, 0.5):
        run = run_at(model, tol * factor, t_limit, max_nodes)
        if run.end != "lost":
            break
    return run


def _time_unit(model: EdgeModel, t_on: float) -> float:
    """The time unit of the march's parameter: the onset time, but at most
    ``_CREEP_TIMES`` of the fastest creep time."""
    unit = min(t_on, _CREEP_TIMES * model.fastest_creep)
    if unit > 0.0:
        return unit
    # (lifted past the onset at t = 0)
    return _CREEP_TIMES * model.fastest_creep if math.isfinite(model.fastest_creep) else 1.0


def run_at(model: EdgeModel, tol: float, t_limit: float, max_nodes: int = MAX_NODES) -> March:
    """One run: the onset, then the march (``run.end`` says how it ended)."""
    run = March(model, tol, t_limit, max_nodes=max_nodes)
    if model.machine is not None:  # (its lift path holds the onset: machine_lift)
        run.t_limit = min(run.t_limit, model.machine.span)
    find_onset(run)
    run.t_limit = t_limit
    if run.end == "no_onset":
        return run
    run.t_unit = _time_unit(model, run.t_on)
    if run.t_unit != run.t_on:
        run.t_origin = run.t_on
        if model.cr[0] == 0.0 and model.machine is None:
            run.first_step = _FIRST_STEP_CAPPED
    try:
        march(run)
    except _Steps:
        run.end = "steps"
    except ZeroDivisionError:
        # a degenerate trial history (two nodes at one sigma, as a slow standard linear solid
        # at 5.2e-6 m/s gave): no answer from this march
        run.end = "lost"
    return run


def _handed_over(run: March) -> bool:
    """Whether a run ended where this solver gives no answer and the contact stepper takes the
    scene: a branch turning back while the bond holds, or a lost branch. A fold of the bond
    can be real (a standard linear solid pulled at 1e-2 m/s with its zone outside snaps 34 us
    after its onset, as the reference finds) or false: slow pulls turned back near their
    onset at every tolerance until the march's time unit was capped
    (:data:`_CREEP_TIMES`), and at tolerances near 1e-8 until the step floor was measured
    against the onset time in that unit (:meth:`March.rounding`; a standard linear solid at
    1e-7 m/s, rtol 1e-8: two marches had agreed on a fold 1.3 s before the separation). The
    march cannot tell a false fold from a real one."""
    return run.end in ("bond_fold", "lost")


def _release_offset(run: March) -> float:
    """Where a zone alone comes off within its dip just after its rim opens
    (:func:`_lets_go_at_release`): that fold's distance from the release, relative to it, a
    bound on the error of its first-order time (0 elsewhere)."""
    if run.end != "unstable_onset" or not run.fold:
        return 0.0
    return (run.fold[0] - run.t_on) / run.fold[0]


class EdgeQuadratureSolver(Solver):
    """A flat punch pulled to separation, the zone outside or on the face, any rheology, by
    quadrature over the history of its radii (no mesh, no fixed steps); through a machine
    spring a Kelvin-Voigt or elastic solid with the zone outside (:mod:`.edge_machine`)."""

    name = "edge_quadrature"
    method = "quadrature"
    kernel = "quadrature.edge_gap_split"
    summary = ("flat punch to separation by quadrature over the radii's history (rigid "
               "machine, any rheology, zone outside or on the face; through a machine "
               "spring, Kelvin-Voigt with the zone outside)")

    def unsupported(self, scene) -> list[str]:
        why = "the quadrature to separation has no steps or element fields"
        out = flat_punch_pull(scene, "edge quadrature", zones=("external", "internal"),
                              machine=True)
        if not out and scene.loading.machine_stiffness is not None:
            out += [problem_line(*line) for line in edge_machine.problems(
                scene, _MAX_SPRING_TO_SOLID)]
        if scene.model.until != "separation":
            out.append(problem_line("model.until", scene.model.until,
                                    "the edge quadrature runs to separation"))
        if scene.model.history != "exact":
            out.append(problem_line("model.history", scene.model.history,
                                    "the edge quadrature solves the exact history"))
        if scene.numerics.method == "stepper":
            out.append(problem_line("numerics.method", "stepper", "asks for the stepper"))
        for key, value in (("numerics.steps", scene.numerics.steps),
                           ("output.every", scene.output.every),
                           ("output.snapshots", scene.output.snapshots or None)):
            if value is not None:
                out.append(problem_line(key, value, why))
        if scene.numerics.rtol < RTOL_FLOOR:
            out.append(problem_line("numerics.rtol", scene.numerics.rtol,
                                    f"the edge quadrature goes to {RTOL_FLOOR:g}"))
        return out

    def solve(self, scene, observers) -> Result:
        wall = time.perf_counter()
        rtol = scene.numerics.rtol
        t_limit = math.inf if scene.numerics.t_max is None else (
            scene.numerics.t_max * scene.loading.v / scene.adhesion.delta)
        try:
            model = EdgeModel.from_scene(scene, t_limit)
        except ValueError:  # no lift path to an onset behind this spring
            from .contact import ContactSolver
            return ContactSolver().solve(scene, observers)
        with observers.progress("edge quadrature", None):
            coarse, fine, estimate, ran = _checked_pair(model, rtol, _TOL_PER_RTOL * rtol,
                                                        t_limit)
            notes = ()
            if _lost(coarse, fine):
                coarse, fine, estimate, notes = _looser_pair(model, rtol, t_limit, coarse, fine,
                                                             estimate, ran)
            if fine is not None and fine.end == "steps" and fine.max_nodes < MAX_NODES:
                return _unchecked(scene, model, coarse, fine, observers, wall)
            # Two marches that do not agree within rtol are no answer either (a zone alone
            # passing the onset's bond radius turned back there at some tolerances:
            # separation_kv lifted by 1.5e-6 m and pulled at 1e-2 m/s, found by a review)
            if fine is None or _handed_over(fine) or not estimate <= rtol:
                from .contact import ContactSolver
                refusal = ContactSolver().unsupported(scene)
                if not refusal:
                    return ContactSolver().solve(scene, observers)
                # no solver goes further (a bond lifted past its onset at t = 0 whose zone
                # alone then grows against the face): what this one found, and why it stops
                run = fine if fine is not None else coarse
                run.refusal = refusal
                return _result(scene, model, run, math.inf, coarse.evaluations + (
                    fine.evaluations if fine is not None else 0), observers,
                    time.perf_counter() - wall)
        if model.machine is not None:  # (both marches share the lift path before the onset)
            estimate += model.machine.path_error
        estimate = max(estimate, _release_offset(fine))
        return _result(scene, model, fine, estimate, coarse.evaluations + fine.evaluations,
                       observers, time.perf_counter() - wall, notes)


def _checked_pair(model: EdgeModel, rtol: float, tol: float, t_limit: float) -> tuple:
    """``(coarse, fine, estimate, ran)``: a march at ``tol`` and its check at a quarter of it,
    the pair moved on by quarters while they differ by more than ``rtol`` (``fine`` None where
    the first march hands the scene over); ``ran``: the summaries of the marches that ran
    through."""
    coarse = run_near(model, tol, t_limit)
    if _handed_over(coarse):
        return coarse, None, math.inf, []
    ran = [summarise(coarse)]
    fine = run_near(model, coarse.tol / _CHECK, t_limit, _check_nodes(coarse))
    ran.append(summarise(fine))
    estimate = _changes(ran[-2], ran[-1])
    while estimate > rtol and fine.tol > 1e-3 * rtol and fine.end not in ("steps", "lost"):
        coarse, fine = fine, run_near(model, fine.tol / _CHECK, t_limit, _check_nodes(fine))
        ran.append(summarise(fine))
        estimate = _changes(ran[-2], ran[-1])
    return coarse, fine, estimate, [s for s in ran if math.isfinite(s.get("t_separation",
                                                                            math.nan))]


def _lost(coarse: March, fine: March | None) -> bool:
    """Whether the pair ended on a lost branch (not a fold of the bond, which may be real)."""
    return (fine if fine is not None else coarse).end == "lost"


#: Tolerances over the asked ones tried where those marches lost their branch: a nearly
#: elastic Kelvin-Voigt face (creep time 1e-9 s in a 20 ms pull) lost it at every march
#: tolerance up to 8e-8 (rtol 1e-8) and went to the contact stepper, which did not finish
#: in 10 minutes, while the marches at 8e-6 and 2e-6 ran through and agreed within 2.4e-9.
_LOOSER = (10.0, 100.0)


def _looser_pair(model: EdgeModel, rtol: float, t_limit: float, coarse: March,
                 fine: March | None, estimate: float, ran: list) -> tuple:
    """``(coarse, fine, estimate, notes)``: a pair at looser tolerances whose marches run
    through and agree within ``rtol``, with each other and with every march at the asked
    tolerances that ran through (``ran``, summaries: a looser pair that agreed only with
    itself could be off by more than the tighter marches' differences, a review); they are
    then the answer, with that estimate and a note. Else the lost pair as it was."""
    lost = fine if fine is not None else coarse
    for factor in _LOOSER:
        looser, checked, agreed, _ = _checked_pair(model, rtol, factor * _TOL_PER_RTOL * rtol,
                                                   t_limit)
        if checked is None or _handed_over(checked) or checked.end == "steps":
            continue
        answer = summarise(checked)
        agreed = max([agreed] + [_changes(other, answer) for other in ran])
        if agreed <= rtol:
            where = (f" at t = {lost.hist[0, lost.n - 1] * model.time_scale:.6g} s"
                     if lost.n else "")
            note = (f"the marches at tolerance {lost.tol:.3g} lost their branch{where}; the "
                    f"values are the marches at {looser.tol:.3g} and {checked.tol:.3g}, which "
                    f"agree within rtol" + (" with those that ran through" if ran else ""))
            return looser, checked, agreed, (note,)
    return coarse, fine, estimate, ()


#: A check march's nodes at most, over its coarser march's (plus 200): a march at a quarter of
#: the tolerance takes 1.2-1.6 times the nodes; at the rtol floor on a slow Kelvin-Voigt face
#: (2.2e-7 m/s, tolerance 2e-9) the steps after the rim's release met the gap's rounding and
#: crept on at ~1e-9 of the time unit, 4000 nodes in a minute and on to MAX_NODES.
_CHECK_NODES = 4


def _check_nodes(run: March) -> int:
    return min(MAX_NODES, _CHECK_NODES * run.n + 200)


def _unchecked(scene, model: EdgeModel, coarse: March, fine: March, observers,
               wall: float) -> Result:
    """The coarser march's answer where its check ran out of nodes: no estimate."""
    note = (f"no error estimate: the check run at tolerance {fine.tol:.3g} stopped after "
            f"{fine.n} nodes at t = {fine.hist[0, fine.n - 1] * model.time_scale:.6g} s (its "
            f"steps met the gap's rounding); the values are the run at tolerance "
            f"{coarse.tol:.3g}")
    return _result(scene, model, coarse, math.inf, coarse.evaluations + fine.evaluations,
                   observers, time.perf_counter() - wall, (note,))


_PHASE_NAMES = {2: "the bond receding", 3: "the zone alone"}


def _notes(run: March, scene, estimate: float) -> list:
    notes = []
    if run.end == "no_onset" and run.model.t_strength <= run.t_limit:
        notes.append(f"the face held at its strength limit from t = "
                     f"{run.model.t_strength * run.model.time_scale:.6g} s, and its rim did not "
                     f"open before t_max = {scene.numerics.t_max:.6g} s")
    elif run.end in ("t_max", "no_onset"):
        what = "separation" if run.end == "t_max" else "the onset"
        notes.append(f"{what} not reached before t_max = {scene.numerics.t_max:.6g} s")
    elif run.end == "steps":
        notes.append(f"stopped after {MAX_NODES} steps without separating")
    elif run.end == "snap":
        notes.append("the zone alone cannot hold the punch behind the machine spring where "
                     "the bond radius reaches 0: it snaps off there")
    elif run.end in ("lost", "bond_fold"):
        notes.append(f"no separation time: the march lost its branch at t = "
                     f"{run.hist[0, run.n - 1] * run.model.time_scale:.6g} s "
                     f"({_PHASE_NAMES[_phases(run)[-1]]}), and the contact stepper does not "
                     "take the scene: " + "; ".join(run.refusal))
    elif run.end == "unstable_onset" and run.model.t_strength < run.t_on:
        ts = run.model.time_scale
        notes.append(f"the face held at its strength limit from t = {run.model.t_strength * ts:.6g}"
                     f" s comes off where its rim opens (t = {run.t_on * ts:.6g} s): a smaller "
                     "zone alone opens the gap further")
    elif run.end == "unstable_onset":
        notes.append("the onset is unstable (a receding edge opens the gap further): the "
                     "punch comes off at once")
    return notes


def _result(scene, model: EdgeModel, run: March, estimate: float, evaluations: int,
            observers, wall: float, notes: tuple = ()) -> Result:
    summary = summarise(run)
    spectrum = scene.material.spectrum()
    summary.update(analytic.dimensionless_groups(
        spectrum.G_inf, spectrum.eta, scene.adhesion.sigma_c, scene.adhesion.delta,
        scene.geometry.radius, scene.loading.v))
    rows = history(run)
    keep = observers.kept_rows(rows["t"].size)
    rows = {name: values[keep] for name, values in rows.items()}
    summary.update(error_estimate=float(estimate), observed_order=math.nan,
                   n_elements=0, n_steps=int(evaluations), wall_time=wall,
                   t_end=float(rows["t"][-1]), solver=EdgeQuadratureSolver.name,
                   history=scene.model.history, until=scene.model.until,
                   cohesive_zone=scene.geometry.cohesive_zone)
    return Result.build(summary, analytic.predictions(scene), rows,
                        notes=_notes(run, scene, estimate) + list(notes),
                        problem=Problem.from_scene(scene))
