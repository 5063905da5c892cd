"""Unit tests of the numba kernels against quadrature of their defining integrals."""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.integrate import quad, solve_ivp

from pulloff import kernels as K

RULE = (K.TS_NODES, K.TS_COMPLEMENTS, K.TS_WEIGHTS)
FINE = (K.TS_FINE_NODES, K.TS_FINE_COMPLEMENTS, K.TS_FINE_WEIGHTS)


@pytest.mark.parametrize("mu", [0.0, 1e-12, 1e-3, 0.099, 0.1, 0.5, 1.0, 3.0, 40.0, 1e4, 1e12])
def test_ramp_moment_and_phi1_against_quadrature(mu):
    ramp = quad(lambda y: math.exp(-mu * y) * y, 0.0, 1.0, epsabs=0, epsrel=2e-14,
                points=[min(1.0, 1.0 / mu)] if 0 < mu < 1e6 else None, limit=200)[0]
    if mu >= 1e6:
        ramp = 1.0 / mu**2  # the tail exp(-mu) is far below double precision
    assert K.ramp_moment(mu) == pytest.approx(ramp, rel=1e-13)
    ph = 1.0 if mu == 0 else -math.expm1(-mu) / mu
    assert K.phi1(mu) == pytest.approx(ph, rel=1e-15)


@pytest.mark.parametrize("k,c", [(1.0, 1.0), (1e-6, 1e-3), (2.0, 1e-9), (0.0, 0.3), (0.7, 0.0)])
def test_linear_load_step_is_exact_for_a_linear_load(k, c):
    """One step of the weights equals the ODE solution for q = q0 + (q1 - q0) t / dt."""
    dt, q0, q1, u0 = 0.37, 0.2, 1.3, 0.05
    decay, w_old, w_new = K.linear_load_weights(k, c, dt)
    u1 = decay * u0 + w_old * q0 + w_new * q1
    if c == 0.0:
        expected = q1 / k
    else:
        sol = solve_ivp(lambda t, u: [(q0 + (q1 - q0) * t / dt - k * u[0]) / c], (0.0, dt), [u0],
                        method="Radau", rtol=1e-12, atol=1e-15)
        expected = sol.y[0, -1]
    assert u1 == pytest.approx(expected, rel=1e-9, abs=1e-14)


def _exp_weighted(g, mu):
    """int_0^1 exp(-mu y) g(y) dy by quad, in p = mu y when the exponential is sharp."""
    if mu <= 10.0:
        return quad(lambda y: math.exp(-mu * y) * g(y), 0, 1, epsabs=0, epsrel=2e-14,
                    limit=200)[0]
    pts = [p for p in (1.0, 10.0, 40.0) if p < mu]
    return quad(lambda p: math.exp(-p) * g(p / mu), 0, min(mu, 800.0), epsabs=0,
                epsrel=2e-14, points=pts, limit=400)[0] / mu


def _onset_reference(k, c, dt, m):
    """Defining integrals of the onset weights, by adaptive quadrature."""
    mu = k * dt / c
    scale = dt / c * math.sqrt(dt)
    if m == 0 and mu <= 10.0:
        # sqrt(1 - y) end point: algebraic weight.
        old = quad(lambda y: math.exp(-mu * y) * y, 0, 1, weight="alg", wvar=(0.0, 0.5))[0]
        new = quad(lambda y: math.exp(-mu * y) * (1 - y), 0, 1, weight="alg",
                   wvar=(0.0, 0.5))[0]
    else:
        old = _exp_weighted(lambda y: y * math.sqrt(max(m + 1 - y, 0.0)), mu)
        new = _exp_weighted(lambda y: (1 - y) * math.sqrt(max(m + 1 - y, 0.0)), mu)
    return scale * old, scale * new


@pytest.mark.parametrize("k,c,dt", [(1.0, 1.0, 0.1), (1e-6, 1e-3, 2.0), (1.0, 1e-3, 0.5),
                                    (3.0, 2.0, 1e-4), (1.0, 1e-5, 1.0)])
def test_onset_weights_against_quadrature(k, c, dt):
    w_old, w_new = K.onset_weights(k, c, dt, 40, *RULE)
    for m in (0, 1, 2, 7, 39):
        ref_old, ref_new = _onset_reference(k, c, dt, m)
        assert w_old[m] == pytest.approx(ref_old, rel=2e-12, abs=1e-14 * abs(ref_new))
        assert w_new[m] == pytest.approx(ref_new, rel=2e-12)


def test_onset_weights_elastic_limit():
    """c -> 0: an element follows its load, U = sqrt(age) r / k."""
    k, dt = 0.8, 0.3
    w_old, w_new = K.onset_weights(k, 0.0, dt, 5, *RULE)
    assert np.all(w_old == 0.0)
    np.testing.assert_allclose(w_new, np.sqrt(dt * np.arange(1, 6)) / k, rtol=1e-15)
    w_old_small, w_new_small = K.onset_weights(k, 1e-10, dt, 5, *RULE)
    np.testing.assert_allclose(w_new_small, w_new, rtol=1e-8)


@pytest.mark.parametrize("age", [0.0, 1e-9, 1e-3, 0.5, 3.9, 4.1, 30.0, 1e4])
@pytest.mark.parametrize("k,c", [(1.0, 0.1), (2.0, 1e-7), (1e-6, 1e-3)])
def test_onset_ratio_against_quadrature(age, k, c):
    """U/q of an element loaded by sqrt(age): F(age)/sqrt(age), both series and asymptotics."""
    if age == 0.0:
        assert K.onset_ratio(age, k, c) == 0.0
        return
    lam = k / c
    # F = (1/c) int_0^age exp(-lam (age - a)) sqrt(a) da, in a = age - y with y = p / lam.
    if lam * age <= 50:
        F = quad(lambda a: math.exp(-lam * (age - a)) / c, 0, age, weight="alg",
                 wvar=(0.5, 0.0), epsabs=0, epsrel=1e-13)[0]
    else:
        F = quad(lambda p: math.exp(-p) * math.sqrt(age - p / lam) / (c * lam), 0,
                 min(lam * age, 800.0), epsabs=0, epsrel=1e-13, points=[1.0, 10.0, 40.0],
                 limit=400)[0]
    assert K.onset_ratio(age, k, c) == pytest.approx(F / math.sqrt(age), rel=1e-12)


def test_onset_ratio_limits():
    assert K.onset_ratio(0.3, 2.0, 0.0) == 0.5
    assert K.onset_ratio(0.3, 0.0, 2.0) == pytest.approx(2 * 0.3 / (3 * 2.0), rel=1e-15)
    # Continuity across the switch from the series to the asymptotic expansion (z = 40).
    below, above = K.onset_ratio(40.0 - 1e-9, 1.0, 1.0), K.onset_ratio(40.0 + 1e-9, 1.0, 1.0)
    assert above == pytest.approx(below, rel=1e-13)


@pytest.mark.parametrize("k,c,dt", [(1.0, 1.0, 0.1), (1.0, 1e-3, 0.5), (2.0, 1e-7, 1.0),
                                    (1e-6, 1e-3, 3.0)])
def test_age_interval_weights_against_quadrature(k, c, dt):
    ratio, w_young, w_old = K.age_interval_weights(k, c, dt, 6, *FINE)
    for m in range(6):
        assert ratio[m] == K.onset_ratio(m * dt, k, c)
        f = lambda z: K.onset_ratio((m + z) * dt, k, c)  # noqa: E731
        pts = [min(0.5, c / (k * dt))] if m == 0 and k * dt / c > 2 else None
        ref_y = quad(lambda z: f(z) * (1 - z), 0, 1, epsabs=0, epsrel=1e-12, points=pts,
                     limit=400)[0]
        ref_o = quad(lambda z: f(z) * z, 0, 1, epsabs=0, epsrel=1e-12, points=pts, limit=400)[0]
        assert w_young[m] == pytest.approx(ref_y, rel=1e-9)
        assert w_old[m] == pytest.approx(ref_o, rel=1e-9)


def test_entered_element_matches_ode_solution():
    """Stepping one element from its entry reproduces the ODE driven by sqrt(s^2 - sigma^2)."""
    k, c, h0, dt, n = 0.9, 0.4, 0.0, 0.05, 60
    sigma = k * (h0 + 0.0) + c  # enters at t = 0
    decay, _, _ = K.linear_load_weights(k, c, dt)
    w_old, w_new = K.onset_weights(k, c, dt, n + 1, *RULE)
    sig = np.array([sigma])
    U = np.zeros(1)
    for step in range(n):
        s_old = k * (h0 + step * dt) + c
        s_new = k * (h0 + (step + 1) * dt) + c
        K.step_entered(sig, U, 1, step, s_old, s_new, k, decay, w_old, w_new)

    def load(t):
        s = k * (h0 + t) + c
        return math.sqrt(max(s * s - sigma * sigma, 0.0))

    t_end = n * dt
    # load(t) / sqrt(t), written out so that quad's algebraic weight carries the sqrt.
    exact = quad(lambda tp: math.exp(-k / c * (t_end - tp)) * math.sqrt(k * (2 * sigma + k * tp))
                 / c, 0, t_end,
                 epsabs=0, epsrel=2e-14, weight="alg", wvar=(0.5, 0.0))[0]
    # The load's sqrt factor is integrated exactly; only its smooth factor is interpolated.
    assert U[0] == pytest.approx(exact, rel=1e-5)


@settings(max_examples=30, deadline=None)
@given(S=st.floats(1e-6, 50.0), k=st.floats(1e-6, 1e3), n=st.integers(3, 40),
       entered_share=st.floats(0.05, 1.0))
def test_displacement_integral_exact_for_the_elastic_field(S, k, n, entered_share):
    """U = sqrt(S^2 - sigma^2)/k (elastic) integrates to (b - 1)/k on any mesh."""
    # Entered elements sit at step boundaries below S; preloaded ones anywhere below those.
    n_born = max(2, int(entered_share * n))
    s0 = S * (1.0 - entered_share)
    k_dt = (S - s0) / (n_born - 1)
    born = S - k_dt * np.arange(n_born - 1, -1, -1)
    born[0], born[-1] = s0, S
    pre = np.sort(s0 * np.random.default_rng(n).uniform(0, 1, n))[:-1] if s0 > 0 else born[:0]
    if pre.size:
        pre[0] = 0.0
    offset = s0 - pre
    nodes = np.concatenate([pre, born])
    U = np.sqrt(np.maximum((S - nodes) * (S + nodes), 0.0)) / k
    widths = np.array([0.0] + [K.interval_width(a, b) for a, b in zip(nodes[:-1], nodes[1:])])
    ratio, w_young, w_old = K.age_interval_weights(k, 0.0, 1.0, n_born, *FINE)
    got = K.displacement_integral(pre, offset, U[:pre.size], widths[:pre.size + 1], born,
                                  U[pre.size:], widths[pre.size:], n_born, S, S - s0, k_dt,
                                  ratio, w_young, w_old)
    b_minus_1 = S * S / (1.0 + math.sqrt(1.0 + S * S))
    assert got == pytest.approx(b_minus_1 / k, rel=1e-12)


def test_gap_from_integral_matches_definition():
    h, S, integral = 3.0, 0.2, 0.01
    b = math.sqrt(1 + S * S)
    direct = h - (2 / math.pi) * (h * math.asin(1 / b) + integral)
    assert K.gap_from_integral(h, S, integral) == pytest.approx(direct, rel=1e-13)
