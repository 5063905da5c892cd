"""Tests of pulloff.analytic: the seed thesis's own numbers, its closed forms, and exact limits.

Equation numbers refer to the seed thesis (seeds/000_cfa5e98cccfc6722.txt).
"""

import math
from fractions import Fraction

import numpy as np
import pytest
from scipy.integrate import quad

from pulloff.model import analytic as A

import mpmath as mp
from hypothesis import given, settings
from hypothesis import strategies as st

SQRT3 = math.sqrt(3.0)

# A representative SI parameter set (soft elastomer, millimetre punch)
BASE = dict(G=1e6, eta=1e3, sigma_c=1e5, delta=1e-6, a=1e-3, v=1e-3)


def params_for_alpha(al, **over):
    """BASE with delta chosen so that alpha(...) == al."""
    p = dict(BASE, **over)
    p["delta"] = al * 4 * p["v"] ** 2 * p["eta"] ** 2 / (math.pi * p["sigma_c"] * p["a"] * p["G"])
    return p


def rel(x, y):
    return abs(x - y) / abs(y)


# ---------------------------------------------------------------------------------------------
# the thesis's numbers at the switch (section 3.3, eq. 90)
# ---------------------------------------------------------------------------------------------


def test_switch_point_numbers():
    assert A.ALPHA_SWITCH == pytest.approx(1.5 + SQRT3, rel=1e-16)
    t = A.seed_t_star(A.ALPHA_SWITCH)
    assert round(t, 5) == 2.54519  # "approximately t* = 2.54519"
    assert A.t_star_small_alpha(A.ALPHA_SWITCH) == pytest.approx(1 + SQRT3, rel=1e-15)
    assert A.t_star_large_alpha(A.ALPHA_SWITCH) == pytest.approx(1 + SQRT3, rel=1e-15)
    H = abs(1 + SQRT3 - t) / t
    assert round(H, 4) == 0.0734  # eq. 90
    # and with the thesis's rounded t*, exactly as printed in eq. 90
    assert round(abs(1 + SQRT3 - 2.54519) / 2.54519, 4) == 0.0734


# ---------------------------------------------------------------------------------------------
# Taylor coefficients (eqs. 65-78)
# ---------------------------------------------------------------------------------------------


def _taylor_of_f_by_exp_series(n):
    """Coefficients of f(t) = t(t+1) - (t+1)^2 (1 - e^{-t})/2, by polynomial multiplication."""
    one_minus_exp = [Fraction(0)] + [Fraction((-1) ** (k + 1), math.factorial(k)) for k in range(1, n + 1)]
    sq = [Fraction(1), Fraction(2), Fraction(1)]  # (t+1)^2
    prod = [Fraction(0)] * (n + 1)
    for i, ci in enumerate(sq):
        for j, cj in enumerate(one_minus_exp):
            if i + j <= n:
                prod[i + j] += ci * cj
    f = [-p / 2 for p in prod]
    f[1] += 1
    f[2] += 1
    return f


def test_taylor_coeffs_by_exact_series():
    derived = _taylor_of_f_by_exp_series(5)
    assert tuple(derived) == tuple(Fraction(c) for c in A.TAYLOR_COEFFS)


def test_taylor_coeffs_from_thesis_derivatives_and_eq73_inconsistency():
    # eqs. 67-71 evaluated at 0 give f^(k)(0) = 1/2, 1/2, -1/2, 5/2, -11/2 ...
    t = 0.0
    derivs = [
        t + math.exp(-t) * (-0.5 * t * t + 0.5),
        1 + math.exp(-t) * (0.5 * t * t - t - 0.5),
        math.exp(-t) * (-0.5 * t * t + 2 * t - 0.5),
        math.exp(-t) * (0.5 * t * t - 3 * t + 2.5),
        math.exp(-t) * (-0.5 * t * t + 4 * t - 5.5),
    ]
    for k, d in enumerate(derivs, start=1):
        # ... and f^(k)(0)/k! is eq. 74, i.e. TAYLOR_COEFFS
        assert Fraction(d).limit_denominator(100) / math.factorial(k) == A.TAYLOR_COEFFS[k]
    # eq. 73 as printed: twice the true coefficient for k >= 2; eq. 74 (what the thesis uses) is right
    eq73 = (Fraction(0), Fraction(1, 2), Fraction(1, 2), Fraction(-1, 6), Fraction(5, 24), Fraction(-11, 120))
    assert eq73[:2] == A.TAYLOR_COEFFS[:2]
    for k in range(2, 6):
        assert eq73[k] == 2 * A.TAYLOR_COEFFS[k]


def test_taylor_coeffs_numerical_fit():
    # independent of any series: least-squares fit of seed_rhs on a small interval
    x = 0.3 * np.cos(np.linspace(0, np.pi, 200))
    poly = np.polynomial.Polynomial.fit(x, A.seed_rhs(x), 14).convert()
    for k in range(6):
        assert poly.coef[k] == pytest.approx(float(A.TAYLOR_COEFFS[k]), abs=1e-8)


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5])
def test_taylor_poly_order(n):
    # f - T_n = O(t^(n+1)): halving t divides the error by ~2^(n+1)
    t1, t2 = 0.02, 0.01
    e1 = abs(A.seed_rhs(t1) - A.taylor_poly(t1, n))
    e2 = abs(A.seed_rhs(t2) - A.taylor_poly(t2, n))
    assert e1 / e2 == pytest.approx(2.0 ** (n + 1), rel=0.1)


def test_taylor_poly_matches_eqs_75_to_78_and_rejects_bad_degree():
    t = 0.37
    assert A.taylor_poly(t, 1) == pytest.approx(t / 2, rel=1e-15)
    assert A.taylor_poly(t, 2) == pytest.approx(t / 2 + t**2 / 4, rel=1e-15)
    assert A.taylor_poly(t, 3) == pytest.approx(t / 2 + t**2 / 4 - t**3 / 12, rel=1e-15)
    assert A.taylor_poly(t, 4) == pytest.approx(t / 2 + t**2 / 4 - t**3 / 12 + 5 * t**4 / 48, rel=1e-15)
    assert A.taylor_poly(np.array([t, t]), 5).shape == (2,)
    for bad in (0, 6):
        with pytest.raises(ValueError):
            A.taylor_poly(t, bad)


# ---------------------------------------------------------------------------------------------
# seed_rhs accuracy
# ---------------------------------------------------------------------------------------------


def test_seed_rhs_small_t_against_exact_rational_series():
    coeffs = _taylor_of_f_by_exp_series(40)
    for t in np.logspace(-15, math.log10(0.9), 60):
        tf = Fraction(float(t))  # the exact value of the float argument
        ref = sum(c * tf**k for k, c in enumerate(coeffs))  # error < 0.9^41/41! ~ 0
        assert rel(A.seed_rhs(t), float(ref)) < 1e-15


def test_seed_rhs_against_mpmath():
    with mp.workdps(40):
        for t in np.logspace(-15, 4, 300):
            T = mp.mpf(float(t))
            ref = float(T * (T + 1) - (T + 1) ** 2 * (1 - mp.exp(-T)) / 2)
            assert rel(A.seed_rhs(t), ref) < 1e-15


def test_seed_rhs_vectorised_and_special_values():
    x = np.array([[0.0, 1e-300], [0.5, 3.0]])
    y = A.seed_rhs(x)
    assert y.shape == x.shape
    assert y[0, 0] == 0.0
    assert y[0, 1] == pytest.approx(0.5e-300, rel=1e-15)
    assert y[1, 1] == pytest.approx(A.seed_rhs(3.0), rel=0)
    assert A.seed_rhs(np.inf) == np.inf
    assert isinstance(A.seed_rhs(0.1), float)
    # continuity across the series/direct switch at t* = 1
    lo, hi = np.nextafter(1.0, 0.0), 1.0
    assert rel(A.seed_rhs(lo), A.seed_rhs(hi)) < 1e-15


# ---------------------------------------------------------------------------------------------
# seed_t_star and its approximations
# ---------------------------------------------------------------------------------------------


def test_seed_t_star_special_values_and_errors():
    assert A.seed_t_star(0.0) == 0.0
    assert A.seed_t_star(math.inf) == math.inf
    for bad in (-1e-300, -1.0, math.nan):
        with pytest.raises(ValueError):
            A.seed_t_star(bad)
    arr = A.seed_t_star(np.array([1e-6, 1.0, 1e6]))
    assert arr.shape == (3,) and np.all(np.diff(arr) > 0)


def test_seed_t_star_inverts_across_all_regimes():
    # including the switches between inverse series / brentq / fixed point
    for al in [1e-300, 1e-20, 1e-8, 0.99e-4, 1e-4, 1.01e-4, 0.1, 1.0, 99.9, 100.0, 100.1, 1e6, 1e12, 1e100]:
        t = A.seed_t_star(al)
        assert rel(A.seed_rhs(t), al) < 2e-15, al


def test_seed_t_star_against_mpmath_root():
    with mp.workdps(40):
        f = lambda T, al: T * (T + 1) - (T + 1) ** 2 * (1 - mp.exp(-T)) / 2 - al  # noqa: E731
        for al in np.logspace(-10, 10, 41):
            t = A.seed_t_star(al)
            ref = mp.findroot(lambda T: f(T, mp.mpf(float(al))), mp.mpf(t))
            assert rel(t, float(ref)) < 1e-14


def test_large_alpha_approximation_converges():
    errs = [rel(A.t_star_large_alpha(al), A.seed_t_star(al)) for al in (1.0, 10.0, 100.0, 1e3)]
    assert all(e2 < e1 for e1, e2 in zip(errs, errs[1:]))
    assert errs[0] > 1e-2 and errs[-1] < 1e-15


def test_small_alpha_approximation_converges():
    alphas = [1e-1, 1e-2, 1e-3, 1e-4]
    errs = [rel(A.t_star_small_alpha(al), A.seed_t_star(al)) for al in alphas]
    assert all(e2 < e1 for e1, e2 in zip(errs, errs[1:]))
    # T2 misses the alpha^3 term of t* = 2a - 2a^2 + 16/3 a^3 - ...: relative error ~ (2/3) alpha^2
    # (t* - t_T2)/t* = (4/3 a^3 - 10 a^4)/(2a (1 - a)) = (2/3) a^2 (1 - 6.5 a + O(a^2))
    for al, e in zip(alphas[1:], errs[1:]):
        assert e == pytest.approx(2.0 / 3.0 * al**2 * (1 - 6.5 * al), rel=1e-2)
    # cancellation-free for tiny alpha
    assert A.t_star_small_alpha(1e-300) == pytest.approx(2e-300, rel=1e-15)
    assert A.t_star_small_alpha(math.inf) == math.inf


# ---------------------------------------------------------------------------------------------
# dimensionless groups
# ---------------------------------------------------------------------------------------------


def test_dimensionless_groups():
    p = BASE
    g = A.dimensionless_groups(**p)
    assert g["alpha"] == pytest.approx(
        math.pi * p["delta"] * p["sigma_c"] * p["a"] * p["G"] / (4 * p["v"] ** 2 * p["eta"] ** 2), rel=1e-15
    )
    assert g["chi"] == pytest.approx(math.pi * p["G"] * p["delta"] / (p["sigma_c"] * p["a"]), rel=1e-15)
    assert g["V"] == pytest.approx(p["eta"] * p["v"] / (p["sigma_c"] * p["a"]), rel=1e-15)
    # alpha = (pi/4) chi / V^2 ... in these units
    assert g["alpha"] == pytest.approx(g["chi"] / (4 * g["V"] ** 2), rel=1e-14)
    assert A.alpha(**dict(p, eta=0.0)) == math.inf
    assert A.alpha(**dict(p, G=0.0)) == 0.0
    arr = A.alpha(np.array([0.0, 1e6]), np.array([1e3, 0.0]), 1e5, 1e-6, 1e-3, 1e-3)
    assert arr[0] == 0.0 and arr[1] == math.inf


# ---------------------------------------------------------------------------------------------
# seed_linearised and seed_closed_form
# ---------------------------------------------------------------------------------------------


def test_seed_linearised_solves_eq53_and_eq48():
    for al in (1e-6, 1e-2, 1.0, A.ALPHA_SWITCH, 50.0, 1e4):
        p = params_for_alpha(al)
        r = A.seed_linearised(**p)
        t_star = r["t_detach"] * p["G"] / p["eta"]
        assert rel(A.seed_rhs(t_star), al) < 1e-13
        assert r["h_detach"] == pytest.approx(p["v"] * r["t_detach"], rel=1e-15)
        F48 = 8 * p["a"] * (p["G"] * p["v"] * r["t_detach"] + p["eta"] * p["v"])
        assert r["F"] == pytest.approx(F48, rel=1e-15)
        # eq. 44 in dimensional form
        t, G, eta = r["t_detach"], p["G"], p["eta"]
        rhs44 = 4 * p["v"] ** 2 / (p["sigma_c"] * p["a"] * math.pi) * (
            t * (G * t + eta) - (G * t + eta) ** 2 / (2 * G) * -math.expm1(-G * t / eta)
        )
        assert rel(rhs44, p["delta"]) < 1e-9


def test_seed_linearised_elastic_limit():
    p = dict(BASE, eta=0.0)
    r = A.seed_linearised(**p)
    t93 = math.sqrt(p["delta"] * math.pi * p["a"] * p["sigma_c"] / (2 * p["G"] * p["v"] ** 2))
    assert rel(r["t_detach"], t93) < 1e-15
    assert rel(r["F"], A.kendall_force(p["G"], p["sigma_c"] * p["delta"], p["a"])) < 1e-14
    # eta -> 0 is continuous (alpha overflows to inf on the way)
    for eta in (1e-3, 1e-10, 1e-200):
        assert rel(A.seed_linearised(**dict(p, eta=eta))["F"], r["F"]) < 1e-4 * eta + 1e-15


def test_seed_linearised_viscous_limit():
    p = dict(BASE, G=0.0)
    r = A.seed_linearised(**p)
    t_lim = math.pi * p["delta"] * p["sigma_c"] * p["a"] / (2 * p["v"] ** 2 * p["eta"])
    assert rel(r["t_detach"], t_lim) < 1e-15
    assert rel(r["F"], A.viscous_force(p["eta"], p["v"], p["a"])) < 1e-15
    # G -> 0 is continuous (alpha underflows to 0 on the way)
    for G in (1e-2, 1e-10, 1e-300):
        rg = A.seed_linearised(**dict(p, G=G))
        assert rel(rg["t_detach"], t_lim) < 1e-2 * G + 1e-15
        assert rel(rg["F"], r["F"]) < 1e-2 * G + 1e-15


def test_seed_linearised_rejects_bad_input():
    with pytest.raises(ValueError):
        A.seed_linearised(**dict(BASE, G=0.0, eta=0.0))
    with pytest.raises(ValueError):
        A.seed_linearised(**dict(BASE, v=0.0))
    with pytest.raises(ValueError):
        A.seed_closed_form(**dict(BASE, G=-1.0))


def test_seed_closed_form_limits():
    pe = dict(BASE, eta=0.0)
    r = A.seed_closed_form(**pe)
    assert r["branch"] == "large_alpha"
    assert rel(r["F"], A.kendall_force(pe["G"], pe["sigma_c"] * pe["delta"], pe["a"])) < 1e-14
    assert rel(r["t_detach"], A.seed_linearised(**pe)["t_detach"]) < 1e-14  # eq. 93

    pv = dict(BASE, G=0.0)
    r = A.seed_closed_form(**pv)
    assert r["branch"] == "small_alpha"
    assert r["F"] == pytest.approx(8 * pv["eta"] * pv["v"] * pv["a"], rel=1e-15)
    assert rel(r["t_detach"], A.seed_linearised(**pv)["t_detach"]) < 1e-15
    assert np.isfinite(r["t_detach"])


def test_seed_closed_form_formulas_as_printed():
    # eqs. 61/64 and 85/89 literally, away from the limits
    for al, branch in ((0.3, "small_alpha"), (30.0, "large_alpha")):
        p = params_for_alpha(al)
        G, eta, s, d, a, v = (p[k] for k in ("G", "eta", "sigma_c", "delta", "a", "v"))
        r = A.seed_closed_form(**p)
        assert r["branch"] == branch
        if branch == "large_alpha":
            t = 1 / (G * v) * math.sqrt((d * s * a * math.pi * G + 2 * v**2 * eta**2) / 2)
            F = 8 * a * math.sqrt((d * s * a * math.pi * G + 2 * v**2 * eta**2) / 2) + 8 * eta * v * a
        else:
            t = eta / G * (-1 + math.sqrt(1 + d * s * a * math.pi * G / (v**2 * eta**2)))
            F = 8 * eta * v * a * math.sqrt(1 + d * s * a * math.pi * G / (v**2 * eta**2))
        assert rel(r["t_detach"], t) < 1e-13
        assert rel(r["F"], F) < 1e-14
        # eq. 48 holds for the closed form too
        assert rel(r["F"], 8 * a * (G * v * r["t_detach"] + eta * v)) < 1e-13


def test_seed_closed_form_error_scan():
    alphas = np.logspace(-4, 4, 801)
    alphas = np.sort(np.append(alphas, [A.ALPHA_SWITCH, np.nextafter(A.ALPHA_SWITCH, 10.0)]))
    errs = []
    for al in alphas:
        p = params_for_alpha(al)
        errs.append(rel(A.seed_closed_form(**p)["F"], A.seed_linearised(**p)["F"]))
    errs = np.array(errs)
    assert errs.max() <= 0.08  # "the approximation error is less than 8 %"
    i = int(np.argmax(errs))
    assert A.ALPHA_SWITCH / 1.05 <= alphas[i] <= A.ALPHA_SWITCH * 1.05
    # force error at the switch = t* error diluted by the eta v term: |1+sqrt3 - t*| / (1 + t*)
    t = A.seed_t_star(A.ALPHA_SWITCH)
    assert errs.max() == pytest.approx(abs(1 + SQRT3 - t) / (1 + t), rel=1e-9)
    assert errs[0] < 1e-8 and errs[-1] < 1e-15


# ---------------------------------------------------------------------------------------------
# Kendall / viscous forces
# ---------------------------------------------------------------------------------------------


def test_kendall_and_viscous_force():
    G, gamma, a = 2.5e6, 0.05, 2e-3
    FK = A.kendall_force(G, gamma, a)
    assert FK == pytest.approx(math.sqrt(8 * math.pi * 4 * G * a**3 * gamma), rel=1e-15)  # eq. 95
    assert FK == pytest.approx(math.sqrt(32 * G * a**3 * gamma * math.pi), rel=1e-15)  # eq. 94
    assert A.viscous_force(7.0, 0.3, 0.01) == pytest.approx(8 * 7.0 * 0.3 * 0.01, rel=1e-15)


# ---------------------------------------------------------------------------------------------
# exact viscous limit (G = 0)
# ---------------------------------------------------------------------------------------------


def _viscous_gap_by_quad(t, eta, sigma_c, a, v):
    b = math.sqrt(a * a + (2 * eta * v / sigma_c) ** 2)  # edge condition with G = 0
    h = v * t
    u = lambda x: 2 * sigma_c * math.sqrt(b * b - x * x) * t / (4 * eta)  # noqa: E731
    integral, _ = quad(lambda x: u(x) / math.sqrt(b * b - x * x), a, b, epsabs=0, epsrel=1e-13)
    return h - (2 / math.pi) * (h * math.asin(a / b) + integral)


@pytest.mark.parametrize("eta", [1e3, 1e4, 1e5, 1e7])
def test_viscous_detach_time_against_direct_model(eta):
    # double precision is enough while the zone is wide: the gap h (1 - (2/pi) asin(a/b)) - ...
    # cancels like 1/S, S = 2 eta v/(sigma_c a) >= 0.02 here
    sigma_c, delta, a, v = 1e5, 1e-6, 1e-3, 1e-3
    t = A.viscous_detach_time(eta, sigma_c, delta, a, v)
    assert np.isfinite(t) and t > 0
    assert rel(_viscous_gap_by_quad(t, eta, sigma_c, a, v), delta) < 1e-12


@pytest.mark.parametrize("eta", [1e-3, 1e-1, 1e1, 1e3, 1e5, 1e7])
def test_viscous_detach_time_against_direct_model_mpmath(eta):
    # the same direct evaluation in 50 digits, down to thin zones (S = 2e-8)
    sigma_c, delta, a, v = 1e5, 1e-6, 1e-3, 1e-3
    t = A.viscous_detach_time(eta, sigma_c, delta, a, v)
    with mp.workdps(50):
        S_, a_, v_, t_ = mp.mpf(sigma_c), mp.mpf(a), mp.mpf(v), mp.mpf(t)
        b = mp.sqrt(a_**2 + (2 * mp.mpf(eta) * v_ / S_) ** 2)
        h = v_ * t_
        u = lambda x: 2 * S_ * mp.sqrt(b**2 - x**2) * t_ / (4 * eta)  # noqa: E731
        # x = b cos(theta) removes the 1/sqrt(b^2 - x^2) endpoint singularity
        integral = mp.quad(lambda th: u(b * mp.cos(th)), [0, mp.acos(a_ / b)])
        gap = h - 2 / mp.pi * (h * mp.asin(a_ / b) + integral)
        assert rel(float(gap), delta) < 1e-14


def test_viscous_detach_time_limits():
    sigma_c, delta, a, v = 1e5, 1e-6, 1e-3, 1e-3
    assert A.viscous_detach_time(0.0, sigma_c, delta, a, v) == math.inf
    # as V -> 0 the exact G = 0 time tends to the linearised one, pi delta sigma_c a / (2 v^2 eta)
    prev = math.inf
    for eta in (1e3, 1e1, 1e-1, 1e-3):
        t_lin = A.seed_linearised(0.0, eta, sigma_c, delta, a, v)["t_detach"]
        d = rel(A.viscous_detach_time(eta, sigma_c, delta, a, v), t_lin)
        assert d < prev
        prev = d
    assert prev < 1e-8


# ---------------------------------------------------------------------------------------------
# exact elastic MDR-Dugdale punch
# ---------------------------------------------------------------------------------------------

EL = dict(G=1e6, sigma_c=1e5, a=1e-3)


def _delta_for_chi(c, G=EL["G"], sigma_c=EL["sigma_c"], a=EL["a"]):
    return c * sigma_c * a / (math.pi * G)


CHIS = np.logspace(-12, 3, 61)


def test_elastic_mdr_dugdale_defining_equations():
    G, s, a = EL["G"], EL["sigma_c"], EL["a"]
    with mp.workdps(40):
        for c in CHIS:
            d = _delta_for_chi(c)
            r = A.elastic_mdr_dugdale(G, s, d, a)
            # edge condition 2 G h = sigma_c sqrt(b^2 - a^2) = sigma_c a S, recovered from h
            S = mp.mpf(2 * G * r["h"]) / (s * a)
            assert rel(r["S"], float(S)) < 1e-15
            # gap condition in high precision
            gap = s * a / (mp.pi * G) * (S * mp.atan(S) - (mp.sqrt(1 + S * S) - 1))
            assert rel(float(gap), d) < 1e-12
            assert rel(r["F_contact"], 8 * a * G * r["h"]) < 1e-15


def test_elastic_mdr_dugdale_defining_equations_in_b():
    # in terms of b itself, where b - a is resolved by a float (the thin-zone end is checked via S)
    G, s, a = EL["G"], EL["sigma_c"], EL["a"]
    for c in CHIS[CHIS >= 1e-2]:
        d = _delta_for_chi(c)
        r = A.elastic_mdr_dugdale(G, s, d, a)
        b, h = r["b"], r["h"]
        root = math.sqrt((b - a) * (b + a))
        assert rel(2 * G * h, s * root) < 1e-12
        gap = s / (math.pi * G) * (root * math.acos(a / b) - (b - a))
        assert rel(gap, d) < 1e-12
        F_total = 2 * s * (a * root + b * b * math.acos(a / b))
        assert rel(r["F_total"], F_total) < 1e-12


def test_elastic_mdr_dugdale_kendall_limit_rate():
    G, s, a = EL["G"], EL["sigma_c"], EL["a"]
    cs = np.logspace(-8, -4, 9)
    dc, dt = [], []
    for c in cs:
        d = _delta_for_chi(c)
        r = A.elastic_mdr_dugdale(G, s, d, a)
        K = A.kendall_force(G, s * d, a)
        dc.append(rel(r["F_contact"], K))
        dt.append(rel(r["F_total"], K))
    slope_c = np.polyfit(np.log(cs), np.log(dc), 1)[0]
    slope_t = np.polyfit(np.log(cs), np.log(dt), 1)[0]
    # at least as fast as sqrt(chi); in fact linearly, F/F_K = 1 + (5/12, 13/12) chi + ...
    assert 0.95 <= slope_c <= 1.05
    assert 0.95 <= slope_t <= 1.05
    assert dc[-1] / cs[-1] == pytest.approx(5 / 12, rel=1e-3)
    assert dt[-1] / cs[-1] == pytest.approx(13 / 12, rel=1e-3)


def test_elastic_mdr_dugdale_finite_and_monotone():
    G, s, a = EL["G"], EL["sigma_c"], EL["a"]
    rows = [A.elastic_mdr_dugdale(G, s, _delta_for_chi(c), a) for c in CHIS]
    for key in ("b", "h", "F_contact", "F_total", "S"):
        vals = np.array([r[key] for r in rows])
        assert np.all(np.isfinite(vals)) and np.all(vals > 0)
        if key == "b":  # b resolves b - a only above ~1e-16 a
            assert np.all(np.diff(vals) >= 0)
        else:
            assert np.all(np.diff(vals) > 0), key
    for r in rows:
        assert r["F_total"] >= r["F_contact"]
    # (b - a)/a -> chi as chi -> 0 (MODEL.md section 4)
    r = A.elastic_mdr_dugdale(G, s, _delta_for_chi(1e-6), a)
    assert r["S"] ** 2 / 2 / 1e-6 == pytest.approx(1.0, rel=1e-5)
    # delta = 0: nothing to pull against
    r0 = A.elastic_mdr_dugdale(G, s, 0.0, a)
    assert r0["h"] == 0.0 and r0["F_total"] == 0.0 and r0["b"] == a


def test_elastic_mdr_dugdale_agrees_with_seed_in_kendall_limit():
    # the linearised seed with eta = 0 is Kendall; so is the exact elastic model as chi -> 0
    p = dict(BASE, eta=0.0, delta=_delta_for_chi(1e-9, BASE["G"], BASE["sigma_c"], BASE["a"]))
    r = A.elastic_mdr_dugdale(p["G"], p["sigma_c"], p["delta"], p["a"])
    s = A.seed_linearised(**p)
    assert rel(r["F_contact"], s["F"]) < 1e-8
    assert rel(r["h"], s["h_detach"]) < 1e-8


# ---------------------------------------------------------------------------------------------
# cohesive_force
# ---------------------------------------------------------------------------------------------


def _b_list():
    # b - a must be a float: the smallest S a float b can express is sqrt(2 * 2^-53) ~ 1.5e-8,
    # reached with a just below 1 and b = 1
    out = [(1.0 - 2.0**-53, 1.0)]
    for S in np.logspace(-7.5, 3, 43):
        a = 1.0
        b = a * math.sqrt(1 + S * S)
        if b > a:
            out.append((a, b))
    return out


def test_cohesive_force_against_quad():
    # force of the line load: 4 sigma_c int_a^b sqrt(b^2 - x^2) dx; with x = b cos(theta) it is
    # 4 sigma_c b^2 int_0^{acos(a/b)} sin^2 dtheta, a positive integrand (no cancellation)
    sigma_c = 3e4
    for a, b in _b_list():
        th = math.atan2(math.sqrt((b - a) * (b + a)), a)
        val, _ = quad(lambda u: math.sin(u) ** 2, 0.0, th, epsabs=0, epsrel=2e-14)
        ref = 4 * sigma_c * b * b * val
        assert rel(A.cohesive_force(sigma_c, a, b), ref) < 1e-13


def test_cohesive_force_against_mpmath():
    sigma_c = 3e4
    with mp.workdps(60):
        for a, b in _b_list():
            B, Aa = mp.mpf(b), mp.mpf(a)
            closed = sigma_c * (mp.pi * B**2 - 2 * Aa * mp.sqrt(B**2 - Aa**2) - 2 * B**2 * mp.asin(Aa / B))
            assert rel(A.cohesive_force(sigma_c, a, b), float(closed)) < 1e-14
        for a, b in _b_list()[::10]:  # the defining integral itself
            B, Aa = mp.mpf(b), mp.mpf(a)
            integ = 4 * sigma_c * mp.quad(lambda x: mp.sqrt(B**2 - x**2), [Aa, B])
            assert rel(A.cohesive_force(sigma_c, a, b), float(integ)) < 1e-14


def test_cohesive_force_small_zone_asymptote_and_vectorisation():
    sigma_c, a = 2e5, 1e-3
    b = np.array([a * (1 + 1e-12), a * (1 + 1e-8), a * (1 + 1e-5)])
    S = np.sqrt((b - a) * (b + a)) / a
    F = A.cohesive_force(sigma_c, a, b)
    assert F.shape == b.shape
    ratio = F / (4.0 / 3.0 * sigma_c * a * a * S**3)
    # 2/3 S^3 - 2/15 S^5 + 2/35 S^7: ratio = 1 - S^2/5 + 3 S^4/35
    assert np.all(np.abs(ratio - (1 - S**2 / 5 + 3 * S**4 / 35)) < 1e-14)
    assert np.all(np.abs(ratio - 1) < S**2 / 4)
    assert A.cohesive_force(sigma_c, a, a) == 0.0
    with pytest.raises(ValueError):
        A.cohesive_force(sigma_c, a, 0.9 * a)
    # F_total - F_contact of the elastic punch is the cohesive zone's force
    r = A.elastic_mdr_dugdale(1e6, 1e5, 1e-6, 1e-3)
    assert rel(r["F_total"] - r["F_contact"], A.cohesive_force(1e5, 1e-3, r["b"])) < 1e-12


# ---------------------------------------------------------------------------------------------
# property tests
# ---------------------------------------------------------------------------------------------

@settings(max_examples=200, deadline=None)
@given(st.floats(min_value=-8.0, max_value=8.0))
def test_property_seed_t_star_inverts_seed_rhs(log_alpha):
    al = 10.0**log_alpha
    t = A.seed_t_star(al)
    assert rel(A.seed_rhs(t), al) < 2e-15
    # the rigorous bracket (see analytic._t_star_scalar)
    assert 2 * al / (0.5 + math.sqrt(0.25 + 2 * al)) * (1 - 1e-15) <= t
    assert t <= min(2 * al, math.sqrt(2 * al + 1)) * (1 + 1e-15)

@settings(max_examples=100, deadline=None)
@given(st.floats(min_value=-12.0, max_value=3.0), st.floats(min_value=-9.0, max_value=0.0))
def test_property_elastic_gap_condition_any_scale(log_chi, log_a):
    # SI scales over many decades: a from 1 nm to 1 m, G = 1 Pa .. 1e11 Pa
    a = 10.0**log_a
    G = 10.0 ** (11 + log_a)
    sigma_c = 10.0 ** (5 - log_a / 2)
    c = 10.0**log_chi
    d = c * sigma_c * a / (math.pi * G)
    r = A.elastic_mdr_dugdale(G, sigma_c, d, a)
    S = r["S"]
    # g(S) = S atan S - S^2/(1 + sqrt(1+S^2)) loses at most a factor ~2 to cancellation
    g = S * math.atan(S) - S * S / (1 + math.sqrt(1 + S * S))
    assert rel(g, c) < 1e-13
    assert rel(r["h"], sigma_c * a * S / (2 * G)) < 1e-15


_ANY_FLOAT = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                       st.sampled_from([0.0, -0.0, 1e-320, 1e-300, 1e300]))


@settings(max_examples=400, deadline=None)
@given(st.tuples(*([_ANY_FLOAT] * 6)))
def test_property_the_groups_of_python_floats_are_their_array_form_bit_for_bit(values):
    """``alpha``, ``chi`` and ``V`` of Python floats (a scene's numbers) take a scalar path;
    it returns the array form's value to the bit, zeros, infinities and nans included, and a
    Python float."""
    G, eta, sigma_c, delta, a, v = values
    pairs = ((A.alpha, (G, eta, sigma_c, delta, a, v)), (A.chi, (G, sigma_c, delta, a)),
             (A.V, (eta, v, sigma_c, a)))
    with np.errstate(all="ignore"):
        for form, args in pairs:
            scalar = form(*args)
            array = form(np.asarray(args[0]), *args[1:])
            assert type(scalar) is float
            assert (scalar == array and math.copysign(1.0, scalar) == math.copysign(1.0, array)
                    or math.isnan(scalar) and math.isnan(array)), (form.__name__, args)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(0.0, 3.0), min_size=0, max_size=40))
def test_property_the_cohesive_force_of_an_array_is_each_of_its_rows_alone(S):
    """Each row of a history's cohesive force is the scalar path's value, bit for bit, whatever
    the other rows (an empty history gives an empty column)."""
    b = np.sqrt(1.0 + np.asarray(S, dtype=float) ** 2)
    rows = A.cohesive_force(2.0, 1.0, b)
    assert rows.shape == b.shape
    assert rows.tolist() == [A.cohesive_force(2.0, 1.0, float(x)) for x in b.tolist()]


# ---------------------------------------------------------------------------------------------
# The compiled root solves (pulloff.kernels.closed_forms) against the Python forms they replace
# on a run's hot path. Tolerance: none, bit for bit (the same operations in the same order and
# the same C library functions; a difference would show a contracted multiply-add or another
# math library).
# ---------------------------------------------------------------------------------------------


def test_compiled_seed_t_star_is_the_python_solve_bit_for_bit():
    from pulloff.kernels import closed_forms
    from pulloff.solvers.problem import compiled_t_star

    f_series = np.array(A._F_SERIES)
    alphas = np.concatenate((np.geomspace(1e-4, 100.0, 2001), [1e-4, 100.0, 1.0, A.ALPHA_SWITCH]))
    for al in alphas.tolist():
        got = closed_forms.root(closed_forms.SEED, al, 0.0, 0.0, math.inf, f_series)
        assert got == A._t_star_scalar(al), al
    # the wrapper: the series below 1e-4 and the fixed point above 100 stay in Python
    for al in [0.0, 1e-12, 9.9e-5, *np.geomspace(1e-6, 1e8, 301).tolist(), math.inf]:
        assert compiled_t_star(al) == A.seed_t_star(al), al
    with pytest.raises(ValueError):
        compiled_t_star(-1.0)


def test_compiled_elastic_zone_is_the_python_solve_bit_for_bit():
    from pulloff.kernels import closed_forms
    from pulloff.solvers.problem import compiled_elastic_zone

    g_series = np.array(A._G_SERIES)
    for chi in np.geomspace(1e-14, 1e3, 2001).tolist() + [1e-2 ** 2 / 2, A._PI_2_M1]:
        got = closed_forms.root(closed_forms.ELASTIC, chi, 0.0, 0.0, math.inf, g_series)
        assert got == A._elastic_zone(chi), chi
        assert compiled_elastic_zone(chi) == A._elastic_zone(chi), chi


def _python_frozen_onset(k, c, h0, t_limit):
    """The frozen onset as pulloff.solvers.frozen computed it in Python before
    kernels.closed_forms.frozen_onset: the reference of the test below."""
    def memory(t):
        if c == 0.0:
            return 1.0 / k, 0.0
        if k == 0.0:
            return t / c, 1.0 / c
        return -math.expm1(-k * t / c) / k, math.exp(-k * t / c) / c

    def gap(t):
        s = k * (h0 + t) + c
        return (2.0 / math.pi) * ((h0 + t) * math.atan(s)
                                  - s * s / (1.0 + math.sqrt(1.0 + s * s)) * memory(t)[0])

    def slope(t):
        s = k * (h0 + t) + c
        m, dm = memory(t)
        root = math.sqrt(1.0 + s * s)
        return (2.0 / math.pi) * (math.atan(s) + (h0 + t) * k / (1.0 + s * s)
                                  - k * s / root * m - s * s / (1.0 + root) * dm)

    if gap(0.0) >= 1.0:
        return 0.0
    hi = 1.0
    while gap(hi) < 1.0:
        if hi > t_limit:
            return math.inf
        hi *= 2.0
    lo = hi / 2.0 if hi > 1.0 else 0.0
    return A.bracketed_newton(lambda t: gap(t) - 1.0, slope, lo, hi, hi)


def test_compiled_frozen_onset_is_the_python_solve_bit_for_bit():
    from pulloff.kernels import closed_forms

    rng = np.random.default_rng(5)
    cases = [(k, c, h0, t_limit)
             for k, c in [(0.012, 1.2), (1e-6, 1e3), (1e4, 1e-6), (3.0, 0.0), (0.0, 2.0)]
             for h0 in (0.0, 0.5, 1e4) for t_limit in (math.inf, 3.0)]
    cases += [(10 ** rng.uniform(-8, 6), 10 ** rng.uniform(-8, 6), rng.choice([0.0, 2.0]),
               math.inf) for _ in range(2000)]
    for k, c, h0, t_limit in cases:
        got = closed_forms.root(closed_forms.FROZEN, float(k), float(c), float(h0),
                                float(t_limit), np.empty(0))
        assert got == _python_frozen_onset(k, c, h0, t_limit), (k, c, h0, t_limit)


def test_compiled_predictions_are_the_python_ones():
    """What an onset run reports beside it (solvers.problem.predictions, compiled solves) is
    analytic.predictions bit for bit, on every branch of eq. 53's solve."""
    from pulloff.io.scene_file import scene_from_groups
    from pulloff.solvers.problem import predictions

    for al in (1e-6, 1e-3, 0.1, 1.0, 3.3, 10.0, 1e3, 1e6):
        for chi in (1e-8, 1e-4, 1.0, 30.0):
            scene = scene_from_groups(al, chi)
            assert predictions(scene) == A.predictions(scene), (al, chi)
