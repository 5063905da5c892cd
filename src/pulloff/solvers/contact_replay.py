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
from .contact_step import quadratic_path

#: The fewest elements strictly inside the zone before new ones are replayed into it.
MIN_INSIDE = 8
#: Phases whose zone grows into virgin solid (elements gather in it) and may be thinned: the
#: bonded punch's. Not the receding phases: a zone end that later recedes over a region
#: thinned there integrates its last intervals too coarsely (errors ~1e-6 in the separation
#: time were measured).
GROWING = (st.BONDED,)


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


def _may_thin(stepper) -> bool:
    """Thinning needs a prescribed lift or a run that ends at the onset. Behind a spring (or
    under force control) past the onset the zone end later recedes over the thinned region
    while the bond vanishes like ``(t_0 - t)^(1/3)``, and the balance there is ill-conditioned:
    compliant_machine.yaml at n = 512 lost it at a = 0.067 R and reported a crack arrest
    instead of its separation (unthinned it lands on a = 0, as n = 64..256 did thinned)."""
    return (stepper.setup.law.c == 0.0 and not stepper.setup.law.maxwell
            or stepper.lift_driven or stepper.setup.until == "detach")


def _paths(rows, kinks, k, column):
    """The quadratic (or, after an event, linear) path of one column over step ``k``."""
    t0, t1 = rows[k - 1][0], rows[k][0]
    r = None
    if k >= 2 and (k - 1) not in kinks and rows[k - 1][0] > rows[k - 2][0]:
        r = (t0 - rows[k - 2][0]) / (t1 - t0)
    prev = rows[k - 2][column] if r is not None else None
    return quadratic_path(prev, rows[k - 1][column], rows[k][column], r)


def _stateless(law) -> bool:
    """An elastic solid's elements hold nothing between steps."""
    return law.c == 0.0 and not law.maxwell


def replay(stepper, xs: np.ndarray):
    """Modes ``Y`` (rows) at the current instant of elements at ``xs``, each run from t = 0
    through every step; None when one of them joined the contact on the way (its memory of
    joining is not kept in the rows)."""
    s = stepper.setup
    law = s.law
    nm = law.n_modes
    rows, kinks, Hfs = stepper.rows, stepper.kinks, stepper.row_Hf
    n = xs.size
    Y = np.zeros((n, max(nm, 1)))
    free = xs > rows[0][2]
    w3 = np.zeros((max(nm, 1), 3))
    for k in range(1, len(rows)):
        t0, t1 = rows[k - 1][0], rows[k][0]
        dt = t1 - t0
        if dt <= 0.0:  # a jump: the contact lets go of what it no longer covers, at once
            for j in np.nonzero(~free & (xs > rows[k][2]))[0]:
                Y[j] = _contact_modes(stepper, xs[j], rows[k - 1][1], Hfs[k - 1])
                free[j] = True
            continue
        bp = _paths(rows, kinks, k, 3)
        ap = _paths(rows, kinks, k, 2)
        hp = _paths(rows, kinks, k, 1)
        mus = -law.lam * dt
        for m, mu in enumerate(mus):
            K.fitted_radau3(mu, w3[m])
        if np.any(free & (xs < K.path_value(*ap, 1.0))):
            return None  # captured by an advancing edge: not replayable from the rows
        s0 = np.zeros(n)
        for j in np.nonzero(~free)[0]:
            if K.path_value(*ap, 1.0) >= xs[j]:
                continue  # still in contact at the end of the step
            s_c = _crossing(ap, xs[j])
            h_c = K.path_value(*hp, s_c)
            Hf_c = _filtered(law, Hfs[k - 1], hp, dt, s_c)
            Y[j] = _contact_modes(stepper, xs[j], h_c, Hf_c)
            s0[j] = s_c
            free[j] = True
        U = np.zeros(n)
        idx = np.nonzero(free)[0]
        if idx.size and nm:
            Yn = np.zeros((idx.size, nm))
            K.free_field(xs[idx], Y[idx, :nm].copy(), s0[idx], 0, idx.size, bp[0], bp[1],
                         bp[2], mus, law.z * dt, law.ctil, law.d, nm, w3, Yn, U[:idx.size])
            Y[idx, :nm] = Yn
    return Y if np.all(free) else None


def _crossing(p, x):
    roots = np.empty(2)
    count = K.path_roots(p[0], p[1], p[2], x, -1e-12, 1.0 + 1e-12, roots)
    return min(max(roots[0], 0.0), 1.0) if count else 1.0


def _filtered(law, Hf0, hp, dt, s):
    if not law.maxwell:
        return Hf0
    out = np.empty(Hf0.size)
    K._filtered_lift(Hf0, dt / law.tau_arms, np.array(hp, float), s, out)
    return out


def _contact_modes(stepper, x, H, Hf):
    """Modes of a contact element at ``x`` (lift ``H``): Kelvin-Voigt its displacement,
    Maxwell its dashpots (a flat punch's bonded elements all share them: no memory term)."""
    law = stepper.setup.law
    G = stepper.setup.indenter.g(x)
    if not law.maxwell:
        return np.array([H + G])
    return law.V_inv @ (Hf + G)


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
    theta_a = math.atan2(math.sqrt(max((now.beta - now.alpha) * (now.beta + now.alpha), 0.0)),
                         now.alpha)
    want = now.beta * np.cos(theta_a * np.arange(1, 2 * MIN_INSIDE) / (2 * MIN_INSIDE))
    spacing = (now.beta - now.alpha) / (4 * MIN_INSIDE)
    xs = np.array([x for x in want if not nodes.near(float(x), spacing)])
    if xs.size == 0:
        return 0
    Y = replay(stepper, xs)
    if Y is None:
        return 0
    for x, y in zip(xs, Y):
        nodes.insert(float(x), y, st.FREE, t_last=now.t)
    return xs.size


def thin(stepper) -> int:
    """Remove free elements deep inside a crowded zone, keeping at least ``2 thin_factor
    per_zone`` of them across its angle ``theta = acos(x/b)`` (the gap's variable, where the
    field is smooth away from the zone end) and every element nearer the end than that
    spacing; returns how many went. A later zone that finds the region sparse replays
    elements back into it."""
    now = stepper.now
    nodes = stepper.nodes
    if (now.beta <= 0.0 or now.beta <= now.alpha or now.phase not in GROWING
            or not _may_thin(stepper)):
        return 0
    factor = thin_factor(stepper.setup.law)
    lo, hi = nodes.below(now.alpha), nodes.below(now.beta)
    idx = np.arange(lo, hi)
    idx = idx[(nodes.status[lo:hi] == st.FREE) & (nodes.xi[lo:hi] > now.alpha)
              & (nodes.xi[lo:hi] < now.beta)]
    budget = int(2 * factor * stepper.per_zone)
    if idx.size <= budget:
        return 0
    theta_zone = math.atan2(math.sqrt((now.beta - now.alpha) * (now.beta + now.alpha)),
                            now.alpha) if now.alpha > 0.0 else 0.5 * math.pi
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
