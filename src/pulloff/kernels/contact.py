"""Numba kernels of the contact stepper (:mod:`pulloff.solvers.contact`).

Everything is dimensionless (lengths in ``L``, displacements in ``delta``, time in ``T``, line
loads in ``2 sigma_c L``; see the solver). A free element at ``xi`` carries the Dugdale load
``Q = sqrt(B^2 - xi^2)`` while the zone end ``B`` is beyond it. Over one step ``B`` is a
quadratic in the step fraction ``s`` in [0, 1], ``B(s) = p0 + p1 s + p2 s^2``.

Element law in state-space form (one law for every rheology): modes ``Y_k`` with
``dY_k/dt = lam_k Y_k + z_k Q`` and ``U = sum ctil_k Y_k + d Q`` (Kelvin-Voigt: one mode, ``Y = U``;
a Maxwell solid: its arms' dashpots in the eigenbasis of the coupled system; elastic: no mode).
A step is exact for the modes; only the load integral ``int e^{-mu_k (1 - s)} Q(s) ds`` is a
quadrature:

- an element far from a root of ``B(s) = xi`` (:func:`young_reach` steps) has a smooth load, and the 3-point Radau rule fitted to the
  exponential (exact for quadratic loads at any ``mu``, and exact as ``mu -> inf`` since it
  has a node at the end of the step) integrates it;
- near a root (an entry into the zone, an exit, wherever in the step it falls) the load is a
  square root of the time from the root: the substitution ``s = root +- w^2`` removes it, and
  Gauss-Legendre panels in ``w``, no wider than the exponential's scale near the end of the
  step where it peaks, integrate it.

Kernels that call each other live in this one module.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit



@njit(cache=True)
def young_reach(mu_max):
    """Steps from a root of ``B(s) = xi`` within which an element's load counts as a square
    root: beyond, the fitted Radau rule's error on ``sqrt(s - root)`` is below ~3e-8 of the
    step's integral (measured: it falls like ``distance^-4.5`` for ``mu <~ 1`` and like
    ``distance^-2.5 / mu`` for ``mu >> 1``)."""
    if mu_max <= 100.0:
        return 16.0 if mu_max <= 1.0 else 24.0
    return 8.0 if mu_max <= 1e4 else 4.0

#: Radau IIA nodes: the last is the end of the step.
RADAU3 = np.array([(4.0 - math.sqrt(6.0)) / 10.0, (4.0 + math.sqrt(6.0)) / 10.0, 1.0])
_x6, _w6 = np.polynomial.legendre.leggauss(6)
GL6_X = 0.5 * (_x6 + 1.0)
GL6_W = 0.5 * _w6


@njit(cache=True)
def exp_moments(mu):
    """``(M0, M1, M2)``, ``M_k = int_0^1 exp(-mu (1 - s)) s^k ds``, stable for ``mu >= 0``."""
    if mu < 0.5:
        # M_k = sum_j (-mu)^j k! / (j + k + 1)!: the recursion below cancels for small mu.
        m0 = m1 = m2 = 0.0
        term = 1.0  # (-mu)^j / j!
        for j in range(30):
            f1 = 1.0 / (j + 1.0)
            f2 = f1 / (j + 2.0)
            f3 = f2 / (j + 3.0)
            m0 += term * f1 * 1.0
            m1 += term * f2 * 1.0
            m2 += term * f3 * 2.0
            term *= -mu / (j + 1.0)
            if abs(term) < 1e-18:
                break
        return m0, m1, m2
    m0 = -math.expm1(-mu) / mu
    m1 = (1.0 - m0) / mu
    m2 = (1.0 - 2.0 * m1) / mu
    return m0, m1, m2


@njit(cache=True)
def fitted_radau3(mu, out):
    """Weights ``W_i`` with ``int_0^1 e^{-mu (1-s)} P(s) ds = sum W_i P(s_i)`` exactly for every
    quadratic ``P``, at the 3 Radau points ``s_i`` (for ``mu = 0`` the Radau rule itself)."""
    m0, m1, m2 = exp_moments(mu)
    for i in range(3):
        a = RADAU3[(i + 1) % 3]
        b = RADAU3[(i + 2) % 3]
        c = RADAU3[i]
        den = (c - a) * (c - b)
        # l_i(s) = (s - a)(s - b) / den = (s^2 - (a + b) s + a b) / den
        out[i] = (m2 - (a + b) * m1 + a * b * m0) / den


@njit(cache=True)
def path_value(p0, p1, p2, s):
    return p0 + s * (p1 + s * p2)


@njit(cache=True)
def load_at(p0, p1, p2, xi, s):
    """``Q = sqrt(B(s)^2 - xi^2)`` inside the zone, 0 beyond it."""
    b = path_value(p0, p1, p2, s)
    d = b - xi
    if d <= 0.0:
        return 0.0
    return math.sqrt(d * (b + xi))


@njit(cache=True)
def path_roots(p0, p1, p2, xi, lo, hi, roots):
    """Real roots of ``B(s) = xi`` in ``(lo, hi)``, ascending, into ``roots``; returns how many."""
    c = p0 - xi
    n = 0
    if abs(p2) < 1e-14 * (abs(p1) + abs(c) + 1e-300):
        if p1 != 0.0:
            r = -c / p1
            if lo < r < hi:
                roots[0] = r
                n = 1
        return n
    disc = p1 * p1 - 4.0 * p2 * c
    if disc < 0.0:
        return 0
    sq = math.sqrt(disc)
    # Citardauq: no cancellation in either root.
    q = -0.5 * (p1 + (sq if p1 >= 0.0 else -sq))
    r1 = q / p2
    r2 = c / q if q != 0.0 else r1
    if r1 > r2:
        r1, r2 = r2, r1
    if lo < r1 < hi:
        roots[n] = r1
        n += 1
    if lo < r2 < hi and r2 != r1:
        roots[n] = r2
        n += 1
    return n


@njit(cache=True)
def _panel(p0, p1, p2, xi, a, b, root, side, mus, nm, s1, out):
    """Adds ``int_a^b e^{-mu_k (s1-s)} Q(s) ds`` to ``out`` by 6-point Gauss-Legendre; with
    ``side = +1`` (-1) the load is a square root of ``s - root`` (``root - s``) and
    ``s = root +- w^2`` removes it."""
    if b <= a:
        return
    if side == 0:
        for i in range(6):
            s = a + (b - a) * GL6_X[i]
            q = load_at(p0, p1, p2, xi, s) * GL6_W[i] * (b - a)
            for k in range(nm):
                out[k] += q * math.exp(-mus[k] * (s1 - s))
        return
    wa = math.sqrt(max(0.0, side * (a - root)))
    wb = math.sqrt(max(0.0, side * (b - root)))
    w_lo, w_hi = min(wa, wb), max(wa, wb)
    for i in range(6):
        w = w_lo + (w_hi - w_lo) * GL6_X[i]
        s = root + side * w * w
        q = load_at(p0, p1, p2, xi, s) * GL6_W[i] * (w_hi - w_lo) * 2.0 * w
        for k in range(nm):
            out[k] += q * math.exp(-mus[k] * (s1 - s))


#: Panel widths (in units of the kernel's scale ``1/mu``) by distance from the end of a piece:
#: 6-point Gauss-Legendre then meets ~1e-11 of the piece's integral (its error is
#: ~ e^-distance (width/2)^12 / 12!); beyond the last distance the kernel is below e^-40.
_PANEL_EDGES = np.array([0.0, 1.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0, 16.0, 20.0, 24.0, 32.0,
                         40.0])


@njit(cache=True)
def _piece(p0, p1, p2, xi, a, b, root, side, mus, nm, mu_max, s1, out):
    """``int_a^b e^{-mu_k (s1-s)} Q ds`` over one loaded piece: one panel where the exponential is
    flat across it, else panels graded away from ``b`` (where the kernel peaks)."""
    if mu_max * (b - a) <= 1.0:
        _panel(p0, p1, p2, xi, a, b, root, side, mus, nm, s1, out)
        return
    scale = 1.0 / mu_max
    for j in range(_PANEL_EDGES.size - 1):
        hi = b - _PANEL_EDGES[j] * scale
        lo = b - _PANEL_EDGES[j + 1] * scale
        if j == _PANEL_EDGES.size - 2 or lo <= a:
            lo = max(lo, a)
            _panel(p0, p1, p2, xi, lo, hi, root, side, mus, nm, s1, out)
            return
        _panel(p0, p1, p2, xi, lo, hi, root, side, mus, nm, s1, out)


@njit(cache=True)
def _graded_around(p0, p1, p2, xi, a, b, centre, width, mus, nm, mu_max, s1, out):
    """Panels from ``centre`` outward, ``width, 2 width, 4 width, ...`` wide, each no wider
    than the kernel's scale allows (:func:`_piece`), over ``[a, b]``."""
    for side in (-1.0, 1.0):
        end = a if side < 0 else b
        lo = centre
        w = width
        while (end - lo) * side > 0.0:
            hi = lo + side * w
            if (hi - end) * side > 0.0:
                hi = end
            _piece(p0, p1, p2, xi, min(lo, hi), max(lo, hi), 0.0, 0, mus, nm, mu_max, s1, out)
            lo = hi
            w *= 2.0


@njit(cache=True)
def load_integrals(p0, p1, p2, xi, s0, s1, mus, nm, w3, out):
    """``out[k] = int_{s0}^{s1} e^{-mu_k (s1-s)} Q(s) ds`` for one element (the whole step
    ``[0, 1]``, or part of it for an element the contact edge releases or captures inside the
    step). ``w3[k, i]`` are the fitted Radau weights of each mode (:func:`fitted_radau3`);
    returns ``Q(s1)``."""
    for k in range(nm):
        out[k] = 0.0
    mu_max = 1.0
    for k in range(nm):
        mu_max = max(mu_max, mus[k])
    reach = young_reach(mu_max)
    roots = np.empty(2)
    n = path_roots(p0, p1, p2, xi, s0 - reach, s1 + reach, roots)
    if n == 0 and p2 != 0.0:
        # B - xi may touch zero only nearly (a turning point of the zone end just beyond the
        # element): the load is then steep around the vertex; panels graded toward it.
        vertex = -p1 / (2.0 * p2)
        depth = (path_value(p0, p1, p2, vertex) - xi) / p2  # = (half-width of the near-root)^2
        centre = min(max(vertex, s0), s1)
        width = max(math.sqrt(max(depth, 0.0)), abs(vertex - centre), 1e-12)
        if depth >= 0.0 and width < reach and path_value(p0, p1, p2, centre) > xi:
            _graded_around(p0, p1, p2, xi, s0, s1, centre, width, mus, nm, mu_max, s1, out)
            return load_at(p0, p1, p2, xi, s1)
    if n == 0 and s0 == 0.0 and s1 == 1.0:
        if path_value(p0, p1, p2, 0.5) > xi:  # loaded all step, far from any root
            for i in range(3):
                q = load_at(p0, p1, p2, xi, RADAU3[i])
                for k in range(nm):
                    out[k] += w3[k, i] * q
        return load_at(p0, p1, p2, xi, 1.0)
    # Pieces of [s0, 1] between roots; the load's sign is that of B - xi at their middle.
    cuts = np.empty(4)
    nc = 0
    cuts[nc] = s0
    nc += 1
    for j in range(n):
        if s0 < roots[j] < s1:
            cuts[nc] = roots[j]
            nc += 1
    cuts[nc] = s1
    nc += 1
    for j in range(nc - 1):
        a = cuts[j]
        b = cuts[j + 1]
        if b <= a or path_value(p0, p1, p2, 0.5 * (a + b)) <= xi:
            continue
        root_lo = -math.inf
        root_hi = math.inf
        for r in range(n):
            if roots[r] <= a + 1e-15:
                root_lo = roots[r]
            elif roots[r] >= b - 1e-15 and root_hi == math.inf:
                root_hi = roots[r]
        near_lo = a - root_lo <= reach
        near_hi = root_hi - b <= reach
        if near_lo and near_hi:
            # An entry and an exit: each half substitutes from its own root.
            mid = 0.5 * (a + b)
            _piece(p0, p1, p2, xi, a, mid, root_lo, 1, mus, nm, mu_max, s1, out)
            _piece(p0, p1, p2, xi, mid, b, root_hi, -1, mus, nm, mu_max, s1, out)
        elif near_lo:
            _piece(p0, p1, p2, xi, a, b, root_lo, 1, mus, nm, mu_max, s1, out)
        elif near_hi:
            _piece(p0, p1, p2, xi, a, b, root_hi, -1, mus, nm, mu_max, s1, out)
        else:
            _piece(p0, p1, p2, xi, a, b, 0.0, 0, mus, nm, mu_max, s1, out)
    return load_at(p0, p1, p2, xi, s1)


@njit(cache=True)
def advance_free(Y, i, integrals, decay, zdt, ctil, d, q_end, nm):
    """Advance element ``i``'s modes by one step and return its displacement ``U``."""
    u = d * q_end
    for k in range(nm):
        y = decay[k] * Y[i, k] + zdt[k] * integrals[k]
        Y[i, k] = y
        u += ctil[k] * y
    return u


# --- gap integral ------------------------------------------------------------------------------

@njit(cache=True)
def _cubic_weights(t0, t1, t2, t3, a, b, w):
    """``w[j] = int_a^b l_j(t) dt`` for the Lagrange cubic through ``t0..t3``."""
    ts = (t0, t1, t2, t3)
    for j in range(4):
        # Coefficients of prod_{m != j} (t - t_m) / (t_j - t_m), integrated exactly.
        den = 1.0
        roots = np.empty(3)
        r = 0
        for m in range(4):
            if m != j:
                den *= ts[j] - ts[m]
                roots[r] = ts[m]
                r += 1
        e1 = roots[0] + roots[1] + roots[2]
        e2 = roots[0] * roots[1] + roots[0] * roots[2] + roots[1] * roots[2]
        e3 = roots[0] * roots[1] * roots[2]
        # t^3 - e1 t^2 + e2 t - e3, integrated in shifted form for accuracy.
        ib = ((b ** 4 - a ** 4) / 4.0 - e1 * (b ** 3 - a ** 3) / 3.0
              + e2 * (b * b - a * a) / 2.0 - e3 * (b - a))
        w[j] = ib / den


@njit(cache=True)
def piecewise_cubic_integral(t, f, n):
    """``int_{t[0]}^{t[n-1]} f dt`` of the piecewise cubic through nodes ``t`` (ascending,
    non-uniform): each interval uses the cubic through its 4 nearest nodes. Fewer than 4
    nodes: the interpolating polynomial of them all."""
    if n < 2:
        return 0.0
    if n == 2:
        return 0.5 * (t[1] - t[0]) * (f[0] + f[1])
    if n == 3:
        # The quadratic through the three, integrated exactly (Simpson on uneven nodes).
        h0 = t[1] - t[0]
        h1 = t[2] - t[1]
        hs = h0 + h1
        return hs / 6.0 * ((2.0 - h1 / h0) * f[0] + hs * hs / (h0 * h1) * f[1]
                           + (2.0 - h0 / h1) * f[2])
    total = 0.0
    w = np.empty(4)
    for j in range(n - 1):
        s = min(max(j - 1, 0), n - 4)
        # Shift the origin to the interval for accuracy on tiny intervals far from 0.
        o = t[j]
        _cubic_weights(t[s] - o, t[s + 1] - o, t[s + 2] - o, t[s + 3] - o, 0.0,
                       t[j + 1] - o, w)
        for m in range(4):
            total += w[m] * f[s + m]
    return total


@njit(cache=True)
def extrapolate_cubic(t, f, n, x):
    """The polynomial through the first ``min(n, 4)`` nodes, evaluated at ``x``."""
    m = min(n, 4)
    out = 0.0
    for j in range(m):
        lj = 1.0
        for k in range(m):
            if k != j:
                lj *= (x - t[k]) / (t[j] - t[k])
        out += lj * f[j]
    return out


@njit(cache=True)
def angle(xi, beta):
    """``acos(xi / beta)`` without cancellation near ``xi = beta``."""
    r2 = (beta - xi) * (beta + xi)
    return math.atan2(math.sqrt(max(r2, 0.0)), xi)


# --- the indenter profile ----------------------------------------------------------------------

@njit(cache=True)
def sin_power_integral(n, theta):
    """``int_0^theta sin(t)^n dt`` for ``n >= 0``: closed forms for n = 0, 1, 2; otherwise
    Gauss-Legendre after ``t = theta w^(1/(n+1))``-like smoothing (24 nodes, ~1e-13)."""
    if n == 0.0:
        return theta
    if n == 1.0:
        return 2.0 * math.sin(0.5 * theta) ** 2  # 1 - cos(theta)
    if n == 2.0:
        return 0.5 * (theta - math.sin(theta) * math.cos(theta))
    total = 0.0
    # t = theta u^2: the integrand ~ (theta u^2)^n 2 theta u is smooth in u near 0.
    for half in range(2):
        for i in range(6):
            u = 0.5 * (half + GL6_X[i])
            t = theta * u * u
            total += 0.5 * GL6_W[i] * math.sin(t) ** n * 2.0 * theta * u
    return total


@njit(cache=True)
def profile_integral(C, n, alpha, beta):
    """``int_0^alpha C x^n / sqrt(beta^2 - x^2) dx`` (a power-law MDR profile, ``alpha <= beta``)."""
    if C == 0.0 or alpha <= 0.0:
        return 0.0
    theta = math.asin(min(1.0, alpha / beta))
    return C * beta ** n * sin_power_integral(n, theta)


# --- the field and the gap -------------------------------------------------------------------

@njit(cache=True)
def free_field(xi, Y0, s0, lo, hi, p0, p1, p2, mus, zdt, ctil, d, nm, w3, Y_out, U_out):
    """Free elements ``lo..hi-1`` advanced from ``s0[i]`` (0, or where the edge released them)
    to the end of the step under the load of the zone-end path ``p``: modes into ``Y_out``,
    displacements into ``U_out``."""
    ints = np.empty(max(nm, 1))
    for i in range(lo, hi):
        q1 = load_integrals(p0, p1, p2, xi[i], s0[i], 1.0, mus, nm, w3, ints)
        u = d * q1
        for k in range(nm):
            y = math.exp(-mus[k] * (1.0 - s0[i])) * Y0[i, k] + zdt[k] * ints[k]
            Y_out[i, k] = y
            u += ctil[k] * y
        U_out[i] = u


@njit(cache=True)
def free_gap_integral(xi, U, lo, hi, alpha, beta, U_alpha, U_beta):
    """``int_alpha^beta U / sqrt(beta^2 - xi^2) dxi = int_0^theta_a U dtheta`` with
    ``xi = beta cos(theta)``: the piecewise cubic through the nodes strictly inside, ``U_alpha``
    at the contact edge and ``U_beta`` at the zone end (nan: extrapolated from the nodes next to
    it, where ``U`` is smooth in ``theta``)."""
    n_in = 0
    for i in range(lo, hi):
        if alpha < xi[i] < beta:
            n_in += 1
    m = n_in + 2
    th = np.empty(m)
    f = np.empty(m)
    j = 1
    for i in range(hi - 1, lo - 1, -1):  # descending xi: ascending theta
        if alpha < xi[i] < beta:
            th[j] = angle(xi[i], beta)
            f[j] = U[i]
            j += 1
    th[0] = 0.0
    th[m - 1] = angle(alpha, beta) if alpha > 0.0 else 0.5 * math.pi
    f[m - 1] = U_alpha
    # Nodes closer than rounding to an end would make a degenerate interval: drop them.
    k = 1
    for i in range(1, m - 1):
        if th[i] - th[k - 1] > 1e-13 and th[m - 1] - th[i] > 1e-13:
            th[k] = th[i]
            f[k] = f[i]
            k += 1
    th[k] = th[m - 1]
    f[k] = f[m - 1]
    m = k + 1
    if math.isnan(U_beta):
        f[0] = extrapolate_cubic(th[1:], f[1:], m - 1, 0.0)
    else:
        f[0] = U_beta
    return piecewise_cubic_integral(th, f, m)


@njit(cache=True)
def interpolate_cubic(xs, fs, x):
    """Lagrange polynomial through the (up to 4) points ``xs``, ``fs`` at ``x``."""
    out = 0.0
    m = xs.size
    for j in range(m):
        lj = 1.0
        for k in range(m):
            if k != j:
                lj *= (x - xs[k]) / (xs[j] - xs[k])
        out += lj * fs[j]
    return out
