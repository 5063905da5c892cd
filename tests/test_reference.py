"""Tests of the quadrature reference (pulloff.references.onset) against closed forms, limits, an ODE
solver and itself."""

import math

import numpy as np
import pytest
from scipy import integrate, optimize

from pulloff.references.onset import reference_detachment, reference_displacement, reference_gap


def scene(chi, alpha, a=1e-3, G=1e6, delta=1e-6, v=1e-3):
    """SI scene with chi = pi G delta/(sigma_c a) and alpha = pi delta sigma_c a G/(4 v^2 eta^2)."""
    sigma_c = math.pi * G * delta / (chi * a)
    eta = math.sqrt(math.pi * delta * sigma_c * a * G / (4.0 * v * v * alpha))
    return dict(G=G, eta=eta, sigma_c=sigma_c, delta=delta, a=a, v=v)


def elastic_closed_form(G, sigma_c, delta, a, v, **_):
    """MODEL.md section 5, eta = 0: returns t_d, h, b, F_contact, F_total."""
    def f(S):
        wid = S * S / (1.0 + math.sqrt(1.0 + S * S))
        return sigma_c * a / (math.pi * G) * (S * math.atan(S) - wid) - delta
    hi = 1.0
    while f(hi) < 0.0:
        hi *= 2.0
    S = optimize.brentq(f, 0.0, hi, xtol=1e-300, rtol=4 * np.finfo(float).eps)
    h = sigma_c * a * S / (2.0 * G)
    b = a * math.sqrt(1.0 + S * S)
    return dict(t_detach=h / v, h_detach=h, b_detach=b, F_contact=8 * a * G * h,
                F_total=2 * sigma_c * (a * a * S + b * b * math.atan(S)))


def rel(x, y):
    return abs(x - y) / abs(y)


# ---------------------------------------------------------------- elastic limit, Kendall
@pytest.mark.parametrize("chi", [1e-8, 1e-4, 1.0])
def test_eta_zero_matches_elastic_closed_form(chi):
    p = scene(chi, 1.0)
    p["eta"] = 0.0
    r = reference_detachment(**p)
    ref = elastic_closed_form(**p)
    assert r["detached"]
    for key in ("t_detach", "h_detach", "b_detach", "F_contact", "F_total"):
        assert rel(r[key], ref[key]) < 1e-12, key
    # thin zone really resolved: (b - a)/a ~ chi
    assert rel((r["b_detach"] - p["a"]) / p["a"], chi) < 0.5


@pytest.mark.parametrize("chi", [1e-4, 1.0])
def test_eta_to_zero_asymptotics(chi):
    """t(eta) - t(0) = t0 eps (A ln(1/eps) + B) + O(eps^2 log^2), eps = eta/(G t0).

    Fitting A, B on eps = 1e-5, 1e-6 must predict eps = 1e-7 (where the correction is 1e-6 of
    t) to ~1e-5 relative: this resolves t to ~1e-11 with G t/eta up to 1e7.
    """
    p = scene(chi, 1.0)
    p["eta"] = 0.0
    t0 = reference_detachment(**p)["t_detach"]
    assert rel(t0, elastic_closed_form(**p)["t_detach"]) < 1e-12
    eps = np.array([1e-5, 1e-6, 1e-7])
    d = []
    for e in eps:
        p["eta"] = p["G"] * t0 * e
        d.append(reference_detachment(**p)["t_detach"] / t0 - 1.0)
    d = np.array(d)
    A, B = np.linalg.solve([[e * math.log(1 / e), e] for e in eps[:2]], d[:2])
    pred = eps[2] * (A * math.log(1 / eps[2]) + B)
    assert abs(pred - d[2]) < 1e-4 * abs(d[2])
    assert d[2] < 0.0  # viscosity lets the zone grow faster: earlier detachment


def test_kendall_limit():
    """F_total -> sqrt(8 pi E* a^3 gamma), E* = 4 G, with an O(chi) correction."""
    devs = []
    for chi in (1e-2, 1e-4, 1e-6):
        p = scene(chi, 1.0)
        p["eta"] = 0.0
        r = reference_detachment(**p)
        K = math.sqrt(8 * math.pi * 4 * p["G"] * p["a"] ** 3 * p["sigma_c"] * p["delta"])
        devs.append(r["F_total"] / K - 1.0)
    assert abs(devs[-1]) < 2e-6
    # linear convergence: each factor 100 in chi gives ~100 in the deviation
    assert 80 < devs[0] / devs[1] < 120 and 95 < devs[1] / devs[2] < 105


# ---------------------------------------------------------------- viscous limit
@pytest.mark.parametrize("alpha_like", [1e-3, 1.0, 1e3])
def test_G_zero_matches_viscous_closed_form(alpha_like):
    a, sigma_c, delta, v = 1e-3, 1e5, 1e-6, 1e-4
    eta = alpha_like * sigma_c * a / v  # V = eta v/(sigma_c a): thin to wide zones
    r = reference_detachment(G=0.0, eta=eta, sigma_c=sigma_c, delta=delta, a=a, v=v)
    S = 2 * eta * v / (sigma_c * a)
    b_minus_a = a * S * S / (1 + math.sqrt(1 + S * S))
    t_d = delta / ((2 * v / math.pi) * math.atan(S) - sigma_c * b_minus_a / (math.pi * eta))
    assert rel(r["t_detach"], t_d) < 1e-12
    assert rel(r["b_detach"] - a, b_minus_a) < 1e-9
    assert rel(r["F_contact"], 8 * eta * v * a) < 1e-14


def test_G_to_zero_asymptotics():
    """t(G) - t(0) = t0 eps (A ln(1/eps) + B) + ..., eps = G t0/eta (cf. the eta -> 0 test);
    fitted on eps = 1e-6, 1e-7 it must predict eps = 1e-8 (a 1e-7 effect) to 1e-4."""
    base = dict(eta=1e3, sigma_c=1e5, delta=1e-6, a=1e-3, v=1e-4)
    t0 = reference_detachment(G=0.0, **base)["t_detach"]
    eps = np.array([1e-6, 1e-7, 1e-8])
    d = np.array([reference_detachment(G=e * base["eta"] / t0, **base)["t_detach"] / t0 - 1
                  for e in eps])
    A, B = np.linalg.solve([[e * math.log(1 / e), e] for e in eps[:2]], d[:2])
    pred = eps[2] * (A * math.log(1 / eps[2]) + B)
    assert abs(pred - d[2]) < 1e-4 * abs(d[2])


# ---------------------------------------------------------------- self-convergence
@pytest.mark.parametrize("chi", [1e-4, 1.0])
@pytest.mark.parametrize("alpha", [1e-2, 1.0, 1e2])
def test_self_convergence(chi, alpha):
    p = scene(chi, alpha)
    r8 = reference_detachment(**p, rtol=1e-8)
    r11 = reference_detachment(**p, rtol=1e-11)
    for key in ("t_detach", "b_detach", "F_total"):
        assert rel(r8[key], r11[key]) < 1e-9, key


def test_self_convergence_thin_and_near_elastic():
    # (b - a)/a ~ 1e-8 and G t/eta ~ 1e4
    p = scene(1e-8, 5e7)
    r8 = reference_detachment(**p, rtol=1e-8)
    r11 = reference_detachment(**p, rtol=1e-11)
    assert (r11["b_detach"] - p["a"]) / p["a"] < 2e-8
    assert p["G"] * r11["t_detach"] / p["eta"] > 5e3
    assert rel(r8["t_detach"], r11["t_detach"]) < 1e-9


# ---------------------------------------------------------------- independent checks
def _edge_S(p, h0, t):
    return (2 * p["G"] * (h0 + p["v"] * t) + 2 * p["eta"] * p["v"]) / (p["sigma_c"] * p["a"])


@pytest.mark.parametrize("case", ["entered_later", "loaded_from_start", "stiff"])
def test_element_against_solve_ivp(case):
    if case == "stiff":
        p, h0 = scene(1e-4, 1e6), 0.0  # G t/eta ~ 1e3 at t_end
    else:
        p, h0 = scene(1e-4, 1.0), (0.0 if case == "entered_later" else 2e-7)
    G, eta, sc, a = p["G"], p["eta"], p["sigma_c"], p["a"]
    t_end = elastic_closed_form(**p)["t_detach"]
    if case == "loaded_from_start":
        S_x = 0.5 * _edge_S(p, h0, 0.0)  # inside the zone at t = 0
        t_e = 0.0
    else:
        t_e = 0.5 * t_end
        S_x = _edge_S(p, h0, t_e)
    x = a * math.sqrt(1 + S_x * S_x)

    def rhs(t, u):
        S = _edge_S(p, h0, t)
        q = 2 * sc * a * math.sqrt(max((S - S_x) * (S + S_x), 0.0))
        return [(q - 4 * G * u[0]) / (4 * eta)]

    method = "Radau" if case == "stiff" else "DOP853"
    sol = integrate.solve_ivp(rhs, (t_e, t_end), [0.0], method=method, rtol=1e-12,
                              atol=1e-12 * p["delta"], dense_output=False)
    assert sol.success
    u_ivp = sol.y[0, -1]
    u_ref = reference_displacement(x, t_end, **p, h0=h0)
    assert u_ref > 0
    assert rel(u_ref, u_ivp) < 1e-8
    # the element is beyond the zone (unloaded) just before it enters
    if t_e > 0:
        assert reference_displacement(x, 0.999 * t_e, **p, h0=h0) == 0.0


def test_gap_against_mpmath():
    """Gap in the original variables (x, t') with mpmath's tanh-sinh, 20 digits."""
    import mpmath as mp

    mp.mp.dps = 20
    p, h0 = scene(1e-4, 1.0), 3e-6
    T = 100.0  # in delta/v
    k = mp.mpf(2 * p["G"] * p["delta"] / (p["sigma_c"] * p["a"]))
    c = mp.mpf(2 * p["eta"] * p["v"] / (p["sigma_c"] * p["a"]))
    H0 = mp.mpf(h0 / p["delta"])

    def S(t):
        return k * (H0 + t) + c

    def U(x):
        sig = mp.sqrt(x * x - 1)
        lo = max((sig - c) / k - H0, 0)
        f = lambda tp: mp.exp(-(k / c) * (T - tp)) * mp.sqrt(max(S(tp) ** 2 - sig ** 2, 0))
        return mp.quad(f, [lo, T]) / c

    bT = mp.sqrt(1 + S(T) ** 2)
    pts = [mp.mpf(1), mp.sqrt(1 + S(0) ** 2), bT]
    I = mp.quad(lambda x: U(x) / mp.sqrt(max(bT ** 2 - x * x, mp.mpf(10) ** -40)), pts)
    H = H0 + T
    g_mp = float(H - 2 / mp.pi * (H * mp.asin(1 / bT) + I))
    g = reference_gap(T * p["delta"] / p["v"], **p, h0=h0) / p["delta"]
    assert rel(g, g_mp) < 1e-12


def test_gap_increases_after_zone_forms():
    p = scene(1e-2, 1.0)
    t_d = reference_detachment(**p)["t_detach"]
    ts = np.linspace(0.0, 3 * t_d, 31)
    g = [reference_gap(t, **p, rtol=1e-9) for t in ts]
    assert g[0] == 0.0 and np.all(np.diff(g) > 0)
    assert rel(reference_gap(t_d, **p), p["delta"]) < 1e-10


# ---------------------------------------------------------------- edge cases
def test_detached_at_t0():
    p = scene(1e-2, 1.0)
    S0 = lambda h0: _edge_S(p, h0, 0.0)
    # gap(0) = (2/pi) h0 atan(S0): find the h0 that just reaches delta
    h_star = optimize.brentq(lambda h0: 2 / math.pi * h0 * math.atan(S0(h0)) - p["delta"],
                             0.0, 1.0, xtol=1e-300, rtol=1e-14)
    r = reference_detachment(**p, h0=1.0001 * h_star)
    assert r["detached"] and r["t_detach"] == 0.0 and r["h_detach"] == 1.0001 * h_star
    assert rel(r["F_contact"], 8 * p["a"] * (p["G"] * r["h_detach"] + p["eta"] * p["v"])) < 1e-14
    r2 = reference_detachment(**p, h0=0.999 * h_star)
    assert r2["detached"] and 0.0 < r2["t_detach"] < 1e-2 * h_star / p["v"]


def test_no_detachment_before_t_max():
    p = scene(1e-2, 1.0)
    t_d = reference_detachment(**p)["t_detach"]
    r = reference_detachment(**p, t_max=0.9 * t_d)
    assert not r["detached"] and math.isnan(r["t_detach"]) and math.isnan(r["F_total"])
    r = reference_detachment(**p, t_max=1.1 * t_d)
    assert r["detached"] and rel(r["t_detach"], t_d) < 1e-10
    assert not reference_detachment(G=0.0, eta=0.0, sigma_c=1e5, delta=1e-6, a=1e-3,
                                    v=1e-3)["detached"]


# ---------------------------------------------------------------- frozen history is an upper bound
@pytest.mark.parametrize("chi,alpha", [(1e-4, 1.0), (1.0, 10.0)])
def test_frozen_history_detaches_later(chi, alpha):
    p = scene(chi, alpha)
    G, eta, sc, delta, a, v = (p[k] for k in ("G", "eta", "sigma_c", "delta", "a", "v"))

    def gap_frozen(t):
        h = v * t
        S = (2 * G * h + 2 * eta * v) / (sc * a)
        b = a * math.sqrt(1 + S * S)
        b_minus_a = a * S * S / (1 + math.sqrt(1 + S * S))
        return h - 2 / math.pi * (h * math.asin(a / b)
                                  + sc / (2 * G) * (-math.expm1(-G * t / eta)) * b_minus_a)

    r = reference_detachment(**p)
    t_hi = r["t_detach"]
    while gap_frozen(t_hi) < delta:
        t_hi *= 2
    t_frozen = optimize.brentq(lambda t: gap_frozen(t) - delta, 0.5 * r["t_detach"], t_hi,
                               xtol=1e-300, rtol=1e-14)
    assert t_frozen >= r["t_detach"]
    # and the difference is not small (MODEL.md section 3, item 2)
    assert t_frozen > 1.01 * r["t_detach"]
