"""Unit tests of the numba kernels against quadrature of their defining integrals."""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.integrate import quad, solve_ivp

from pulloff.kernels import onset as K

RULE = (K.TS_NODES, K.TS_COMPLEMENTS, K.TS_WEIGHTS)


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
    # Continuity across every switch: series, each octave's Chebyshev series, asymptotics.
    for j in range(K.RATIO_OCTAVES + 1):
        z = K.RATIO_Z_LOW * 2.0 ** j
        below, above = K.onset_ratio(z * (1 - 1e-15), 1.0, 1.0), K.onset_ratio(z, 1.0, 1.0)
        assert above == pytest.approx(below, rel=1e-14)


@pytest.mark.parametrize("z", np.geomspace(1e-4, 3e3, 31).tolist())
def test_onset_ratio_in_every_octave_against_quadrature(z):
    """The Chebyshev series (near zero from the power series, per octave from scipy's Dawson
    integral) against direct quadrature of F, to 1e-14 (measured: 5.3e-15 at worst over 600
    points from z = 1e-6 to 5000)."""
    if z <= 50:
        F = quad(lambda a: math.exp(-(z - a)), 0, z, weight="alg", wvar=(0.5, 0.0), epsabs=0,
                 epsrel=1e-13)[0]
    else:
        F = quad(lambda p: math.exp(-p) * math.sqrt(z - p), 0, min(z, 800.0), epsabs=0,
                 epsrel=1e-13, points=[1.0, 10.0, 40.0], limit=400)[0]
    assert K.onset_ratio(z, 1.0, 1.0) == pytest.approx(F / math.sqrt(z), rel=1e-14)


@pytest.mark.parametrize("k,c,dt", [(1.0, 1.0, 0.1), (1.0, 1e-3, 0.5), (2.0, 1e-7, 1.0),
                                    (1e-6, 1e-3, 3.0)])
def test_age_interval_weights_against_quadrature(k, c, dt):
    ratio, w_young, w_old = K.age_interval_weights(k, c, dt, 6)
    for m in range(6):
        assert ratio[m] == K.onset_ratio(m * dt, k, c)
        f = lambda z: K.onset_ratio((m + z) * dt, k, c)  # noqa: E731
        pts = [min(0.5, c / (k * dt))] if m == 0 and k * dt / c > 2 else None
        ref_y = quad(lambda z: f(z) * (1 - z), 0, 1, epsabs=0, epsrel=1e-12, points=pts,
                     limit=400)[0]
        ref_o = quad(lambda z: f(z) * z, 0, 1, epsabs=0, epsrel=1e-12, points=pts, limit=400)[0]
        assert w_young[m] == pytest.approx(ref_y, rel=1e-9)
        assert w_old[m] == pytest.approx(ref_o, rel=1e-9)


@pytest.mark.parametrize("mu", [0.6, 3.0, 30.0, 1e3, 1e5, 1e8])
def test_youngest_interval_weights_resolve_a_layer_of_any_thinness(mu):
    """The octave panels of the youngest interval (relaxation layer ``1/mu`` of a step)
    against adaptive quadrature split at the layer's octaves, to 1e-13 (measured within 9e-16
    of a 923-point tanh-sinh rule)."""
    k, c = 1.0, 1.0
    dt = mu * c / k
    breaks = [b for b in (2.0 ** j / mu for j in range(60)) if b < 1.0]
    w_young, w_old = K._youngest_interval_weights(k, c, dt)
    for value, weight in ((w_young, lambda z: 1.0 - z), (w_old, lambda z: z)):
        ref = quad(lambda z: K.onset_ratio(z * dt, k, c) * weight(z), 0.0, 1.0, epsabs=0,
                   epsrel=1e-13, points=breaks or None, limit=400)[0]
        assert value == pytest.approx(ref, rel=1e-13)


def test_entered_element_matches_ode_solution():
    """Stepping one element from its entry reproduces the ODE driven by sqrt(s^2 - sigma^2)."""
    k, c, h0, dt, n = 0.9, 0.4, 0.0, 0.05, 60
    sigma = k * (h0 + 0.0) + c  # enters at t = 0
    decay, _, _ = K.linear_load_weights(k, c, dt)
    w_old, w_new = K.onset_weights(k, c, dt, n + 1, *RULE)
    moments = K.onset_moments(k, c, dt, *RULE)
    sig = np.array([sigma])
    U = np.zeros(1)
    r = np.sqrt(k * (sig + sigma))  # the load's root at the entry, carried from step to step
    for step in range(n):
        s_new = k * (h0 + (step + 1) * dt) + c
        if step % 2:  # both update paths: tables by consecutive age, and by born step
            K.step_entered(sig, U, r, 0, 1, step, s_new, k, decay, w_old, w_new)
        else:
            K.step_entered_aged(np.zeros(1, dtype=np.int64), sig, U, r, 1, step, s_new, k,
                                decay, w_old, w_new, *moments)

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
    ratio, w_young, w_old = K.age_interval_weights(k, 0.0, 1.0, n_born)
    steps = np.arange(n_born, dtype=np.int64)
    q_pre = np.sqrt((offset + (S - s0)) * (S + pre))  # the preloaded loads at S
    got = K.displacement_integral(pre, offset, U[:pre.size], widths[:pre.size + 1],
                                  np.zeros((1, 4)), steps, born, U[pre.size:], widths[pre.size:],
                                  np.zeros((1, 4)), n_born, n_born - 1, S, S - s0, k_dt, ratio,
                                  w_young, w_old, np.empty(nodes.size + 1), q_pre)
    b_minus_1 = S * S / (1.0 + math.sqrt(1.0 + S * S))
    assert got == pytest.approx(b_minus_1 / k, rel=1e-12)
    # Thinned (and with tables shorter than the oldest age), the trapezoid on v = 1/k that
    # replaces the product weights is exact too.
    sig_e, U_e, dx_e = born.copy(), U[pre.size:].copy(), widths[pre.size:].copy()
    thin_w = np.zeros((n_born, 4))
    kept = K.thin_entered(steps, sig_e, U_e, dx_e, thin_w, n_born, n_born - 1, 2, 1.5)
    pre_w = (K.preloaded_cubic_weights(widths[:pre.size + 1]) if pre.size >= 3
             else np.zeros((1, 4)))
    got = K.displacement_integral(pre, offset, U[:pre.size], widths[:pre.size + 1], pre_w,
                                  steps, sig_e, U_e, dx_e, thin_w, kept, n_born - 1, S, S - s0,
                                  k_dt, ratio[:3], w_young[:2], w_old[:2],
                                  np.empty(nodes.size + 1), q_pre)
    assert got == pytest.approx(b_minus_1 / k, rel=1e-12)


@settings(max_examples=40, deadline=None)
@given(n_pre=st.integers(0, 40), n_born=st.integers(2, 60), seed=st.integers(0, 2**31),
       k=st.floats(1e-3, 1e3), c=st.floats(1e-6, 1e2))
def test_property_the_vectorised_gap_integral_is_the_general_loop_bit_for_bit(n_pre, n_born,
                                                                             seed, k, c):
    """A ladder's level integrates the gap in two passes (the field first, vectorised; then
    the sum); it must be the general loop's operations in the general loop's order."""
    rng = np.random.default_rng(seed)
    dt = 0.05
    step = n_born - 1
    s0 = 0.5 + rng.uniform()
    sig_pre = np.sort(rng.uniform(0.0, s0, n_pre))
    offset = s0 - sig_pre
    U_pre = rng.uniform(0.1, 1.0, n_pre)
    dx_pre = rng.uniform(1e-3, 1e-2, n_pre + 1)
    born = np.arange(n_born, dtype=np.int64)
    sig_born = s0 + k * dt * born
    U_born = rng.uniform(0.1, 1.0, n_born)
    dx_born = rng.uniform(1e-3, 1e-2, n_born)
    ratio, w_young, w_old = K.age_interval_weights(k, c, dt, n_born + 2)
    S, kt = sig_born[-1], k * dt * step
    no_cubic = np.zeros((1, 4))
    q_pre = np.sqrt((offset + kt) * (S + sig_pre))
    fast = K.displacement_integral(sig_pre, offset, U_pre, dx_pre, no_cubic, born, sig_born,
                                   U_born, dx_born, no_cubic, n_born, step, S, kt, k * dt, ratio,
                                   w_young, w_old, np.empty(n_pre + n_born + 1), q_pre)
    loop = (K._preloaded_integral(U_pre, q_pre, dx_pre, no_cubic, sig_born, U_born, n_born, S,
                                  kt)
            + K._entered_integral(born, sig_born, U_born, dx_born, no_cubic, n_born, step, S,
                                  k * dt, ratio, w_young, w_old))
    assert fast == loop


@pytest.mark.parametrize("k,c,dt", [(0.9, 0.4, 0.05), (1e-3, 2.0, 1e-4), (50.0, 1e-6, 0.3),
                                    (2.0, 0.0, 0.01), (1e-8, 1e-9, 1e3)])
def test_onset_weights_expansion_matches_the_tables(k, c, dt):
    """Beyond the tables, the 1/age expansion gives the tabulated weights to rounding."""
    n = 3000
    w_old, w_new = K.onset_weights(k, c, dt, n, *RULE)
    moments = K.onset_moments(k, c, dt, *RULE)
    short_old, short_new = w_old[:K.ONSET_ASYMPTOTIC_AGE], w_new[:K.ONSET_ASYMPTOTIC_AGE]
    for age in [K.ONSET_ASYMPTOTIC_AGE, 65, 100, 999, 2999]:
        wo, wn = K.onset_weight_pair(age, short_old, short_new, *moments)
        assert wo == pytest.approx(w_old[age], rel=1e-13, abs=1e-300)
        assert wn == pytest.approx(w_new[age], rel=1e-13)
        # Inside the tables they are read, not expanded.
        assert K.onset_weight_pair(age, w_old, w_new, *moments) == (w_old[age], w_new[age])


def test_thin_entered_keeps_young_and_oldest_and_grades_the_rest():
    n, step, keep_young, ratio_max = 5000, 4999, 100, 1.05
    born = np.arange(n, dtype=np.int64)
    sigma = 0.3 + 1e-3 * born
    U = np.sin(born.astype(float))
    dx = np.zeros(n)
    thin_w = np.zeros((n, 4))
    kept = K.thin_entered(born, sigma, U, dx, thin_w, n, step, keep_young, ratio_max)
    ages = step - born[:kept]
    assert born[0] == 0 and ages[-1] == 0
    assert np.all(np.diff(born[:kept]) > 0)
    # Every element younger than keep_young survives, with its state.
    young = ages < keep_young
    assert young.sum() == keep_young
    assert np.array_equal(U[:kept], np.sin(born[:kept].astype(float)))
    # Gaps grow at most geometrically: older kept age <= ratio_max * younger (or adjacent).
    older, younger = ages[:-1], ages[1:]
    assert np.all((older <= ratio_max * younger) | (older - younger == 1) | (younger == 0)
                  | (older == ages[0]))
    # Geometric grading: about log(oldest/keep_young)/log(ratio_max) old elements remain.
    expected = math.log(step / keep_young) / math.log(ratio_max)
    assert expected / 2 < (kept - keep_young) < 2 * expected + 2
    widths = [K.interval_width(a, b) for a, b in zip(sigma[:kept - 1], sigma[1:kept])]
    assert np.allclose(dx[1:kept], widths, rtol=1e-15)
    # The cubic weights of the thinned intervals integrate cubics exactly (quadratic first).
    x = np.concatenate([[0.0], np.cumsum(dx[1:kept])])
    for j in range(1, kept - 1):
        if born[j] - born[j - 1] > 1:
            cubic = [2.0, 0.0, 0.0, 1.5] if j > 1 else [2.0, 0.0, 1.5]  # quadratic at j = 1
            for poly in ([1.0], [0.3, -2.0], [0.1, 0.5, -1.0], cubic):
                f = np.polynomial.Polynomial(poly)
                exact = f.integ()(x[j]) - f.integ()(x[j - 1])
                nodes = f(x[max(j - 2, 0):j + 2]) if j > 1 else np.concatenate([[0.0], f(x[0:3])])
                assert thin_w[j] @ nodes == pytest.approx(exact, rel=1e-9, abs=1e-12 * abs(f(x[j])))


def test_cubic_interval_weights_integrate_cubics():
    out = np.zeros(4)
    K.cubic_interval_weights(0.3, 0.5, 0.9, out)
    nodes = np.array([-0.3, 0.0, 0.5, 1.4])
    f = np.polynomial.Polynomial([0.2, -1.0, 0.7, 3.0])
    assert out @ f(nodes) == pytest.approx(f.integ()(0.5) - f.integ()(0.0), rel=1e-14)
    K.cubic_interval_weights(0.0, 0.5, 0.9, out)
    assert out[0] == 0.0
    g = np.polynomial.Polynomial([0.2, -1.0, 0.7])
    assert out @ g(nodes) == pytest.approx(g.integ()(0.5) - g.integ()(0.0), rel=1e-14)
    K.cubic_interval_weights(0.3, 0.5, 0.0, out)
    assert out[3] == 0.0
    assert out @ g(nodes) == pytest.approx(g.integ()(0.5) - g.integ()(0.0), rel=1e-14)


def test_preloaded_cubic_weights_integrate_a_smooth_field():
    """On a cosine-graded mesh, the cubic rule converges at fourth order (trapezoid: second)."""
    def error(n):
        theta = np.linspace(0.5 * np.pi, 0.0, n + 1)
        x = 1.0 + np.cos(theta)
        widths = np.concatenate([[0.0], np.diff(x)])
        w = K.preloaded_cubic_weights(widths)
        f = np.exp(x) * np.sin(3 * x)
        got = sum(w[i, 0] * f[i - 2] * (i >= 2) + w[i, 1] * f[i - 1] + w[i, 2] * f[i]
                  + (w[i, 3] * f[i + 1] if i + 1 <= n else 0.0) for i in range(1, n + 1))
        # int e^y sin(3y) dy = e^y (sin 3y - 3 cos 3y) / 10
        prim = lambda y: math.exp(y) * (math.sin(3 * y) - 3 * math.cos(3 * y)) / 10  # noqa: E731
        exact = prim(2.0) - prim(1.0)
        return abs(got - exact)
    order = math.log2(error(40) / error(80))
    assert 3.7 < order < 4.6


def test_gap_from_integral_matches_definition():
    h, S, integral = 3.0, 0.2, 0.01
    b = math.sqrt(1 + S * S)
    direct = h - (2 / math.pi) * (h * math.asin(1 / b) + integral)
    assert K.gap_from_integral(h, S, integral) == pytest.approx(direct, rel=1e-13)


def test_free_gap_integral_extrapolates_the_end_value_from_beyond_a_kink():
    """A receding zone over a flat punch's first bond edge: the displacement has a kink there
    (bonded inside, zone-loaded beyond). The end value comes from the nodes beyond the kink
    alone (once a stencil across it made the gap jump by 1.3e-2 delta as the end passed a
    node, and separation_kv at 1e-2 m/s came apart 2 % early at some levels)."""
    from pulloff.kernels import contact as C

    beta, kink = 1.2, 1.0
    theta = np.concatenate([[0.25, 0.45], np.linspace(0.65, 1.4, 6)])  # two beyond the kink
    xi = np.sort(beta * np.cos(theta))
    th = np.arccos(xi / beta)
    U = np.where(xi > kink, 1.0 + 2.0 * th, 2.2 + 0.3 * (th - math.acos(kink / beta)) ** 2)
    n = xi.size
    given_end = C.free_gap_integral(xi, U, 0, n, 0.0, beta, U[0], 1.0, kink)
    beyond = C.free_gap_integral(xi, U, 0, n, 0.0, beta, U[0], math.nan, kink)
    across = C.free_gap_integral(xi, U, 0, n, 0.0, beta, U[0], math.nan, 0.0)
    assert beyond == pytest.approx(given_end, rel=1e-13)
    assert abs(across - given_end) > 1e-4 * abs(given_end)


def test_free_gap_integral_keeps_its_fourth_order_across_a_kink():
    """With the kink known no stencil crosses it: each side is integrated to the kink with
    the value there extrapolated from its own nodes, and the error falls at fourth order in
    the spacing (measured ratios 15-26 per halving at 48..192 nodes, wherever the nodes sit
    against the kink); a stencil across it converges irregularly at about second order and
    is 400-8000x larger at 192 nodes."""
    from pulloff.kernels import contact as C

    beta, kink = 1.2, 1.0
    th_k = math.acos(kink / beta)

    def field(th):
        return np.where(th < th_k, 1.0 + np.sin(2.0 * th), 1.0 + math.sin(2.0 * th_k)
                        + 0.3 * (th - th_k) + np.cos(th) - math.cos(th_k))

    exact = (th_k - 0.5 * math.cos(2.0 * th_k) + 0.5) + (
        (1.0 + math.sin(2.0 * th_k) - math.cos(th_k)) * (0.5 * math.pi - th_k)
        + 0.15 * (0.5 * math.pi - th_k) ** 2 + 1.0 - math.sin(th_k))
    for offset in (0.1, 0.37, 0.9):  # no node on the kink
        split, across = [], []
        for nodes in (48, 96, 192):
            th = (np.arange(nodes) + offset) * (0.5 * math.pi / nodes)
            xi = np.sort(beta * np.cos(th))
            U = field(np.arccos(xi / beta))
            args = (xi, U, 0, nodes, 0.0, beta, float(field(0.5 * math.pi)), float(field(0.0)))
            split.append(abs(C.free_gap_integral(*args, kink) - exact))
            across.append(abs(C.free_gap_integral(*args, 0.0) - exact))
        assert split[0] / split[1] > 10.0 and split[1] / split[2] > 10.0, (offset, split)
        assert across[-1] > 100.0 * split[-1], (offset, split, across)


@settings(max_examples=100, deadline=None)
@given(old=st.lists(st.floats(0.0, 2.0), max_size=40, unique=True),
       new=st.lists(st.floats(0.0, 2.0), min_size=1, max_size=12, unique=True))
def test_property_a_batch_of_new_elements_lands_as_one_by_one_inserts_would(old, new):
    """contact_state.Nodes.insert_many (one merge per step) against insert (one shift per
    element): the same sorted mesh with every column carried along."""
    from pulloff.solvers.contact_state import CONTACT, FREE, Nodes

    new = [x for x in new if x not in old] or [2.5]
    one, batch = Nodes(2, 1, capacity=4), Nodes(2, 1, capacity=4)
    for k, x in enumerate(sorted(old)):
        for nodes in (one, batch):
            nodes.insert(x, np.array([x, -x]), FREE, np.array([k]), tj=0.5, t_last=0.25)
    xs = np.array(new)
    Y = np.column_stack([2 * xs, 3 * xs])
    status = np.where(xs < 1.0, CONTACT, FREE)
    D, tj = xs[:, None] * 7.0, np.where(xs < 1.0, 1.5, 0.0)
    for j, x in enumerate(xs):
        one.insert(float(x), Y[j], int(status[j]), D[j], tj=float(tj[j]), t_last=1.0)
    batch.insert_many(xs, Y, status, D, tj, 1.0)
    assert batch.n == one.n and batch.xi_max == one.xi_max
    for name in ("xi", "Y", "status", "D", "tj", "t_last"):
        np.testing.assert_array_equal(getattr(batch, name)[:batch.n], getattr(one, name)[:one.n])


@settings(max_examples=100, deadline=None)
@given(old=st.lists(st.floats(0.0, 2.0), min_size=1, max_size=40, unique=True),
       cut=st.floats(0.0, 2.0), at_least=st.integers(0, 8),
       new=st.lists(st.floats(0.0, 3.0), min_size=1, max_size=12, unique=True))
def test_property_archived_elements_come_back_as_they_left(old, cut, at_least, new):
    """contact_state.Nodes: the free elements beyond ``cut`` archived (if there are at least
    ``at_least``), then new ones inserted, some beyond the archived ones: the mesh is the one
    that never archived, every column carried along, and nothing is lost on the way."""
    from pulloff.solvers.contact_state import FREE, Nodes

    new = [x for x in new if x not in old]
    kept, archived = Nodes(2, 1, capacity=4), Nodes(2, 1, capacity=4)
    for k, x in enumerate(sorted(old)):
        for nodes in (kept, archived):
            nodes.insert(x, np.array([x, -x]), FREE, np.array([k]), tj=0.5, t_last=0.25 * k)
    moved = archived.archive_beyond(cut, at_least)
    beyond = sum(x >= cut for x in old)
    assert moved == (beyond if beyond >= max(at_least, 1) else 0)
    assert archived.n == len(old) - moved and archived.total == len(old)
    assert archived.live_end == (min(x for x in old if x >= cut) if moved else math.inf)
    for x in new:
        for nodes in (kept, archived):
            nodes.insert(float(x), np.array([2 * x, 3 * x]), FREE, np.array([7 * x]), tj=1.5,
                         t_last=1.0)
    assert archived.total == kept.total == kept.n
    archived.restore()
    assert archived.n == kept.n and archived.live_end == math.inf
    for name in ("xi", "Y", "status", "D", "tj", "t_last"):
        np.testing.assert_array_equal(getattr(archived, name)[:archived.n],
                                      getattr(kept, name)[:kept.n])


_COEFFICIENT = st.one_of(st.just(0.0), st.floats(1e-8, 1e8), st.floats(-1e8, -1e-8))


@settings(max_examples=300, deadline=None)
@given(c=st.tuples(_COEFFICIENT, _COEFFICIENT, _COEFFICIENT))
def test_property_the_rows_quadratic_has_numpys_first_positive_root(c):
    """contact_stepper._real_roots (the landing on a vanishing edge, every step) against
    np.roots as the extrapolation took it (imaginary parts below 1e-12 count as real): the
    first positive root, which is what the landing uses, or none for both. Coefficients
    of the rows' scales (squared edges and times in units of the run)."""
    from pulloff.solvers.contact_stepper import _real_roots

    if not any(c):
        return
    ours = [r for r in _real_roots(*c) if r > 0.0]
    theirs = [r.real for r in np.roots(c) if abs(r.imag) < 1e-12 and r.real > 0.0]
    assert bool(ours) == bool(theirs), (ours, theirs)
    if ours:
        assert min(ours) == pytest.approx(min(theirs), rel=1e-9), (ours, theirs)


def test_a_relaxation_layer_below_the_smallest_float_is_the_elastic_limit():
    """c / (k dt) underflowing to zero (or dt overflowing) ends at once with R = 1/k."""
    assert K._youngest_interval_weights(1.0, 5e-324, 10.0) == (0.5, 0.5)
    assert K._youngest_interval_weights(1e200, 1e-200, 1e100) == (0.5e-200, 0.5e-200)


@settings(max_examples=200, deadline=None)
@given(x=st.lists(st.one_of(st.sampled_from([0.0, 1.0, -1.0, math.nan, math.inf]),
                            st.floats(-5.0, 5.0)), max_size=70))
def test_property_the_compiled_stable_argsort_is_numpys(x):
    """kernels.contact.stable_argsort replaced np.argsort(kind="mergesort") (numba's compiles
    for seconds): the same order, ties (kept in input order) and nan (last) included."""
    from pulloff.kernels import contact as C

    x = np.array(x, dtype=float)
    np.testing.assert_array_equal(C.stable_argsort(x), np.argsort(x, kind="stable"))


@settings(max_examples=200, deadline=None)
@given(n=st.integers(0, 12), data=st.data(), two_d=st.booleans())
def test_property_merge_sorted_inserts_as_numpy_does(n, data, two_d):
    """kernels.contact.merge_sorted (element by element, in place) against np.insert."""
    from pulloff.kernels import contact as C

    k = data.draw(st.integers(0, 6))
    at = np.sort(np.array(data.draw(st.lists(st.integers(0, n), min_size=k, max_size=k)),
                          dtype=np.int64))
    shape = (lambda rows: (rows, 3)) if two_d else (lambda rows: (rows,))
    old = np.arange(float(np.prod(shape(n)))).reshape(shape(n))
    new = -1.0 - np.arange(float(np.prod(shape(k)))).reshape(shape(k))
    arr = np.full(shape(n + k + 2), np.nan)
    arr[:n] = old
    C.merge_sorted(arr, n, at, new)
    np.testing.assert_array_equal(arr[:n + k], np.insert(old, at, new, axis=0))


@settings(max_examples=200, deadline=None)
@given(old=st.lists(st.floats(0.0, 1.0), max_size=60, unique=True),
       alpha=st.floats(0.0, 0.9), beta=st.floats(0.05, 1.0), shrink=st.floats(0.0, 0.5),
       dtheta=st.floats(1e-4, 0.3), count=st.integers(1, 20))
def test_property_a_receding_ends_targets_are_new_spaced_and_inside(old, alpha, beta, shrink,
                                                                    dtheta, count):
    """kernels.contact.end_targets against its definition in Python: for each end (the
    present, the predicted), ``b cos(k dtheta)`` inside ``(alpha, beta)`` and not within 0.4
    of the angle spacing of an element or of a target taken before; ascending."""
    from pulloff.kernels import contact as C

    xi = np.sort(np.array(old + [7.0]))  # (an element beyond, as the mesh's archived side)
    n = xi.size - 1
    ends = np.array([beta, beta * (1.0 - shrink)])
    out = np.empty(2 * count)
    taken = C.end_targets(xi, n, alpha, ends, dtheta, count, out)
    expected = []
    for b in ends:
        for k in range(1, count + 1):
            x = b * math.cos(k * dtheta)
            tol = 0.4 * b * max(math.sin(k * dtheta) * dtheta, 0.5 * dtheta**2)
            if (alpha < x < beta and all(abs(x - y) > tol for y in xi[:n])
                    and all(abs(x - y) > tol for y in expected)):
                expected.append(x)
    np.testing.assert_array_equal(out[:taken], np.sort(expected))


def _scanned_memory(xi, status, D, tj, kappa, tau, t, x):
    """The contact memory at ``x`` as it was found before the contact view: a scan of every
    element up to the first contact element beyond ``x``."""
    left = right = -1
    for j in range(xi.size):
        if status[j] != 1:
            continue
        if xi[j] <= x:
            left = j
        else:
            right = j
            break
    out = np.zeros(tau.size)
    for i in range(tau.size):
        vl = D[left, i] * math.exp(-(t - tj[left]) / tau[i]) if left >= 0 else 0.0
        vr = D[right, i] * math.exp(-(t - tj[right]) / tau[i]) if right >= 0 else 0.0
        if left >= 0 and right >= 0 and xi[right] > xi[left]:
            w = (x - xi[left]) / (xi[right] - xi[left])
            out[i] = (1.0 - w) * vl + w * vr
        else:
            out[i] = vl if left >= 0 else vr
    return out


@settings(max_examples=80, deadline=None)
@given(data=st.data(), n=st.integers(0, 30), n_arms=st.integers(1, 3))
def test_property_the_contact_view_is_a_scan_of_every_element(data, n, n_arms):
    """kernels.contact.contact_view and _memory with it (a step's contact elements gathered
    once, then bisected) against a scan of every element: the same neighbours and values, bit
    for bit, repeated and tied positions, no contact element, and points beyond them all
    included; its running sums are the trapezoid from the centre. And _free_modes (a smooth
    edge beyond the contact meets a free element) against np.interp over the free ones."""
    from pulloff.kernels import contact as C

    xs = data.draw(st.lists(st.sampled_from([0.0, 0.25, 0.5, 0.75, 1.0, 1.5]) | st.floats(0.0, 2.0),
                            min_size=n, max_size=n))
    xi = np.sort(np.array(xs, dtype=float))
    status = np.array(data.draw(st.lists(st.sampled_from([0, 1, 2]), min_size=n, max_size=n)),
                      dtype=np.int64)
    D = np.array(data.draw(st.lists(st.floats(-2.0, 2.0), min_size=n * n_arms,
                                    max_size=n * n_arms)), dtype=float).reshape(n, n_arms)
    tj = np.array(data.draw(st.lists(st.floats(0.0, 1.0), min_size=n, max_size=n)), dtype=float)
    kappa = np.linspace(1.0, 2.0, n_arms)
    tau = np.linspace(0.3, 3.0, n_arms)
    sc = np.zeros(C.S_N)
    sc[C.S_T0], sc[C.S_DT] = 1.0, 0.25
    t1 = sc[C.S_T0] + sc[C.S_DT]
    idx, acc, first_free = C.contact_view(xi, status, D, tj, n, kappa, tau, sc)
    assert idx.tolist() == [j for j in range(n) if status[j] == 1]
    assert first_free.tolist() == [min([j for j in range(n) if status[j] == 0] + [n])]
    total, x_prev, v_prev = 0.0, 0.0, math.nan
    for k, j in enumerate(idx.tolist()):
        v = 0.0
        for i in range(n_arms):
            v += kappa[i] * D[j, i] * math.exp(-(t1 - tj[j]) / tau[i])
        total += v * xi[j] if math.isnan(v_prev) else 0.5 * (v + v_prev) * (xi[j] - x_prev)
        x_prev, v_prev = xi[j], v
        assert acc[0, k] == v and acc[1, k] == total
    points = list(xi) + [-0.5, 0.6, 2.5] + data.draw(st.lists(st.floats(0.0, 2.0), max_size=5))
    out = np.empty(n_arms)
    # The free elements' modes (here D's columns) at x, as np.interp between them gives them
    # (the nearest below them all, zero beyond), found from the bisection outward.
    free = [j for j in range(n) if status[j] == 0]
    unique = len({xi[j] for j in free}) == len(free)
    for x in points:
        C._free_modes(float(x), xi, D, status, n, int(first_free[0]), out)
        if not free or x > xi[free[-1]]:
            want = [0.0] * n_arms
        else:
            want = [float(np.interp(x, xi[free], D[free, i])) for i in range(n_arms)]
        if unique:  # (np.interp between tied nodes is its own convention)
            assert out.tolist() == want, (x, free)
    for x in points:
        for t in (t1, 0.5):
            got = C._memory(xi, status, D, tj, n, kappa, tau, t, float(x), out, idx)
            want = _scanned_memory(xi, status, D, tj, kappa, tau, t, float(x))
            assert out.tolist() == want.tolist(), (x, t)
            assert got == sum(kappa[i] * want[i] for i in range(n_arms))


def test_compiled_history_columns_are_numpys_bit_for_bit():
    """si_history's one compiled pass (kernels.history.flat_punch_columns) equals the numpy
    columns bit for bit: thin zones (all of the cohesive series), wide ones (series and closed
    form mixed), a preload, the elastic and viscous limits; empty, short and long histories,
    and a 2-d shape."""
    from pulloff.solvers.problem import Problem, numpy_si_history, si_history

    rng = np.random.default_rng(11)
    problems = [Problem(G=3e5, eta=3e3, sigma_c=5e6, delta=1e-8, a=1e-3, v=1e-3),
                Problem(G=1e6, eta=50.0, sigma_c=1e6, delta=3.1831e-12, a=1e-3, v=1e-3),
                Problem(G=1e6, eta=1e3, sigma_c=1e6, delta=1e-4, a=1e-3, v=1e-3, h0=2e-5),
                Problem(G=1e6, eta=0.0, sigma_c=1e6, delta=1e-6, a=1e-3, v=4e-5),
                Problem(G=0.0, eta=1e5, sigma_c=1e6, delta=1e-7, a=1e-3, v=1e-3)]
    for p in problems:
        for t_max in (1e-6, 1.0, 1e3, 1e6):
            for n in (0, 1, 5, 16, 17, 257, 1000):
                t = np.sort(t_max * rng.random(n))
                gap = rng.random(n)
                got, want = si_history(p, t, gap), numpy_si_history(p, t, gap)
                assert list(got) == list(want)
                for name in want:
                    assert got[name].tobytes() == want[name].tobytes(), (p, t_max, n, name)
    t, gap = rng.random((3, 4)), rng.random((3, 4))
    got, want = si_history(problems[0], t, gap), numpy_si_history(problems[0], t, gap)
    assert all(got[name].tobytes() == want[name].tobytes() for name in want)
    assert all(got[name].shape == (3, 4) for name in want)


def test_scalar_forces_with_the_compiled_series_are_analytics_bit_for_bit():
    """Problem.forces at one time (the cohesive series compiled, kernels.history.
    cohesive_bracket) and zone_ratio of a float (math) equal the Python/numpy forms bit for
    bit, in thin zones (series), wide ones (closed form) and at the switch."""
    from pulloff.model import analytic
    from pulloff.solvers.frozen import zone_ratio
    from pulloff.solvers.problem import Problem

    rng = np.random.default_rng(7)
    for p in (Problem(G=3e5, eta=3e3, sigma_c=5e6, delta=1e-8, a=1e-3, v=1e-3),
              Problem(G=1e6, eta=1e3, sigma_c=1e6, delta=1e-4, a=1e-3, v=1e-3, h0=2e-5),
              Problem(G=0.0, eta=1e5, sigma_c=1e6, delta=1e-7, a=1e-3, v=1e-3)):
        times = [0.0, *(10.0 ** rng.uniform(-6, 6, 500)).tolist()]
        for t in times:
            F_contact, F_total = p.forces(t)
            b = p.zone_end(t)
            want = F_contact + analytic._cohesive_force_scalar(p.sigma_c, p.a, b)
            assert type(F_total) is float and F_total == want, (p, t)
            s = p.s_of(t)
            assert zone_ratio(s) == zone_ratio(np.array([s]))[0]
