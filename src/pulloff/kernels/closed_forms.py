"""Numba kernels of the root solves of the closed forms beside a flat-punch onset run: the
seed's eq. 53 (:func:`pulloff.model.analytic.seed_t_star`), the elastic MDR-Dugdale zone
(:func:`pulloff.model.analytic.elastic_mdr_dugdale`) and the frozen onset
(:func:`pulloff.solvers.frozen.frozen_detach_time`).

In Python each is a Newton iteration of ~5-10 steps on scalars, 4-10 us apiece, ~25 us of a
~0.3 ms onset run. Here each is the same operations in the same order (``math``'s functions
are the C library's in both, numba contracts no multiply-add), so the same bits: the tests
compare them with the Python forms. Series coefficients come in as arrays from
:mod:`pulloff.model.analytic`, which stays their one source. Float powers stay in Python
(``x ** 2`` is the C library's ``pow``, which differs from ``x * x`` in ~1 in 1000 cases).
Two compiled functions, each series and bracket written out in them: every compiled function
costs ~0.1 s of a first run, and ten of them took 1 s.
"""

from __future__ import annotations

import math

from numba import njit

#: ``np.finfo(float).eps``: Newton stops at a step below four of them (relative).
EPS = 2.220446049250313e-16

# What root solves (its ``kind``): the seed's eq. 53, f(t*) = alpha; the elastic gap at
# r = b, g(S) = chi; the frozen gap, gap(t) = 1.
SEED, ELASTIC, FROZEN = 0, 1, 2


@njit(cache=True)
def residual(kind, x, p0, p1, p2, coeffs):
    """``(f(x), f'(x))`` of the equation ``kind`` (see :func:`root`), dimensionless."""
    if kind == SEED:  # f(t) - alpha: analytic._seed_rhs_scalar, _seed_rhs_prime
        if x < 1.0:  # the series (analytic._F_SERIES) by Horner's rule from the top
            f = coeffs[coeffs.size - 1]
            for j in range(coeffs.size - 2, -1, -1):
                f = f * x + coeffs[j]
        else:
            f = 0.5 * (x + 1.0) * (2.0 * x + (x + 1.0) * math.expm1(-x))
        return f - p0, x + 0.5 * (1.0 - x * x) * math.exp(-x)
    if kind == ELASTIC:  # g(S) - chi: analytic._g_gap, _g_gap_prime
        if x < 1e-2:  # the series in S^2 (analytic._G_SERIES)
            s2 = x * x
            g = coeffs[coeffs.size - 1]
            for j in range(coeffs.size - 2, -1, -1):
                g = g * s2 + coeffs[j]
            g = s2 * g
        else:
            g = x * math.atan(x) - x * x / (1.0 + math.sqrt(1.0 + x * x))
        return g - p0, math.atan(x) + x / (1.0 + x * x) - x / math.sqrt(1.0 + x * x)
    # the frozen gap - 1 (k, c, h0 = p0, p1, p2), as frozen.py had it in Python (the tests keep
    # that form: test_analytic._python_frozen_onset); its memory
    # (1 - exp(-k t / c)) / k has the limits 1 / k (c = 0) and t / c (k = 0)
    k, c, h0 = p0, p1, p2
    if c == 0.0:
        m, dm = 1.0 / k, 0.0
    elif k == 0.0:
        m, dm = x / c, 1.0 / c
    else:
        m, dm = -math.expm1(-k * x / c) / k, math.exp(-k * x / c) / c
    s = k * (h0 + x) + c
    r = math.sqrt(1.0 + s * s)
    gap = (2.0 / math.pi) * ((h0 + x) * math.atan(s) - s * s / (1.0 + r) * m)
    slope = (2.0 / math.pi) * (math.atan(s) + (h0 + x) * k / (1.0 + s * s)
                               - k * s / r * m - s * s / (1.0 + r) * dm)
    return gap - 1.0, slope


@njit(cache=True)
def root(kind, p0, p1, p2, t_limit, coeffs):
    """The root of equation ``kind`` (dimensionless), in a bracket as the Python form finds
    it, then :func:`pulloff.model.analytic.bracketed_newton`'s steps (Newton inside the
    bracket, bisection where it leaves, to a step below four ulp):

    - ``SEED``: ``t*`` of eq. 53, ``f(t*) = alpha = p0``, for ``1e-4 <= alpha <= 100``
      (``analytic._t_star_scalar``'s bracket; the caller takes the series below and the fixed
      point above); ``coeffs``: ``analytic._F_SERIES``;
    - ``ELASTIC``: ``S`` of the elastic onset, ``g(S) = chi = p0 > 0``
      (``analytic._elastic_zone``); ``coeffs``: ``analytic._G_SERIES``;
    - ``FROZEN``: the first time with frozen gap 1 (``k, c, h0 = p0, p1, p2``), ``inf`` if
      none before ``t_limit`` (``frozen.frozen_detach_time``); ``coeffs``: empty.

    ``f(x) > 0`` here is the Python forms' ``g(x) > chi`` (or ``gap(x) >= 1``...): a
    difference of finite floats has the sign of their order."""
    if kind == SEED:
        lo = 2.0 * p0 / (0.5 + math.sqrt(0.25 + 2.0 * p0))
        hi = min(2.0 * p0, math.sqrt(2.0 * p0 + 1.0))
        while residual(kind, lo, p0, p1, p2, coeffs)[0] > 0:
            lo *= 0.5
        while residual(kind, hi, p0, p1, p2, coeffs)[0] < 0:
            hi *= 2.0
        x = hi
    elif kind == ELASTIC:
        lo = max(math.sqrt(2.0 * p0), p0 / (0.5 * math.pi - 1.0))
        while residual(kind, lo, p0, p1, p2, coeffs)[0] > 0:
            lo *= 0.5
        hi = 2.0 * lo
        while residual(kind, hi, p0, p1, p2, coeffs)[0] < 0:
            hi *= 2.0
        x = lo
    else:
        if residual(kind, 0.0, p0, p1, p2, coeffs)[0] >= 0.0:
            return 0.0
        hi = 1.0
        while residual(kind, hi, p0, p1, p2, coeffs)[0] < 0.0:
            if hi > t_limit:
                return math.inf
            hi *= 2.0
        lo = hi / 2.0 if hi > 1.0 else 0.0
        x = hi
    for _ in range(200):
        fx, d = residual(kind, x, p0, p1, p2, coeffs)
        if fx == 0.0:
            return x
        if fx < 0.0:
            lo = x
        else:
            hi = x
        x_new = x - fx / d if d > 0.0 else math.nan
        if abs(x_new - x) <= 4.0 * EPS * abs(x):
            return x_new  # converged (before the bracket test: x is now one of its ends)
        if not lo < x_new < hi:
            x_new = 0.5 * (lo + hi)
            if not lo < x_new < hi:
                return x_new
        x = x_new
    return x
