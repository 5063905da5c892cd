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

# Numba gives every kernel a C-callable wrapper (for use as a first-class function, which none
# is here) and a Python entry, each compiled with it: seconds in all from an empty cache. No
# kernel here gets the first; the private ones only kernels call (all but _filtered_lift and
# _memory) go without the second too (called from Python, one would crash).

#: 0 as an argument of a kernel's call: numba compiles the callee once more for a literal 0
#: (it specialises on integer constants, and on a count's initial 0 while it infers types).
_ZERO = np.int64(0)


@njit(cache=True, no_cfunc_wrapper=True)
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
GL2_X = 1.0 / math.sqrt(3.0)  # 2-point Gauss-Legendre node on [-1, 1]


@njit(cache=True, no_cfunc_wrapper=True)
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


@njit(cache=True, no_cfunc_wrapper=True)
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


@njit(cache=True, no_cfunc_wrapper=True)
def path_value(p0, p1, p2, s):
    return p0 + s * (p1 + s * p2)


@njit(cache=True, no_cfunc_wrapper=True)
def load_at(p0, p1, p2, xi, s):
    """``Q = sqrt(B(s)^2 - xi^2)`` inside the zone, 0 beyond it."""
    b = path_value(p0, p1, p2, s)
    d = b - xi
    if d <= 0.0:
        return 0.0
    return math.sqrt(d * (b + xi))


@njit(cache=True, no_cfunc_wrapper=True)
def path_roots2(p0, p1, p2, xi, lo, hi):
    """``(count, r1, r2)``: the real roots of ``B(s) = xi`` in ``(lo, hi)``, ascending."""
    c = p0 - xi
    r1 = r2 = math.nan
    if abs(p2) < 1e-14 * (abs(p1) + abs(c) + 1e-300):
        if p1 != 0.0:
            r = -c / p1
            if lo < r < hi:
                return 1, r, math.nan
        return 0, r1, r2
    disc = p1 * p1 - 4.0 * p2 * c
    if disc < 0.0:
        return 0, r1, r2
    sq = math.sqrt(disc)
    # Citardauq: no cancellation in either root.
    q = -0.5 * (p1 + (sq if p1 >= 0.0 else -sq))
    a = q / p2
    b = c / q if q != 0.0 else a
    if a > b:
        a, b = b, a
    n = 0
    if lo < a < hi:
        r1 = a
        n = 1
    if lo < b < hi and b != a:
        if n == 0:
            r1 = b
        else:
            r2 = b
        n += 1
    return n, r1, r2


@njit(cache=True, no_cfunc_wrapper=True)
def path_roots(p0, p1, p2, xi, lo, hi, roots):
    """Real roots of ``B(s) = xi`` in ``(lo, hi)``, ascending, into ``roots``; returns how many."""
    n, r1, r2 = path_roots2(p0, p1, p2, xi, lo, hi)
    if n > 0:
        roots[0] = r1
    if n > 1:
        roots[1] = r2
    return n


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _panel(p0, p1, p2, xi, a, b, root, side, mus, nm, s1, out):
    """Adds ``int_a^b e^{-mu_k (s1-s)} Q(s) ds`` to ``out`` by 6-point Gauss-Legendre; with
    ``side = +1.0`` (-1.0) the load is a square root of ``s - root`` (``root - s``) and
    ``s = root +- w^2`` removes it (0.0: no substitution). ``side`` is a float: numba
    compiles a kernel once per integer constant it is passed (and this one with its callers)."""
    if b <= a:
        return
    if side == 0.0:
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


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _piece(p0, p1, p2, xi, a, b, root, side, mus, nm, mu_max, s1, out):
    """``int_a^b e^{-mu_k (s1-s)} Q ds`` over one loaded piece: one panel where the exponential is
    flat across it, else panels graded away from ``b`` (where the kernel peaks) on the fastest
    mode's scale, then, while a slower mode still sees the piece, panels a quarter of their
    distance from ``b`` wide (6-point error below ~2e-12 of that mode's integral)."""
    if mu_max * (b - a) <= 1.0:
        _panel(p0, p1, p2, xi, a, b, root, side, mus, nm, s1, out)
        return
    scale = 1.0 / mu_max
    mu_min = mu_max
    for k in range(nm):
        mu_min = min(mu_min, mus[k])
    for j in range(_PANEL_EDGES.size - 1):
        hi = b - _PANEL_EDGES[j] * scale
        lo = max(b - _PANEL_EDGES[j + 1] * scale, a)
        _panel(p0, p1, p2, xi, lo, hi, root, side, mus, nm, s1, out)
        if lo <= a:
            return
    distance = _PANEL_EDGES[-1] * scale
    while mu_min * distance < 40.0 and b - distance > a:
        lo = max(b - 1.25 * distance, a)
        _panel(p0, p1, p2, xi, lo, b - distance, root, side, mus, nm, s1, out)
        distance *= 1.25


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
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
            _piece(p0, p1, p2, xi, min(lo, hi), max(lo, hi), 0.0, 0.0, mus, nm, mu_max, s1, out)
            lo = hi
            w *= 2.0


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _loaded_piece(p0, p1, p2, xi, a, b, n, r1, r2, reach, mus, nm, mu_max, s1, out):
    """One piece ``[a, b]`` between roots: skipped where the zone does not reach, else
    integrated with the square-root substitution from whichever root is near."""
    if b <= a or path_value(p0, p1, p2, 0.5 * (a + b)) <= xi:
        return
    root_lo = -math.inf
    root_hi = math.inf
    for j in range(n):
        r = r1 if j == 0 else r2
        if r <= a + 1e-15:
            root_lo = r
        elif r >= b - 1e-15 and root_hi == math.inf:
            root_hi = r
    near_lo = a - root_lo <= reach
    near_hi = root_hi - b <= reach
    if near_lo and near_hi:
        # An entry and an exit: each half substitutes from its own root.
        mid = 0.5 * (a + b)
        _piece(p0, p1, p2, xi, a, mid, root_lo, 1.0, mus, nm, mu_max, s1, out)
        _piece(p0, p1, p2, xi, mid, b, root_hi, -1.0, mus, nm, mu_max, s1, out)
    elif near_lo:
        _piece(p0, p1, p2, xi, a, b, root_lo, 1.0, mus, nm, mu_max, s1, out)
    elif near_hi:
        _piece(p0, p1, p2, xi, a, b, root_hi, -1.0, mus, nm, mu_max, s1, out)
    else:
        _piece(p0, p1, p2, xi, a, b, 0.0, 0.0, mus, nm, mu_max, s1, out)


@njit(cache=True, no_cfunc_wrapper=True)
def load_integrals(p0, p1, p2, xi, s0, s1, mus, nm, w3, out):
    """``out[k] = int_{s0}^{s1} e^{-mu_k (s1-s)} Q(s) ds`` for one element (the whole step
    ``[0, 1]``, or part of it for an element the contact edge releases or captures inside the
    step). ``w3[k, i]`` are the fitted Radau weights of each mode (:func:`fitted_radau3`);
    returns ``Q(s1)``."""
    for k in range(nm):
        out[k] = 0.0
    mu_max = 1.0
    mu_min = math.inf
    for k in range(nm):
        mu_max = max(mu_max, mus[k])
        mu_min = min(mu_min, mus[k])
    # The slowest mode sees the square root farthest (the reach falls with mu).
    reach = young_reach(min(mu_min, mu_max))
    n, r1, r2 = path_roots2(p0, p1, p2, xi, s0 - reach, s1 + reach)
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
        return load_at(p0, p1, p2, xi, s1)
    # Pieces of [s0, s1] between the roots inside it.
    c1 = r1 if (n > 0 and s0 < r1 < s1) else math.nan
    c2 = r2 if (n > 1 and s0 < r2 < s1) else math.nan
    a = s0
    for j in range(3):
        cut = c1 if j == 0 else (c2 if j == 1 else s1)
        if math.isnan(cut):
            continue
        _loaded_piece(p0, p1, p2, xi, a, cut, n, r1, r2, reach, mus, nm, mu_max, s1, out)
        a = cut
    return load_at(p0, p1, p2, xi, s1)


@njit(cache=True, no_cfunc_wrapper=True)
def advance_free(Y, i, integrals, decay, zdt, ctil, d, q_end, nm):
    """Advance element ``i``'s modes by one step and return its displacement ``U``."""
    u = d * q_end
    for k in range(nm):
        y = decay[k] * Y[i, k] + zdt[k] * integrals[k]
        Y[i, k] = y
        u += ctil[k] * y
    return u


# --- gap integral ------------------------------------------------------------------------------

@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _basis_integral(tj, r0, r1, r2, a, b):
    """``int_a^b prod_m (t - r_m) / (tj - r_m) dt`` over the three other nodes ``r``."""
    den = (tj - r0) * (tj - r1) * (tj - r2)
    e1 = r0 + r1 + r2
    e2 = r0 * r1 + r0 * r2 + r1 * r2
    e3 = r0 * r1 * r2
    ib = ((b ** 4 - a ** 4) / 4.0 - e1 * (b ** 3 - a ** 3) / 3.0
          + e2 * (b * b - a * a) / 2.0 - e3 * (b - a))
    return ib / den


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _cubic_weights(t0, t1, t2, t3, a, b, w):
    """``w[j] = int_a^b l_j(t) dt`` for the Lagrange cubic through ``t0..t3``."""
    w[0] = _basis_integral(t0, t1, t2, t3, a, b)
    w[1] = _basis_integral(t1, t0, t2, t3, a, b)
    w[2] = _basis_integral(t2, t0, t1, t3, a, b)
    w[3] = _basis_integral(t3, t0, t1, t2, a, b)


#: A stencil node closer than this share of the interval to the stencil's last node on its side
#: is passed over: Lagrange weights through clustered nodes (a zone end's graded start beside a
#: wide released stretch) grow like the spacing ratio cubed and turn rounding into garbage.
SPREAD = 0.25


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _spread_stencil(t, n, j, idx):
    """Up to 4 nodes for the interval ``t[j]..t[j+1]``: its ends, then outward one side at a
    time (left first), each at least ``SPREAD`` times the interval from the last one taken on
    its side; on an even or gently graded mesh this is ``j-1..j+2`` (shifted at the ends).
    Returns the count."""
    gap = SPREAD * (t[j + 1] - t[j])
    idx[0], idx[1] = j, j + 1
    m, left, right, kl, kr = 2, j, j + 1, j - 1, j + 2
    while m < 4:
        grew = False
        while kl >= 0 and t[left] - t[kl] < gap:
            kl -= 1
        if kl >= 0:
            idx[m] = kl
            left, kl, m, grew = kl, kl - 1, m + 1, True
        if m == 4:
            break
        while kr < n and t[kr] - t[right] < gap:
            kr += 1
        if kr < n:
            idx[m] = kr
            right, kr, m, grew = kr, kr + 1, m + 1, True
        if not grew:
            break
    return m


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _lagrange_integral_weights(ts, m, a, b, w):
    """``w[k] = int_a^b l_k(t) dt`` for the Lagrange basis through ``ts[:m]`` (m <= 4), by
    2-point Gauss-Legendre, exact for these cubics."""
    half, mid = 0.5 * (b - a), 0.5 * (a + b)
    for k in range(m):
        w[k] = 0.0
    for g in range(2):
        x = mid + half * (GL2_X if g == 0 else -GL2_X)
        for k in range(m):
            lk = 1.0
            for q in range(m):
                if q != k:
                    lk *= (x - ts[q]) / (ts[k] - ts[q])
            w[k] += half * lk


@njit(cache=True, no_cfunc_wrapper=True)
def piecewise_cubic_integral(t, f, n):
    """``int_{t[0]}^{t[n-1]} f dt`` of the piecewise cubic through nodes ``t`` (ascending,
    non-uniform): each interval uses the cubic through its well-spread neighbours
    (:func:`_spread_stencil`; fewer than 4 where the mesh has no more: a lower degree)."""
    if n < 2:
        return 0.0
    total = 0.0
    w = np.empty(4)
    ts = np.empty(4)
    idx = np.empty(4, dtype=np.int64)
    for j in range(n - 1):
        if t[j + 1] <= t[j]:  # an empty interval (a zone of no width)
            continue
        m = _spread_stencil(t, n, j, idx)
        # Shift the origin to the interval for accuracy on tiny intervals far from 0.
        o = t[j]
        for k in range(m):
            ts[k] = t[idx[k]] - o
        if m == 4:
            _cubic_weights(ts[0], ts[1], ts[2], ts[3], 0.0, t[j + 1] - o, w)
        else:
            _lagrange_integral_weights(ts, m, 0.0, t[j + 1] - o, w)
        for k in range(m):
            total += w[k] * f[idx[k]]
    return total


@njit(cache=True, no_cfunc_wrapper=True)
def extrapolate_cubic(t, f, n, x):
    """The polynomial through up to 4 of the first nodes, evaluated at ``x`` (outside them):
    the first, then each next one at least ``SPREAD`` times the distance to ``x`` beyond the
    last taken (clustered nodes would multiply rounding by the distance ratio cubed)."""
    idx = np.empty(4, dtype=np.int64)
    idx[0] = 0
    m = 1
    gap = SPREAD * abs(x - t[0])
    for j in range(1, n):
        if m == 4:
            break
        if abs(t[j] - t[idx[m - 1]]) >= gap:
            idx[m] = j
            m += 1
    out = 0.0
    for a in range(m):
        lj = 1.0
        for b in range(m):
            if b != a:
                lj *= (x - t[idx[b]]) / (t[idx[a]] - t[idx[b]])
        out += lj * f[idx[a]]
    return out


@njit(cache=True, no_cfunc_wrapper=True)
def angle(xi, beta):
    """``acos(xi / beta)`` without cancellation near ``xi = beta``."""
    r2 = (beta - xi) * (beta + xi)
    return math.atan2(math.sqrt(max(r2, 0.0)), xi)


# --- the indenter profile ----------------------------------------------------------------------

@njit(cache=True, no_cfunc_wrapper=True)
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


@njit(cache=True, no_cfunc_wrapper=True)
def profile_integral(C, n, alpha, beta):
    """``int_0^alpha C x^n / sqrt(beta^2 - x^2) dx`` (a power-law MDR profile, ``alpha <= beta``)."""
    if C == 0.0 or alpha <= 0.0:
        return 0.0
    theta = math.asin(min(1.0, alpha / beta))
    return C * beta ** n * sin_power_integral(n, theta)


# --- the field and the gap -------------------------------------------------------------------

@njit(cache=True, no_cfunc_wrapper=True)
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


@njit(cache=True, no_cfunc_wrapper=True)
def free_gap_integral(xi, U, lo, hi, alpha, beta, U_alpha, U_beta, kink=0.0):
    """``int_alpha^beta U / sqrt(beta^2 - xi^2) dxi = int_0^theta_a U dtheta`` with
    ``xi = beta cos(theta)``: the piecewise cubic through the nodes strictly inside, ``U_alpha``
    at the contact edge and ``U_beta`` at the zone end (nan: extrapolated from the nodes next to
    it, where ``U`` is smooth in ``theta``; only from those beyond ``kink``, where ``U`` has a
    kink inside the zone and at least two nodes lie between it and the end). With two nodes or
    more on each side of the kink no stencil crosses it (:func:`_split_integral`); with one,
    the side's value at the kink would be a linear extrapolation over a sparse stretch
    (tried: separation_kv at 1e-2 m/s then jumped out spuriously at n = 128), so the cubic
    crosses it there."""
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
    # The nodes are in ascending theta: those beyond the kink come first.
    th_kink = angle(kink, beta) if alpha < kink < beta else math.nan
    beyond = 0  # interior nodes beyond the kink
    while beyond < m - 2 and th[beyond + 1] < th_kink:
        beyond += 1
    if math.isnan(U_beta):
        usable = beyond if beyond >= 2 else m - 1
        f[0] = extrapolate_cubic(th[1:], f[1:], usable, 0.0)
    else:
        f[0] = U_beta
    if beyond >= 2 and m - 2 - beyond >= 2:
        return _split_integral(th, f, m, beyond + 1, th_kink)
    return piecewise_cubic_integral(th, f, m)


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _split_integral(th, f, m, s, th_kink):
    """The piecewise cubic integral of ``f(th)`` with no stencil across ``th_kink``, between
    nodes ``s - 1`` and ``s``, where ``f`` is continuous but its slope jumps (a stencil across
    it is only second order in the spacing): each side runs to the kink with the value there
    extrapolated from its own nodes."""
    left_th = np.empty(s + 1)
    left_f = np.empty(s + 1)
    right_th = np.empty(m - s + 1)
    right_f = np.empty(m - s + 1)
    # Loops, not slice assignments: numba compiles a shape check with a formatted message
    # for each of those, into every caller.
    for j in range(s):
        left_th[j], left_f[j] = th[j], f[j]
    for j in range(s, m):
        right_th[j - s + 1], right_f[j - s + 1] = th[j], f[j]
    near_th = left_th[:s][::-1].copy()  # nearest the kink first
    near_f = left_f[:s][::-1].copy()
    left_th[s] = th_kink
    left_f[s] = extrapolate_cubic(near_th, near_f, s, th_kink)
    right_th[0] = th_kink
    right_f[0] = extrapolate_cubic(right_th[1:], right_f[1:], m - s, th_kink)
    return (piecewise_cubic_integral(left_th, left_f, s + 1)
            + piecewise_cubic_integral(right_th, right_f, m - s + 1))


# --- one trial step, compiled ------------------------------------------------------------------
#: Indices of the scalar results of :func:`evaluate_step`.
R_GAP, R_EDGE_LOAD, R_F_CONTACT, R_F_TOTAL, R_CENTRE_U, R_N = range(6)
#: Indices of the step constants ``sc`` of :func:`evaluate_step`.
#: ``S_LIVE_END``: the nearest archived element (inf: none; see ``contact_state.Nodes``).
#: ``S_JUMP``: 1.0 in a zero-time transition (``Step.jump``: the dashpots do not move).
(S_T0, S_DT, S_ALPHA0, S_BETA0, S_H1, S_HDOT, S_XIMAX, S_KAPPA, S_C, S_D, S_FLAT, S_AF, S_C_G,
 S_N_G, S_K_ALPHA, S_K_BETA, S_FRESH, S_KINK, S_LIVE_END, S_JUMP, S_N) = range(21)


@njit(cache=True, no_cfunc_wrapper=True)
def path_root(p0, p1, p2, x):
    """The fraction of the step where the path passes ``x`` (clamped to the step)."""
    n, r1, r2 = path_roots2(p0, p1, p2, x, -1e-12, 1.0 + 1e-12)
    if n == 0:
        return 1.0 if abs(path_value(p0, p1, p2, 1.0) - x) < abs(p0 - x) else 0.0
    return min(max(r1, 0.0), 1.0)


@njit(cache=True, no_cfunc_wrapper=True)
def table_g(knots, jumps, x):
    """``g(x) = sum_j s_j x acos(r_j/x)`` of a tabulated tip written as ramps
    ``f = sum_j s_j (r - r_j)_+`` (exact for the piecewise-linear interpolant)."""
    x = abs(x)
    total = 0.0
    for j in range(knots.size):
        r = knots[j]
        if x > r:
            total += jumps[j] * x * math.atan2(math.sqrt((x - r) * (x + r)), r)
    return total


@njit(cache=True, no_cfunc_wrapper=True)
def table_f(knots, jumps, r):
    total = 0.0
    for j in range(knots.size):
        if r > knots[j]:
            total += jumps[j] * (r - knots[j])
    return total


@njit(cache=True, no_cfunc_wrapper=True)
def table_contact_integral(knots, jumps, alpha, beta):
    """``int_0^alpha g / sqrt(beta^2 - x^2) dx = sum_j s_j int_{r_j}^alpha atan(rho/c) dr``
    (``rho = sqrt(alpha^2 - r^2)``, ``c = sqrt(beta^2 - alpha^2)``), each by its
    antiderivative ``r atan(rho/c) - c asin(r/alpha) + beta atan(c r/(beta rho))``."""
    c = math.sqrt(max((beta - alpha) * (beta + alpha), 0.0))
    top = 0.5 * math.pi * (beta - c)
    total = 0.0
    for j in range(knots.size):
        r = knots[j]
        if r >= alpha:
            continue
        rho = math.sqrt((alpha - r) * (alpha + r))
        phi = (r * math.atan2(rho, c) - c * math.atan2(r, rho)
               + beta * math.atan2(c * r, beta * rho))
        total += jumps[j] * (top - phi)
    return total


@njit(cache=True, no_cfunc_wrapper=True)
def table_g_integral(knots, jumps, alpha):
    """``int_0^alpha g dx``: per ramp ``alpha^2/2 acos(r_j/alpha) - r_j/2 sqrt(alpha^2 - r_j^2)``."""
    total = 0.0
    for j in range(knots.size):
        r = knots[j]
        if alpha > r:
            rho = math.sqrt((alpha - r) * (alpha + r))
            total += jumps[j] * (0.5 * alpha * alpha * math.atan2(rho, r) - 0.5 * r * rho)
    return total


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _profile(sc, x, prof):
    """``g(x)`` of the indenter: a power law, a table (``prof = (knots, jumps)``), or 0 (a
    flat punch)."""
    if prof[0].size:
        return table_g(prof[0], prof[1], x)
    if sc[S_C_G] == 0.0:
        return 0.0
    return sc[S_C_G] * abs(x) ** sc[S_N_G]


@njit(cache=True, no_cfunc_wrapper=True)
def contact_view(xi, status, D, tj, n_all, kappa_arms, tau_arms, sc):
    """The contact elements of a mesh, once per step: ``(idx, acc, first_free)``, their
    indices in ascending ``x``, and at the step's end ``t1`` each one's memory in the contact
    load ``v = sum_i kappa_i D_i e^{-(t1 - tj)/tau_i}`` (``acc[0]``) and the trapezoid of
    ``v`` from the centre to it (``acc[1]``), summed as :func:`_memory_integral` sums them;
    and the index of the first free element (``n_all``: none), below which
    :func:`_free_modes` looks no further.

    A smooth indenter's contact holds thousands of elements after a slow approach, and every
    trial scanned them all, twice or more (the memory at the edge, and its integral with an
    exponential per element and arm): a standard linear solid's sphere retracted at 1e-8 m/s
    spent most of its time there."""
    nc = 0
    first_free = n_all
    for j in range(n_all):
        if status[j] == 1:
            nc += 1
        elif status[j] == 0 and first_free == n_all:
            first_free = j
    idx = np.empty(nc, dtype=np.int64)
    acc = np.empty((2, nc))
    t1 = sc[S_T0] + sc[S_DT]
    total = 0.0
    x_prev, v_prev = 0.0, math.nan
    k = 0
    for j in range(n_all):
        if status[j] != 1:
            continue
        v = 0.0
        for i in range(tau_arms.size):
            v += kappa_arms[i] * D[j, i] * math.exp(-(t1 - tj[j]) / tau_arms[i])
        if math.isnan(v_prev):
            total += v * xi[j]  # flat from the centre to the first contact element
        else:
            total += 0.5 * (v + v_prev) * (xi[j] - x_prev)
        x_prev, v_prev = xi[j], v
        idx[k] = j
        acc[0, k] = v
        acc[1, k] = total
        k += 1
    return idx, acc, np.array([first_free])


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _contacts_up_to(xi, idx, x, inclusive):
    """How many contact elements (``idx``, see :func:`contact_view`) lie below ``x`` (at or
    below, ``inclusive``): a bisection of their ascending ``x``."""
    lo, hi = 0, idx.size
    while lo < hi:
        mid = (lo + hi) // 2
        if xi[idx[mid]] < x or (inclusive and xi[idx[mid]] == x):
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True, no_cfunc_wrapper=True)
def _memory(xi, status, D, tj, n_all, kappa_arms, tau_arms, t, x, out, idx):
    """``D_i e^{-(t - tj)/tau_i}`` of a contact element at ``x``, linear between the contact
    elements ``idx`` (:func:`contact_view`; 0 with none); returns ``sum_i kappa_i`` of it."""
    na = tau_arms.size
    for i in range(na):
        out[i] = 0.0
    k = _contacts_up_to(xi, idx, x, True)
    left = idx[k - 1] if k > 0 else -1
    right = idx[k] if k < idx.size else -1
    if left < 0 and right < 0:
        return 0.0
    total = 0.0
    for i in range(na):
        vl = D[left, i] * math.exp(-(t - tj[left]) / tau_arms[i]) if left >= 0 else 0.0
        vr = D[right, i] * math.exp(-(t - tj[right]) / tau_arms[i]) if right >= 0 else 0.0
        if left >= 0 and right >= 0 and xi[right] > xi[left]:
            w = (x - xi[left]) / (xi[right] - xi[left])
            out[i] = (1.0 - w) * vl + w * vr
        else:
            out[i] = vl if left >= 0 else vr
        total += kappa_arms[i] * out[i]
    return total


@njit(cache=True, no_cfunc_wrapper=True)
def _filtered_lift(Hf0, arm_mus, hp, s, out):
    """The arms' filtered lift ``Hf`` at fraction ``s`` of the step (``hp`` the lift path)."""
    for i in range(Hf0.size):
        mu = arm_mus[i] * s
        m0, m1, m2 = exp_moments(mu)
        out[i] = (math.exp(-mu) * Hf0[i]
                  + mu * (hp[0] * m0 + hp[1] * s * m1 + hp[2] * s * s * m2))


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _contact_modes(x, s_c, sc, hp, Hf0, arm_mus, V_inv, xi, status, D, tj, n_all,
                   kappa_arms, tau_arms, nm, prof, work, out, idx):
    """Modes of a contact element at ``x`` released at fraction ``s_c`` (``work``: two rows
    of scratch, one entry per arm)."""
    G = _profile(sc, x, prof)
    if tau_arms.size == 0:
        if nm > 0:
            out[0] = path_value(hp[0], hp[1], hp[2], s_c) + G
        return
    na = tau_arms.size
    Hf, mem = work[0], work[1]
    _filtered_lift(Hf0, arm_mus, hp, s_c, Hf)
    _memory(xi, status, D, tj, n_all, kappa_arms, tau_arms, sc[S_T0] + s_c * sc[S_DT], x, mem,
            idx)
    for k in range(nm):
        acc = 0.0
        for i in range(na):
            acc += V_inv[k, i] * (Hf[i] + G + mem[i])
        out[k] = acc


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _gather(mesh, law, stepw, paths, sc, lo, hi, alpha1, beta1, n_all, prof, out):
    """The elements a trial step advances, in ascending ``x``: new ones where a receding flat
    punch releases the solid, the existing ones ``lo..hi-1``, new ones where the zone end
    enters virgin solid. Each is advanced from where its free stretch starts; returns the
    count. ``flag``: 0 an existing element, 1 a new one, 2 one that stays in contact."""
    xi, Y, status, D, tj, t_last = mesh
    ctil, kappa_arms, tau_arms, V_inv, V = law
    mus, decay, zdt, w3, arm_mus, Hf0, Hf1, idx, acc, first_free = stepw
    xo, Yo, Uo, fo = out
    nm = mus.size
    ap, bp, hp = paths[0], paths[1], paths[2]
    alpha0 = sc[S_ALPHA0]
    # A receding edge releases new elements as well as the contact's own: a smooth indenter's
    # contact elements are spaced as the approach captured them, often wider than the zone.
    k_a = int(sc[S_K_ALPHA]) if alpha1 < alpha0 else 0
    start = max(sc[S_BETA0], sc[S_XIMAX], 0.0)
    fresh = sc[S_FRESH] > 0.0
    if fresh:
        # A solid without history (elastic): new elements evenly in angle over the whole
        # zone, the centre included, stand for every existing free one.
        start, k_a, hi = alpha1, 0, lo
    k_b = int(sc[S_K_BETA]) if beta1 > start else 0
    theta_b = math.acos(min(start / beta1, 1.0)) if k_b > 0 else 0.0
    first_b = 0 if (fresh and start == 0.0) else 1
    y0 = np.zeros(max(nm, 1))
    ints = np.empty(max(nm, 1))
    work = np.empty((2, max(tau_arms.size, 1)))
    m = np.int64(0)  # not a literal 0: see _ZERO
    for j in range(k_a + (hi - lo) + k_b + 1 - first_b):
        s0 = 0.0
        for k in range(nm):
            y0[k] = 0.0
        if j < k_a:  # released by the receding rim, in ascending order
            x = alpha0 + (alpha1 - alpha0) * (k_a - j) / k_a
            s0 = path_root(ap[0], ap[1], ap[2], x)
            _contact_modes(x, s0, sc, hp, Hf0, arm_mus, V_inv, xi, status, D, tj, n_all,
                           kappa_arms, tau_arms, nm, prof, work, y0, idx)
            flag = 1
        elif j < k_a + hi - lo:
            i = lo + j - k_a
            x = xi[i]
            flag = 0
            if status[i] == 1 and x <= alpha1:
                xo[m] = x
                Uo[m] = hp[0] + hp[1] + hp[2] + _profile(sc, x, prof)
                fo[m] = 2
                for k in range(nm):
                    Yo[m, k] = Y[i, k]
                m += 1
                continue
            if status[i] == 1:  # released by the receding edge inside the step
                s0 = path_root(ap[0], ap[1], ap[2], x)
                _contact_modes(x, s0, sc, hp, Hf0, arm_mus, V_inv, xi, status, D, tj,
                               n_all, kappa_arms, tau_arms, nm, prof, work, y0, idx)
            else:
                lag = (sc[S_T0] - t_last[i]) / sc[S_DT]
                for k in range(nm):
                    y0[k] = Y[i, k] * (math.exp(-mus[k] * lag) if lag > 0.0 else 1.0)
        else:  # entering virgin solid, evenly in angle toward the zone end
            jj = j - k_a - (hi - lo) + first_b
            x = beta1 * math.cos(theta_b * (k_b - jj) / k_b) if jj > 0 else start
            flag = 1
        q1 = load_integrals(bp[0], bp[1], bp[2], x, s0, 1.0, mus, nm, w3, ints)
        u = sc[S_D] * q1
        for k in range(nm):
            y = math.exp(-mus[k] * (1.0 - s0)) * y0[k] + zdt[k] * ints[k]
            Yo[m, k] = y
            u += ctil[k] * y
        xo[m] = x
        Uo[m] = u
        fo[m] = flag
        m += 1
    if k_a > 0 and sc[S_FLAT] == 0.0:
        _sort_gathered(xo, Yo, Uo, fo, m, nm)
    return m


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _sort_gathered(xo, Yo, Uo, fo, m, nm):
    """The gathered elements in ascending ``x`` (stable: the existing ones keep their order),
    once a receding smooth edge's new elements went in ahead of the contact's own."""
    order = stable_argsort(xo[:m])
    # From copies by a loop: fancy indexing (xo[:m][order]) compiles to ~1800 more lines of
    # LLVM IR, which every caller's compile then carries.
    x_c, U_c, f_c, Y_c = xo[:m].copy(), Uo[:m].copy(), fo[:m].copy(), Yo[:m].copy()
    for j in range(m):
        i = order[j]
        xo[j], Uo[j], fo[j] = x_c[i], U_c[i], f_c[i]
        for k in range(nm):
            Yo[j, k] = Y_c[i, k]


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _gap_and_edge(xo, Uo, fo, m, alpha1, beta1, sc, prof, res):
    """The free part of the gap integral (and the centre element's displacement into ``res``)."""
    H1 = sc[S_H1]
    centre = math.nan
    n_in = 0
    for j in range(m):
        if xo[j] == 0.0 and fo[j] != 2:
            centre = Uo[j]
        if fo[j] != 2 and alpha1 < xo[j] < beta1:
            n_in += 1
    res[R_CENTRE_U] = centre
    if beta1 <= 0.0:
        res[R_GAP] = H1 - centre
        return 0.0
    xs = np.empty(n_in)
    us = np.empty(n_in)
    c = 0
    for j in range(m):
        if fo[j] != 2 and alpha1 < xo[j] < beta1:
            xs[c] = xo[j]
            us[c] = Uo[j]
            c += 1
    virgin = beta1 > sc[S_XIMAX] * (1.0 + 1e-12) and beta1 > sc[S_BETA0]
    U_beta = 0.0 if virgin else math.nan
    U_alpha = H1 + _profile(sc, alpha1, prof) if alpha1 > 0.0 else centre
    integral = free_gap_integral(xs, us, _ZERO, xs.size, alpha1, beta1, U_alpha, U_beta,
                                 sc[S_KINK])
    return integral


@njit(cache=True, no_cfunc_wrapper=True)
def evaluate_step(mesh, law, stepw, paths, sc, lo, hi, alpha1, beta1, n_all, prof, out, res):
    """One trial step's end for trial edges ``alpha1``, ``beta1`` (and the lift in ``sc``):
    every element advanced (:func:`_gather`), then into ``res`` the gap at ``b``, the line
    load of the contact element at ``a``, the forces
    and the centre's displacement. Returns the element count written to ``out``."""
    xi, Y, status, D, tj, t_last = mesh
    ctil, kappa_arms, tau_arms, V_inv, V = law
    mus, decay, zdt, w3, arm_mus, Hf0, Hf1, idx, acc, first_free = stepw
    xo, Yo, Uo, fo = out
    m = _gather(mesh, law, stepw, paths, sc, lo, hi, alpha1, beta1, n_all, prof, out)
    integral = _gap_and_edge(xo, Uo, fo, m, alpha1, beta1, sc, prof, res)
    if beta1 <= 0.0:
        res[R_EDGE_LOAD] = math.nan
        res[R_F_CONTACT] = 0.0
        res[R_F_TOTAL] = 0.0
        return m
    H1 = sc[S_H1]
    ell = math.sqrt(max((beta1 - alpha1) * (beta1 + alpha1), 0.0))
    theta_a = math.atan2(ell, alpha1)
    knots, jumps = prof
    if knots.size:
        contact = table_contact_integral(knots, jumps, alpha1, beta1)
        f_beta = table_f(knots, jumps, beta1)
    else:
        contact = profile_integral(sc[S_C_G], sc[S_N_G], alpha1, beta1)
        f_beta = sc[S_AF] * beta1 ** sc[S_N_G] if sc[S_AF] != 0.0 else 0.0
    res[R_GAP] = (2.0 / math.pi) * H1 * theta_a + f_beta - (2.0 / math.pi) * (contact + integral)
    # The contact side: its line load at the edge and its force.
    t1 = sc[S_T0] + sc[S_DT]
    G = _profile(sc, alpha1, prof)
    if knots.size:
        g_int = table_g_integral(knots, jumps, alpha1)
    else:
        g_int = (sc[S_C_G] * alpha1 ** (sc[S_N_G] + 1.0) / (sc[S_N_G] + 1.0)
                 if sc[S_C_G] != 0.0 else 0.0)
    kappa, c = sc[S_KAPPA], sc[S_C]
    load = kappa * (H1 + G) + c * sc[S_HDOT]
    force = kappa * (H1 * alpha1 + g_int) + c * sc[S_HDOT] * alpha1
    na = tau_arms.size
    if na > 0 and alpha1 > 0.0:
        mem = np.empty(na)
        load -= _memory(xi, status, D, tj, n_all, kappa_arms, tau_arms, t1, alpha1, mem, idx)
        for i in range(na):
            load += kappa_arms[i] * (H1 - Hf1[i])
            force += alpha1 * kappa_arms[i] * (H1 - Hf1[i])
        force -= _memory_integral(xi, status, D, tj, n_all, kappa_arms, tau_arms, t1, alpha1,
                                  idx, acc)
    res[R_EDGE_LOAD] = load if alpha1 > 0.0 else 0.0
    res[R_F_CONTACT] = 4.0 * force if alpha1 > 0.0 else 0.0
    res[R_F_TOTAL] = res[R_F_CONTACT] + 2.0 * (beta1 * beta1 * theta_a - alpha1 * ell)
    return m


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _memory_integral(xi, status, D, tj, n_all, kappa_arms, tau_arms, t, alpha, idx, acc):
    """``int_0^alpha`` of the arms' contact memory at ``t``, the step's end (trapezoid over
    the contact elements, whose values and running sums ``acc`` the step's
    :func:`contact_view` holds: those below ``alpha``, then the stretch to ``alpha``)."""
    k = _contacts_up_to(xi, idx, alpha, False)
    mem = np.empty(tau_arms.size)
    v_a = _memory(xi, status, D, tj, n_all, kappa_arms, tau_arms, t, alpha, mem, idx)
    if k == 0:
        return 0.0 + v_a * alpha  # (as the sum from 0.0 was)
    total, x_prev, v_prev = acc[1, k - 1], xi[idx[k - 1]], acc[0, k - 1]
    return total + 0.5 * (v_a + v_prev) * (alpha - x_prev)


# --- a phase's edge search, compiled ------------------------------------------------------------
#: Entries of ``edges`` in :func:`trial_ranges`: the edges now and one step earlier (nan
#: after an event), the earlier step's length in this one's (nan: none) and the released
#: elements' spacing.
E_ALPHA, E_BETA, E_ALPHA_PREV, E_BETA_PREV, E_R, E_SPACING, E_MOST_RELEASED = range(7)
_TINY = 1e-13


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _quadratic(prev, now, new, r, out):
    """``out`` = the quadratic path through ``(-r, prev)``, ``(0, now)``, ``(1, new)`` (linear
    through the last two where ``r`` or ``prev`` is nan): as ``contact_step.quadratic_path``."""
    if math.isnan(r) or r <= 0.0 or not math.isfinite(prev):
        out[0], out[1], out[2] = now, new - now, 0.0
        return
    p2 = (prev - now + r * (new - now)) / (r * (r + 1.0))
    out[0], out[1], out[2] = now, new - now - p2, p2


@njit(cache=True, no_cfunc_wrapper=True)
def trial_ranges(alpha, beta, xi, n_all, edges, lift, paths, sc):
    """What a trial step with edges ``alpha``, ``beta`` advances: its paths into ``paths``
    (the edges' quadratics through the last instants, the lift's ``lift``), the released
    elements' count in ``sc[S_K_ALPHA]`` widened to the zone's spacing however far the edge
    recedes (``edges[E_SPACING]`` inf: never) up to ``edges[E_MOST_RELEASED]``, and ``(lo,
    hi)``, the elements from the edge's lower position to past the zone end's highest (the
    centre's alone without a zone);
    ``hi`` is -1 where that reaches the archived elements (``sc[S_LIVE_END]``): they must
    come back first."""
    _quadratic(edges[E_ALPHA_PREV], edges[E_ALPHA], alpha, edges[E_R], paths[0])
    _quadratic(edges[E_BETA_PREV], edges[E_BETA], beta, edges[E_R], paths[1])
    for i in range(3):  # (a slice assignment compiles a shape check)
        paths[2, i] = lift[i]
    bp = paths[1]
    xs = xi[:n_all]
    lo = np.searchsorted(xs, min(edges[E_ALPHA], alpha) - _TINY)
    if beta > 0.0:
        b_top = max(edges[E_BETA], beta, bp[0] + 0.5 * (bp[1] + 0.5 * bp[2]))
        if b_top * (1.0 + 1e-12) + _TINY >= sc[S_LIVE_END]:
            return lo, -1
        hi = max(np.searchsorted(xs, b_top * (1.0 + 1e-12) + _TINY), lo)
    else:
        hi = lo + 1 if n_all and xi[0] == 0.0 and lo == 0 else lo
    if alpha < edges[E_ALPHA]:
        sc[S_K_ALPHA] = max(int(sc[S_K_ALPHA]), int(math.ceil(min(
            (edges[E_ALPHA] - alpha) / edges[E_SPACING], edges[E_MOST_RELEASED]))))
    return lo, hi


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _no_state(nm):
    """``(lo, hi, m, out, res)`` of a trial that could not be evaluated (see
    :func:`trial_state`): empty."""
    out = (np.empty(0), np.empty((0, nm)), np.empty(0), np.empty(0, dtype=np.int64))
    return 0, 0, 0, out, np.empty(R_N)


@njit(cache=True, no_cfunc_wrapper=True)
def trial_state(alpha, beta, mesh, law, stepw, prof, sc0, edges, lift, n_all):
    """``gap(b) - 1`` at the end of a step with trial edges ``alpha``, ``beta`` (what
    ``Step.evaluate`` gives), with the rest of that evaluation: ``(lo, hi)``, the rows
    written ``m``, the rows ``out`` and ``res`` of :func:`evaluate_step`. ``sc0``: the step's
    constants with the lift and its rate set; ``lift``: its path; ``edges``: see ``E_*``;
    ``n_all`` elements in ``mesh``.
    A step that places its own elements (``sc0[S_FRESH]``) advances none of the mesh. nan,
    with ``hi`` -1 and nothing evaluated, where the trial reaches archived elements: they
    must come back first."""
    paths = np.empty((3, 3))
    sc = sc0.copy()
    nm = stepw[0].size
    lo, hi = trial_ranges(alpha, beta, mesh[0], n_all, edges, lift, paths, sc)
    if hi < 0:
        lo, _, m, out, res = _no_state(nm)
        return math.nan, lo, -1, m, out, res
    if sc[S_FRESH] > 0.0:
        lo = hi = 0
    size = (hi - lo) + int(sc[S_K_ALPHA]) + int(sc[S_K_BETA]) + 1
    out = (np.empty(size), np.empty((size, nm)), np.empty(size), np.empty(size, dtype=np.int64))
    res = np.empty(R_N)
    m = evaluate_step(mesh, law, stepw, paths, sc, lo, hi, alpha, beta, n_all, prof, out, res)
    return res[R_GAP] - 1.0, lo, hi, m, out, res


@njit(cache=True, no_cfunc_wrapper=True)
def edge_load(alpha, mesh, law, stepw, prof, sc0, n_all):
    """The line load of a contact element at ``alpha`` at the end of the step, as
    ``contact_step.Step.contact_load`` gives it (the same sums in the same order: that calls
    this for a smooth indenter on a solid with arms). With arms, a smooth edge beyond where it
    was (or any edge in a jump, ``sc0[S_JUMP]``) meets a free element: its dashpots where the
    free side left them (the free elements at the step's start, interpolated:
    :func:`_free_modes`), relaxing toward the indenter over the step, or held in a jump (the
    glassy modulus)."""
    xi, Y, status, D, tj, t_last = mesh
    ctil, kappa_arms, tau_arms, V_inv, V = law
    H1 = sc0[S_H1]
    G = _profile(sc0, alpha, prof)
    na = tau_arms.size
    if na == 0:
        return sc0[S_KAPPA] * (H1 + G) + sc0[S_C] * sc0[S_HDOT]
    Hf0, Hf1, idx, first_free = stepw[5], stepw[6], stepw[7], stepw[9]
    if sc0[S_FLAT] == 0.0 and (sc0[S_JUMP] > 0.0 or alpha > sc0[S_ALPHA0]):
        nm = V.shape[1]
        modes = np.zeros(nm)
        _free_modes(alpha, xi, Y, status, n_all, first_free[0], modes)
        instant = sc0[S_KAPPA]
        held = memory = arms = 0.0
        for i in range(na):
            E = 0.0  # the arm's dashpot
            for k in range(nm):
                E += V[i, k] * modes[k]
            instant += kappa_arms[i]
            held += kappa_arms[i] * E
            memory += kappa_arms[i] * (E - Hf0[i] - G) * math.exp(-sc0[S_DT] / tau_arms[i])
            arms += kappa_arms[i] * (H1 - Hf1[i])
        if sc0[S_JUMP] > 0.0:
            return instant * (H1 + G) - held
        return sc0[S_KAPPA] * (H1 + G) + arms - memory
    arms = 0.0
    for i in range(na):
        arms += kappa_arms[i] * (H1 - Hf1[i])
    mem = np.empty(na)
    t1 = sc0[S_T0] + sc0[S_DT]
    load = sc0[S_KAPPA] * (H1 + G)
    return load + arms - _memory(xi, status, D, tj, n_all, kappa_arms, tau_arms, t1, alpha,
                                 mem, idx)


@njit(cache=True, no_cfunc_wrapper=True)
def _free_modes(x, xi, Y, status, n_all, first_free, out):
    """Modes of a free element at ``x`` (into ``out``): linear between the free elements
    around it (as ``np.interp`` between them), the nearest one's below them all, zero beyond
    them all (virgin solid). From the bisection of the mesh outward to the nearest free
    element each side: beyond a smooth edge they lie next to it (a slow approach leaves
    thousands of contact elements below it: the search down stops at the first free
    element, ``first_free``)."""
    lo, hi = 0, n_all
    while lo < hi:  # elements at or below x: [0, lo)
        mid = (lo + hi) // 2
        if xi[mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    left = lo - 1
    while left >= first_free and status[left] != 0:
        left -= 1
    if left < first_free:
        left = -1
    right = lo
    while right < n_all and status[right] != 0:
        right += 1
    for k in range(out.size):
        out[k] = 0.0
    if right >= n_all:  # beyond every free element: virgin, unless x is the last one
        if left >= 0 and xi[left] == x:
            for k in range(out.size):
                out[k] = Y[left, k]
        return
    if left < 0 or xi[left] == x:
        j = right if left < 0 else left
        for k in range(out.size):
            out[k] = Y[j, k]
        return
    for k in range(out.size):
        slope = (Y[right, k] - Y[left, k]) / (xi[right] - xi[left])
        out[k] = slope * (x - xi[left]) + Y[left, k]


@njit(cache=True, no_cfunc_wrapper=True)
def edge_zone(alpha, mesh, law, stepw, prof, sc0, n_all):
    """The zone end the edge condition puts with the edge at ``alpha``, as
    ``contact_phases.edge_zone`` computes it."""
    q = max(edge_load(alpha, mesh, law, stepw, prof, sc0, n_all), 0.0)
    return math.sqrt(alpha * alpha + q * q)  # (numba's hypot rounds otherwise)


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _trial_edges(x, alpha, mesh, law, stepw, prof, sc0, n_all):
    """The edges a phase's secant tries at ``x``: the edge at ``x`` with the zone end from the
    edge condition (``alpha`` nan), or the zone end at ``x`` with the edge held at
    ``alpha``."""
    if math.isnan(alpha):
        return x, edge_zone(x, mesh, law, stepw, prof, sc0, n_all)
    return alpha, x


_XTOL = 1e-14
_STALL = 1e-13
_SMALL_RESIDUAL = 1e-9


@njit(cache=True, no_cfunc_wrapper=True)
def edge_secant(x_held, f_held, x_guess, lo, hi, reach, alpha, mesh, law, stepw, prof, sc0,
                edges, lift, n_all):
    """``contact_phases._secant`` on ``gap(b) - 1`` of :func:`trial_state` at the edges
    :func:`_trial_edges` puts at ``x``, step for step (the same iterates, brackets and
    stopping rules): the root, or nan where it gives up; and the evaluation at the last
    iterate tried (the root, where one is returned): its edges and the rest of
    :func:`trial_state`."""
    x0, f0 = x_held, f_held
    x1 = min(max(x_guess, lo), hi)
    if x1 == x0:
        lo0, hi0, m, out, res = _no_state(stepw[0].size)
        return math.nan, (math.nan, math.nan, lo0, hi0, m, out, res)
    bracketed, b_lo, b_hi = False, 0.0, 0.0
    slope = math.nan
    x2 = x1
    for it in range(41):
        # One call site of trial_state, at x1 first, then at each new iterate x2: with two
        # (or a kernel between), numba's first compile took ~4 s longer.
        a, b = _trial_edges(x2, alpha, mesh, law, stepw, prof, sc0, n_all)
        f2, lo2, hi2, m2, out2, res2 = trial_state(a, b, mesh, law, stepw, prof, sc0, edges,
                                                   lift, n_all)
        last = (a, b, lo2, hi2, m2, out2, res2)
        if it == 0:
            f1 = f2
        else:
            if bracketed and not math.isnan(f2):
                if (f2 > 0.0) != (f1 > 0.0):
                    b_lo, b_hi = min(x1, x2), max(x1, x2)
                else:
                    keep = x0 if (f0 > 0.0) != (f2 > 0.0) else (
                        b_lo if x2 > 0.5 * (b_lo + b_hi) else b_hi)
                    b_lo, b_hi = min(keep, x2), max(keep, x2)
            x0, f0, x1, f1 = x1, f1, x2, f2
            if it == 40:
                break
        if math.isnan(f1):
            return math.nan, last
        if abs(x1 - x0) > 1e-9 * max(abs(x1), 1e-300):
            slope = (f1 - f0) / (x1 - x0) if x1 != x0 else math.nan
        if f1 == 0.0 or abs(f1) <= 1e-14:
            return x1, last
        if (f1 > 0.0) != (f0 > 0.0):
            bracketed, b_lo, b_hi = True, min(x0, x1), max(x0, x1)
        elif bracketed and not b_lo <= x1 <= b_hi:
            return math.nan, last
        if abs(x1 - x0) <= _XTOL * max(abs(x1), 1e-300) and bracketed:
            return x1, last
        x2 = x1 - f1 * (x1 - x0) / (f1 - f0) if f1 != f0 else math.nan
        if (abs(f1) <= _SMALL_RESIDUAL
                and abs(f1) <= abs(slope) * _STALL * max(abs(x1), 1e-300)):
            return x1, last
        if bracketed and not b_lo < x2 < b_hi:
            x2 = 0.5 * (b_lo + b_hi)
        if not (lo <= x2 <= hi) or abs(x2 - x_held) > reach:
            return math.nan, last
    return math.nan, last


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _sorts_before(x, a, b):
    """``x[a]`` sorts before ``x[b]`` in NumPy's order (nan last)."""
    return x[a] < x[b] or (math.isnan(x[b]) and not math.isnan(x[a]))


@njit(cache=True, no_cfunc_wrapper=True)
def stable_argsort(x):
    """``np.argsort(x, kind="mergesort")``: the same order (a stable sort's is unique), by a
    bottom-up merge sort; numba's own compiles for seconds."""
    n = x.size
    order = np.empty(n, dtype=np.int64)
    for i in range(n):
        order[i] = i
    work = np.empty(n, dtype=np.int64)
    width = 1
    while width < n:
        for lo in range(0, n, 2 * width):
            mid, hi = min(lo + width, n), min(lo + 2 * width, n)
            i, j = lo, mid
            for k in range(lo, hi):  # a tie takes the left run's: stable
                if j >= hi or (i < mid and not _sorts_before(x, order[j], order[i])):
                    work[k] = order[i]
                    i += 1
                else:
                    work[k] = order[j]
                    j += 1
        order, work = work, order
        width *= 2
    return order


@njit(cache=True, no_cfunc_wrapper=True)
def merge_sorted(arr, n, at, new):
    """Insert the rows ``new`` into the first ``n`` rows of ``arr`` (which has room), new row
    ``j`` before old row ``at[j]`` (``at`` ascending), in place: ``np.insert`` without its
    copies (a step's new elements, every step). Rows of ``new`` as wide as ``arr``'s (no
    broadcasting, unlike ``np.insert``)."""
    if arr.ndim == 2 and new.shape[1] != arr.shape[1]:
        raise ValueError("merge_sorted: new rows must be as wide as arr's")
    i, j = n - 1, at.size - 1
    while j >= 0:  # row i + j + 1, from the end, takes old row i or new row j
        old = i >= 0 and at[j] <= i
        # Element by element (a row assignment compiles a shape check with a formatted
        # message); numba drops the branch that does not fit arr's ndim before typing.
        if arr.ndim == 1:
            arr[i + j + 1] = arr[i] if old else new[j]
        else:
            for c in range(arr.shape[1]):
                arr[i + j + 1, c] = arr[i, c] if old else new[j, c]
        if old:
            i -= 1
        else:
            j -= 1


@njit(cache=True, no_cfunc_wrapper=True)
def fitted_radau3_rows(mus, out):
    """:func:`fitted_radau3` for every ``mus[k]`` into ``out[k]`` (one call per step)."""
    for k in range(mus.size):
        fitted_radau3(mus[k], out[k])


@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _rows(new, order, width):
    """``new[order]`` with ``width`` columns (missing ones 0: an elastic element has no
    modes, while the mesh keeps one column)."""
    if new.shape[1] > width:
        raise ValueError("new elements have more columns than the mesh")
    out = np.zeros((order.size, width))
    for j in range(order.size):
        for k in range(min(width, new.shape[1])):
            out[j, k] = new[order[j], k]
    return out


@njit(cache=True, no_cfunc_wrapper=True)
def insert_batch(mesh, n, x, Y, status, D, tj, t_last):
    """Insert new elements (at ``x``, any order, with their rows of ``Y``, ``D``, ``status``
    and ``tj``; all valid at ``t_last``) into the first ``n`` of ``mesh`` = (xi, Y, status, D,
    tj, t_last), which has room, keeping it sorted: as one-by-one inserts would."""
    xi_m, Y_m, status_m, D_m, tj_m, t_last_m = mesh
    order = stable_argsort(x)
    xs = x[order]
    at = np.searchsorted(xi_m[:n], xs)
    merge_sorted(xi_m, n, at, xs)
    merge_sorted(Y_m, n, at, _rows(Y, order, Y_m.shape[1]))
    merge_sorted(status_m, n, at, status[order])
    merge_sorted(D_m, n, at, _rows(D, order, D_m.shape[1]))
    merge_sorted(tj_m, n, at, tj[order])
    merge_sorted(t_last_m, n, at, np.full(x.size, t_last))
    where = np.empty(x.size, dtype=np.int64)
    for j in range(x.size):
        where[order[j]] = at[j] + j
    return where


@njit(cache=True, no_cfunc_wrapper=True)
def commit_plain(mesh, n, lo, hi, x_ev, Y_ev, flags, alpha, t1, live_end, furthest):
    """A step's end into the mesh when nothing needs the Python path (no free element captured
    by the edge, no new element beyond ``live_end``, room for the new ones): every advanced
    element ``lo..hi-1`` takes its row of ``Y_ev`` (the evaluation's rows with ``flags`` 1 are
    new), is valid at ``t1`` and is freed beyond ``alpha``; the new ones are merged in, in
    contact (joined at ``t1``) inside ``alpha``. Returns how many were inserted and the mesh
    indices of those inside ``alpha`` (their arms' memory is the caller's), or -1 with
    nothing changed; ``furthest[0]`` the furthest new one."""
    xi_m, Y_m, status_m, D_m, tj_m, t_last_m = mesh
    m = x_ev.size
    none = np.empty(0, dtype=np.int64)
    if Y_ev.shape[1] != Y_m.shape[1]:
        return -1, none
    k_new = 0
    for j in range(m):
        if flags[j] == 1:
            if x_ev[j] >= live_end:
                return -1, none
            k_new += 1
    if m - k_new != hi - lo or n + k_new > xi_m.size:
        return -1, none
    if alpha > 0.0:
        for i in range(lo, hi):
            if status_m[i] == 0 and xi_m[i] <= alpha:
                return -1, none
    i = lo
    for j in range(m):
        if flags[j] == 1:
            continue
        for k in range(Y_ev.shape[1]):
            Y_m[i, k] = Y_ev[j, k]
        t_last_m[i] = t1
        if status_m[i] == 1 and xi_m[i] > alpha:
            status_m[i] = 0
        i += 1
    if k_new == 0:
        return 0, none
    xs = np.empty(k_new)
    Ys = np.empty((k_new, Y_ev.shape[1]))
    status_new = np.zeros(k_new, dtype=np.int64)
    tj_new = np.zeros(k_new)
    j_new = 0
    furthest[0] = -np.inf
    for j in range(m):
        if flags[j] != 1:
            continue
        xs[j_new] = x_ev[j]
        for k in range(Y_ev.shape[1]):  # (a row assignment compiles a shape check)
            Ys[j_new, k] = Y_ev[j, k]
        if 0.0 < x_ev[j] <= alpha:
            status_new[j_new], tj_new[j_new] = 1, t1
        furthest[0] = max(furthest[0], x_ev[j])
        j_new += 1
    where = insert_batch(mesh, n, xs, Ys, status_new, np.zeros((k_new, D_m.shape[1])), tj_new,
                         t1)
    inside_at = np.empty(k_new, dtype=np.int64)
    n_inside = 0
    for j in range(k_new):
        if status_new[j] == 1:
            inside_at[n_inside] = where[j]
            n_inside += 1
    return k_new, inside_at[:n_inside]


# --- new elements replayed from the rows ----------------------------------------------------------
@njit(cache=True, no_cfunc_wrapper=True, no_cpython_wrapper=True)
def _replayed_contact_modes(x, H, Hf, maxwell, V_inv, sc, prof, out):
    """Modes of a contact element at ``x`` (lift ``H``, arms' filtered lift ``Hf``):
    Kelvin-Voigt its displacement, Maxwell its dashpots (a flat punch's bonded elements all
    share them: no memory term)."""
    G = _profile(sc, x, prof)
    if not maxwell:
        out[0] = H + G
        return
    modes = np.dot(V_inv, Hf + G)
    for k in range(modes.size):  # (a slice assignment compiles a shape check)
        out[k] = modes[k]


@njit(cache=True, no_cfunc_wrapper=True)
def end_targets(xi, n, alpha, ends, dtheta, count, out):
    """Where a receding zone end wants elements and has none: for each end ``b`` of
    ``ends`` (the present one, the one predicted for the next step), ``b cos(k dtheta)`` for
    ``k = 1..count`` inside ``(alpha, ends[0])``, unless one of the ``n`` sorted elements
    ``xi`` (or a target already taken) lies within 0.4 of the angle spacing there. Fills
    ``out`` (ascending) and returns how many. Compiled: it runs at every receding step, and
    in numpy its few dozen tiny array operations cost a tenth of a step."""
    taken = 0
    for e in range(ends.size):
        b = ends[e]
        for k in range(1, count + 1):
            th = k * dtheta
            x = b * math.cos(th)
            if not alpha < x < ends[0]:
                continue
            tol = 0.4 * b * max(math.sin(th) * dtheta, 0.5 * dtheta * dtheta)
            lo, hi = 0, n  # (a bisection: numba's searchsorted costs microseconds a call)
            while lo < hi:
                mid = (lo + hi) // 2
                if xi[mid] < x:
                    lo = mid + 1
                else:
                    hi = mid
            if lo > 0 and x - xi[lo - 1] <= tol or lo < n and xi[lo] - x <= tol:
                continue
            near = False
            for j in range(taken):
                if abs(out[j] - x) <= tol:
                    near = True
                    break
            if not near:
                out[taken] = x
                taken += 1
    out[:taken].sort()
    return taken


@njit(cache=True, no_cfunc_wrapper=True)
def replay_elements(rows, kink, row_Hf, first, xs, lam, z, ctil, d, tau_arms, V_inv, maxwell,
                    sc, prof, Y):
    """``contact_replay.replay`` compiled: the modes (rows of ``Y``, zeroed) at the last row
    of elements at ``xs``, each run from row ``first`` (at rest there if free: the caller
    picks a row after which any earlier state has decayed below rounding) through every step
    of ``rows`` (the stepper's rows: t, H, alpha, beta, ...; ``kink[k]``: row ``k`` is an
    event's; ``row_Hf[k]``: the arms' filtered lift there). False (``Y`` then meaningless)
    where one of them joined the contact on the way: its memory of joining is not in the
    rows."""
    nm = lam.size
    n = xs.size
    Y[:, :] = 0.0
    free = xs > rows[first, 2]
    w3 = np.zeros((max(nm, 1), 3))
    ap, bp, hp = np.empty(3), np.empty(3), np.empty(3)
    s0 = np.zeros(n)
    hf_c = np.empty(row_Hf.shape[1])
    # The free elements gathered for free_field (allocated once: this runs every step).
    x_sel, s_sel, U_sel = np.empty(n), np.empty(n), np.empty(n)
    Y_sel = np.empty((n, max(nm, 1)))
    pick = np.empty(n, dtype=np.int64)
    for k in range(first + 1, rows.shape[0]):
        t0, t1 = rows[k - 1, 0], rows[k, 0]
        dt = t1 - t0
        if dt <= 0.0:  # a jump: the contact lets go of what it no longer covers, at once
            for j in range(n):
                if not free[j] and xs[j] > rows[k, 2]:
                    _replayed_contact_modes(xs[j], rows[k - 1, 1], row_Hf[k - 1], maxwell,
                                            V_inv, sc, prof, Y[j])
                    free[j] = True
            continue
        r = math.nan
        if k >= 2 and not kink[k - 1] and rows[k - 1, 0] > rows[k - 2, 0]:
            r = (t0 - rows[k - 2, 0]) / (t1 - t0)
        for path, column in ((bp, 3), (ap, 2), (hp, 1)):
            prev = rows[k - 2, column] if not math.isnan(r) else math.nan
            _quadratic(prev, rows[k - 1, column], rows[k, column], r, path)
        mus = -lam * dt
        for m in range(nm):
            fitted_radau3(mus[m], w3[m])
        a_end = path_value(ap[0], ap[1], ap[2], 1.0)
        for j in range(n):
            if free[j] and xs[j] < a_end:
                return False  # captured by an advancing edge: not replayable from the rows
        for j in range(n):
            s0[j] = 0.0
        for j in range(n):
            if free[j] or a_end >= xs[j]:
                continue  # free already, or still in contact at the end of the step
            count, r1, _ = path_roots2(ap[0], ap[1], ap[2], xs[j], -1e-12, 1.0 + 1e-12)
            s_c = min(max(r1, 0.0), 1.0) if count else 1.0
            h_c = path_value(hp[0], hp[1], hp[2], s_c)
            if maxwell:
                _filtered_lift(row_Hf[k - 1], dt / tau_arms, hp, s_c, hf_c)
            else:
                for i in range(hf_c.size):  # (a slice assignment compiles a shape check)
                    hf_c[i] = row_Hf[k - 1, i]
            _replayed_contact_modes(xs[j], h_c, hf_c, maxwell, V_inv, sc, prof, Y[j])
            s0[j] = s_c
            free[j] = True
        if nm == 0:
            continue
        picked = 0
        for j in range(n):
            if free[j]:
                pick[picked] = j
                x_sel[picked], s_sel[picked] = xs[j], s0[j]
                for m in range(nm):
                    Y_sel[picked, m] = Y[j, m]
                picked += 1
        # (free_field reads each element's modes before it writes them: in place is safe)
        free_field(x_sel, Y_sel, s_sel, _ZERO, picked, bp[0], bp[1], bp[2], mus, z * dt,
                   ctil, d, nm, w3, Y_sel, U_sel)
        for i in range(picked):
            for m in range(nm):
                Y[pick[i], m] = Y_sel[i, m]
    for j in range(n):
        if not free[j]:
            return False
    return True
