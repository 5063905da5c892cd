"""Numba kernels of the quadratures: the exact gap of a flat punch as one integral over its
load history, with the zone's part in closed form (Carlson's elliptic integrals).

**The seed's onset** (the first part of this module). Dimensionless as
:mod:`pulloff.kernels.onset` (lengths in ``a``, displacements in ``delta``, time in
``delta / v``; ``S(T) = k (H0 + T) + c``). An element at ``sigma`` entered the zone when ``S``
passed it (or at ``T = 0``) and carries
``U = (1/c) int exp(-k (T - T')/c) sqrt(S(T')^2 - sigma^2) dT'``. Swapping the order of the
gap's two integrals (over elements, then over their load history) gives

    gap = (2/pi) [ H atan(S) - I ],
    I(T) = (1/c) int_0^T exp(-k tau / c) K(S(T - tau)^2, S(T)^2) dtau,
    K(P, Q) = 1/2 int_0^P sqrt(P - w) / sqrt((1 + w)(Q - w)) dw   (w = sigma^2),

and ``K`` is an elliptic integral: Carlson's ``R_D`` in closed form (:func:`zone_kernel`). What
is left is a one-dimensional integral in ``tau``, smooth but for a ``tau log tau`` term at
``tau = 0`` (``K`` has ``d log d`` at ``d = Q - P -> 0``), which Gauss rules on panels graded
geometrically toward ``tau = 0`` integrate to full precision with a few dozen nodes. The
stepper (:mod:`pulloff.kernels.onset`) marches every element of the zone instead; both
methods solve the same model, and the reference (:mod:`pulloff.references.onset`) integrates
over the elements first, adaptively.

**A moving edge** (the second part, :func:`edge_gap_split`): the same swap for a flat punch whose
bond radius ``a`` and zone end ``b`` both move, under any rheology with a creep compliance
``J(t) = J(0) + int J'`` of exponentials. See :mod:`pulloff.solvers.edge_quadrature`.

Kernels that call each other live in this one module (numba's disk cache does not track
cross-module changes).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: The memory kernel is cut where ``exp(-k tau / c)`` falls below ``exp(-DECAYS)``: e^-40
#: ~ 4e-18 of an integrand that is largest at ``tau = 0``.
DECAYS = 40.0
#: Edges, in relaxation times ``c / k``, of the panels past the first relaxation time: each
#: short enough for a Gauss rule of the level's order on ``exp(-y)`` (the error of ``n``
#: points on a panel of length ``L`` is ~``(L/2)^(2n) / (2n)!`` of its weight).
DECAY_EDGES = np.array([1.0, 2.0, 4.0, 8.0, 13.0, 19.0, 26.0, 33.0, DECAYS])
#: The power of the substitution ``u^p`` on the half of a history panel next to a logarithmic
#: point (``T`` itself, where the newest element's zone load starts: the integrand goes like
#: ``(T - s) log(T - s)``, and where ``b(s) = b(T)`` again), the other half plain Gauss: in
#: place of panels graded geometrically toward it. On the shipped pulls to separation at rtol
#: 1e-6 the runs took 25 % less time and every error stayed within 4.5e-8 of the reference
#: (5.5e-8 before); ``p`` = 3 or 4 over the whole panel left the Prony pull's error at
#: 6e-7, 3x its estimate (twentieth session, ``/tmp`` study). With Gauss rules of at least
#: ``LOG_RULE_POINTS`` (march tolerances below 1e-5); with the 8 points of coarser ones the
#: standard linear solid's error at tolerance 1e-5 grew from 4.2e-8 to 4.3e-7.
LOG_POWER = 4
LOG_RULE_POINTS = 12
#: The same at a square root (where the old bond radius passes the zone end, ``a_s = b_T``):
#: ``u^2`` makes the opening, a series in the root, smooth.
SQRT_POWER = 2
#: Ratio of consecutive panels graded toward ``tau = 0``.
_GRADING = 0.25


@njit(cache=True, inline='always')
def _rd_series(X, Y):
    """R_D's seventh-order series in the duplication's last deviations (DLMF 19.36.2)."""
    Z = -(X + Y) / 3.0
    xy, zz = X * Y, Z * Z
    e2 = xy - 6.0 * zz
    e3 = (3.0 * xy - 8.0 * zz) * Z
    e4 = 3.0 * (xy - zz) * zz
    e5 = xy * zz * Z
    return (1.0 - 3.0 * e2 / 14.0 + e3 / 6.0 + 9.0 * e2 * e2 / 88.0 - 3.0 * e4 / 22.0
            - 9.0 * e2 * e3 / 52.0 + 3.0 * e5 / 26.0)


@njit(cache=True, inline='always')
def _rf_series(X, Y):
    """R_F's fifth-order series in the duplication's last deviations (DLMF 19.36.1)."""
    Z = -(X + Y)
    e2 = X * Y - Z * Z
    e3 = X * Y * Z
    return 1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0


@njit(cache=True)
def carlson_rd(x, y, z):
    """Carlson's ``R_D(x, y, z) = 3/2 int_0^inf dt / (sqrt((t+x)(t+y)) (t+z)^(3/2))`` for
    ``x, y >= 0`` (at most one zero) and ``z > 0``, to ~1e-16 relative: duplication until the
    arguments agree to the series' order, then its seventh-order expansion (B. C. Carlson,
    Numer. Algorithms 10 (1995) 13-26; DLMF 19.36.2)."""
    a0 = (x + y + 3.0 * z) / 5.0
    a = a0
    # (r/4)^(-1/6) = 575 for r = 2^-53: the series' error then stays below the rounding.
    q = 6.0e2 * max(abs(a0 - x), abs(a0 - y), abs(a0 - z))
    total = 0.0
    scale = 1.0
    while scale * q >= abs(a):
        sx, sy, sz = math.sqrt(x), math.sqrt(y), math.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        total += scale / (sz * (z + lam))
        scale *= 0.25
        x, y, z, a = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam), 0.25 * (a + lam)
    series = _rd_series((a - x) / a, (a - y) / a)
    return scale * series / (a * math.sqrt(a)) + 3.0 * total


@njit(cache=True)
def zone_kernel(P, d):
    """``K(P, P + d) = 1/2 int_0^P sqrt(P - w) / sqrt((1 + w)(P + d - w)) dw`` for
    ``P, d >= 0``: the zone's weight of a load ``S'^2 = P`` seen by the gap at ``S^2 = P + d``.

    With ``w = P - P / (t + 1)`` the integral is ``P^(3/2) R_D(1/(1+P), (P+d)/d, 1) /
    (3 sqrt((1+P) d))``; at ``d = 0`` it is ``sqrt(1 + P) - 1``, the frozen zone's width."""
    if d <= 0.0:
        return P / (1.0 + math.sqrt(1.0 + P))
    if P <= 0.0:
        return 0.0
    return P * math.sqrt(P) * carlson_rd(1.0 / (1.0 + P), (P + d) / d, 1.0) / (
        3.0 * math.sqrt((1.0 + P) * d))


def lobatto_nodes(n: int) -> np.ndarray:
    """The ``n + 1`` Chebyshev-Lobatto nodes of [0, 1], ``(1 - cos(pi j / n)) / 2``, ascending,
    0 and 1 exact: the nodes of every interpolant here (plain Python, kept per ``n``)."""
    if n not in _LOBATTO:
        u = 0.5 * (1.0 - np.cos(np.pi * np.arange(n + 1) / n))
        u[0], u[-1] = 0.0, 1.0
        _LOBATTO[n] = u
    return _LOBATTO[n]


_LOBATTO: dict = {}


@njit(cache=True)
def _barycentric(u_nodes, values, u):
    """The polynomial through ``values`` at the Chebyshev-Lobatto nodes ``u_nodes`` of
    [0, 1] (:func:`lobatto_nodes`), at ``u``: the barycentric formula, stable at every
    degree."""
    n = u_nodes.size - 1
    num = 0.0
    den = 0.0
    for j in range(n + 1):
        diff = u - u_nodes[j]
        if diff == 0.0:
            return values[j]
        w = (0.5 if j == 0 or j == n else 1.0) * (1.0 if j % 2 == 0 else -1.0) / diff
        num += w * values[j]
        den += w
    return num / den


@njit(cache=True)
def path_value(path, row, span, T):
    """Row ``row`` (1: the lift ``H``, 2: ``S``) of a lift path at ``T``: the polynomial
    through ``path[row]`` at the Chebyshev-Lobatto nodes ``path[0]`` of ``sqrt(T / span)``
    in [0, 1] (the lift's start is smooth in the square root)."""
    return _barycentric(path[0], path[row], math.sqrt(max(T, 0.0) / span))


@njit(cache=True)
def lift_and_zone(k, c, H0, path, span, T):
    """``(H, S)`` at ``T``: the rigid pull's ``H0 + T`` and ``k H + c``, or a lift path's
    (``path`` of shape ``(3, n + 1)``: nodes, ``H``, ``S``; shape ``(3, 0)``: rigid)."""
    if path.shape[1] == 0:
        return H0 + T, k * (H0 + T) + c
    return path_value(path, 1, span, T), path_value(path, 2, span, T)


@njit(cache=True)
def _panel(lo, hi, k, c, S, T, path, span, nodes, weights):
    """``(1/c) int_lo^hi exp(-k tau/c) K(S(T - tau)^2, S^2) dtau`` by the Gauss rule
    ``nodes, weights`` on [0, 1]; ``S(T - tau) = S - k tau`` on a rigid pull, else the
    path's (never above ``S``: the zone only grows before the onset)."""
    width = hi - lo
    total = 0.0
    rigid = path.shape[1] == 0
    for i in range(nodes.size):
        tau = lo + width * nodes[i]
        if rigid:
            k_tau = k * tau
            s_then = S - k_tau
            d = k_tau * (S + s_then)
        else:
            s_then = min(path_value(path, 2, span, T - tau), S)
            d = (S - s_then) * (S + s_then)
        total += weights[i] * math.exp(-k * tau / c) * zone_kernel(s_then * s_then, d)
    return total * width / c


@njit(cache=True)
def memory_integral(k, c, H0, path, span, T, n_graded, nodes, weights):
    """``I(T)`` of the module docstring (:func:`_over_panels`); ``path``, ``span``: the lift
    (:func:`lift_and_zone`)."""
    S = lift_and_zone(k, c, H0, path, span, T)[1]
    if c == 0.0:  # elastic: every element carries its current load, at t = 0 too
        return zone_kernel(S * S, 0.0) / k
    if T <= 0.0:  # a damper cannot move at once (MODEL.md, settled questions)
        return 0.0
    if k == 0.0 and path.shape[1] == 0:  # viscous, rigid: S is constant, the load too
        return T / c * zone_kernel(S * S, 0.0)
    return _over_panels(k, c, S, T, path, span, n_graded, nodes, weights, False)


@njit(cache=True)
def nodes_per_gap(k, c, H0, path, span, T, n_graded, nodes, weights):
    """Gauss nodes of one :func:`memory_integral` at ``T`` (none for its closed forms)."""
    if c == 0.0 or T <= 0.0 or (k == 0.0 and path.shape[1] == 0):
        return 0
    return int(_over_panels(k, c, 0.0, T, path, span, n_graded, nodes, weights, True))


@njit(cache=True)
def _over_panels(k, c, S, T, path, span, n_graded, nodes, weights, count):
    """The sum of :func:`_panel` over the layout (or, with ``count``, its number of nodes):
    ``n_graded`` panels graded toward ``tau = 0`` over the first relaxation time ``c / k``
    (or all of ``[0, T]`` if shorter), then panels ending at ``DECAY_EDGES`` relaxation
    times, cut at ``T``; behind a lift path whose memory reaches back to the pull's start,
    the first half only, and ``n_graded`` panels graded toward ``tau = T`` on the rest."""
    relax = c / k if k > 0.0 else math.inf
    # A lift path starts with the punch catching up with the driver: a layer at tau = T.
    end = T
    if path.shape[1] > 0 and 0.5 * T < DECAYS * relax:
        end = 0.5 * T
    hi = min(end, relax)
    total = 0.0
    for j in range(n_graded):
        lo = hi * _GRADING if j < n_graded - 1 else 0.0
        total += nodes.size if count else _panel(lo, hi, k, c, S, T, path, span, nodes,
                                                 weights)
        hi = lo
    for j in range(DECAY_EDGES.size - 1):
        lo = DECAY_EDGES[j] * relax
        if lo >= end:
            break
        total += nodes.size if count else _panel(
            lo, min(end, DECAY_EDGES[j + 1] * relax), k, c, S, T, path, span, nodes, weights)
    width = T - end
    for j in range(n_graded if width > 0.0 else 0):
        # [T - width r^j, T - width r^(j+1)], the last one reaching T
        lo = T - width * _GRADING ** j
        hi = T - width * _GRADING ** (j + 1) if j < n_graded - 1 else T
        total += nodes.size if count else _panel(lo, hi, k, c, S, T, path, span, nodes,
                                                 weights)
    return total


@njit(cache=True)
def gap(k, c, H0, path, span, T, n_graded, nodes, weights):
    """The gap at the end of the zone at ``T``, in ``delta``."""
    H, S = lift_and_zone(k, c, H0, path, span, T)
    return (2.0 / math.pi) * (H * math.atan(S) - memory_integral(k, c, H0, path, span, T,
                                                                 n_graded, nodes, weights))


@njit(cache=True)
def gaps(k, c, H0, path, span, times, n_graded, nodes, weights):
    """:func:`gap` at each of ``times``."""
    out = np.empty(times.size)
    for i in range(times.size):
        out[i] = gap(k, c, H0, path, span, times[i], n_graded, nodes, weights)
    return out


@njit(cache=True)
def _illinois(lo, hi, f_lo, f_hi, x, fx, side):
    """One update of the Illinois bracket ``[lo, hi]`` (values ``f_lo``, ``f_hi`` of opposite
    signs) by the new point ``x`` (value ``fx``): ``(lo, hi, f_lo, f_hi, side)``; the end
    kept twice in a row has its value halved."""
    if (fx < 0.0) == (f_lo < 0.0):
        if side == -1:
            f_hi *= 0.5
        return x, hi, fx, f_hi, -1
    if side == 1:
        f_lo *= 0.5
    return lo, x, f_lo, fx, 1


@njit(cache=True)
def detach_time(k, c, H0, path, span, lo, hi, g_lo, g_hi, n_graded, nodes, weights):
    """The root of ``gap = 1`` in ``[lo, hi]``, where ``g_lo = gap(lo) - 1 < 0 <= g_hi =
    gap(hi) - 1``, by the Illinois variant of regula falsi, to rounding: ``(T, slope,
    evaluations)`` with ``slope`` the last secant's ``d gap / dT``."""
    n_eval = 0
    side = 0
    last = hi
    for _ in range(100):
        if g_hi == 0.0 or hi - lo <= 4.0 * 2.2e-16 * hi:
            break
        mid = hi - g_hi * (hi - lo) / (g_hi - g_lo)
        if not lo < mid < hi:
            mid = 0.5 * (lo + hi)
        if abs(mid - last) <= 2.2e-16 * mid:
            break  # the iterates stand still: rounding decides the last digit
        last = mid
        g_mid = gap(k, c, H0, path, span, mid, n_graded, nodes, weights) - 1.0
        n_eval += 1
        lo, hi, g_lo, g_hi, side = _illinois(lo, hi, g_lo, g_hi, mid, g_mid, side)
    slope = (g_hi - g_lo) / (hi - lo) if hi > lo else 0.0
    root = hi if g_hi == 0.0 or -g_lo > g_hi else lo
    return root, slope, n_eval


@njit(cache=True)
def secant_root(k, c, H0, path, span, t0, slope, n_graded, nodes, weights):
    """The root of ``gap = 1`` near ``t0`` by secants from ``t0`` with the first slope
    ``slope`` (a root of a nearby rule): ``(T, evaluations)``; ``T`` is nan where the
    iterates do not settle within 12 evaluations (the caller then brackets)."""
    g0 = gap(k, c, H0, path, span, t0, n_graded, nodes, weights) - 1.0
    n_eval = 1
    for _ in range(11):
        if g0 == 0.0 or not slope != 0.0:
            return t0, n_eval
        t1 = t0 - g0 / slope
        if abs(t1 - t0) <= 2.2e-16 * abs(t1):
            return t1, n_eval
        g1 = gap(k, c, H0, path, span, t1, n_graded, nodes, weights) - 1.0
        n_eval += 1
        if g1 != g0:
            slope = (g1 - g0) / (t1 - t0)
        t0, g0 = t1, g1
    return math.nan, n_eval


@njit(cache=True)
def lobatto_interpolate(u_nodes, values, u, out):
    """:func:`_barycentric` at each of ``u``, written to ``out``."""
    for i in range(u.size):
        out[i] = _barycentric(u_nodes, values, u[i])


@njit(cache=True)
def lobatto_spread(u_nodes, values):
    """The largest difference between ``values`` at the odd nodes and the interpolant through
    the even ones (half as many nodes, nested): how far that interpolant is from converged,
    a cautious estimate for the one through all of them."""
    spread = 0.0
    coarse_u, coarse_values = u_nodes[::2], values[::2]
    for j in range(1, u_nodes.size, 2):
        spread = max(spread, abs(_barycentric(coarse_u, coarse_values, u_nodes[j]) - values[j]))
    return spread


@njit(cache=True)
def zone_of_force(y, out):
    """``S = Phi^-1(y)`` for each of ``y``, ``Phi(S) = S + (1 + S^2) atan(S)`` (odd, convex
    for ``S >= 0``): Newton from above, written to ``out``. The lift behind a machine spring
    inverts it ~100 times a run (:mod:`pulloff.solvers.machine_lift`)."""
    for i in range(y.size):
        target = abs(y[i])
        # Phi(S) >= 2 S and >= (pi/2) S^2: the smaller inverse bounds S from above.
        S = min(0.5 * target, math.sqrt(2.0 * target / math.pi))
        for _ in range(60):
            atan = math.atan(S)
            step = (S + (1.0 + S * S) * atan - target) / (2.0 + 2.0 * S * atan)
            S -= step
            if abs(step) <= 4e-16 * S or S <= 0.0:
                break
        S = max(S, 0.0)
        out[i] = S if y[i] >= 0.0 else -S


# --------------------------------------------------------------------------------------------
# A moving edge. Units: lengths in the punch radius R, line loads in 2 sigma_c R, compliances
# in pi delta / (sigma_c R) (so the gap comes out in delta), time in the solver's scale.
# Whatever the rheology, an element's opening against a bonded one, d = u_bonded - u, is
# (1/4) int J(T - s) dg(s) with g = L - f >= 0 the load it lacks (f = L while bonded), so
#     gap(b_T) = (2/pi) int_0^b_T d(x, T) / sqrt(b_T^2 - x^2) dx
#              = J(0) opening(T, T) + int J'(T - s) opening(s, T) ds,
#     opening(s, T) = int_0^b_T g(x, s) / sqrt(b_T^2 - x^2) dx
# is elementary plus one elliptic integral (zone_weight). No h, so no cancellation when the
# lift is many delta. A state is (ell, r, P): the bonded load ell = L / (2 sigma_c R),
# r = 1 - a^2 (1 once the bond is gone) and P = b^2 - a^2.
# The history after the onset is held as nodes hist[0] = t, hist[1] = p (r while bonded, b^2
# once the zone is alone), hist[2] = sigma (the march's parameter, in which both t and p are
# smooth, also at a fold); segs[i] = (first node, phase 2 or 3) of its smooth pieces, each
# piece's last node repeated as the next one's first. The onset's phase (a or b pinned) is
# explicit. ctx = [t_onset, zone (0 external, 1 internal), T, ell_T, r_T, P_T].
# --------------------------------------------------------------------------------------------


@njit(cache=True)
def carlson_rf(x, y, z):
    a0 = (x + y + z) / 3.0
    a = a0
    x0, y0 = x, y
    q = 3.0e3 * max(abs(a0 - x), abs(a0 - y), abs(a0 - z))
    scale = 1.0
    while scale * q >= abs(a):
        sx, sy, sz = math.sqrt(x), math.sqrt(y), math.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        scale *= 0.25
        x, y, z, a = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam), 0.25 * (a + lam)
    return _rf_series((a0 - x0) * scale / a, (a0 - y0) * scale / a) / math.sqrt(a)


@njit(cache=True)
def carlson_rf_rd(x, y, z):
    """``(R_F(x, y, z), R_D(x, y, z))`` from one duplication (:func:`carlson_rf` and
    :func:`carlson_rd`, each with its own mean and series; run until both have converged)."""
    af = (x + y + z) / 3.0
    ad = (x + y + 3.0 * z) / 5.0
    a0f = af
    x0, y0 = x, y
    qf = 3.0e3 * max(abs(af - x), abs(af - y), abs(af - z))
    qd = 6.0e2 * max(abs(ad - x), abs(ad - y), abs(ad - z))
    total = 0.0
    scale = 1.0
    while scale * qf >= abs(af) or scale * qd >= abs(ad):
        sx, sy, sz = math.sqrt(x), math.sqrt(y), math.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        total += scale / (sz * (z + lam))
        scale *= 0.25
        x, y, z = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam)
        af, ad = 0.25 * (af + lam), 0.25 * (ad + lam)
    rf = _rf_series((a0f - x0) * scale / af, (a0f - y0) * scale / af) / math.sqrt(af)
    series = _rd_series((ad - x) / ad, (ad - y) / ad)
    return rf, scale * series / (ad * math.sqrt(ad)) + 3.0 * total


@njit(cache=True)
def _zone_weight_below(p, d, A):
    return p * math.sqrt(p) * carlson_rd(A / (A + p), (p + d) / d, 1.0) / (
        3.0 * math.sqrt((A + p) * d))


@njit(cache=True)
def zone_weight(P, d, A):
    """1/2 int_0^min(P, P+d) sqrt(P-w)/sqrt((A+w)(P+d-w)) dw."""
    if P <= 0.0:
        return 0.0
    Q = P + d
    if Q <= 0.0:
        return 0.0
    if abs(d) <= 1e-17 * P:  # (the d log d correction is below the rounding)
        return P / (math.sqrt(A + P) + math.sqrt(A))
    if d > 0.0:
        return _zone_weight_below(P, d, A)
    # the zone's weight below Q plus the zone above it, R_D and R_F of one argument triple
    # (R_F(A e, P (A + Q), (A + Q) e) scaled by homogeneity): one duplication for both, where
    # two took ~120 ns, most of an old element's cost in the memory
    e = -d
    rf, rd = carlson_rf_rd(A / (A + Q), (Q + e) / e, 1.0)
    return math.sqrt(Q / ((A + Q) * e)) * (Q * rd / 3.0 + e * rf)


@njit(cache=True)
def ell_of(s, rh):
    """The bonded load ``ell`` at ``s`` while the bond radius is pinned: a rigid pull's
    ``rh = [c0, cv, g_inf, eta, (g_i, tau_i)...]``, or a pull through a machine spring's lift
    path (:mod:`pulloff.solvers.machine_lift`) ``rh = [nan, span, n + 1, nodes, H, S]``
    (after the onset such a pull's ``ell`` is the history's: :func:`_node_state`)."""
    if rh[0] != rh[0]:
        size = int(rh[2])
        return _barycentric(rh[3:3 + size], rh[3 + 2 * size:3 + 3 * size],
                            math.sqrt(max(s, 0.0) / rh[1]))
    c0, cv, g_inf, eta = rh[0], rh[1], rh[2], rh[3]
    G = g_inf
    Gam = g_inf * s + eta
    for i in range(4, rh.size, 2):
        e = math.exp(-s / rh[i + 1])
        G += rh[i] * e
        Gam += rh[i] * rh[i + 1] * (-math.expm1(-s / rh[i + 1]))
    return c0 * G + cv * Gam


@njit(cache=True)
def creep_rate(tau, cr):
    """cr = [J0, I_imp, (lam, w)...]"""
    tot = 0.0
    for i in range(2, cr.size, 2):
        tot += cr[i + 1] * math.exp(-cr[i] * tau)
    return tot


@njit(cache=True)
def lagrange(xs, ys, i0, n, x):
    tot = 0.0
    for j in range(i0, i0 + n):
        num = 1.0
        den = 1.0
        xj = xs[j]
        for m in range(i0, i0 + n):
            if m != j:
                num *= x - xs[m]
                den *= xj - xs[m]
        tot += ys[j] * num / den
    return tot


@njit(cache=True)
def opening(ell_s, r_s, P_s, ell_T, r_T, P_T):
    """int_0^{b_T} g(x, s) / sqrt(b_T^2 - x^2) dx with g = ell_s - sqrt(b_s^2 - x^2)_+ on
    x > a_s (0 inside): the opening's load against a bonded element."""
    if P_T == 0.0 and r_T == 1.0:
        if r_s == 1.0:
            return 0.5 * math.pi * (ell_s - math.sqrt(P_s))
        return 0.0
    Q = P_T + r_s - r_T
    if Q <= 0.0:
        return 0.0
    A = 1.0 - r_s
    theta = math.atan2(math.sqrt(Q), math.sqrt(A))
    if r_s == r_T and r_s != 1.0:
        d = (ell_T - ell_s) * (ell_T + ell_s)
    else:
        d = Q - P_s
    return ell_s * theta - zone_weight(P_s, d, A)


@njit(cache=True)
def opening_now(ell_T, r_T, P_T):
    if P_T == 0.0 and r_T == 1.0:
        return 0.5 * math.pi * ell_T
    A = 1.0 - r_T
    theta = math.atan2(math.sqrt(P_T), math.sqrt(A))
    return ell_T * theta - P_T / (math.sqrt(A + P_T) + math.sqrt(A))


@njit(cache=True)
def _stencil(k, n, segs, deg):
    """(first node, count, phase) of the interpolant on the history's interval k."""
    i = segs.shape[0] - 1
    while segs[i, 0] > k:
        i -= 1
    lo = segs[i, 0]
    hi = segs[i + 1, 0] - 1 if i + 1 < segs.shape[0] and segs[i + 1, 0] < n else n - 1
    m = deg + 1
    if hi - lo + 1 <= m:
        return lo, hi - lo + 1, segs[i, 1]
    return min(max(k - (m // 2 - 1), lo), hi - m + 1), m, segs[i, 1]


@njit(cache=True)
def _basis(hist, row, i0, m, x, w, dw):
    """Lagrange basis at x over hist[row, i0:i0+m] and its derivative, into w, dw (the
    products of ``x - x_l`` and their derivative accumulated together: no division but the m
    weights; the nodes read in place, where a row's view cost as much as the arithmetic)."""
    for j in range(m):
        xj = hist[row, i0 + j]
        val = 1.0
        der = 0.0
        den = 1.0
        for l in range(m):
            if l != j:
                d = x - hist[row, i0 + l]
                der = der * d + val
                val *= d
                den *= xj - hist[row, i0 + l]
        w[j] = val / den
        dw[j] = der / den


@njit(cache=True)
def _at_sigma(x, hist, i0, m, w, dw):
    """(t, dt/dsigma, p) of the interpolant at sigma = x. The times from the stencil's first
    (the weights sum to 1, their derivatives to 0): summed from the clock since ``t = 0``,
    ``dt/dsigma`` lost ~1e-15 of ``t`` against steps of 1e-9 on slow pulls, a relative noise
    of up to 1e-6 in the memory's integrand (found by a review)."""
    _basis(hist, 2, i0, m, x, w, dw)
    t0 = hist[0, i0]
    t = 0.0
    dt = 0.0
    p = 0.0
    for j in range(m):
        since = hist[0, i0 + j] - t0
        t += w[j] * since
        dt += dw[j] * since
        p += w[j] * hist[1, i0 + j]
    return t0 + t, dt, p


@njit(cache=True)
def _lag(T, hist, i0, m, w):
    """``T - t(sigma)`` of the interpolant whose basis is ``w`` (:func:`_at_sigma`), summed
    from the nodes' own lags: ``T - sum w_j t_j`` lost ~1e-15 of ``t`` (the clock since
    ``t = 0``, up to 2e5 creep times on slow pulls), which the memory's ``exp(-lam (T - s))``
    magnified to ~1e-10 of the gap: noise that the secants ground on."""
    lag = 0.0
    for j in range(m):
        lag += w[j] * (T - hist[0, i0 + j])
    return lag


@njit(cache=True)
def _sigma_of(s, k, hist, i0, m, w, dw):
    """The sigma in [sigma_k, sigma_k+1] where t(sigma) = s (safeguarded Newton)."""
    a, b = hist[2, k], hist[2, k + 1]
    ta, tb = hist[0, k], hist[0, k + 1]
    if s <= ta:
        return a
    if s >= tb:
        return b
    x = a + (b - a) * (s - ta) / (tb - ta)
    for _ in range(60):
        t, dt, _p = _at_sigma(x, hist, i0, m, w, dw)
        f = t - s
        if f > 0.0:
            b = x
        else:
            a = x
        xn = x - f / dt if dt > 0.0 else 0.5 * (a + b)
        if not a <= xn <= b:
            xn = 0.5 * (a + b)
        if abs(xn - x) <= 4e-16 * max(abs(x), 1.0):
            return xn
        x = xn
    return x


@njit(cache=True)
def _pinned_state(s, rh, ctx):
    """``(ell, r, P)`` at ``s`` while the bond is pinned: the zone outside (``r = 0``), or on
    the face (``r = P = ell^2``, ``b = R``) until the face's strength limit ``ctx[6]``, from
    which the zone alone holds the whole face (``r = P = 1``: ``a = 0``, ``b = R``)."""
    ell = ell_of(s, rh)
    if int(ctx[1]) == 0:
        return ell, 0.0, ell * ell
    if s >= ctx[6]:
        return ell, 1.0, 1.0
    return ell, ell * ell, ell * ell


@njit(cache=True)
def _node_state(j, phase, hist, rh):
    """``(ell, r, P)`` at node ``j``: ``ell`` the rigid pull's, or the history's fourth row
    behind a machine spring (where the lift is solved for with the edges)."""
    t = hist[0, j]
    ell = hist[3, j] if hist.shape[0] > 3 else ell_of(t, rh)
    if phase == 2:
        return ell, hist[1, j], ell * ell
    return ell, 1.0, hist[1, j]


@njit(cache=True)
def _node_rp(j, phase, hist, rh, n, states):
    """``(r, P)`` at node ``j`` (:func:`_node_state`), kept in the last three columns of
    ``states[j]`` (a flag, r, P) once the node is no trial (``j < n - 1``): every evaluation
    of the memory tests the crossings at every node (the solver clears a node's entry when
    it pushes one there)."""
    col = states.shape[1] - 3
    kept = j < n - 1 and j < states.shape[0]
    if kept and states[j, col] == 1.0:
        return states[j, col + 1], states[j, col + 2]
    _ell, r, P = _node_state(j, phase, hist, rh)
    if kept:
        states[j, col], states[j, col + 1], states[j, col + 2] = 1.0, r, P
    return r, P


@njit(cache=True)
def _state_sigma(x, phase, hist, i0, m, w, dw, rh):
    """(s, ds/dsigma, ell, r, P) at sigma = x (``ell`` as :func:`_node_state`'s)."""
    t, dt, p = _at_sigma(x, hist, i0, m, w, dw)
    if hist.shape[0] > 3:
        ell = 0.0
        for j in range(m):
            ell += w[j] * hist[3, i0 + j]
    else:
        ell = ell_of(t, rh)
    if phase == 2:
        return t, dt, ell, p, ell * ell
    return t, dt, ell, 1.0, p


@njit(cache=True)
def _crossing_value(which, r, P, ctx):
    Q = ctx[5] + r - ctx[4]  # b_T^2 - a_s^2
    if which == 0:
        return Q
    return Q - P  # b_T^2 - b_s^2


@njit(cache=True)
def _crossings_at_edge(s, k, ctx, rh, hist, n, segs, deg, w, dw, states):
    """Both crossing functions (``a_s``, then ``b_s`` against ``b_T``) at an edge s of a
    panel on interval k (-1: before the onset), from one state."""
    if k < 0:
        _ell, r, P = _pinned_state(s, rh, ctx)
    else:
        i0, m, phase = _stencil(k, n, segs, deg)
        if s == hist[0, k]:
            r, P = _node_rp(k, phase, hist, rh, n, states)
        elif s == hist[0, k + 1]:
            r, P = _node_rp(k + 1, phase, hist, rh, n, states)
        else:
            x = _sigma_of(s, k, hist, i0, m, w, dw)
            _t, _dt, _ell, r, P = _state_sigma(x, phase, hist, i0, m, w, dw, rh)
    return _crossing_value(0, r, P, ctx), _crossing_value(1, r, P, ctx)


@njit(cache=True)
def _crossing_time(lo, hi, flo, fhi, k, which, ctx, rh, hist, n, segs, deg, w, dw):
    """The s in (lo, hi) where the crossing function changes sign (Illinois; in sigma on a
    history interval)."""
    if k >= 0:
        i0, m, phase = _stencil(k, n, segs, deg)
        lo = _sigma_of(lo, k, hist, i0, m, w, dw)
        hi = _sigma_of(hi, k, hist, i0, m, w, dw)
    side = 0
    x = hi
    for _ in range(100):
        if hi - lo <= 4e-16 * max(abs(hi), 1e-300):
            break
        x = hi - fhi * (hi - lo) / (fhi - flo)
        if not lo < x < hi:
            x = 0.5 * (lo + hi)
        if k < 0:
            _ell, r, P = _pinned_state(x, rh, ctx)
        else:
            _t, _dt, _ell, r, P = _state_sigma(x, phase, hist, i0, m, w, dw, rh)
        fx = _crossing_value(which, r, P, ctx)
        if fx == 0.0:
            break
        lo, hi, flo, fhi, side = _illinois(lo, hi, flo, fhi, x, fx, side)
    if k < 0:
        return x
    return _at_sigma(x, hist, i0, m, w, dw)[0]


@njit(cache=True)
def _history_panel(lo, hi, k, sub, ctx, rh, cr, hist, n, segs, deg, gx, gw, w, dw):
    """Gauss over [lo, hi] (in s before the onset, in sigma on history interval k) of
    J'(T - s) opening(s, T) ds; ``sub = +-p``: a ``u^p`` substitution at the high (low) end,
    ``p = 2`` at a square root, :data:`LOG_POWER` at a logarithm (0: none)."""
    T, ell_T, r_T, P_T = ctx[2], ctx[3], ctx[4], ctx[5]
    if k >= 0:
        i0, m, phase = _stencil(k, n, segs, deg)
        a = _sigma_of(lo, k, hist, i0, m, w, dw)
        b = _sigma_of(hi, k, hist, i0, m, w, dw)
    else:
        a, b = lo, hi
    width = b - a
    # (before the onset the lag from the panel's ends: T - a, T - b are exact where close)
    lag_a, lag_b = T - a, T - b
    tot = 0.0
    for i in range(gx.size):
        u = gx[i]
        if sub == 0:
            x = a + width * u
            lag = lag_a - width * u
            wgt = gw[i]
        elif sub == 2:
            x = b - width * u * u
            lag = lag_b + width * u * u
            wgt = gw[i] * 2.0 * u
        elif sub == -2:
            x = a + width * u * u
            lag = lag_a - width * u * u
            wgt = gw[i] * 2.0 * u
        else:
            power = abs(sub)
            x = b - width * u ** power if sub > 0 else a + width * u ** power
            lag = lag_b + width * u ** power if sub > 0 else lag_a - width * u ** power
            wgt = gw[i] * power * u ** (power - 1)
        if k >= 0:
            _s, ds, ell, r, P = _state_sigma(x, phase, hist, i0, m, w, dw, rh)
            lag = _lag(T, hist, i0, m, w)
            wgt *= ds
        else:
            ell, r, P = _pinned_state(x, rh, ctx)
        tot += wgt * creep_rate(lag, cr) * opening(ell, r, P, ell_T, r_T, P_T)
    return tot * width


@njit(cache=True)
def _graded_toward(lo, hi, k, c, toward_hi, m_graded, sq_end, ctx, rh, cr, hist, n, segs, deg, gx,
            gw, w, dw):
    """[lo, hi] in panels graded (ratio 1/4 in the distance) toward the singular point c."""
    tot = 0.0
    if toward_hi:
        far, near = c - lo, c - hi
    else:
        far, near = hi - c, lo - c
    floor = far * 0.25 ** (m_graded - 1)
    d0 = far
    for _ in range(200):
        d1 = 0.25 * d0
        last = d1 <= near or d1 <= floor
        if last:
            d1 = near
        # (one variable for every substitution: a constant argument would compile the panel
        # again for its literal value)
        sub = (2 if toward_hi else -2) if last and sq_end and near == 0.0 else 0
        if toward_hi:
            tot += _history_panel(c - d0, c - d1, k, sub, ctx, rh, cr, hist, n, segs, deg, gx,
                                  gw, w, dw)
        else:
            tot += _history_panel(c + d1, c + d0, k, sub, ctx, rh, cr, hist, n, segs, deg, gx,
                                  gw, w, dw)
        if last:
            break
        d0 = d1
    return tot


@njit(cache=True)
def _toward_point(lo, hi, k, toward_hi, power, ctx, rh, cr, hist, n, segs, deg, gx, gw, w,
                  dw):
    """[lo, hi] with a singular point at its high (low) end: Gauss on the half away from it,
    ``u^power`` on the half next to it (a logarithm: :data:`LOG_POWER`; a square root: 2)."""
    mid = 0.5 * (lo + hi)
    sub = power if toward_hi else -power
    plain = sub - sub  # (0, not a constant: see _graded_toward)
    sub_lo, sub_hi = (plain, sub) if toward_hi else (sub, plain)
    return (_history_panel(lo, mid, k, sub_lo, ctx, rh, cr, hist, n, segs, deg, gx, gw, w, dw)
            + _history_panel(mid, hi, k, sub_hi, ctx, rh, cr, hist, n, segs, deg, gx, gw, w,
                             dw))


@njit(cache=True)
def _substituted(kind, at_edge, points):
    """The power of the substitution that takes a singular point of ``kind`` at a panel's
    edge (0: none, grade toward it)."""
    if not at_edge:
        return 0
    if kind == 0:
        return SQRT_POWER
    return LOG_POWER if kind == 1 and points >= LOG_RULE_POINTS else 0


@njit(cache=True)
def memory_start(T, cr):
    lam_min = math.inf
    for i in range(2, cr.size, 2):
        lam_min = min(lam_min, cr[i])
    if lam_min > 0.0 and T - DECAYS / lam_min > 0.0:
        return T - DECAYS / lam_min
    return 0.0


@njit(cache=True)
def _interval_of(s, hist, n):
    """the history interval k (nodes k, k+1, of positive length) holding s."""
    a, b = 0, n - 1
    while b - a > 1:
        mid = (a + b) // 2
        if hist[0, mid] <= s:
            a = mid
        else:
            b = mid
    return a


@njit(cache=True)
def _merged(pos, kidx, extras, c):
    """``pos[:c]`` sorted (stably, as a merge sort of the whole would; and ``kidx`` with it),
    of which ``pos[extras:c]`` (the history's nodes) are sorted already and the few before
    them are not: those sorted by insertion, then the two merged, in O(c) where a sort of
    all of them was most of a long history's panel edges."""
    for i in range(1, extras):
        p, k = pos[i], kidx[i]
        j = i
        while j > 0 and pos[j - 1] > p:
            pos[j], kidx[j] = pos[j - 1], kidx[j - 1]
            j -= 1
        pos[j], kidx[j] = p, k
    p2 = np.empty(c)
    k2 = np.empty(c, dtype=np.int64)
    a, b = 0, extras
    for i in range(c):
        if b >= c or (a < extras and pos[a] <= pos[b]):
            p2[i], k2[i] = pos[a], kidx[a]
            a += 1
        else:
            p2[i], k2[i] = pos[b], kidx[b]
            b += 1
    return p2, k2


@njit(cache=True)
def _panel_edges(T, t_on, t_strength, cr, hist, n, s0, cut, pos, kidx):
    """Panel edges in [s0, T] (sorted) and the interval of the panel each one starts; the
    face's strength limit among them where it comes before the onset. Only the edges from
    ``cut`` on where ``cut > s0`` (the rest of the list is the same)."""
    c = 0
    if cut <= s0:
        pos[c], kidx[c] = s0, -1 if s0 < t_on else _interval_of(s0, hist, n)
        c += 1
    if max(s0, cut) <= t_strength < min(T, t_on) and t_strength > s0:
        pos[c], kidx[c] = t_strength, -1
        c += 1
    for i in range(2, cr.size, 2):
        lam = cr[i]
        if lam <= 0.0:
            continue
        for j in range(DECAY_EDGES.size):
            s = T - DECAY_EDGES[j] / lam
            if s > s0 and s >= cut:
                pos[c], kidx[c] = s, -1 if s < t_on else _interval_of(s, hist, n)
                c += 1
    extras = c
    j_first = 0
    if cut > s0:
        while j_first < n - 1 and hist[0, j_first] < cut:
            j_first += 1
    for j in range(j_first, n - 1):
        if hist[0, j] >= s0 and hist[0, j + 1] > hist[0, j]:
            pos[c], kidx[c] = hist[0, j], j
            c += 1
    p2, k2 = _merged(pos, kidx, extras, c)
    m = 0
    for i in range(c):
        if m > 0 and p2[i] == pos[m - 1]:
            kidx[m - 1] = max(kidx[m - 1], k2[i])
            continue
        pos[m], kidx[m] = p2[i], k2[i]
        m += 1
    pos[m], kidx[m] = T, -2
    return m + 1


@njit(cache=True)
def _edges_cut(s_from, hist, n):
    """A time from which on the panel edges are enough for :func:`_singular_points` from
    ``s_from``: three history nodes before it (it needs the edge before the one before
    ``s_from``), or ``-inf`` where the history has no three nodes before it."""
    if n < 4 or not s_from > hist[0, 3]:
        return -math.inf
    j = _interval_of(s_from, hist, n)
    return hist[0, j - 3] if j >= 3 else -math.inf


@njit(cache=True)
def _singular_points(ctx, rh, cr, hist, n, segs, deg, w, dw, s_from, states):
    """The panels' edges from ``s_from`` on, sorted: ``(pos [s], interval of the panel
    starting there (-1: before the onset), kind, dead)``; kind 1 marks ``T`` and the times
    where ``b_s = b_T`` (a log in the integrand), 0 those where ``a_s = b_T`` (a square root),
    -1 a plain edge; dead 1 where the panel starting there has ``a_s > b_T`` at both its ends
    and no crossing between, so its openings are all 0 (:func:`opening`)."""
    T = ctx[2]
    cap = 2 * n + 34 + DECAY_EDGES.size * (cr.size // 2)
    base = np.empty(cap)
    bk = np.empty(cap, dtype=np.int64)
    m = _panel_edges(T, ctx[0], ctx[6], cr, hist, n, memory_start(T, cr),
                     _edges_cut(s_from, hist, n), base, bk)
    first = 0
    while first < m - 2 and base[first + 1] <= s_from:
        first += 1
    # (and the panel before: a crossing there, just left of s_from, is the first interval's
    # nearest singular point; without it a part from a split integrated an interval 1e-3 of
    # its width from a square root as if nothing were near: the seed, 1e-8 off in the gap)
    first = max(first - 1, 0)
    pos = np.empty(2 * m + 8)
    kidx = np.empty(2 * m + 8, dtype=np.int64)
    kind = np.empty(2 * m + 8, dtype=np.int64)
    dead = np.zeros(2 * m + 8, dtype=np.int64)
    # (the zone alone shrunk to b_T = 0 sees its own past zone: no opening is 0 there)
    can_die = not (ctx[5] == 0.0 and ctx[4] == 1.0)
    kept = states.shape[1] - 3  # (the nodes' (r, P): _node_rp)
    f_lo = np.empty(2)
    f_hi = np.empty(2)
    f_lo[0], f_lo[1] = _crossings_at_edge(base[first], bk[first], ctx, rh, hist, n, segs, deg,
                                          w, dw, states)
    c = 0
    for i in range(first, m - 1):
        lo, hi, k = base[i], base[i + 1], bk[i]
        # (the strength limit: a square root of a_s^2 = 1 - ell_s^2, on its left only)
        pos[c], kidx[c], kind[c] = lo, k, 0 if lo == ctx[6] else -1
        start = c
        c += 1
        # (the values at hi, on this panel's interval: a join of pieces is continuous)
        if 0 <= k < n - 2 and hi == hist[0, k + 1] and states[k + 1, kept] == 1.0:
            # (a node's kept (r, P) read here: the call cost ~100 ns an edge, 80 % of these
            # points on a long history)
            r, P = states[k + 1, kept + 1], states[k + 1, kept + 2]
            f_hi[0], f_hi[1] = _crossing_value(0, r, P, ctx), _crossing_value(1, r, P, ctx)
        else:
            f_hi[0], f_hi[1] = _crossings_at_edge(hi, k, ctx, rh, hist, n, segs, deg, w, dw,
                                                  states)
        lo_dead, hi_dead = can_die and f_lo[0] < 0.0, can_die and f_hi[0] < 0.0
        root = math.nan  # (where a_s = b_T in this panel)
        for which in range(2):
            if (f_lo[which] < 0.0) != (f_hi[which] < 0.0) and f_lo[which] != 0.0 \
                    and f_hi[which] != 0.0:
                pos[c] = _crossing_time(lo, hi, f_lo[which], f_hi[which], k, which, ctx, rh,
                                        hist, n, segs, deg, w, dw)
                kidx[c], kind[c] = k, which
                if which == 0:
                    root = pos[c]
                elif c - start == 2 and pos[c] < pos[c - 1]:  # (both: in order)
                    pos[c - 1], pos[c] = pos[c], pos[c - 1]
                    kind[c - 1], kind[c] = 1, 0
                c += 1
            f_lo[which] = f_hi[which]
        for j in range(start, c):
            # (a crossing time outside its panel, where t(sigma) turns near a fold: its sides
            # are not known, so nothing there is dead; found by a review)
            if lo <= root <= hi:
                dead[j] = hi_dead if pos[j] >= root else lo_dead
            else:
                dead[j] = lo_dead and hi_dead
    pos[c], kidx[c], kind[c] = T, -2, 1
    c += 1
    # (in order as made but where a crossing's time came out past its panel's end, then
    # sorted as before)
    for i in range(1, c):
        if pos[i] < pos[i - 1]:
            order = np.argsort(pos[:c], kind="mergesort")
            return pos[order], kidx[order], kind[order], dead[:c][order]
    return pos[:c], kidx[:c], kind[:c], dead[:c]


@njit(cache=True)
def _interval_from_states(k, states, rule, rules, ctx, rh, cr, hist, n, segs, deg, w, dw):
    """:func:`_history_panel` over the whole history interval ``k`` by the Gauss rule
    ``rules[rule]`` (``[points, column, distance, width, x..., weights...]`` on [0, 1]), from its
    points' ``(t_k - s, weight, ell, r, P)``, kept in ``states[k]`` from the rule's column on (its
    first entry 1 once filled) the first time: an interval whose stencil holds no trial node is
    the same at every later step, so only the memory's kernel and the opening against the
    zone end are left to evaluate (the state's interpolation was ~45 % of a point's cost)."""
    row = states[k]
    points, col = int(rules[rule, 0]), int(rules[rule, 1])
    if row[col] == 0.0:
        i0, m, phase = _stencil(k, n, segs, deg)
        a = hist[2, k]
        width = hist[2, k + 1] - a
        for i in range(points):
            _s, ds, ell, r, P = _state_sigma(a + width * rules[rule, 4 + i], phase, hist, i0, m,
                                             w, dw, rh)
            j = col + 1 + 5 * i
            # (t_k - s, from the nodes' own lags: see _lag)
            row[j] = _lag(hist[0, k], hist, i0, m, w)
            row[j + 1], row[j + 2] = rules[rule, 4 + points + i] * ds, ell
            row[j + 3], row[j + 4] = r, P
        row[col] = 1.0
    T, ell_T, r_T, P_T = ctx[2], ctx[3], ctx[4], ctx[5]
    since = T - hist[0, k]
    tot = 0.0
    for i in range(points):
        j = col + 1 + 5 * i
        tot += row[j + 1] * creep_rate(since + row[j], cr) * opening(row[j + 2], row[j + 3],
                                                                     row[j + 4], ell_T, r_T, P_T)
    return tot * (hist[2, k + 1] - hist[2, k])


@njit(cache=True)
def _rule_at(lo, hi, prev_c, next_c, k, n, segs, hist, rules):
    """The smallest of ``rules`` (by points, the last the finest) that integrates the whole
    history interval ``k`` = ``[lo, hi]``: its nearest singular point (``prev_c``,
    ``next_c``, and the end of its piece, where ``a`` may reach 0: a square root of
    ``1 - r``) at least ``rules[:, 2]`` widths away, its width at most ``rules[:, 3]`` (the
    kernel's and the bonded load's exponentials)."""
    i = segs.shape[0] - 1
    while segs[i, 0] > k:
        i -= 1
    end = segs[i + 1, 0] - 1 if i + 1 < segs.shape[0] and segs[i + 1, 0] < n else n - 1
    width = hi - lo
    distance = min(lo - prev_c, next_c - hi, hist[0, end] - hi) / width
    for j in range(rules.shape[0] - 1):
        if distance >= rules[j, 2] and width <= rules[j, 3]:
            return j
    return rules.shape[0] - 1


@njit(cache=True)
def history_integral(ctx, rh, cr, hist, n, segs, deg, gx, gw, n_graded, s_lo, s_hi, states,
                     rules):
    """``int_{s_lo}^{s_hi} J'(T - s) opening(s, T) ds`` (``s_hi <= T``): Gauss panels between
    the history's nodes, graded geometrically toward every singular point closer than three
    panel widths (:func:`_singular_points`), with ``u^2`` at a square root; whole intervals
    whose stencil is final from ``states`` (:func:`_interval_from_states`)."""
    w = np.empty(deg + 1)
    dw = np.empty(deg + 1)
    pos, kidx, kind, dead = _singular_points(ctx, rh, cr, hist, n, segs, deg, w, dw, s_lo,
                                             states)
    c = pos.size
    acc = 0.0
    prev_c, prev_k = -math.inf, -1
    ahead = 0  # (the first singular point after i: a scan from each i cost O(c^2))
    for i in range(c - 1):
        if kind[i] >= 0:
            prev_c, prev_k = pos[i], kind[i]
        lo, hi, k = max(pos[i], s_lo), min(pos[i + 1], s_hi), kidx[i]
        if hi <= lo or dead[i]:
            continue
        if ahead <= i:
            ahead = i + 1
            while ahead < c and kind[ahead] < 0:
                ahead += 1
        next_c, next_k = (pos[ahead], kind[ahead]) if ahead < c else (math.inf, -1)
        if lo == 0.0 and k < 0 and rh[0] != rh[0]:
            # behind a machine spring the lift path starts like sqrt(s) (the punch catching
            # up with the driver, machine_lift): graded toward s = 0 with u^2 there (kind 2:
            # the path is a polynomial of high degree in sqrt(s), which one u^2 panel left
            # 2e-9 off in the force at a stiff spring's onset)
            prev_c, prev_k = 0.0, 2
        width = hi - lo
        need_l = (lo - prev_c) * 3.0 < width
        need_r = (next_c - hi) * 3.0 < width
        mid = 0.5 * (lo + hi) if need_l and need_r else (hi if need_l else lo)
        power_l = _substituted(prev_k, prev_c == lo, gx.size)
        power_r = _substituted(next_k, next_c == hi, gx.size)
        if need_l and power_l:
            acc += _toward_point(lo, mid, k, not need_l, power_l, ctx, rh, cr, hist, n, segs,
                                 deg, gx, gw, w, dw)
        elif need_l:
            acc += _graded_toward(lo, mid, k, prev_c, not need_l, n_graded, prev_k != 1, ctx, rh,
                                  cr, hist, n, segs, deg, gx, gw, w, dw)
        if need_r and power_r:
            acc += _toward_point(mid, hi, k, need_r, power_r, ctx, rh, cr, hist, n, segs, deg,
                                 gx, gw, w, dw)
        elif need_r:
            acc += _graded_toward(mid, hi, k, next_c, need_r, n_graded, next_k == 0, ctx, rh,
                                  cr, hist, n, segs, deg, gx, gw, w, dw)
        if need_l or need_r:
            continue
        if (0 <= k < states.shape[0] and k + deg + 2 < n and lo == hist[0, k]
                and hi == hist[0, k + 1]):
            rule = _rule_at(lo, hi, prev_c, next_c, k, n, segs, hist, rules)
            acc += _interval_from_states(k, states, rule, rules, ctx, rh, cr, hist, n, segs,
                                         deg, w, dw)
        else:
            acc += _history_panel(lo, hi, k, k - k, ctx, rh, cr, hist, n, segs, deg, gx, gw,
                                  w, dw)  # (k - k: 0, not a constant)
    return acc


@njit(cache=True)
def local_terms(ctx, rh, cr):
    """The instantaneous compliance's term and the Kelvin-Voigt lift step's impulse."""
    T, ell_T, r_T, P_T = ctx[2], ctx[3], ctx[4], ctx[5]
    total = cr[0] * opening_now(ell_T, r_T, P_T)
    if cr[1] != 0.0:
        r0 = _pinned_state(0.0, rh, ctx)[1]
        Q = P_T + r0 - r_T
        if Q > 0.0:
            total += cr[1] * creep_rate(T, cr) * math.atan2(math.sqrt(Q), math.sqrt(1.0 - r0))
    return total


@njit(cache=True)
def edge_gap_split(ctx, rh, cr, hist, n, segs, deg, gx, gw, n_graded, s_split, part, states,
                   rules):
    """gap(b_T)/delta; ctx = [t_on, zone, T, ell_T, r_T, P_T, t_strength] (t_strength: the
    face's strength limit, :func:`_pinned_state`; inf for none). part 0: the memory before
    s_split; 1: the rest (with the local terms); all of it: part 1 from ``-inf``. ``states``:
    the history's intervals' Gauss states, rows of ``1 + 5 gx.size`` and the nodes' (r, P) in the
    last three columns (:func:`history_integral`, :func:`_node_rp`).
    (One entry point: numba optimises each with its callees, so a second one for the whole
    memory cost ~1.5 s more of a first compile.)"""
    T = ctx[2]
    s0 = memory_start(T, cr)
    if part == 0:
        if cr.size <= 2 or T <= 0.0 or s_split <= s0:
            return 0.0
        return history_integral(ctx, rh, cr, hist, n, segs, deg, gx, gw, n_graded, s0, s_split,
                                states, rules)
    total = local_terms(ctx, rh, cr)
    if cr.size <= 2 or T <= 0.0:
        return total
    return total + history_integral(ctx, rh, cr, hist, n, segs, deg, gx, gw, n_graded,
                                    max(s0, s_split), T, states, rules)


# --- the lift behind a machine spring while the bond recedes (solvers.edge_machine) -------------
@njit(cache=True)
def total_force(a, ell):
    """``(f, df/dell)``: ``f = a ell + (a^2 + ell^2) atan2(ell, a)``, the whole line load
    over ``2 sigma_c R^2`` with the edge condition ``b^2 = a^2 + ell^2``."""
    angle = math.atan2(ell, a)
    return a * ell + (a * a + ell * ell) * angle, 2.0 * (a + ell * angle)


@njit(cache=True)
def lift_step_weights(hist, first, i, rate, gx, gw, weights):
    """``int e^(-rate (t_i - s)) ell(s) ds`` over the history's last interval (``i - 1``
    to ``i``) is ``weights @ ell`` at the last ``m`` nodes of the piece from ``first`` (the
    degree-5 interpolant in sigma, Gauss ``gx, gw`` on [0, 1]); returns ``m`` and writes
    ``weights[:m]``."""
    m = min(i - first + 1, 6)
    i0 = i - m + 1
    lo, hi = hist[2, i - 1], hist[2, i]
    basis = np.empty(m)
    dbasis = np.empty(m)
    for j in range(m):
        weights[j] = 0.0
    for g in range(gx.size):
        _basis(hist, 2, i0, m, lo + (hi - lo) * gx[g], basis, dbasis)
        lag = 0.0
        ds = 0.0
        for j in range(m):
            lag += basis[j] * (hist[0, i] - hist[0, i0 + j])  # (see _lag, _at_sigma)
            ds += dbasis[j] * (hist[0, i0 + j] - hist[0, i0])
        factor = gw[g] * (hi - lo) * ds * math.exp(-rate * lag)
        for j in range(m):
            weights[j] += factor * basis[j]
    return m


@njit(cache=True)
def receding_lift(hist, lifts, first, i, kappa, k, c, gx, gw):
    """``(ell, H)`` at node ``i`` of a receding bond behind a machine spring (``hist`` rows
    0-2 set there; ``ell = hist[3]`` and ``H = lifts`` at the earlier nodes): the force
    balance ``kappa (t - H) = f(a, ell)`` with ``ell = k H + c dH/dt``, the lift as the
    exponential integral of ``ell`` over the last interval (see ``solvers.edge_machine``);
    Newton on ``ell`` from the last node's."""
    t = hist[0, i]
    a = math.sqrt(max(1.0 - hist[1, i], 0.0))
    ell = hist[3, i - 1]
    known = 0.0
    w_new = 0.0
    if c > 0.0:
        weights = np.empty(6)
        m = lift_step_weights(hist, first, i, k / c, gx, gw, weights)
        known = math.exp(-k * (t - hist[0, i - 1]) / c) * lifts[i - 1]
        for j in range(m - 1):
            known += weights[j] * hist[3, i - m + 1 + j] / c
        w_new = weights[m - 1] / c
    for _ in range(60):
        f, df = total_force(a, ell)
        if c > 0.0:
            g = t - f / kappa - known - w_new * ell
            dg = -df / kappa - w_new
        else:
            g = ell / k - t + f / kappa
            dg = 1.0 / k + df / kappa
        ell_new = ell - g / dg
        if ell_new <= 0.0:
            ell_new = 0.5 * ell
        done = abs(ell_new - ell) <= 1e-15 * ell
        ell = ell_new
        if done:
            break
    return ell, t - total_force(a, ell)[0] / kappa
