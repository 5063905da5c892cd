"""The contact stepper: any axisymmetric indenter, any rheology, any loading path, with the contact
edge ``a`` and the zone end ``b`` both free to move (MODEL.md sections 3, 6 and 9).

Units and element law: :mod:`.contact_setup`. One step (:mod:`.contact_step`) advances every
element exactly for its rheology under the load the trial edges give; this module chooses the
trial edges phase by phase, sizes the steps, finds events inside a step and lands a step on
them, and keeps the foundation's elements:

- elements are placed where the zone sweeps: where a receding contact edge releases them and
  where the zone end enters the virgin solid, spaced at most ``zone width / M``; they keep
  their place in ``x``, so elements do not grow with the steps, only with the swept length;
- the zone end is found from ``gap(b) = delta`` (a smooth indenter, or any indenter once the
  edge recedes), or from the edge condition while a flat punch's rim pins the edge (bonded,
  the seed) or the zone (on the face); the contact edge from the edge condition while it
  recedes, from contact (a free element reaching the indenter) while it advances.
"""

from __future__ import annotations

import math

import numpy as np

from ..kernels import contact as K
from . import contact_balance as balance
from . import contact_fold as fold
from . import contact_phases as phases
from . import contact_replay as replay
from . import contact_state as st
from .contact_setup import FLAT_EXTERNAL, FLAT_INTERNAL, Setup
from .contact_step import Evaluation, Step, is_fresh, step_constants

#: Nodes per zone width at resolution n = 64. They grow like sqrt(n) where they enter the zone
#: or are thinned in it (the gap quadrature is fourth order in their spacing, the step second
#: order), but like n from n = 64 on where a receding edge releases them
#: (``Stepper.per_release``): next to the edge the quadrature is second order in their
#: spacing. With sqrt(n) there the seed scene's peak force converged at order 1.1-1.5 in n
#: (errors 1.9e-6, 9.6e-7, 4.2e-7 at n = 64, 128, 256), with n at 1.9-2.3 (1.9e-6, 4.9e-7,
#: 1.1e-7, 2.2e-8 to n = 512), for 8-19 % more time a level there; the other shipped flat
#: punches' results moved by less than their errors. Below n = 64 releases keep the sqrt(n)
#: spacing (so coarse levels are unchanged): a spacing like 1/n there, coarser, cost a zone
#: alone holding a face at n = 16 accuracy (3.1e-8 off, 1.5e-9 before).
_NODES_PER_ZONE = 16.0
#: Elements placed per step where the zone end enters virgin solid (evenly in angle).
ENTRY_NODES = 4
#: The most elements a receding edge releases in one step, in ``per_release``. The count
#: spaces the released stretch at the zone's width when the step starts, which on a face
#: whose rim opens is that of a zone just born: a near-elastic Kelvin-Voigt face
#: (``finite_punch_face`` with ``material.eta = 3``, a creep time 1.5e-4 of the pull) had
#: trials of 2e7 elements and 17 s in its first step (eta = 1: minutes, rtol 1e-3). The
#: shipped flat punches release at most ~55 ``per_release`` in a step.
MOST_RELEASED = 256.0
#: The most elements entering per step to resolve an advancing end's memory, in ``per_zone``.
ENTRY_CAP = 2.0
#: Steps a run may take (per level).
#: A step that went further than this many targets (``1/n`` of the measure) is redone.
REDO_MEASURE = 4.0
MAX_STEPS = 40_000
#: The first step after an event, as a share of the step before it.
RESTART_SHRINK = 16.0
#: The same after the onset: the crack leaves it on a time scale of its own, which the bonded
#: phase's steps do not see (a standard linear solid pulled at 1e-7 m/s: its force peaks
#: 0.15 s after the onset, 1/10 of the last bonded step at n = 16; with 1/16 of that step
#: the peak was missed by 1.6e-4, with 1/256 by 1.4e-6). Four more steps per run.
ONSET_SHRINK = 256.0
#: Where a Kelvin-Voigt bond behind a spring loses its balance, its end is landed on if the
#: ``a^3`` extrapolation puts it within this many last steps (and the bond holds most of the
#: way): near ``a ~ (t_0 - t)^(1/3)`` the balance is ill-conditioned and a step can fail
#: while a longer one from the same state succeeds. compliant_machine.yaml at n = 128 and
#: 256 lost it at a = 0.155 and 0.095 R, 11.7 steps before the end, and reported an arrest;
#: landed, they separate 3.9e-7 and 8.5e-8 off the reference. The horizon is this many
#: steps at n <= 128 and the same time above (steps at n are 1/n of the run's scale): the
#: balance is lost near a = 0.155 R at every level, which at n = 512 is 43 steps before the
#: end, and with 32 steps there the run reported an arrest and no separation.
_LOST_BALANCE_HORIZON = 32.0
_LOST_BALANCE_N = 128
#: Events one step may cross, each located in the step that the one before ended on.
_EVENT_TRIES = 4
#: An edge's travel [L] within this share of the zone's size is its roots' rounding (their
#: secants stop at 1e-14 of the edge, their residuals at ~1e-12 of delta).
_EDGE_ROUNDING = 1e-10
#: The force range the steps start from under a driven lift [sigma_c L^2] (it grows with the
#: force seen): the order of a flat punch's strength limit (pi R^2 sigma_c). From 1e-3 a
#: bonded phase resolved its force on a log scale from t = 0 (sls_finite_punch at n = 32:
#: 340 rows before the onset, 51-122 of them before 1e-3 of its time; from 1: 110-120). With
#: n = 8..128 fitted, every output then converges at order 2.2-3.6 (the peaks included, which
#: stalled before), though n = 8 is coarser; the rate sweep took 26 % less time at the same
#: accuracy.
FORCE_RANGE = 1.0
#: The same where the lift follows a balance (behind a spring, under force control): there
#: the log scale stays. From 1 those runs were 2-4.5x faster and as accurate, but their
#: levels converged less regularly and the estimate grew to 18x the true error
#: (compliant_machine.yaml at rtol 1e-3: error 7.2e-7, estimate 1.3e-5) and 128x (the
#: reference's finite_punch_spring_kv at 1e-6: 1.3e-9, 1.7e-7), over issue 10's 10x.
BALANCED_FORCE_RANGE = 1e-3
#: A zone extrapolated to vanish must still hold this share of the way to its end.
_HOLD_SHARE = 0.9
#: A receding flat punch's zone archives the elements it left behind beyond this many zone
#: widths past its end (and 1e-3 of the end), once there are ARCHIVE_AT of them: a trial that
#: reaches them brings them back (a step moves the end by a small share of that).
ARCHIVE_WIDTHS = 2.0
ARCHIVE_AT = 256


def _real_roots(c2, c1, c0) -> list:
    """Real roots of ``c2 x^2 + c1 x + c0`` (a double root where the pair's imaginary parts
    are below 1e-12, as the rows' extrapolations took ``np.roots``)."""
    if c2 == 0.0:
        return [-c0 / c1] if c1 != 0.0 else []
    disc = c1 * c1 - 4.0 * c2 * c0
    if disc < 0.0:
        return [-c1 / (2.0 * c2)] if math.sqrt(-disc) < 2e-12 * abs(c2) else []
    q = -0.5 * (c1 + math.copysign(math.sqrt(disc), c1))
    return [q / c2, c0 / q] if q != 0.0 else [0.0, 0.0]


class NoSolution(Exception):
    """No state on the current branch at the end of a trial step (it may be a jump)."""


#: A step shorter than this many ulps of the clock would not move it (numpy's finfo costs
#: microseconds a call, every step).
_CLOCK_ULPS = 64 * float(np.finfo(float).eps)


class Stepper:
    """One pass at resolution ``n`` (about ``n`` steps per unit of the step measure)."""

    def __init__(self, setup: Setup, n: int, t_scale: float):
        self.setup = setup
        self.n = n
        self.t_scale = t_scale
        law = setup.law
        self.nodes = st.Nodes(law.n_modes, law.kappa_arms.size)
        self._arms_scratch = np.empty(law.tau_arms.size)
        self._furthest = np.empty(1)  # commit_plain's furthest new element
        self.fresh = is_fresh(setup)
        self.step_constants = step_constants(setup)
        self.per_zone = _NODES_PER_ZONE * math.sqrt(n / 64.0)
        self.per_release = self.per_zone * max(1.0, math.sqrt(n / 64.0))
        self.most_released = MOST_RELEASED * self.per_release
        self.rows = []
        self.row_Hf = []  # the arms' filtered lift at each row (a replay needs it)
        self.row_arrays = None  # the rows as arrays, for replays (contact_replay._history)
        self.events = []  # (t, name)
        self.notes = []  # (what, t): why a run stopped early
        self.kinks = set()  # rows at events: the history may have a corner there
        self.phase_row = 0  # the row where the current phase began
        self.segment = 0
        self.last_dt = None
        # A flat punch's first bond edge: inside it the elements were bonded, beyond it
        # loaded by the zone, and their displacement has a kink there (0: none).
        self.first_edge = 0.0
        # The force balance's Jacobian where the last step of each kind ended
        # (contact_balance: the next step's iterations start from it).
        self.balance_jacobians = {}
        # The ranges the lift and the force are measured in (grow with what is seen).
        self.H_range = max([1.0, abs(setup.h0)] + [abs(d.end[1]) for d in setup.drives
                                                    if d.end[0] == "lift"]
                           + [t_scale * abs(d.rate) for d in setup.drives
                              if d.kind == "speed" and d.end == ("event", "end")])
        self.F_range = max([FORCE_RANGE if self.lift_driven else BALANCED_FORCE_RANGE]
                           + [abs(d.end[1]) for d in setup.drives if d.end[0] == "force"])
        self.now = self._start()
        self.before = None
        self._begin_segment()

    # --- the loading -----------------------------------------------------------------------
    @property
    def drive(self):
        return self.setup.drives[self.segment]

    @property
    def lift_driven(self) -> bool:
        """Whether the lift is prescribed (a rigid machine, or a speed segment)."""
        return self.setup.machine is None and (self.setup.control == "displacement"
                                               or self.drive.kind == "speed")

    @property
    def force_driven(self) -> bool:
        """Whether the force is prescribed (under force control, no speed segment): the lift
        follows it."""
        return not self.lift_driven and self.setup.machine is None

    # --- start -------------------------------------------------------------------------------
    def _start(self) -> st.Instant:
        s = self.setup
        law = s.law
        Hf = np.zeros(law.kappa_arms.size)
        H0 = s.h0
        Hdot = self.drive.rate if self.lift_driven and self.drive.kind == "speed" else 0.0
        kind = s.indenter.kind
        if kind in (FLAT_EXTERNAL, FLAT_INTERNAL):
            Q_b = law.kappa_instant * H0 + law.c * Hdot if law.maxwell else \
                law.kappa_inf * H0 + law.c * Hdot
            if kind == FLAT_EXTERNAL:
                alpha, beta, phase = 1.0, math.hypot(1.0, max(Q_b, 0.0)), st.BONDED
            elif Q_b >= 1.0:
                alpha, beta, phase = 0.0, 1.0, st.FACE
            else:
                alpha, beta, phase = math.sqrt(1.0 - max(Q_b, 0.0) ** 2), 1.0, st.PINNED
            self._preload(alpha, beta, Q_b, H0)
        else:
            alpha, beta, phase = 0.0, 0.0, st.APART
            self.nodes.insert(0.0, t_last=0.0)
        now = st.Instant(0.0, H0, Hdot, alpha, beta, phase, Hf=Hf)
        self.first_edge = alpha if s.flat else 0.0
        ev = Step(self, now, 1e-300, None).evaluate(alpha, beta, H0) if phase != st.APART \
            else None
        if ev is not None:
            now.gap, now.F_contact, now.F_total = ev.gap, ev.F_contact, ev.F_total
            if phase == st.FACE and ev.gap >= 1.0:
                now.phase = st.ZONE
        else:  # apart: the solid at rest, the gap is the tip's lift
            now.gap, now.centre_u = H0, 0.0
        if s.machine is not None:  # the driver stands where the spring holds the indenter
            now.driver = H0 + now.F_total / s.machine
        self._row(now)
        return now

    def _preload(self, alpha, beta, Q_b, H0):
        """Elements inside the zone at t = 0, graded toward its end; a damped solid has not
        moved yet, an elastic one follows its load at once (MODEL.md, settled questions)."""
        law = self.setup.law
        if beta <= alpha:
            return
        m = max(8, int(math.ceil(self.per_zone * 2)))
        theta = np.linspace(0.0, 0.5 * math.pi, m)
        for x in alpha + (beta - alpha) * np.sin(theta[1:]):
            self.nodes.insert(float(x), t_last=0.0)
        del Q_b, H0  # an elastic element has no modes: its U follows Q each evaluation
        if law.n_modes:
            self.nodes.Y[:self.nodes.n] = 0.0

    # --- evaluation details the step needs -----------------------------------------------
    def contact_memory_arms(self, xi, t, contacts):
        """``D_i e^{-(t - tj)/tau_i}`` of a contact element at ``xi`` (a Maxwell solid), arm by
        arm: what its dashpots remember of how it joined (``E_i = Hf_i + g + this``),
        interpolated between the contact elements ``contacts`` (their indices, the step's
        ``Step.contacts``); 0 where none joined by contact (a flat punch bonded from the
        start)."""
        nodes = self.nodes
        law = self.setup.law
        out = np.empty(law.tau_arms.size)
        K._memory(nodes.xi, nodes.status, nodes.D, nodes.tj, nodes.n, law.kappa_arms,
                  law.tau_arms, t, xi, out, contacts)
        return out

    def contact_memory(self, xi, t, contacts):
        """``sum_i kappa_i D_i e^{-(t - tj)/tau_i}``: the arms' memory in the contact load."""
        nodes, law = self.nodes, self.setup.law
        return K._memory(nodes.xi, nodes.status, nodes.D, nodes.tj, nodes.n, law.kappa_arms,
                         law.tau_arms, t, xi, self._arms_scratch, contacts)

    # --- history ---------------------------------------------------------------------------
    def _row(self, now):
        self.rows.append((now.t, now.H, now.alpha, now.beta, now.gap, now.F_contact,
                          now.F_total, float(self.drive.index)))
        self.row_Hf.append(now.Hf.copy())

    # --- where new elements go ------------------------------------------------------------
    @staticmethod
    def _zone_width(now) -> float:
        width = now.beta - now.alpha if now.beta > now.alpha else now.beta
        return max(width, 1e-9 * max(now.beta, 1.0))

    def spacing(self, now) -> float:
        """Target distance between the elements a receding edge releases: a
        ``per_release``-th of the zone's width."""
        return self._zone_width(now) / self.per_release

    def make_step(self, dt) -> Step:
        """A trial step of ``dt``, with the number of new elements chosen from the motion the
        last step predicts."""
        step = Step(self, self.now, dt, self.before)
        now, before = self.now, self.before
        h = self.spacing(now)
        grow_a = grow_b = 0.0
        if before is not None and now.t > before.t:
            rate = dt / (now.t - before.t)
            grow_a = max(before.alpha - now.alpha, 0.0) * rate
            grow_b = max(now.beta - before.beta, 0.0) * rate
        step.k_alpha = max(1, int(math.ceil(min(grow_a / h, self.most_released))))
        # Entering elements evenly in angle, at least per_zone across the zone's angle.
        step.k_beta = ENTRY_NODES
        if grow_b > 0.0 and now.beta > 0.0:
            beta_next = now.beta + grow_b
            start = max(now.beta, self.nodes.xi_max, 0.0)
            swept = math.acos(min(start / beta_next, 1.0))
            zone = replay.zone_angle(now.alpha, now.beta)
            step.k_beta = max(ENTRY_NODES, int(math.ceil(self.per_zone * swept / max(zone, 1e-300))),
                              self._memory_entries(start))
        return step

    def _memory_entries(self, start) -> int:
        """Entering elements that resolve the advancing end's memory: the angle its fastest
        mode spans (``contact_replay.memory_angle``) in steps of ``END_SPACING / per_zone``,
        as next to a receding end, over the stretch beyond ``start``; at most ``ENTRY_CAP
        per_zone``. A slow Kelvin-Voigt pull
        (separation_kv at 1e-7 m/s: a 97 s pull against a 1 ms memory) entered 4 elements a
        step across an end whose displacement turns over within a hundredth of their spacing:
        its onset was 3.2e-5, 2.8e-5, 2.4e-5, 3.4e-6 late at n = 16..128 (not converging);
        now 6.4e-6, -7.6e-7, -2.0e-7, -1.2e-9 against the onset solver. Behind 1 and 10 N/m
        (compliant_machine) the onset force's error at rtol 1e-3 fell from 1.1e-5 and
        2.1e-5 to below 1.6e-6. The cap: 4 gave the slow pull 2-100x less error but took
        compliant_machine behind 1 N/m from 16 s to 35 s at rtol 1e-3 (20 s then; unthinned
        behind a spring then, its entering elements stayed; thinned since the thirteenth
        session), 1 took the one behind 10 N/m to 14 s
        (a bisection; 3.8 s now, 12 s before). Those times hinge on whether a level falls
        into the bisection after a lost balance, which flips with small changes of state
        (README, Known issues)."""
        law, now, before = self.setup.law, self.now, self.before
        if not self.setup.flat or law.fastest_decay == 0.0:
            return 0
        # One count for every trial of the step, from the last step's motion: the longest a
        # step may be (twice the last) sweeps this angle. (Counted from each trial's own
        # length it jumped with the trial, and an event's residual with it, by ~6e-8.)
        grown = now.beta - before.beta
        swept = math.acos(min(start / (now.beta + 2.0 * grown), 1.0))
        theta = replay.memory_angle(law, grown / (now.t - before.t), now.beta)
        want = self.per_zone * swept / (replay.END_SPACING * theta)
        return int(math.ceil(min(want, ENTRY_CAP * self.per_zone)))

    # --- running -----------------------------------------------------------------------------
    def run(self, t_end: float, progress=None) -> None:
        """Step until the loading ends (or the run's end), ``t_end`` or ``MAX_STEPS``."""
        while self.now.phase != st.DONE:
            if self.now.t >= t_end * (1.0 - 1e-14):
                self.notes.append(("t_max", self.now.t))
                break
            if len(self.rows) > MAX_STEPS:
                self.notes.append(("steps", self.now.t))
                break
            self._advance(self._next_dt(t_end))
            if progress is not None:
                progress(1)

    def _next_dt(self, t_end) -> float:
        """About ``1/n`` of the step measure: time in ``t_scale``, the edges' travel in the
        zone's size, the lift's in its range, the force's in its range (each rate from the
        last step, at most doubling per step)."""
        now, before = self.now, self.before
        dt = self.t_scale / self.n
        if self.lift_driven and self.drive.kind == "speed":
            dt = min(dt, self.H_range / (self.n * abs(self.drive.rate)))
        self.H_range = max(self.H_range, abs(now.H))
        self.F_range = max(self.F_range, abs(now.F_total))
        if before is not None and now.t > before.t:
            dt_prev = now.t - before.t
            rate = self._measure(before, now, dt_prev) / dt_prev
            dt = min(1.0 / (self.n * rate), 2.0 * dt_prev)
        elif self.last_dt is not None:
            # After an event the edges may start like sqrt(t - t_event) (a zone left alone, an
            # edge set free): the first step is a fraction of the last, and doubling regrows it.
            onset = self.events and self.events[-1][1] == "onset"
            dt = min(dt, self.last_dt / (ONSET_SHRINK if onset else RESTART_SHRINK))
        # A step must move the clock: below its resolution the run would stand still.
        dt = max(dt, _CLOCK_ULPS * max(abs(now.t), self.t_scale))
        return min(dt, t_end - now.t, self._segment_left())

    def _measure(self, a, b, dt) -> float:
        """How far a step of length ``dt`` went from state ``a`` to ``b``: time in ``t_scale``,
        the edges' travel in the zone's size and in e-folds of a crack growing from its onset
        (:meth:`_growth`), the lift's and the force's in their ranges."""
        scale = max(1.0, b.beta)
        return (dt / self.t_scale
                + (abs(b.alpha - a.alpha) + abs(b.beta - a.beta)) / scale
                + self._growth(a, b, dt)
                + abs(b.H - a.H) / self.H_range
                + abs(b.F_total - a.F_total) / self.F_range)

    def _growth(self, a, b, dt) -> float:
        """How much faster than linearly in time the edges moved away from where the receding
        phase began, over a step from state ``a``: ``ln(D_b / D_a) - ln(t_b / t_a)`` (``D``
        their distance from the phase's first row, ``t`` the time since it), never below 0.

        A crack leaving its onset can grow like an instability (a standard linear solid pulled
        slowly: an elastic crack would run at once, its dashpot makes it grow about
        exponentially, ~55 ms per e-fold against a 155 s pull). Its travel is then a
        thousandth of the zone while its timing is decided, so the travel and time measures
        took steps of several e-folds at every level, doubling from the restart: at
        ``v`` = 1.39e-7 m/s the levels n = 64..512 missed the separation by 1.6e-4, 1.6e-4,
        6e-5, 1.6e-5 (relative; the estimate 3e-5). Measured on a log scale the growth gets
        ``1/n`` of an e-fold per step. Linear growth or slower (a ``sqrt`` onset) costs
        nothing here. Only a flat punch's receding phase is measured so: the bonded phase's
        edge (an internal zone's ``a`` from ``t = 0``) converges without it, at twice the
        steps with it, and a smooth indenter's contact phase begins at the touch, not at an
        onset (an SLS sphere's retraction then crept on for minutes)."""
        if not self.setup.flat or self.now.phase != st.CONTACT_PHASE:
            return 0.0
        start = self.rows[self.phase_row]
        t_a, t_b = a.t - start[0], a.t + dt - start[0]
        d_a = abs(a.alpha - start[2]) + abs(a.beta - start[3])
        d_b = abs(b.alpha - start[2]) + abs(b.beta - start[3])
        # An edge that has moved no further than its roots' rounding does not grow: the
        # logarithm of two rounding errors read 0.5 to 20 e-folds a step on a held edge (a
        # force-controlled hold after its ramp), and its steps were redone down to 1e-11.
        if t_a <= 0.0 or d_a <= _EDGE_ROUNDING * max(1.0, a.beta) or d_b * t_a <= d_a * t_b:
            return 0.0
        return math.log((d_b * t_a) / (d_a * t_b))

    def _segment_left(self) -> float:
        name, value = self.drive.end
        if name == "time":
            return max(self.now.segment_start + value - self.now.t, 0.0) or math.inf
        return math.inf

    def _advance(self, dt) -> None:
        if self._ends_within(dt) or self._bond_vanishes():
            return
        for _ in range(8):
            step = self.make_step(dt)
            try:
                ev = self.solve(step)
            except phases.Lost as lost:
                self._branch_end(dt, lost.what)
                return
            # A step sized from the last one can overshoot where the motion starts at once
            # (a crack leaving its onset): such a step is redone shorter.
            went = self._measure(self.now, ev, dt) * self.n
            floor = _CLOCK_ULPS * max(abs(self.now.t), self.t_scale)
            if went <= REDO_MEASURE or dt <= 2 * floor:
                break
            dt = max(dt * 0.5 / went, floor)
        event = self.crossed(ev)
        if event is None:
            self.commit(step, ev)
            return
        try:
            event, step, ev = self._first_event(event, dt)
        except phases.Lost as lost:
            self._branch_end(dt, lost.what)
            return
        self.commit(step, ev)
        self.transition(event)

    def _first_event(self, event, dt):
        """``(event, step, evaluation)`` landed on the first event of a step of ``dt`` that
        crosses ``event`` and maybe others: which comes first is guessed linearly
        (:meth:`crossed`), and where another one has crossed by the time the guess is landed
        on, that one is located instead, inside the shorter step (else the phase went on
        past it: a bonded punch's gap above delta after the end of a force ramp)."""
        for _ in range(_EVENT_TRIES):
            step, ev = self._locate(event, dt)
            earlier = self.crossed(ev)
            if earlier is None or earlier == event:
                break
            event, dt = earlier, step.dt
        return event, step, ev

    def _last_quadratic(self, column, power=1):
        """``(t2, c, shrank)``: the quadratic ``c`` (in ``t - t2``) through the last three rows
        of this phase where row ``column`` is positive, of that column to the ``power``, and
        whether it fell over the last of them; None without three such rows at distinct
        times. Scanned from the end: it runs every step."""
        picked = []
        for k in range(len(self.rows) - 1, self.phase_row - 1, -1):
            if self.rows[k][column] > 0.0:
                picked.append(self.rows[k])
                if len(picked) == 3:
                    break
        if len(picked) < 3:
            return None
        (t2, y2), (t1, y1), (t0, y0) = [(r[0], r[column] ** power) for r in picked]
        if not t0 < t1 < t2:
            return None
        # Newton's form through (t0 - t2, y0), (t1 - t2, y1), (0, y2), highest power first.
        x0, x1 = t0 - t2, t1 - t2
        slope = (y2 - y1) / -x1
        curve = (slope - (y1 - y0) / (x1 - x0)) / -x0
        return t2, (curve, slope - curve * x1, y2), y2 < y1

    def _vanishes_within(self, dt, column, power=2):
        """The time at which an edge (row ``column``) that vanishes like
        ``(t_end - t)^(1/power)`` reaches 0 within the next ``dt``, or None. Its equation
        becomes ill-conditioned there, but its ``power`` is smooth in time: the root of the
        quadratic through its last three values in this phase is the end."""
        fit = self._last_quadratic(column, power)
        if fit is None or not fit[2]:
            return None
        roots = [r for r in _real_roots(*fit[1]) if r > 0.0]
        if not roots or min(roots) > dt:
            return None
        return self.now.t + min(roots)

    def _land(self, t_end, what, **values) -> None:
        """End the phase at ``t_end`` with the state ``values`` (a vanishing edge's limit): the
        lift driven, or where the machine's spring holds their force."""
        now = self.now
        driver = now.driver + self._driver_rate() * (t_end - now.t)
        if self.setup.machine is not None:
            H = driver - values["F_total"] / self.setup.machine
        else:
            H = now.H + (t_end - now.t) * (self.drive.rate if self.lift_driven
                                            and self.drive.kind == "speed" else now.Hdot)
        self.before, self.last_dt = now, t_end - now.t
        self.now = now.copy(t=t_end, H=H, driver=driver, **values)
        self._row(self.now)
        self.transition(what)

    def _ends_within(self, dt) -> bool:
        """Land on separation where the zone alone vanishes like ``b ~ sqrt(t_sep - t)``. Not
        where its branch folds at a finite ``b`` first (a DMT-like sphere's last zone: with
        coarse steps its ``b^2`` extrapolated past the fold, and the run came apart late and
        without the jump): the zone must still hold most of the way to the end."""
        if self.now.phase != st.ZONE:
            return False
        t_end = self._vanishes_within(dt, 3)
        if t_end is None or not self._holds(_HOLD_SHARE * (t_end - self.now.t)):
            return False
        self._land(t_end, "separation", beta=0.0, gap=1.0, F_total=0.0, F_contact=0.0)
        return True

    def _bond_vanishes(self, horizon=None) -> bool:
        """Step onto the end of a receding flat-punch bond. Under a driven lift
        ``a ~ (t_0 - t)^(1/2)`` (sls_finite_punch at n = 32: ``a^2 / (t_0 - t)`` 8.2..9.2 over
        the last ten rows; separation_kv 105..107), so ``a^2`` is extrapolated; behind a
        spring the punch relaxes against it ever faster and ``a ~ (t_0 - t)^(1/3)``
        (compliant_machine.yaml at n = 64: ``a^3 / (t_0 - t)`` within 2 % over the last six
        rows), so ``a^3``; under a driven force likewise (separation_kv pulled at 0.1 N/s:
        ``d(a^3)/dt`` within 3 % over the last eleven rows at n = 64, 128 and 256). It lands
        within ``horizon`` steps of the end (by default the next step under a driven lift,
        two otherwise), where the bond still holds most of the way (no fold first). The last
        steps toward the end are ill-conditioned: behind the spring the balance was lost at
        a = 0.55, 0.14, 0.09 (n = 16, 32, 64) and the punch reported to snap off there; under
        a driven force at a = 0.063 and 0.13 (n = 128, 256), the separation 6.7e-6 and
        4.5e-5 early and not converging; under a driven lift a step failed at a = 0.029 and
        the bisection to the end took a quarter of the run's evaluations. The step to
        ``t_0`` ends in the zone-alone phase."""
        now = self.now
        if now.phase != st.CONTACT_PHASE or not self.setup.flat or self.last_dt is None:
            return False
        driven = self.lift_driven
        if horizon is None:
            horizon = 1.0 if driven else 2.0
        t_end = self._vanishes_within(horizon * self.last_dt, 2, 2 if driven else 3)
        if t_end is None or not self._holds(_HOLD_SHARE * (t_end - now.t)):
            return False
        step = self.make_step(t_end - now.t)
        now.phase = st.ZONE
        try:
            ev = self.solve(step)
        except phases.Lost:
            ev = None
        finally:
            now.phase = st.CONTACT_PHASE
        if ev is None and driven:
            return False  # (finite_punch_internal at n = 8: its zone-alone phase; stepped to)
        if ev is None:
            # No zone-alone state balances the spring (or the driven force) at a = 0
            # (measured: the punch lets go there, the reference's "snap_at_a_zero"). The
            # bond's elements go free with their state now; they would relax unloaded for the
            # short landing.
            zone = self._last_quadratic(3)  # the zone end stays smooth: b ~ b0 + c (t0 - t)
            beta = float(np.polyval(zone[1], t_end - zone[0])) if zone else now.beta
            force = math.pi * beta ** 2
            if self.force_driven:  # the force driven then
                force = now.F_total + self._force_rate() * (t_end - now.t)
            self._release_all()
            self._land(t_end, "contact", alpha=0.0, beta=beta, F_contact=0.0, F_total=force)
            return True
        self.commit(step, ev)
        self.transition("contact")
        return True

    def _holds(self, dt) -> bool:
        """Whether the phase has a state ``dt`` from now."""
        try:
            self.solve(self.make_step(dt))
        except phases.Lost:
            return False
        return True

    def _reaches_strength(self) -> bool:
        """Land on the strength limit where a bond on a finite punch's face vanishes but its
        last steps fail first (behind a spring the balance is lost a step early, and the run
        snapped off at ``a`` ~ 1/n: first order). Behind a spring ``a ~ (t_s - t)^(1/3)``
        (the punch relaxes against it ever faster as ``a -> 0``; the reference's analysis):
        ``a^3`` is extrapolated (measured 1.1e-5 off the reference at n = 256 with ``a^2``,
        2.9e-6 with ``a^3``). Within four steps of the extrapolated end, and with no onset
        (the rim's gap reaching 1) before it."""
        if self.now.phase != st.PINNED or self.setup.machine is None or self.last_dt is None:
            return False
        if self.now.alpha <= 0.0:  # the last step already ended on the limit
            self.transition("strength")
            return True
        t_end = self._vanishes_within(4.0 * self.last_dt, 2, 3)
        if t_end is None:
            return False
        rim = self._last_quadratic(4)  # the rim's gap, to check no onset comes first
        if rim is None or np.polyval(rim[1], t_end - rim[0]) >= 1.0:
            return False
        beta = self.now.beta
        self._land(t_end, "strength", alpha=0.0, F_contact=0.0, F_total=math.pi * beta * beta)
        return True

    def solve(self, step) -> Evaluation:
        """The state at the end of ``step`` that satisfies the phase's conditions."""
        if self.lift_driven:
            drive = self.drive
            H = self.now.H + (drive.rate * step.dt if drive.kind == "speed" else 0.0)
            return self._phase(step, H)
        return self._balanced(step)

    def guesses(self, step) -> tuple[float, float]:
        """The edge and the zone end at the end of ``step`` extrapolated from the last step."""
        now, before = self.now, self.before
        if before is None or now.t <= before.t:
            return now.alpha, now.beta
        f = step.dt / (now.t - before.t)
        return (max(now.alpha + f * (now.alpha - before.alpha), 0.0),
                max(now.beta + f * (now.beta - before.beta), 0.0))

    def _phase(self, step, H) -> Evaluation:
        now = self.now
        guess_a, guess_b = self.guesses(step)
        phase = now.phase
        if phase == st.BONDED:
            return phases.bonded(step, H)
        if phase == st.PINNED:
            return phases.pinned(step, H)
        if phase == st.CONTACT_PHASE:
            if self.setup.flat:
                return phases.flat_contact(step, H, guess_a)
            return phases.smooth_contact(step, H, guess_a)
        if phase == st.ZONE:
            return phases.zone_only(step, H, guess_b)
        if phase == st.FACE:
            return phases.face(step, H)
        return phases.apart(step, H)

    def force_residual(self, dt):
        """The force balance at the end of a step of ``dt`` behind the machine spring or under
        the driven force, as a function of the evaluation there (zero when it holds)."""
        s, now, drive = self.setup, self.now, self.drive
        if s.machine is not None:
            driver = now.driver + drive.rate * dt
            return lambda ev: s.machine * (driver - ev.H) - ev.F_total
        target = now.F_total + self._force_rate() * dt
        return lambda ev: target - ev.F_total

    def _balanced(self, step) -> Evaluation:
        """The lift at the end of the step balances the machine spring or the driven force:
        Newton on the lift and the phase's own unknown together."""
        s = self.setup
        now = self.now
        drive = self.drive
        force_residual = self.force_residual(step.dt)
        # After an event the paths restart; the lift's rate still carries over (a viscous
        # solid's force follows the rate: a short step tolerates only a narrow lift).
        rate = now.Hdot if math.isfinite(now.Hdot) else 0.0
        if rate == 0.0 and s.machine is not None and drive.kind == "speed":
            rate = drive.rate  # at rest: the driver's speed sizes the lift's first move
        if self.before is not None and now.t > self.before.t:
            rate = (now.H - self.before.H) / (now.t - self.before.t)
        guess = now.H + rate * step.dt
        return balance.solve(self, step, guess, force_residual, abs(rate) * step.dt)

    # --- events ------------------------------------------------------------------------------
    def event_values(self, x) -> dict:
        """Continuous functions of an instant or evaluation whose sign change is an event (from
        negative to non-negative)."""
        phase = self.now.phase
        out = {}
        if phase in (st.BONDED, st.PINNED):
            out["onset"] = x.gap - 1.0
        if phase == st.FACE:
            out["release"] = x.gap - 1.0
        centre_gap = x.H - x.centre_u if math.isfinite(x.centre_u) else math.nan
        if phase == st.APART and math.isfinite(centre_gap):
            out["birth"] = 1.0 - centre_gap
        if phase == st.ZONE and math.isfinite(centre_gap):
            if not self.setup.flat:  # a flat punch's face does not re-bond
                out["touch"] = -centre_gap
            out["separation"] = centre_gap - 1.0
        out.update(self._knot_values(x))
        name, value = self.drive.end
        t = x.t if isinstance(x, st.Instant) else self.now.t + x.dt
        if name == "time":
            out["end"] = t - (self.now.segment_start + value)
        elif name in ("lift", "force"):
            current = x.H if name == "lift" else x.F_total
            out["end"] = self.now.segment_sign * (current - value)
        return out

    def _knot_values(self, x) -> dict:
        """A tabulated tip's force has a corner wherever an edge crosses a knot (the
        interpolant's slope jumps there): each crossing is an event, so that no step straddles
        a corner and a peak at one is sampled exactly. The knots next to each edge are those
        of the current instant, whichever way the edge moves."""
        knots = self.setup.indenter.knots
        if not knots.size or self.now.phase not in (st.CONTACT_PHASE, st.ZONE):
            return {}
        out = {}
        for name in ("alpha", "beta"):
            e0, e1 = getattr(self.now, name), getattr(x, name)
            if name == "alpha" and (self.now.phase != st.CONTACT_PHASE or e0 <= 0.0):
                continue
            if not (e0 > 0.0 and math.isfinite(e1)):
                continue
            margin = 1e-12 * e0
            j = int(np.searchsorted(knots, e0 + margin, side="right"))
            if j < knots.size:
                out[f"knot_{name}_up"] = e1 - knots[j]
            j = int(np.searchsorted(knots, e0 - margin, side="left")) - 1
            if j >= 1:  # the knot at the centre is no corner of a moving edge
                out[f"knot_{name}_down"] = knots[j] - e1
        return out

    def crossed(self, ev):
        """The first event between now and ``ev`` (by a linear guess of where it falls)."""
        before = self.event_values(self.now)
        after = self.event_values(ev)
        best, best_frac = None, math.inf
        for name, v1 in after.items():
            v0 = before.get(name, math.nan)
            if math.isfinite(v0) and math.isfinite(v1) and v0 < 0.0 <= v1:
                frac = -v0 / (v1 - v0)
                if frac < best_frac:
                    best, best_frac = name, frac
        return best

    def _locate(self, event, dt):
        """Re-solve the step so that it ends on ``event`` (a root in its length)."""
        v0 = self.event_values(self.now)[event]
        cache = {}

        def value(d):
            step = self.make_step(d)
            ev = self.solve(step)
            ev.dt = d
            cache[d] = (step, ev)
            return self.event_values(ev)[event]

        v1 = value(dt)
        lo, hi, f_lo, f_hi = 0.0, dt, v0, v1
        last_lost = None
        for _ in range(100):
            # Illinois-flavoured regula falsi, falling back to bisection.
            d = hi - f_hi * (hi - lo) / (f_hi - f_lo) if f_hi != f_lo else 0.5 * (lo + hi)
            if not lo < d < hi:
                d = 0.5 * (lo + hi)
            try:
                f = value(d)
            except phases.Lost as lost:
                hi, f_hi = d, abs(f_hi)  # the branch ends before: the event is earlier
                last_lost = lost
                continue
            if 0.0 <= f <= 1e-13:
                # On the event, to rounding, on its far side (an event landed short of it
                # would cross again). Converged from below, the search goes on until the
                # bracket closes: it once stopped there and took the bracket's far end, and a
                # target met in one step from below (a driven force meeting its segment's
                # end) ended its segment a whole step late.
                return cache[d]
            if f >= 0.0:
                hi, f_hi = d, f
                f_lo *= 0.5
            else:
                lo, f_lo = d, f
                f_hi *= 0.5
            if hi - lo <= 1e-15 * max(self.now.t + dt, self.t_scale):
                break
        if hi in cache:
            return cache[hi]
        if d in cache:
            return cache[d]
        raise last_lost  # the branch ends before any event: not one to land on

    def _branch_end(self, dt, what) -> None:
        """No state of the phase at the end of the step. If there is none even a moment
        later, the branch ends here (at a natural limit, or by a jump, resolved as two rows
        at one time); otherwise step to the longest step that works (by bisection) and try
        again from there."""
        if (what == "balance" and self.setup.law.c > 0.0
                and self._bond_vanishes(_LOST_BALANCE_HORIZON
                                        * max(1.0, self.n / _LOST_BALANCE_N))):
            return
        # A moment is at least a few units of the clock's rounding: a shorter one is no step
        # at all, its state is the one at hand, and the branch was searched for a fold and
        # bisected to a 1e-13 step (4.5 s of a 5.7 s level behind a spring).
        moment = min(max(1e-12 * dt, _CLOCK_ULPS * max(abs(self.now.t), self.t_scale)), dt)
        try:
            self.solve(self.make_step(moment))
        except phases.Lost:
            if not self._reaches_strength():
                self.transition(what)
            return
        if self._at_limit(what):
            self.transition(what)
            return
        if fold.foldable(self, what):
            found = fold.locate(self, dt, what)
            if found is not None:
                if found != fold.NOW:
                    self.commit(*found)
                self.transition(what)
                return
        best, lo = self._longest_step(dt, what)
        if best is None:
            self.transition(what)
            return
        self.commit(*best)
        if self._at_limit(what) or lo <= 1e-10 * self.t_scale:
            self.transition(what)  # the natural end, or only a vanishing step still works

    def _longest_step(self, dt, what):
        """``((step, evaluation), length)`` of the longest step up to ``dt`` whose state
        exists and crosses no event (bisection to 1e-14 of the time), ``(None, 0)`` if none."""
        lo, hi = 0.0, dt
        best = None
        for _ in range(100):
            mid = 0.5 * (lo + hi)
            step = self.make_step(mid)
            try:
                ev = self.solve(step)
            except phases.Lost:
                hi = mid
                continue
            if self.crossed(ev) is not None:
                hi = mid  # an event comes first: take it at its own time
                continue
            lo, best = mid, (step, ev)
            if self._at_limit(what, ev) or hi - lo <= 1e-14 * max(self.now.t + hi, 1.0):
                break
        return best, lo

    def _at_limit(self, what, now=None) -> bool:
        """Whether the state (now, or an evaluation) is at the natural end of its branch: the
        edge at the centre, the zone gone, or (whatever the state) a flat punch's zone alone
        under a rising force (it pulls with ``sigma_c pi b^2`` and cannot grow, its broken
        bonds do not re-form: no state carries more than it does now; located as a fold and
        then bisected, the end took 4.3 s of a 5.1 s level)."""
        now = now or self.now
        # A sliver this thin released at once changes the gap by ~(sliver)^2.
        if what == "contact":
            return now.alpha <= 1e-6 * max(now.beta, 1.0)
        if what == "zone":  # a vanishing zone, not one being born
            return now.beta <= 1e-6 and not self._growing_zone()
        if what == "balance":
            return self.setup.flat and self.now.phase == st.ZONE and self._force_rate() > 0.0
        return False

    # --- committing a step ---------------------------------------------------------------------
    def commit(self, step, ev) -> None:
        """Make the end of ``step`` the new instant: element states, statuses, new elements."""
        t1 = self.now.t + step.dt
        if step.fresh or not self._commit_plain(ev, t1):
            self._commit_elements(step, ev, t1)
        if self.setup.law.maxwell and not self.setup.flat:
            self._edge_node(ev, t1)
        self.before = self.now
        self.last_dt = step.dt
        self.now = self.now.copy(t=t1, H=ev.H, Hdot=ev.Hdot, alpha=ev.alpha, beta=ev.beta,
                                 gap=ev.gap, F_contact=ev.F_contact, F_total=ev.F_total,
                                 Hf=ev.Hf.copy(), centre_u=ev.centre_u,
                                 driver=self.now.driver + self._driver_rate() * step.dt)
        self._row(self.now)
        replay.refine(self)
        replay.fill_receding_end(self)
        replay.thin(self)
        self._archive_behind()

    def _commit_plain(self, ev, t1) -> bool:
        """The step's elements committed in one compiled call where no capture, restore or
        growth asks for :meth:`_commit_elements` (most steps: its array operations on a few
        dozen elements were a fifth of a standard linear solid's run); whether it was."""
        nodes, law = self.nodes, self.setup.law
        mesh = nodes.mesh
        added, inside = K.commit_plain(mesh, nodes.n, ev.lo, ev.hi, ev.xi, ev.Y, ev.flags,
                                       ev.alpha, t1, nodes.live_end, self._furthest)
        if added < 0:
            return False
        nodes.n += added
        if added:
            nodes.xi_max = max(nodes.xi_max, float(self._furthest[0]))
        if law.maxwell:
            for i in inside.tolist():
                nodes.D[i, :law.tau_arms.size] = self._joining_memory(nodes.Y[i], ev.Hf,
                                                                      float(nodes.xi[i]))
        return True

    def _joining_memory(self, Y, Hf, x):
        """What the arms of an element at ``x`` with modes ``Y`` remember on joining the
        contact with the filtered lift ``Hf``: ``D = E - Hf - g(x)``."""
        law = self.setup.law
        return law.V @ Y[:law.n_modes] - Hf - self.setup.indenter.g(x)

    def _commit_elements(self, step, ev, t1) -> None:
        """The step's elements committed in Python: captures, releases, new elements."""
        nodes = self.nodes
        lo, hi = ev.lo, ev.hi
        status = nodes.status[lo:hi]
        x = nodes.xi[lo:hi]
        released = (status == st.CONTACT) & (x > ev.alpha)
        captured = np.nonzero((status == st.FREE) & (x <= ev.alpha) & (ev.alpha > 0.0))[0]
        for j in captured:  # before the modes move on: capture needs them at the start
            self._capture(step, ev, lo + j)
        nodes.Y[lo:hi] = ev.Y[~ev.virtual]
        nodes.t_last[lo:hi] = t1
        status[released] = st.FREE
        if not step.fresh:  # an elastic solid's evaluations place their own elements
            self._insert_new(ev, t1)

    def _archive_behind(self) -> None:
        """A flat punch's zone end receding archives what it leaves behind (``Nodes``)."""
        now, before = self.now, self.before
        if not self.setup.flat or now.beta <= 0.0 or now.beta >= before.beta:
            return
        cut = now.beta * (1.0 + 1e-3) + ARCHIVE_WIDTHS * (now.beta - now.alpha)
        self.nodes.archive_beyond(cut, ARCHIVE_AT)

    def _insert_new(self, ev, t1) -> None:
        """The step's new elements join the mesh. One new in the step and already inside the
        contact (a jump in, or an edge overtaking the zone's new elements) joins it at the
        step's end, with the dashpot state it has (virgin in a jump: the glassy response)."""
        nodes, law = self.nodes, self.setup.law
        xs, Ys = ev.xi[ev.virtual], ev.Y[ev.virtual]
        inside = (xs > 0.0) & (xs <= ev.alpha)
        D = np.zeros((xs.size, nodes.D.shape[1]))
        if law.maxwell:
            for j in np.nonzero(inside)[0]:
                D[j, :law.tau_arms.size] = self._joining_memory(Ys[j], ev.Hf, float(xs[j]))
        nodes.insert_many(xs, Ys, np.where(inside, st.CONTACT, st.FREE), D,
                          np.where(inside, t1, 0.0), t1)

    def _edge_node(self, ev, t1) -> None:
        """An advancing smooth contact gets a contact element at its new edge, joined now
        with the free state there: the contact memory then runs continuously into the free
        side's state (the edge condition's load has no jump at the old edge)."""
        nodes = self.nodes
        if ev.alpha <= self.now.alpha or nodes.near(ev.alpha, 1e-12 * max(ev.alpha, 1.0)):
            return
        free = ~ev.stays & (ev.xi > ev.alpha)
        if np.count_nonzero(free) < 2:
            return
        law = self.setup.law
        xs = ev.xi[free]
        Y = np.array([np.interp(ev.alpha, xs, ev.Y[free][:, k]) for k in range(law.n_modes)])
        D_full = np.zeros(nodes.D.shape[1])
        D_full[:law.tau_arms.size] = self._joining_memory(Y, ev.Hf, ev.alpha)
        nodes.insert(float(ev.alpha), Y, st.CONTACT, D=D_full, tj=t1, t_last=t1)

    def _driver_rate(self) -> float:
        drive = self.drive
        return drive.rate if drive.kind == "speed" else 0.0

    def _capture(self, step, ev, i) -> None:
        """Element ``i`` joins the contact inside the step: remember how (Maxwell arms)."""
        nodes = self.nodes
        nodes.status[i] = st.CONTACT
        law = self.setup.law
        ap = step.path("alpha", ev.alpha)
        s_c = K.path_root(ap[0], ap[1], ap[2], nodes.xi[i])
        nodes.tj[i] = self.now.t + s_c * step.dt
        if not law.maxwell:
            return
        bp = step.path("beta", ev.beta)
        ints = np.zeros(law.n_modes)
        K.load_integrals(bp[0], bp[1], bp[2], nodes.xi[i], 0.0, s_c, step.mus, law.n_modes,
                         step.w3, ints)
        Y_c = np.exp(-step.mus * s_c) * nodes.Y[i, :law.n_modes] + law.z * step.dt * ints
        E = law.V @ Y_c
        nodes.D[i, :law.tau_arms.size] = (E - step.filtered_lift(ev.H, s_c)
                                          - self.setup.indenter.g(nodes.xi[i]))

    # --- transitions -----------------------------------------------------------------------------
    def transition(self, what) -> None:
        """Apply an event at the current instant (the step was landed on it)."""
        now = self.now
        self.before = None  # the edges may kink here: paths restart
        self.phase_row = len(self.rows) - 1
        self.events.append((now.t, what))
        self.kinks.add(len(self.rows) - 1)
        if sum(t == now.t for t, _ in self.events[-12:]) > 10:  # a bug, not input
            raise RuntimeError(f"no progress at t = {now.t}: events {self.events[-12:]}")
        if what == "onset":
            now.phase = st.CONTACT_PHASE
            return self._physical_end("onset")
        if what == "strength":
            # The bond's last point: the limit a -> 0 (the step landed within 1e-6 of it),
            # where the face pulls at sigma_c alone and the contact carries nothing.
            now.alpha, now.F_contact = 0.0, 0.0
            now.F_total = math.pi * now.beta ** 2
            self.rows[-1] = (now.t, now.H, 0.0, now.beta, now.gap, 0.0, now.F_total,
                             self.rows[-1][7])
            self.events.append((now.t, "onset"))
            self._release_all()
            # The zone alone then holds the whole face until the rim's gap reaches delta (it
            # was once put in the zone-alone phase at once, which has no state with
            # gap(R) < delta: an elastic punch was reported apart with the rim at 0.61 delta).
            now.phase = st.FACE if now.gap < 1.0 else st.ZONE
            return self._physical_end("onset")
        if what == "release":  # the rim's gap reached delta: the zone recedes from the rim
            now.phase = st.ZONE
            return None
        if what == "contact":
            at_limit = self._at_limit("contact")
            self._release_all()
            now.phase = st.ZONE
            if not self.setup.flat and not at_limit:
                return self._jump("out")
            return
        if what == "advance":
            return self._jump("in")
        if what in ("separation", "zone", "balance"):
            return self._branch_lost(what)
        if what == "birth":
            now.phase = st.ZONE
            return
        if what in ("touch", "advance"):
            return self._touch()
        if what == "end":
            return self._next_segment()
        if what.startswith("knot_"):
            return
        raise RuntimeError(f"unknown event {what!r}")  # a bug, not input

    def _branch_lost(self, what) -> None:
        """The separation, or the end of the zone's or the force balance's branch: a jump
        into contact (an approach), an arrest behind a spring, or the indenter off."""
        now = self.now
        if now.phase == st.APART:  # (never touched, or apart already: nothing comes off)
            self._free_under_force()
            return None
        if what in ("zone", "balance") and now.alpha == 0.0 and self._growing_zone():
            # (behind a spring the zone's lost branch shows as a lost balance)
            self._touch()
            return self._jump("in")
        if (what == "balance" and now.alpha > 0.0 and now.phase == st.CONTACT_PHASE
                and self.setup.law.c > 0.0 and self.setup.machine is not None):
            return self._arrest()
        if what == "balance":
            # No equilibrium under the spring or the force: the indenter snaps off (the zone
            # alone too: its force drops to zero at once); a bond that had held until then
            # fails in that instant (its onset).
            if now.phase in (st.BONDED, st.PINNED) and not any(
                    name == "onset" for _, name in self.events):
                self.events.append((now.t, "onset"))
            self.events.append((now.t, "jump_out"))
        if what == "zone" and not self._at_limit("zone"):
            # A zone alone whose branch folds while it still pulls (a DMT-like sphere's last
            # zone): the force drops to zero at once, a jump.
            self.events.append((now.t, "jump_out"))
        now.phase, now.alpha, now.beta = st.APART, 0.0, 0.0
        self.events.append((now.t, "separated"))
        self._row(now)
        if self.setup.until == "detach" and any(n == "onset" for _, n in self.events):
            return self._physical_end("onset")
        self._physical_end("separation")
        if now.phase != st.DONE:
            # Off inside a segment that drives the force: the path cannot go on (a hold past
            # the separation looped on its lost balance until the run stopped).
            self._free_under_force()
        return None

    def _growing_zone(self) -> bool:
        """Whether a zone-only branch ended while the zone grew or was just born (an approach:
        the surface jumps into contact), not while it shrank (the surfaces come apart). A
        flat punch never re-bonds."""
        rows = self.rows
        if self.setup.flat or self.events[-2:-1] == [(self.now.t, "contact")]:
            return False
        born = [t for t, name in self.events if name == "birth"]
        just_born = bool(born) and rows[self.phase_row][3] <= 0.0
        return just_born or (len(rows) > 2 and rows[-1][3] > rows[-2][3])

    def _jump(self, kind) -> None:
        """A zero-time transition (a fold of the branch): the new state at the same time,
        searched widely, recorded as its own row; ``in`` lands in contact, ``out`` in the
        zone alone (or apart, when no zone holds)."""
        now = self.now
        step = Step(self, now, 1e-12 * self.t_scale, None)
        step.k_alpha, step.k_beta, step.jump = 1, int(4 * self.per_zone), True
        try:
            ev = self.solve(step)
        except phases.Lost:
            if kind == "in" and self._driver_rate() <= 0.0:
                raise RuntimeError(f"no contact state to jump into at t = {now.t}") from None
            # Retracting, a zone that ended while still growing has no contact to land in:
            # it lets go (a DMT-like sphere's last zone).
            self.events.append((now.t, "jump_out"))
            now.phase, now.alpha, now.beta = st.APART, 0.0, 0.0
            self.events.append((now.t, "separated"))
            self._row(now)
            return self._physical_end("separation")
        self.events.append((now.t, f"jump_{kind}"))
        self.kinks.add(len(self.rows) - 1)
        self.commit(step, ev)
        if self.setup.law.maxwell and self.now.alpha > 0.0:
            self._recount_forces()
        self.kinks.add(len(self.rows) - 1)
        self.phase_row = len(self.rows) - 1
        self.before = None

    def _recount_forces(self) -> None:
        """The forces of the instant again, now that the elements a jump brought into contact
        remember how they joined (the jump's own evaluation counted them as relaxed)."""
        step = Step(self, self.now, 1e-12 * self.t_scale, None)
        now = self.now
        ev = step.evaluate(now.alpha, now.beta, now.H)
        now.F_contact, now.F_total = ev.F_contact, ev.F_total
        row = list(self.rows[-1])
        row[5], row[6] = now.F_contact, now.F_total
        self.rows[-1] = tuple(row)

    def _touch(self) -> None:
        """The surface meets the indenter at the centre: contact begins there."""
        now = self.now
        nodes = self.nodes
        if nodes.n and nodes.xi[0] == 0.0:
            nodes.status[0] = st.CONTACT
            nodes.tj[0] = now.t
            law = self.setup.law
            if law.maxwell:
                E = law.V @ nodes.Y[0, :law.n_modes]
                nodes.D[0, :law.tau_arms.size] = E - now.Hf
        now.phase = st.CONTACT_PHASE
        now.alpha = 0.0

    def _release_all(self) -> None:
        """The contact is lost at once: its elements go free with their contact state (a
        flat punch's bonded elements get elements of their own first)."""
        now = self.now
        nodes = self.nodes
        law = self.setup.law
        if self.setup.flat and now.alpha > 0.0:
            # (per_zone, not per_release: no edge is left to resolve, and a thin zone would
            # put alpha / width times per_release elements on the face)
            count = max(2, int(math.ceil(now.alpha / (self._zone_width(now) / self.per_zone))))
            for x in np.linspace(0.0, now.alpha, count + 1)[:-1]:
                if not nodes.near(float(x), 1e-14):
                    nodes.insert(float(x), status=st.CONTACT, t_last=now.t)
        elif not nodes.near(0.0, 0.0):
            nodes.insert(0.0, status=st.CONTACT, t_last=now.t)
        idx = np.nonzero((nodes.status[:nodes.n] == st.CONTACT)
                         & (nodes.xi[:nodes.n] <= now.alpha))[0]
        step = Step(self, now, 1e-300, None)
        for i in idx:
            if law.n_modes:
                nodes.Y[i, :law.n_modes] = step.released_modes(nodes.xi[i], 0.0, now.H)
            nodes.status[i] = st.FREE
            nodes.t_last[i] = now.t
        now.alpha = 0.0

    def _arrest(self) -> None:
        """A receding bond on a solid with a dashpot in parallel (Kelvin-Voigt) behind a
        spring whose balance is lost while it still holds: the lift cannot jump (the
        dashpots would take an infinite force), so this is no snap: a step too coarse for
        the bond's last stretch, or a crack that arrests (its edge would advance again, which
        neither method models). Behind 1 N/m this stopped every level three steps after the
        onset until the crack's growth was measured in e-folds (:meth:`_growth`); it now runs
        through and snaps at a = 0, as the reference does given the propagation's time scale
        (from its own coarse pilot it too reported an arrest). The run stops here without a
        separation."""
        self.notes.append(("arrest", self.now.t))
        self.now.phase = st.DONE

    def _physical_end(self, name) -> None:
        """An onset or separation: the end of the run or of the segment waiting for it."""
        if self.setup.until == "detach" and name == "onset":
            self.now.phase = st.DONE
        elif self.setup.until == "separation" and name == "separation":
            self.now.phase = st.DONE
        elif self.drive.end == ("event", name):
            self._next_segment()

    def _next_segment(self) -> None:
        if self.segment + 1 >= len(self.setup.drives):
            self.now.phase = st.DONE
            return
        self.segment += 1
        if self._free_under_force():
            return
        self._begin_segment()

    def _free_under_force(self) -> bool:
        """End the run where an indenter apart would have to carry a driven force (a force
        or hold segment under force control): a free indenter carries none. (A hold after a
        speed segment that ended apart moved it on at its last speed; a force segment
        there stopped with a RuntimeError.)"""
        if self.now.phase != st.APART or not self.force_driven:
            return False
        self.notes.append(("free", self.now.t))
        self.now.phase = st.DONE
        return True

    def _force_rate(self) -> float:
        drive = self.drive
        return drive.rate if drive.kind == "force_rate" else 0.0

    def _begin_segment(self) -> None:
        now = self.now
        now.segment = self.segment
        now.segment_start = now.t
        name, value = self.drive.end
        if name in ("lift", "force"):
            current = now.H if name == "lift" else now.F_total
            now.segment_sign = 1.0 if value >= current else -1.0
        if self.lift_driven and self.drive.kind == "speed":
            now.Hdot = self.drive.rate
