"""Numba kernels of the onset by quadrature: the exact gap of the seed scene as one integral
over the load history, with the zone's part in closed form.

Dimensionless as :mod:`pulloff.kernels.onset` (lengths in ``a``, displacements in ``delta``,
time in ``delta / v``; ``S(T) = k (H0 + T) + c``). An element at ``sigma`` entered the zone
when ``S`` passed it (or at ``T = 0``) and carries
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
#: Ratio of consecutive panels graded toward ``tau = 0``.
_GRADING = 0.25


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
    X = (a - x) / a
    Y = (a - y) / a
    Z = -(X + Y) / 3.0
    xy, zz = X * Y, Z * Z
    e2 = xy - 6.0 * zz
    e3 = (3.0 * xy - 8.0 * zz) * Z
    e4 = 3.0 * (xy - zz) * zz
    e5 = xy * zz * Z
    series = (1.0 - 3.0 * e2 / 14.0 + e3 / 6.0 + 9.0 * e2 * e2 / 88.0 - 3.0 * e4 / 22.0
              - 9.0 * e2 * e3 / 52.0 + 3.0 * e5 / 26.0)
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
        if g_mid < 0.0:
            lo, g_lo = mid, g_mid
            if side == -1:
                g_hi *= 0.5
            side = -1
        else:
            hi, g_hi = mid, g_mid
            if side == 1:
                g_lo *= 0.5
            side = 1
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
