"""New elements with their whole history: since elements do not interact, the state of an
element anywhere follows from the edges' and the lift's paths alone, which the stepper's rows
keep. Replaying them gives a new element exactly the state a resident one would have, so the
zone can be refined wherever it has become sparse (a zone shrinking toward the centre before
separation) without interpolating any state.
"""

from __future__ import annotations

import math

import numpy as np

from ..kernels import contact as K
from . import contact_state as st

#: The fewest elements strictly inside the zone before new ones are replayed into it.
MIN_INSIDE = 8
#: Phases whose zone grows into virgin solid (elements gather in it) and may be thinned: the
#: bonded punch's. Not the receding phases: a zone end that later recedes over a region
#: thinned there integrates its last intervals too coarsely (errors ~1e-6 in the separation
#: time were measured).
GROWING = (st.BONDED,)


#: Where the lift follows a force balance (behind a spring, under force control) past the
#: onset a thinned zone keeps this many times more elements: with the driven lift's factor
#: the crack behind 1 N/m (compliant_machine) ran through 2.5e-3 early at n = 128 (unthinned
#: -8.9e-8; thinned, n = 64 and 256 were regular), its timing decided while it has moved a
#: thousandth of the zone; with twice it, every level n = 16..512 of the 1, 10 and 100 N/m
#: scenes is regular and as accurate as unthinned (behind 1 N/m 5.4e-6 .. 2.1e-9 in the
#: separation time), and compliant_machine at n = 256 takes 16 s against 48 s unthinned.
#: A run that ends at its onset, and an elastic solid, were thinned with the driven factor
#: before and still are. A path under force control or behind a spring (``until`` "path")
#: with memory is thinned with the margin (it was not thinned). Its factor follows the
#: segment: a driven segment of a mixed path thins with the driven factor, and what it
#: removed is not put back.
BALANCED_MARGIN = 2.0


def thin_factor(law) -> float:
    """A thinned zone keeps this many times ``per_zone`` elements across its angle (fewer
    where the elements hold more state).

    * elastic (elements hold no state): 8; without thinning an elastic punch finds a
      spurious branch past its onset among the crowded elements;
    * Kelvin-Voigt: 32. Measured on separation_kv at n = 64..512 against the reference: the
      onset's errors as without thinning (t_detach 9.1e-10, 2.2e-10, 6.0e-11, 1.7e-12 without,
      8.9e-10, 2.8e-10, 5.8e-11, -3.3e-12 with), the separation's within 2.1x of them, and
      2.4x (n = 256) to 3.1x (n = 512) faster; at 16 or 8 the onset stalled at 3e-10 or 1e-8
      and lost its order;
    * Maxwell arms: 64. On sls_finite_punch with the zone outside at 1e-2 m/s the onset's
      errors stall near 1e-9 (-2.9e-9, -6.1e-10, -2.4e-10, -8.0e-10 at n = 64..512; -3.8e-10,
      -4.8e-11 unthinned at 128, 256), the separation's stay within 10 % of the unthinned
      ones; prony_external is 2.9x (n = 256) and 3.5x (n = 512) faster; behind 1e2 and
      1e4 N/m the onset moves by at most 7e-10 with 1700-3900 elements against 14000-29600
      at n = 256-512, 2.5-3.5x faster. At 32 the onset stalled at ~5e-9 with irregular signs.
    """
    if law.maxwell:
        return 64.0
    return 8.0 if _stateless(law) else 32.0


def _stateless(law) -> bool:
    """An elastic solid's elements hold nothing between steps."""
    return law.c == 0.0 and not law.maxwell


def replay(stepper, xs: np.ndarray):
    """Modes ``Y`` (rows) at the current instant of elements at ``xs``, each run through
    every step since its memory began (:func:`_forgotten_before`); None when one of them
    joined the contact on the way (its memory of joining is not kept in the rows). Compiled
    (:func:`pulloff.kernels.contact.replay_elements`): in Python a coarse level of
    seed_flat_punch, whose thin receding zone is refilled nearly every step, spent 85 % of its
    time here."""
    s = stepper.setup
    law = s.law
    Y = np.zeros((xs.size, max(law.n_modes, 1)))
    rows, kink, row_Hf = _history(stepper)
    done = K.replay_elements(rows, kink, row_Hf, _forgotten_before(rows, law, xs),
                             np.ascontiguousarray(xs, dtype=float), law.lam, law.z, law.ctil,
                             law.d, law.tau_arms, law.V_inv, law.maxwell,
                             stepper.step_constants, s.indenter.table, Y)
    return Y if done else None


#: A free element's state is replaced by rest once its slowest mode has decayed by this many
#: e-folds since (exp(-37) = 8.5e-17: below rounding).
FORGET_EFOLDS = 37.0


def _forgotten_before(rows, law, xs) -> int:
    """The last row from which elements at ``xs`` may be replayed from rest: by the last row
    the slowest mode has forgotten everything before it. 0 where a mode never decays, and with
    Maxwell arms where one of them is in contact there (its arms' memory of joining is known
    only for a bond since ``t = 0``). A standard linear solid pulled at 1e-7 m/s skips half
    of its rows."""
    if law.slowest_decay == 0.0:
        return 0
    t_forget = rows[-1, 0] - FORGET_EFOLDS / law.slowest_decay
    # At least the last step is replayed: a memory shorter than the clock's rounding would
    # otherwise leave the elements at rest.
    first = min(int(np.searchsorted(rows[:, 0], t_forget, side="right")) - 1,
                rows.shape[0] - 2)
    first = max(first, 0)
    if law.maxwell and np.any(xs <= rows[first, 2]):
        return 0
    return first


def _history(stepper):
    """The rows, their kinks and the arms' filtered lift as arrays. Converted once: a call
    converts only the rows added since the last one, and that one's last row (a transition
    may rewrite the last row); the whole list each time cost more than the replay."""
    rows, row_Hf = stepper.rows, stepper.row_Hf
    n_rows, width = len(rows), row_Hf[0].size
    known = stepper.row_arrays
    done = 0 if known is None else min(known[0], n_rows) - 1
    if done < 1:
        arr = np.array(rows, dtype=float)
        hf = np.array(row_Hf, dtype=float).reshape(n_rows, width)
    else:
        arr = np.concatenate([known[1][:done], np.array(rows[done:], dtype=float)])
        hf = np.concatenate([known[2][:done],
                             np.array(row_Hf[done:], dtype=float).reshape(n_rows - done, width)])
    stepper.row_arrays = (n_rows, arr, hf)
    kink = np.zeros(n_rows, dtype=np.bool_)
    kink[[k for k in stepper.kinks if k < n_rows]] = True
    return arr, kink, hf


#: Next to a receding zone end, elements lie at most ``END_SPACING / per_zone`` of the angle
#: its fastest mode's memory spans apart, out to ``END_REACH`` times that angle (see
#: :func:`fill_receding_end`; 4 and 3 gave 2-4x the error at n = 16..64 on the slow standard
#: linear solid, 1 no gain on prony_external for 1.3x the time, a reach of 3 the same errors
#: as 1.5).
END_SPACING = 2.0
END_REACH = 1.5


def zone_angle(alpha: float, beta: float) -> float:
    """The angle ``acos(alpha / beta)`` the zone spans in the gap's variable (``pi / 2``
    without a contact), without cancellation near ``alpha = beta``."""
    if alpha <= 0.0:
        return 0.5 * math.pi
    return math.atan2(math.sqrt(max((beta - alpha) * (beta + alpha), 0.0)), alpha)


def memory_angle(law, speed: float, beta: float) -> float:
    """The angle ``sqrt(2 d / beta)`` next to a zone end moving at ``speed`` over which its
    fastest mode remembers it (``d = speed / decay``, the distance the end travels in that
    memory): the displacement varies on this scale there. Dimensionless."""
    return math.sqrt(2.0 * abs(speed) / (law.fastest_decay * beta))


def fill_receding_end(stepper) -> int:
    """Replay elements evenly in angle next to a receding zone end; returns how many.

    The gap at the end is integrated in the angle ``theta = acos(x / b)`` (the end value
    extrapolated from the elements next to it), but the end recedes into elements released
    evenly in ``x`` for the zone of their time, sparse in angle just there. The displacement
    next to the end varies over the distance the end travels in its fastest mode's memory,
    ``d = speed / decay`` (the angle ``sqrt(2 d / b)``): where that is short against the
    elements' spacing, the end's quadrature limited the run (a standard linear solid pulled
    at 1e-7 m/s converged at order 1.2-1.5 in its separation time; ``python
    benchmarks/zone_end_quadrature.py``). Elements are placed at the present end and at the
    end the last step's speed predicts for the next step, wherever none lies near.

    Only under a prescribed lift: new elements change the gap the last step balanced, and
    behind a spring the next step's force balance then lost its state and bisected
    (compliant_machine behind 10 N/m at rtol 1e-4: 12.5 s -> 30.5 s with the same
    results; its zone places few, 7-35 per level)."""
    now, before = stepper.now, stepper.before
    law = stepper.setup.law
    if (not stepper.setup.flat or not stepper.lift_driven or before is None
            or now.t <= before.t
            or now.phase not in (st.CONTACT_PHASE, st.ZONE)
            or not 0.0 < now.beta < before.beta or law.fastest_decay == 0.0):
        return 0
    b, a = now.beta, max(now.alpha, 0.0)
    theta_zone = zone_angle(a, b)
    theta_memory = memory_angle(law, (before.beta - b) / (now.t - before.t), b)
    dtheta = theta_memory * END_SPACING / stepper.per_zone
    reach = min(END_REACH * theta_memory, theta_zone)
    if not dtheta > 0.0 or reach < dtheta:
        return 0
    count = int(reach / dtheta)
    ends = np.array([b, max(b - (before.beta - b), 0.5 * b)])
    nodes = stepper.nodes
    xs = np.empty(2 * count)
    xs = xs[:K.end_targets(nodes.xi, nodes.n, a, ends, dtheta, count, xs)]
    return _place(stepper, xs)


def _place(stepper, xs) -> int:
    """Replay free elements at ``xs`` into the mesh now; how many (none where one of them
    cannot be replayed)."""
    if xs.size == 0:
        return 0
    Y = replay(stepper, xs)
    if Y is None:
        return 0
    nodes = stepper.nodes
    nodes.insert_many(xs, Y, np.full(xs.size, st.FREE), np.zeros((xs.size, nodes.D.shape[1])),
                      np.zeros(xs.size), stepper.now.t)
    return xs.size


def refine(stepper) -> int:
    """Replay new elements into the zone where fewer than :data:`MIN_INSIDE` lie inside it
    (evenly in the angle the gap is integrated in); returns how many were placed."""
    now = stepper.now
    if (now.beta <= 0.0 or now.phase in (st.APART, st.DONE)
            or (not stepper.setup.flat and _stateless(stepper.setup.law))):
        return 0  # an elastic smooth contact places fresh elements in every evaluation
    nodes = stepper.nodes
    # (the elements strictly inside, counted on the sorted mesh: this runs every step)
    if nodes.below(now.beta) - nodes.at_most(now.alpha) >= MIN_INSIDE:
        return 0
    theta_a = zone_angle(now.alpha, now.beta)
    want = now.beta * np.cos(theta_a * np.arange(1, 2 * MIN_INSIDE) / (2 * MIN_INSIDE))
    spacing = (now.beta - now.alpha) / (4 * MIN_INSIDE)
    xs = np.array([x for x in want if not nodes.near(float(x), spacing)])
    return _place(stepper, xs)


def thin(stepper) -> int:
    """Remove free elements deep inside a crowded zone, keeping at least ``2 thin_factor
    per_zone`` of them across its angle ``theta = acos(x/b)`` (the gap's variable, where the
    field is smooth away from the zone end) and every element nearer the end than that
    spacing; returns how many went. A later zone that finds the region sparse replays
    elements back into it."""
    now = stepper.now
    nodes = stepper.nodes
    # Behind a spring or under force control too (until the thirteenth session those were
    # not thinned past their onset: compliant_machine at n = 512 reported a crack arrest,
    # but it did unthinned as well, from a horizon counted in steps: _LOST_BALANCE_N).
    if now.beta <= 0.0 or now.beta <= now.alpha or now.phase not in GROWING:
        return 0
    law = stepper.setup.law
    balanced_run_past_onset = (not stepper.lift_driven and stepper.setup.until != "detach"
                               and not _stateless(law))
    factor = thin_factor(law) * (BALANCED_MARGIN if balanced_run_past_onset else 1.0)
    lo, hi = nodes.below(now.alpha), nodes.below(now.beta)
    idx = np.arange(lo, hi)
    idx = idx[(nodes.status[lo:hi] == st.FREE) & (nodes.xi[lo:hi] > now.alpha)
              & (nodes.xi[lo:hi] < now.beta)]
    budget = int(2 * factor * stepper.per_zone)
    if idx.size <= budget:
        return 0
    theta_zone = zone_angle(now.alpha, now.beta)
    spacing = theta_zone / (factor * stepper.per_zone)
    x = nodes.xi[idx]  # the angle acos(x/b) without cancellation near b, as K.angle
    theta = np.arctan2(np.sqrt(np.maximum((now.beta - x) * (now.beta + x), 0.0)), x)
    order = np.argsort(theta)
    drop, last = [], -math.inf
    for j, i in enumerate(order):
        near_end = theta[i] < spacing
        if near_end or theta[i] - last >= spacing or j == order.size - 1:
            last = theta[i]
        else:
            drop.append(idx[i])
    if drop:
        nodes.remove(np.array(drop, dtype=np.int64))
    return len(drop)
