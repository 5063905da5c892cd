"""Closed forms of the seed thesis and exact limits of the MDR-Dugdale pull-off model.

Everything here is a plain function of SI quantities (m, s, Pa, Pa s, N).  Equation numbers
"eq. N" refer to the seed thesis ``seeds/000_cfa5e98cccfc6722.txt``; sections refer to
``MODEL.md``.  Symbols: shear modulus ``G`` [Pa], viscosity ``eta`` [Pa s], Dugdale stress
``sigma_c`` [Pa], Dugdale range ``delta`` [m], bond (contact) radius ``a`` [m], pull-off
velocity ``v`` [m/s].  Incompressible half-space: ``E* = 4 G``.

Two families live here:

* the seed's linearised model (eq. 53 for ``t* = t G / eta``, eq. 48 for the force) and its
  closed-form approximations (eqs. 59/61/64 for large ``alpha``, 74-78 and 83/85/89 for small
  ``alpha``);
* exact limits of the unlinearised model of MODEL.md section 3 that the simulator must
  reproduce: the elastic (``eta = 0``) MDR-Dugdale punch and the purely viscous (``G = 0``)
  detachment time (MODEL.md section 5).

Thesis check (eqs. 73/74): the derivatives of eqs. 67-71 are right, and eq. 74 is the correct
Taylor polynomial, ``f = t/2 + t^2/4 - t^3/12 + 5 t^4/48 - 11 t^5/240 + O(t^6)``.  Eq. 73, which
is supposed to list ``f^(k)(0)/k!``, instead lists ``f^(k)(0)/(k!/2)`` for ``k >= 2``
(1/2, -1/6, 5/24, -11/120: twice the true coefficients); the "=" from eq. 73 to eq. 74 is
therefore not an identity, but eq. 74 and everything derived from it (eqs. 75-83) is right.
"""

from __future__ import annotations

import json
import math
from fractions import Fraction

import numpy as np

__all__ = [
    "ALPHA_SWITCH",
    "TAYLOR_COEFFS",
    "alpha",
    "chi",
    "V",
    "dimensionless_groups",
    "seed_rhs",
    "seed_t_star",
    "taylor_poly",
    "t_star_large_alpha",
    "t_star_small_alpha",
    "seed_linearised",
    "seed_closed_form",
    "kendall_force",
    "viscous_force",
    "viscous_detach_time",
    "elastic_mdr_dugdale",
    "cohesive_force",
]

#: Where the small- and large-alpha approximations of the seed intersect (section 3.3):
#: both give ``t* = 1 + sqrt(3)`` there.
ALPHA_SWITCH = 1.5 + math.sqrt(3.0)

#: Coefficients ``c_0..c_5`` of T5 (eq. 74), ``f(t*) = sum c_k t*^k + O(t*^6)``.  Verified
#: against an independent series expansion of ``f`` (see the module docstring: eq. 73 is off by
#: a factor 2 for k >= 2, eq. 74 is right).
TAYLOR_COEFFS = (
    Fraction(0),
    Fraction(1, 2),
    Fraction(1, 4),
    Fraction(-1, 12),
    Fraction(5, 48),
    Fraction(-11, 240),
)

_EPS = np.finfo(float).eps


def _all_floats(*values) -> bool:
    """Whether every value is a Python float (a scene's numbers are): the scalar forms apply."""
    for x in values:  # (a loop, not all() over a generator: half the ~1 us, 6 calls a run)
        if type(x) is not float:
            return False
    return True


def _out(x):
    """Return a Python float for 0-d input, the array otherwise."""
    x = np.asarray(x, dtype=float)
    return float(x) if x.ndim == 0 else x


def _series_coeffs_f(n_terms):
    # Taylor coefficients of f(t) = t + t^2 - (1/2)(1 + 2t + t^2)(1 - e^{-t}), exact rationals:
    # with e_k = (-1)^(k+1)/k! the coefficients of 1 - e^{-t}, c_n = [n=1] + [n=2]
    # - (e_n + 2 e_{n-1} + e_{n-2})/2.
    e = [Fraction(0)] + [Fraction((-1) ** (k + 1), math.factorial(k)) for k in range(1, n_terms)]
    c = []
    for n in range(n_terms):
        cn = Fraction(int(n == 1) + int(n == 2))
        s = e[n]
        if n >= 1:
            s += 2 * e[n - 1]
        if n >= 2:
            s += e[n - 2]
        c.append(cn - s / 2)
    return c


# |c_n| ~ n^2/(2 n!), so 26 terms reach below 1e-22 at |t| = 1.
_F_SERIES = [float(c) for c in _series_coeffs_f(26)]
_F_SERIES_MAX_T = 1.0

# Inverse series of eq. 53 about alpha = 0: t* = alpha * (2 - 2 alpha + 16/3 alpha^2 - ...).
# Used where the root bracket would be narrower than the float spacing.
_T_OVER_ALPHA_SERIES = (2.0, -2.0, 16.0 / 3.0, -20.0, 408.0 / 5.0, -352.0, 100096.0 / 63.0)
_ALPHA_SERIES_MAX = 1e-4  # next term ~ 8e3 alpha^7: < 1e-21 relative below this
_ALPHA_FIXED_POINT_MIN = 100.0  # t* > 14: e^{-t*} < 1e-6, the large-alpha iteration contracts


#: Up to this many values a series is summed value by value in Python floats: a numpy pass
#: costs ~0.8 us per operation whatever the size (a sweep's two-row history spent 47 us in
#: the cohesive series' 30 terms); the same operations in the same order, so bit for bit.
_HORNER_SCALAR_MAX = 16


def _horner(coeffs, x):
    if np.size(x) <= _HORNER_SCALAR_MAX:
        values = np.asarray(x, dtype=float)
        return np.array([_horner_scalar(coeffs, v) for v in values.ravel().tolist()],
                        dtype=float).reshape(values.shape)
    # In place: the history's cohesive force runs 30 terms over every row of a run.
    acc = np.full(np.shape(x), coeffs[-1], dtype=float)
    for c in coeffs[-2::-1]:
        np.multiply(acc, x, out=acc)
        np.add(acc, c, out=acc)
    return acc


def _horner_scalar(coeffs, x: float) -> float:
    acc = coeffs[-1]
    for c in coeffs[-2::-1]:
        acc = acc * x + c
    return acc


def bracketed_newton(f, fprime, lo: float, hi: float, x: float) -> float:
    """Root of an increasing ``f`` with ``f(lo) <= 0 <= f(hi)``, from ``x`` in the bracket.

    Newton's step where it stays inside the bracket, bisection where it does not; the bracket
    shrinks with every evaluation. Stops at a step below four ulp, in ~5 evaluations for the
    smooth convex functions here (scipy's brentq took 10-12, and its call overhead dominated
    the closed forms beside a run).
    """
    for _ in range(200):
        fx = f(x)
        if fx == 0.0:
            return x
        if fx < 0.0:
            lo = x
        else:
            hi = x
        d = fprime(x)
        x_new = x - fx / d if d > 0.0 else math.nan
        if abs(x_new - x) <= 4.0 * _EPS * abs(x):
            return x_new  # converged (before the bracket test: x is now one of its ends)
        if not lo < x_new < hi:
            x_new = 0.5 * (lo + hi)
            if not lo < x_new < hi:
                return x_new
        x = x_new
    return x


# ---------------------------------------------------------------------------------------------
# Dimensionless groups (MODEL.md section 4)
# ---------------------------------------------------------------------------------------------


def alpha(G, eta, sigma_c, delta, a, v):
    """Seed parameter ``alpha = pi delta sigma_c a G / (4 v^2 eta^2)`` (eq. 52), dimensionless.

    Inputs: G [Pa], eta [Pa s], sigma_c [Pa], delta [m], a [m], v [m/s] (scalars or arrays).
    Returns ``inf`` for ``eta == 0`` with ``G > 0`` (elastic limit) and ``0`` for ``G == 0``.
    """
    if _all_floats(G, eta, sigma_c, delta, a, v):
        # The same operations on Python floats: the array form's errstate and wheres cost
        # 20 us, three calls a run, a tenth of an onset run at rtol 1e-6.
        if G == 0.0:
            return 0.0
        if eta == 0.0:
            return math.inf
        try:
            return (0.25 * math.pi) * (sigma_c * a / (v * eta)) * (G * delta / (v * eta))
        except ZeroDivisionError:
            pass  # v eta underflowed to 0: the array form's inf or nan
    G = np.asarray(G, dtype=float)
    eta = np.asarray(eta, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # split into two O(1)-ish factors so eta**2 cannot underflow on its own
        val = (0.25 * math.pi) * (sigma_c * a / (v * eta)) * (G * delta / (v * eta))
    val = np.where(eta == 0, np.inf, val)
    val = np.where(G == 0, 0.0, val)
    return _out(val)


def chi(G, sigma_c, delta, a):
    """Elastic cohesive-zone size ``chi = pi G delta / (sigma_c a)``, dimensionless.

    Inputs: G [Pa], sigma_c [Pa], delta [m], a [m].  ``(b - a)/a -> chi`` at detachment in the
    elastic limit; Kendall's limit is ``chi -> 0``.
    """
    if _all_floats(G, sigma_c, delta, a) and sigma_c * a != 0.0:
        return math.pi * G * delta / (sigma_c * a)
    return _out(math.pi * np.asarray(G, dtype=float) * delta / (np.asarray(sigma_c, dtype=float) * a))


def V(eta, v, sigma_c, a):
    """Viscous against cohesive stress ``V = eta v / (sigma_c a)``, dimensionless.

    Inputs: eta [Pa s], v [m/s], sigma_c [Pa], a [m].
    """
    if _all_floats(eta, v, sigma_c, a) and sigma_c * a != 0.0:
        return eta * v / (sigma_c * a)
    return _out(np.asarray(eta, dtype=float) * v / (np.asarray(sigma_c, dtype=float) * a))


def dimensionless_groups(G, eta, sigma_c, delta, a, v):
    """The three groups of the seed scene, ``dict(alpha=..., chi=..., V=...)`` (dimensionless).

    Inputs: G [Pa], eta [Pa s], sigma_c [Pa], delta [m], a [m], v [m/s].
    """
    return dict(
        alpha=alpha(G, eta, sigma_c, delta, a, v),
        chi=chi(G, sigma_c, delta, a),
        V=V(eta, v, sigma_c, a),
    )


# ---------------------------------------------------------------------------------------------
# Eq. 53 and its approximations
# ---------------------------------------------------------------------------------------------


def seed_rhs(t_star):
    """Right side of eq. 53, ``f(t*) = t*(t*+1) - (t*+1)^2 (1 - exp(-t*))/2`` (dimensionless).

    ``t_star`` is the dimensionless time ``t G / eta`` (scalar or array).  Accurate to a few ulp
    for all ``t* >= 0``: below ``t* = 1`` a 26-term Taylor series (``f ~ t*/2`` would otherwise
    cancel), above it ``f = (t*+1)/2 * (2 t* + (t*+1) expm1(-t*))``, whose bracket loses at most
    a factor ~3 to cancellation.  ``f(inf) = inf``.
    """
    t = np.asarray(t_star, dtype=float)
    small = np.abs(t) < _F_SERIES_MAX_T
    ts = np.where(small, t, 0.0)
    series = _horner(_F_SERIES, ts)
    tl = np.where(small | ~np.isfinite(t), 2.0, t)
    with np.errstate(over="ignore"):
        direct = 0.5 * (tl + 1.0) * (2.0 * tl + (tl + 1.0) * np.expm1(-tl))
    out = np.where(small, series, direct)
    out = np.where(np.isposinf(t), np.inf, out)
    out = np.where(np.isnan(t), np.nan, out)
    return _out(out)


def _seed_rhs_scalar(t: float) -> float:
    """:func:`seed_rhs` for one finite ``t >= 0`` (math, no arrays)."""
    if t < _F_SERIES_MAX_T:
        return _horner_scalar(_F_SERIES, t)
    return 0.5 * (t + 1.0) * (2.0 * t + (t + 1.0) * math.expm1(-t))


def _seed_rhs_prime(t):
    # eq. 67; both terms positive for t <= 1 and t dominates beyond, so no cancellation
    return t + 0.5 * (1.0 - t * t) * math.exp(-t)


def t_star_large_alpha(alpha):
    """Large-alpha root of eq. 53, ``t* = sqrt(2 alpha + 1)`` (eq. 59), dimensionless.

    ``alpha`` dimensionless (scalar or array); drops ``exp(-t*)`` from eq. 53 (eq. 54).
    """
    al = np.asarray(alpha, dtype=float)
    with np.errstate(over="ignore"):
        return _out(np.sqrt(2.0 * al + 1.0))


def t_star_small_alpha(alpha):
    """Small-alpha root of eq. 53 via T2 (eq. 79): ``t* = -1 + sqrt(1 + 4 alpha)`` (eq. 83).

    ``alpha`` dimensionless (scalar or array).  Evaluated as ``4 alpha / (1 + sqrt(1 + 4 alpha))``
    so that tiny ``alpha`` does not cancel; ``inf -> inf``.
    """
    al = np.asarray(alpha, dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):
        val = 4.0 * al / (1.0 + np.sqrt(1.0 + 4.0 * al))
    val = np.where(np.isposinf(al), np.inf, val)
    return _out(val)


def _t_star_scalar(al):
    if math.isnan(al) or al < 0:
        raise ValueError(f"alpha must be >= 0, got {al!r}")
    if al == 0.0:
        return 0.0
    if math.isinf(al):
        return math.inf
    if al < _ALPHA_SERIES_MAX:
        return al * _t_over_alpha_series(al)
    if al > _ALPHA_FIXED_POINT_MIN:
        # eq. 53 rearranged: t*^2 = 2 alpha + 1 - (t*+1)^2 e^{-t*}; for t* > 14 the map's slope is
        # ~ t* e^{-t*}/2 < 1e-5, so the iteration from eq. 59 converges to machine precision in a
        # few steps.  A bracketed search would fail here once e^{-t*} falls below the float spacing, because
        # eq. 59 then brackets the root only up to rounding.
        t = math.sqrt(2.0 * al + 1.0)
        for _ in range(20):
            t_new = math.sqrt(2.0 * al + 1.0 - (t + 1.0) ** 2 * math.exp(-t))
            if t_new == t:
                break
            t = t_new
        return t
    # Bracket, valid for every alpha > 0 (not only asymptotically):
    #  * (t+1) e^{-t} <= 1 gives f(t) <= t (t+1)/2, so t* >= -1/2 + sqrt(1/4 + 2 alpha)
    #    (the large-alpha form eq. 59 shifted by -1/2; ~ the small-alpha form 2 alpha);
    #  * f is convex (f'' >= 0.44) with f'(0) = 1/2, so f(t) >= t/2, i.e. t* <= 2 alpha (eq. 78);
    #  * e^{-t} > 0 gives f(t) > (t^2 - 1)/2, i.e. t* < sqrt(2 alpha + 1) (eq. 59).
    lo = 2.0 * al / (0.5 + math.sqrt(0.25 + 2.0 * al))
    hi = min(2.0 * al, math.sqrt(2.0 * al + 1.0))

    def res(t):
        return _seed_rhs_scalar(t) - al

    # guard against rounding at the bracket ends (never triggered in tests, cheap insurance)
    while res(lo) > 0:
        lo *= 0.5
    while res(hi) < 0:
        hi *= 2.0
    # f is convex: Newton from the upper end approaches the root from above, never leaving.
    return bracketed_newton(res, _seed_rhs_prime, lo, hi, hi)


def _t_over_alpha_series(al):
    return _horner_scalar(_T_OVER_ALPHA_SERIES, float(al))


def seed_t_star(alpha):
    """Root ``t* >= 0`` of eq. 53, ``f(t*) = alpha``; dimensionless in and out.

    ``alpha = 0 -> 0``, ``alpha = inf -> inf``; ``ValueError`` for negative or NaN ``alpha``.
    Relative accuracy ~1e-15: an inverse series below ``alpha = 1e-4``
    (``t* = 2 alpha - 2 alpha^2 + 16/3 alpha^3 - ...``), Newton inside a rigorous bracket
    between the small- and large-alpha bounds up to ``alpha = 100``, and a contracting fixed-point
    iteration on eq. 53 rearranged as ``t*^2 = 2 alpha + 1 - (t*+1)^2 exp(-t*)`` above.
    Accepts arrays (element by element).
    """
    if np.ndim(alpha) > 0:
        arr = np.asarray(alpha, dtype=float)
        return np.array([_t_star_scalar(float(x)) for x in arr.ravel()]).reshape(arr.shape)
    return _t_star_scalar(float(alpha))


def taylor_poly(t_star, degree):
    """Taylor polynomial ``T_degree(t*)`` of ``f`` about 0 (eqs. 74-78), dimensionless.

    ``degree`` in 1..5; ``t_star`` scalar or array.
    """
    if degree not in (1, 2, 3, 4, 5):
        raise ValueError(f"degree must be 1..5, got {degree!r}")
    coeffs = [float(c) for c in TAYLOR_COEFFS[: degree + 1]]
    return _out(_horner(coeffs, np.asarray(t_star, dtype=float)))


# ---------------------------------------------------------------------------------------------
# The seed's detachment time and force
# ---------------------------------------------------------------------------------------------


def _check_params(G, eta, sigma_c, delta, a, v):
    if (_all_floats(G, eta, sigma_c, delta, a, v) and sigma_c > 0 and delta > 0 and a > 0
            and v > 0 and G >= 0 and eta >= 0 and (G > 0 or eta > 0)
            and math.isfinite(G + eta + sigma_c + delta + a + v)):
        return  # a scene's valid floats, at once (the checks below cost ~1.3 us, twice a run)
    vals = dict(G=G, eta=eta, sigma_c=sigma_c, delta=delta, a=a, v=v)
    for name, x in vals.items():
        if not (isinstance(x, (int, float, np.floating, np.integer)) and math.isfinite(x)):
            raise ValueError(f"{name} must be a finite real scalar, got {x!r}")
    for name in ("sigma_c", "delta", "a", "v"):
        if vals[name] <= 0:
            raise ValueError(f"{name} must be > 0, got {vals[name]!r}")
    for name in ("G", "eta"):
        if vals[name] < 0:
            raise ValueError(f"{name} must be >= 0, got {vals[name]!r}")
    if G == 0 and eta == 0:
        raise ValueError("G and eta cannot both be 0 (the half-space would offer no resistance)")


def seed_linearised(G, eta, sigma_c, delta, a, v, t_star=None):
    """The seed's linearised model solved without further approximation.

    Eq. 53 is solved numerically for ``t* = t G / eta``, and the force is eq. 48,
    ``F = 8 a (G v t + eta v)``.  Inputs: G [Pa], eta [Pa s], sigma_c [Pa], delta [m], a [m],
    v [m/s] (scalars; G, eta >= 0, not both 0).  Returns
    ``dict(t_detach=[s], h_detach=[m], F=[N])`` with ``h_detach = v t_detach``.
    ``t_star(alpha)`` solves eq. 53 (default :func:`seed_t_star`; the solvers pass a compiled
    one with the same bits: this module stays free of numba).

    Like the seed (eq. 9) this assumes ``h0 = 0`` and ignores any initial lift.

    Limits, reached continuously:
      * ``eta = 0``: eqs. 93/94, ``t = sqrt(pi delta a sigma_c / (2 G v^2))``,
        ``F = 8 G v t a`` (= Kendall, eq. 95);
      * ``G = 0``: ``f ~ t*/2`` gives ``t = 2 alpha eta / G = pi delta sigma_c a / (2 v^2 eta)``
        and ``F = 8 eta v a`` (eq. 96).
    """
    _check_params(G, eta, sigma_c, delta, a, v)
    G, eta, sigma_c, delta, a, v = map(float, (G, eta, sigma_c, delta, a, v))
    t_star = t_star or seed_t_star
    if eta == 0.0:
        t = math.sqrt(math.pi * delta * a * sigma_c / (2.0 * G)) / v
    elif G == 0.0:
        t = math.pi * delta * sigma_c * a / (2.0 * v * v * eta)
    else:
        al = alpha(G, eta, sigma_c, delta, a, v)
        if al <= 1.0:
            # t = (t*/alpha) * (alpha eta/G); the second factor does not involve G, so this
            # stays finite and accurate as G -> 0 (where t* = alpha eta/G alone would be 0/0)
            ratio = 2.0 if al == 0.0 else (
                _t_over_alpha_series(al) if al < _ALPHA_SERIES_MAX else t_star(al) / al
            )
            t = ratio * math.pi * delta * sigma_c * a / (4.0 * v * v * eta)
        else:
            # t = (t*/sqrt(2 alpha + 1)) * (sqrt(2 alpha + 1) eta/G); the second factor is eq. 61,
            # finite as eta -> 0 even where alpha itself overflows
            ratio = 1.0 if math.isinf(al) else t_star(al) / math.sqrt(2.0 * al + 1.0)
            t = ratio * math.sqrt(math.pi * delta * sigma_c * a / (2.0 * G) + (eta * v / G) ** 2) / v
    F = 8.0 * a * (G * v * t + eta * v)
    return dict(t_detach=t, h_detach=v * t, F=F)


def seed_closed_form(G, eta, sigma_c, delta, a, v):
    """The seed's closed-form approximation of detachment time and force (section 3).

    Inputs: G [Pa], eta [Pa s], sigma_c [Pa], delta [m], a [m], v [m/s] (scalars; G, eta >= 0,
    not both 0).  Returns ``dict(t_detach=[s], F=[N], branch=str)``:

      * ``alpha > ALPHA_SWITCH`` (``branch="large_alpha"``): eq. 61,
        ``t = sqrt((pi delta sigma_c a G + 2 v^2 eta^2)/2) / (G v)``, and eq. 64,
        ``F = 8 a sqrt((pi delta sigma_c a G + 2 v^2 eta^2)/2) + 8 eta v a``; at ``eta = 0``
        these are eqs. 93 and 95 (Kendall);
      * otherwise (``branch="small_alpha"``): eq. 85 written as
        ``t = pi delta sigma_c a / (v^2 eta (1 + sqrt(1 + 4 alpha)))`` (no 0/0 at ``G = 0``)
        and eq. 89, ``F = 8 eta v a sqrt(1 + 4 alpha)``; at ``G = 0`` this is ``8 eta v a``.

    Relative to :func:`seed_linearised` the force error is at most ~5.3 % (at the switch; the
    7.34 % of eq. 90 is the error in ``t*``, which the ``eta v`` term in eq. 48 dilutes).
    """
    _check_params(G, eta, sigma_c, delta, a, v)
    G, eta, sigma_c, delta, a, v = map(float, (G, eta, sigma_c, delta, a, v))
    al = alpha(G, eta, sigma_c, delta, a, v)
    if al > ALPHA_SWITCH:
        root = math.sqrt(0.5 * math.pi * delta * sigma_c * a * G + (v * eta) ** 2)
        t = root / (G * v)
        F = 8.0 * a * root + 8.0 * eta * v * a
        branch = "large_alpha"
    else:
        s = math.sqrt(1.0 + 4.0 * al)
        t = math.pi * delta * sigma_c * a / (v * v * eta * (1.0 + s))
        F = 8.0 * eta * v * a * s
        branch = "small_alpha"
    return dict(t_detach=t, F=F, branch=branch)


def kendall_force(G, gamma, a):
    """Kendall's flat-punch pull-off force ``sqrt(8 pi E* a^3 gamma)`` with ``E* = 4 G`` (eq. 95).

    Inputs: G [Pa], gamma = sigma_c delta [N/m], a [m].  Returns [N].
    """
    G = np.asarray(G, dtype=float)
    return _out(np.sqrt(32.0 * math.pi * G * gamma) * np.asarray(a, dtype=float) ** 1.5)


def viscous_force(eta, v, a):
    """Purely viscous pull-off force ``8 eta v a`` (eq. 96).

    Inputs: eta [Pa s], v [m/s], a [m].  Returns [N].
    """
    if _all_floats(eta, v, a):  # (the same products without a 0-d array: 1 us a run)
        return 8.0 * eta * v * a
    return _out(8.0 * np.asarray(eta, dtype=float) * v * a)


# ---------------------------------------------------------------------------------------------
# Exact limits of the unlinearised model (MODEL.md section 5)
# ---------------------------------------------------------------------------------------------


def viscous_detach_time(eta, sigma_c, delta, a, v):
    """Exact detachment time of the model with ``G = 0`` (MODEL.md section 5), in [s].

    Inputs: eta [Pa s], sigma_c [Pa], delta [m], a [m], v [m/s].  With ``G = 0`` the edge
    condition ``4 eta v = 2 sigma_c sqrt(b^2 - a^2)`` fixes ``b`` for all time,
    ``S = sqrt(b^2 - a^2)/a = 2 eta v / (sigma_c a)``; the free elements creep as
    ``u = q t / (4 eta)`` and the gap at ``r = b`` grows linearly,
    ``gap = t [ (2v/pi) acos(a/b) - sigma_c (b - a) / (pi eta) ]``, so
    ``t_d = delta / [ ... ]``.  Returns ``inf`` if the bracket is ``<= 0`` (only at ``eta = 0``,
    where the gap never opens).  Like the seed, ``h0 = 0``.
    """
    eta, sigma_c, delta, a, v = map(float, (eta, sigma_c, delta, a, v))
    S = 2.0 * eta * v / (sigma_c * a)
    # acos(a/b) = atan(S), b - a = a S^2/(1 + sqrt(1 + S^2)); with sigma_c a S / eta = 2 v the
    # bracket becomes (2v/pi) [atan(S) - S/(1 + sqrt(1 + S^2))], positive for every S > 0 and
    # free of both cancellation and a 0/0 at eta = 0
    denom = (2.0 * v / math.pi) * (math.atan(S) - S / (1.0 + math.sqrt(1.0 + S * S)))
    if not denom > 0.0:
        return math.inf
    return delta / denom


def _g_coeffs(n_terms):
    # g(S) = S atan(S) - (sqrt(1+S^2) - 1) = sum_k g_k S^{2k}, k >= 1,
    # g_k = (-1)^(k-1)/(2k-1) - binom(1/2, k)
    out = []
    binom = Fraction(1)
    for k in range(1, n_terms + 1):
        binom = binom * (Fraction(1, 2) - (k - 1)) / k
        out.append(float(Fraction((-1) ** (k - 1), 2 * k - 1) - binom))
    return out


_G_SERIES = _g_coeffs(6)  # in S^2, starting at S^2: error ~ S^12 < 1e-20 relative for S < 1e-2
_G_SERIES_MAX_S = 1e-2
_PI_2_M1 = 0.5 * math.pi - 1.0


def _g_gap(S):
    """``g(S) = S atan(S) - (sqrt(1+S^2) - 1)``: the elastic gap at r = b in units sigma_c a/(pi G)."""
    if S < _G_SERIES_MAX_S:
        s2 = S * S
        return s2 * _horner_scalar(_G_SERIES, float(s2))
    return S * math.atan(S) - S * S / (1.0 + math.sqrt(1.0 + S * S))


def _g_gap_prime(S):
    """``g'(S) = atan(S) + S / (1 + S^2) - S / sqrt(1 + S^2)`` (only steers Newton)."""
    return math.atan(S) + S / (1.0 + S * S) - S / math.sqrt(1.0 + S * S)


def elastic_mdr_dugdale(G, sigma_c, delta, a, zone=None):
    """Exact elastic (``eta = 0``) MDR-Dugdale flat punch at the onset of detachment.

    Inputs: G [Pa] (> 0), sigma_c [Pa], delta [m], a [m].  With ``S = sqrt(b^2 - a^2)/a`` the two
    conditions of MODEL.md section 5 read

      * edge: ``2 G h = sigma_c a S``;
      * gap at ``r = b``: ``(sigma_c a / (pi G)) [S atan(S) - (sqrt(1+S^2) - 1)] = delta``
        (``acos(a/b) = atan(S)``), i.e. ``g(S) = chi = pi G delta / (sigma_c a)``.

    Returns ``dict(b=[m], h=[m], F_contact=[N], F_total=[N], S=[-])`` with ``h`` the punch lift
    at detachment, ``F_contact = 8 a G h = 4 sigma_c a^2 S`` and
    ``F_total = 2 sigma_c [a sqrt(b^2-a^2) + b^2 acos(a/b)] = 2 sigma_c a^2 [S + (1+S^2) atan S]``.
    ``S`` is returned as well because ``b`` as a float cannot resolve ``b - a`` (= a S^2/2 for
    thin zones) below ~1e-16 a.  Both forces tend to Kendall (eq. 95) as ``chi -> 0``:
    ``F_contact/F_K = 1 + 5 chi/12 + ...``, ``F_total/F_K = 1 + 13 chi/12 + ...``.
    ``zone(chi)`` solves ``g(S) = chi > 0`` (default: :func:`_elastic_zone`; the solvers
    pass a compiled one with the same bits).
    """
    G, sigma_c, delta, a = map(float, (G, sigma_c, delta, a))
    if not (G > 0 and sigma_c > 0 and a > 0 and delta >= 0):
        raise ValueError("need G > 0, sigma_c > 0, a > 0, delta >= 0")
    c = math.pi * G * delta / (sigma_c * a)
    S = 0.0 if c == 0.0 else (zone or _elastic_zone)(c)
    h = sigma_c * a * S / (2.0 * G)
    b = a * math.sqrt(1.0 + S * S)
    F_contact = 8.0 * a * G * h
    F_total = 2.0 * sigma_c * a * a * (S + (1.0 + S * S) * math.atan(S))
    return dict(b=b, h=h, F_contact=F_contact, F_total=F_total, S=S)


def _elastic_zone(c: float) -> float:
    """The root ``S`` of ``g(S) = c > 0`` (:func:`elastic_mdr_dugdale`)."""
    # g(S) <= S^2/2 and g(S) <= (pi/2 - 1) S for all S (g/S = theta - tan(theta/2) increases
    # to pi/2 - 1 with theta = atan S), so the root is at least the larger of the two
    # asymptotic solutions; the doubling loop finds the upper end in a step or two.
    lo = max(math.sqrt(2.0 * c), c / _PI_2_M1)
    while _g_gap(lo) > c:
        lo *= 0.5
    hi = 2.0 * lo
    while _g_gap(hi) < c:
        hi *= 2.0
    return bracketed_newton(lambda s: _g_gap(s) - c, _g_gap_prime, lo, hi, lo)


def elastic_internal_onset(G, sigma_c, delta, R):
    """Exact elastic MDR-Dugdale onset for a punch whose cohesive zone lies on its own face.

    Inputs: G [Pa] (> 0), sigma_c [Pa], delta [m], R [m] (the punch radius). The zone spans
    ``a < r < R`` (``b = R``); with ``a = R cos(theta)`` the edge condition gives
    ``2 G h = sigma_c R sin(theta)`` and the gap at the rim (MODEL.md section 5 with ``b = R``)
    ``(sigma_c R / (pi G)) [theta sin(theta) - 2 sin^2(theta/2)] = delta``, i.e.
    ``g(theta) = chi_R = pi G delta / (sigma_c R)``. ``g`` grows from 0 to ``pi/2 - 1`` as the
    bond shrinks to nothing; for ``chi_R >= pi/2 - 1`` the bond is gone (``a = 0``) before the
    gap reaches ``delta``: the strength limit, ``F_total = pi R^2 sigma_c``.

    Returns ``dict(a=[m], h=[m], F_contact=[N], F_total=[N], theta=[rad],
    strength_limited=bool)``: ``F_contact = 8 a G h = 4 sigma_c R^2 cos(theta) sin(theta)``,
    ``F_total = 2 sigma_c R^2 [cos(theta) sin(theta) + theta]`` (the whole line load). An
    elastic crack is unstable under a rigid lift, so these are also the peak forces.
    """
    G, sigma_c, delta, R = map(float, (G, sigma_c, delta, R))
    if not (G > 0 and sigma_c > 0 and R > 0 and delta >= 0):
        raise ValueError("need G > 0, sigma_c > 0, R > 0, delta >= 0")
    chi_R = math.pi * G * delta / (sigma_c * R)

    def g(theta):
        return theta * math.sin(theta) - 2.0 * math.sin(0.5 * theta) ** 2

    strength_limited = chi_R >= _PI_2_M1
    if strength_limited:
        theta = 0.5 * math.pi
    elif chi_R == 0.0:
        theta = 0.0
    else:
        # g ~ theta^2/2 for small theta and g <= theta^2/2: start there and widen.
        hi = min(0.5 * math.pi, 2.0 * math.sqrt(2.0 * chi_R))
        while g(hi) < chi_R and hi < 0.5 * math.pi:
            hi = min(0.5 * math.pi, 2.0 * hi)
        # g' = theta cos(theta) > 0 below pi/2
        theta = bracketed_newton(lambda x: g(x) - chi_R, lambda x: x * math.cos(x), 0.0, hi,
                                  min(hi, math.sqrt(2.0 * chi_R)))
    a = R * math.cos(theta) if not strength_limited else 0.0
    h = sigma_c * R * math.sin(theta) / (2.0 * G)
    F_contact = 4.0 * sigma_c * R * R * math.cos(theta) * math.sin(theta) if a > 0 else 0.0
    F_total = 2.0 * sigma_c * R * R * (math.cos(theta) * math.sin(theta) + theta)
    return dict(a=a, h=h, F_contact=F_contact, F_total=F_total, theta=theta,
                strength_limited=strength_limited)


# (1 + S^2) atan(S) - S = sum_{n>=1} (-1)^(n+1) 2 S^(2n+1) / ((2n-1)(2n+1)).  Below S = 0.5 the
# direct form would lose ~1/S^2 to cancellation; 30 terms of the series reach 0.25^29 ~ 3e-18
# relative there.  Coefficients listed from S^3 on, in powers of S^2.
_COH_SERIES = [(-1) ** (n + 1) * 2.0 / ((2 * n - 1) * (2 * n + 1)) for n in range(1, 31)]
_COH_SERIES_MAX_S = 0.5


def _cohesive_bracket(S):
    """``(1 + S^2) atan(S) - S`` for an array ``S >= 0``, to ~1e-15 relative."""
    S = np.asarray(S, dtype=float)
    small = S < _COH_SERIES_MAX_S
    if small.all():  # (a thin zone's whole history: no masks)
        return _cohesive_series(S)
    # math.atan, not np.arctan: numpy's vectorised arctan may round differently in the last
    # bit (it did on an Intel Xeon, not on an AMD EPYC), and a history's row must be the
    # scalar path's value whatever the machine.
    atan = np.array([math.atan(s) for s in S.ravel().tolist()]).reshape(S.shape)
    with np.errstate(over="ignore", invalid="ignore"):
        out = (1.0 + S * S) * atan - S
    if small.any():
        out[small] = _cohesive_series(S[small])
    return out


def _cohesive_series(S):
    """The series below ``S = 0.5``, all its terms (as :func:`_cohesive_force_scalar`, bit
    for bit; a truncation chosen per array made an element depend on its neighbours)."""
    s2 = S * S
    return S * s2 * _horner(_COH_SERIES, s2)


def _cohesive_force_scalar(sigma_c: float, a: float, b: float) -> float:
    """:func:`cohesive_force` for one ``b`` (math, no arrays: it is on a run's hot path)."""
    if not b >= a:
        raise ValueError("cohesive_force needs b >= a")
    S = math.sqrt((b - a) * (b + a)) / a
    if S < _COH_SERIES_MAX_S:
        s2 = S * S
        bracket = S * s2 * _horner_scalar(_COH_SERIES, s2)
    else:
        bracket = (1.0 + S * S) * math.atan(S) - S
    return 2.0 * sigma_c * a * a * bracket


def cohesive_force(sigma_c, a, b):
    """Force of the cohesive annulus ``a < r < b`` alone, in [N] (MODEL.md section 3).

    ``sigma_c [pi b^2 - 2 a sqrt(b^2-a^2) - 2 b^2 asin(a/b)] = 2 sigma_c a^2 [(1+S^2) atan S - S]``
    with ``S = sqrt(b^2 - a^2)/a``; inputs sigma_c [Pa], a [m], b [m] (``b >= a``; ``b`` may be an
    array).  For small ``S`` the force is ``~ (4/3) sigma_c a^2 S^3`` and both forms cancel
    catastrophically, so a series is used below ``S = 0.5``; accurate to ~1e-15 relative.
    (A run's history is summed by a compiled twin, :mod:`pulloff.kernels.history`.)
    """
    a = float(a)
    if np.ndim(b) == 0:
        return _cohesive_force_scalar(float(sigma_c), a, float(b))
    b = np.asarray(b, dtype=float)
    if np.any(b < a):
        raise ValueError("cohesive_force needs b >= a")
    # (b - a) is exact for b <= 2a (Sterbenz), so S keeps full relative precision for thin zones
    S = np.sqrt((b - a) * (b + a)) / a
    return _out(2.0 * sigma_c * a * a * _cohesive_bracket(S))


def predictions(scene, t_star=None, elastic_zone=None) -> dict:
    """The closed forms beside a flat-punch pull, SI, keyed as in :mod:`pulloff.model.outputs`
    (nan where a formula does not apply). ``t_star`` and ``elastic_zone``: the root solves
    (see :func:`seed_linearised` and :func:`elastic_mdr_dugdale`; default the Python ones).

    With the zone on the punch face (``cohesive_zone: internal``) the elastic MDR-Dugdale forces
    are those of :func:`elastic_internal_onset` (``elastic_b`` is then the radius); the seed's
    forms are for its external zone. A Maxwell solid's elastic forms are those of the relaxed
    modulus, and beside them the instantaneous modulus's (a pull much faster than every tau).
    """
    nan = math.nan
    spectrum = scene.material.spectrum()
    G, eta = spectrum.G_inf, spectrum.eta
    sigma_c, delta, gamma = scene.adhesion.sigma_c, scene.adhesion.delta, scene.adhesion.gamma
    a, v = scene.geometry.radius, scene.loading.v
    internal = scene.geometry.cohesive_zone == "internal"
    out = dict.fromkeys(("seed_linearised_t_detach", "seed_linearised_F",
                         "seed_closed_form_t_detach", "seed_closed_form_F"), nan)
    out["seed_closed_form_branch"] = ""
    if not internal:
        lin = seed_linearised(G, eta, sigma_c, delta, a, v, t_star)
        closed = seed_closed_form(G, eta, sigma_c, delta, a, v)
        out.update(seed_linearised_t_detach=lin["t_detach"], seed_linearised_F=lin["F"],
                   seed_closed_form_t_detach=closed["t_detach"], seed_closed_form_F=closed["F"],
                   seed_closed_form_branch=closed["branch"])
    out["kendall_F"] = kendall_force(G, gamma, a) if G > 0 else nan
    out["viscous_F"] = viscous_force(eta, v, a)
    out["elastic_F_contact"] = out["elastic_F_total"] = out["elastic_b"] = nan
    if G > 0:
        el = _elastic_onset(G, sigma_c, delta, a, internal, elastic_zone)
        out.update(elastic_F_contact=el["F_contact"], elastic_F_total=el["F_total"],
                   elastic_b=a if internal else el["b"])
    out["elastic_instant_F_contact"] = out["elastic_instant_F_total"] = nan
    if spectrum.arms:
        el = _elastic_onset(spectrum.instantaneous_modulus, sigma_c, delta, a, internal,
                            elastic_zone)
        out.update(elastic_instant_F_contact=el["F_contact"], elastic_instant_F_total=el["F_total"])
    return out


def _elastic_onset(G, sigma_c, delta, a, internal, zone=None):
    return (elastic_internal_onset(G, sigma_c, delta, a) if internal
            else elastic_mdr_dugdale(G, sigma_c, delta, a, zone))


PATH_KEYS = ("mdr_dugdale_F_pulloff_load", "mdr_dugdale_F_pulloff_displacement",
             "jkr_F_pulloff_load", "maugis_F_pulloff_load", "maugis_F_pulloff_displacement",
             "relaxed_F_pulloff", "instant_F_pulloff")


#: path_predictions' answers by what they depend on: a sweep over speeds or paths computes
#: them once per process (0.24-0.62 s a run on the shipped paths, a quarter of sphere_elastic).
_PATH_CACHE: dict = {}
_PATH_CACHE_SIZE = 64


def path_predictions(scene) -> dict:
    """The closed forms beside an indenter's path, SI, keyed as in :mod:`pulloff.model.outputs`
    (nan where they do not apply): a smooth indenter's elastic pull-off curves, or a flat
    punch's elastic onset force (its pull-off on any path); with Maxwell arms the elastic
    limits of the relaxed and instantaneous moduli."""
    key = json.dumps([scene.geometry.model_dump(mode="json"),
                      scene.material.model_dump(mode="json"),
                      scene.adhesion.model_dump(mode="json"),
                      getattr(scene.loading, "machine_stiffness", None)], sort_keys=True)
    if key not in _PATH_CACHE:
        if len(_PATH_CACHE) >= _PATH_CACHE_SIZE:
            _PATH_CACHE.clear()
        _PATH_CACHE[key] = _path_predictions(scene)
    return dict(_PATH_CACHE[key])


def _path_predictions(scene) -> dict:
    from . import elastic_contact as ec

    out = dict.fromkeys(PATH_KEYS, math.nan)
    geometry, spectrum = scene.geometry, scene.material.spectrum()
    if geometry.kind == "flat_punch":
        return _flat_punch_path(scene, spectrum, out)
    G = spectrum.G_inf
    sigma_c, delta, gamma = scene.adhesion.sigma_c, scene.adhesion.delta, scene.adhesion.gamma
    if geometry.kind == "profile":
        profile = ec.mdr_profile_tabulated(np.asarray(geometry.r), np.asarray(geometry.f))
    else:
        profile = ec.mdr_profile_power_law(*geometry.power_law())
    if spectrum.relaxation_times:
        # A solid with memory: the elastic curves of its two limits bound the pull-off.
        if math.isfinite(spectrum.instantaneous_modulus):
            for key, modulus in (("relaxed", G), ("instant", spectrum.instantaneous_modulus)):
                out[f"{key}_F_pulloff"] = ec.mdr_dugdale_pulloff(
                    profile, modulus, sigma_c=sigma_c, delta=delta, control="load").F
        return out
    machine = getattr(scene.loading, "machine_stiffness", None)
    for control in ("load", "displacement"):
        out[f"mdr_dugdale_F_pulloff_{control}"] = ec.mdr_dugdale_pulloff(
            profile, G, sigma_c=sigma_c, delta=delta, control=control,
            machine_stiffness=machine).F
    out["jkr_F_pulloff_load"] = ec.jkr_pulloff(profile, 4.0 * G, gamma, "load").F
    if geometry.kind == "sphere":
        # (Maugis' displacement control is a rigid machine's: not a spring's)
        for control in ("load",) if machine else ("load", "displacement"):
            out[f"maugis_F_pulloff_{control}"] = ec.maugis_pulloff_force(
                geometry.radius, G, sigma_c, gamma, control)
    return out


def _flat_punch_path(scene, spectrum, out: dict) -> dict:
    """An elastic flat punch's pull-off on any path is its onset force: the force rises with
    the lift until the onset, where the elastic crack runs (the simulator's F_pulloff agrees
    to 1e-10 under load and displacement control, behind springs of 1 and 100 N/m, with the
    zone outside and on the face). Kendall's force is the short-range limit. A solid with
    memory gets the onset forces of its relaxed modulus (a slow pull's limit) and, with
    Maxwell arms, of its instantaneous one (a fast pull's; a Kelvin-Voigt solid's is
    infinite): its pull-off depends on the rate, so no single elastic value is its own."""
    sigma_c, delta, gamma = scene.adhesion.sigma_c, scene.adhesion.delta, scene.adhesion.gamma
    a, internal = scene.geometry.radius, scene.geometry.cohesive_zone == "internal"
    G = spectrum.G_inf
    if spectrum.relaxation_times:  # Kelvin-Voigt (eta/G) or Maxwell arms
        for key, modulus in (("relaxed", G), ("instant", spectrum.instantaneous_modulus)):
            if modulus > 0 and math.isfinite(modulus):
                out[f"{key}_F_pulloff"] = _elastic_onset(modulus, sigma_c, delta, a,
                                                         internal)["F_total"]
        return out
    if G > 0:
        F = _elastic_onset(G, sigma_c, delta, a, internal)["F_total"]
        out["mdr_dugdale_F_pulloff_load"] = out["mdr_dugdale_F_pulloff_displacement"] = F
        out["jkr_F_pulloff_load"] = kendall_force(G, gamma, a)
    return out
