"""Numba kernels of the seed's onset stepper: exponential step weights, element updates, gap
integral, the step loop and thinning.

Everything here is dimensionless (see :mod:`pulloff.solver` for the scales): lengths along the
foundation in units of the contact radius ``a``, displacements in ``delta``, time in ``delta/v``.
The zone is parametrised by ``sigma = sqrt(x^2 - 1)`` instead of ``x`` so that a cohesive zone of
``1e-8 a`` keeps full relative precision (``x - 1`` would cancel). The edge condition makes
``s(t) = sqrt(b^2 - 1) = k (h0 + t) + c`` exact and linear in time, with
``k = 2 G delta / (sigma_c a)`` and ``c = 2 eta v / (sigma_c a)``; an element at ``sigma`` feels
the load ``q = sqrt(s^2 - sigma^2)`` once ``s`` has passed it and obeys ``k U + c dU/dt = q``.

Kernels that call each other live in this one module (numba's disk cache does not track
cross-module changes).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# Tanh-sinh rule on [0, 1]: doubly exponential clustering at both ends copes with the sqrt
# end point of a freshly loaded element and with the boundary layer of a stiff exponential.
_TS_STEP = 1.0 / 24.0
_TS_HALF_WIDTH = 3.3


def _tanh_sinh_rule(step: float = _TS_STEP, half_width: float = _TS_HALF_WIDTH):
    """Nodes ``u``, complements ``1 - u`` (to full precision near 1) and weights on [0, 1]."""
    t = np.arange(-half_width, half_width + 0.5 * step, step)
    arg = 0.5 * np.pi * np.sinh(t)
    # 1 - tanh(arg) and 1 + tanh(arg), each without cancellation.
    one_minus = 2.0 / (1.0 + np.exp(2.0 * arg))
    one_plus = 2.0 / (1.0 + np.exp(-2.0 * arg))
    weights = step * 0.5 * np.pi * np.cosh(t) / np.cosh(arg) ** 2
    keep = (one_minus > 0.0) & (one_plus > 0.0)
    return 0.5 * one_plus[keep], 0.5 * one_minus[keep], 0.5 * weights[keep]


TS_NODES, TS_COMPLEMENTS, TS_WEIGHTS = _tanh_sinh_rule()


@njit(cache=True)
def phi1(mu):
    """``(1 - exp(-mu)) / mu``, exact limit 1 at ``mu = 0``, no cancellation for small ``mu``."""
    if mu == 0.0:
        return 1.0
    if math.isinf(mu):
        return 0.0
    return -math.expm1(-mu) / mu


@njit(cache=True)
def ramp_moment(mu):
    """``int_0^1 exp(-mu y) y dy = (1 - exp(-mu)(1 + mu)) / mu^2``, stable for every ``mu >= 0``."""
    if mu < 0.1:
        # Series sum_j (-mu)^j / (j! (j + 2)): the closed form loses ~mu^-2 digits here.
        total = 0.0
        term = 1.0
        for j in range(18):
            total += term / (j + 2)
            term *= -mu / (j + 1)
        return total
    if math.isinf(mu):
        return 0.0
    return (-math.expm1(-mu) - mu * math.exp(-mu)) / (mu * mu)


@njit(cache=True)
def linear_load_weights(k, c, dt):
    """Exact one-step update for ``k U + c dU/dt = q`` with ``q`` linear over the step.

    Returns ``(decay, w_old, w_new)`` such that
    ``U(t + dt) = decay U(t) + w_old q(t) + w_new q(t + dt)``. Valid for any ``k dt / c``,
    including ``c = 0`` (elastic: ``U = q / k``) and ``k = 0`` (viscous: trapezoid in time).
    """
    if c == 0.0:
        return 0.0, 0.0, 1.0 / k
    theta = dt / c
    mu = k * theta
    a = ramp_moment(mu)
    return math.exp(-mu), theta * a, theta * (phi1(mu) - a)


@njit(cache=True)
def _exp_map(u, one_minus_u, mu):
    """Map ``u`` in [0, 1] to ``y`` in [0, 1] with density ~ ``exp(-mu y)``; returns ``(y, 1 - y)``."""
    if mu == 0.0:
        return u, one_minus_u
    if mu <= 1.0:
        y = -math.log1p(u * math.expm1(-mu)) / mu
        return y, math.log1p(one_minus_u * math.expm1(mu)) / mu
    arg = one_minus_u + u * math.exp(-mu)
    y = min(-math.log(arg) / mu, 1.0)
    return y, max(1.0 + math.log(arg) / mu, 0.0)


# 8-point Gauss-Legendre on [0, 1]: ages older than one step see a smooth U/q.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)
_GL_X = 0.5 * (_GL_X + 1.0)
_GL_W = 0.5 * _GL_W

#: Below this many relaxation times per step the youngest interval holds no layer: ``R`` is
#: entire with Taylor terms ``(k dt/c)^n / n!``, and Gauss-Legendre's 8 points (exact to degree
#: 15) leave less than ``0.5^16/16!`` ~ 1e-18 of it.
_SMOOTH_FIRST_INTERVAL = 0.5
#: From this age on (in steps) ``sqrt(age)`` is analytic on the step with its branch point at
#: least 4 steps away: Gauss-Legendre's 8 points integrate it against a mild exponential
#: (``k dt/c <= _SMOOTH_FIRST_INTERVAL``) to ~1e-19 (convergence factor 13.9^-16).
_SMOOTH_ONSET_AGE = 3


@njit(cache=True)
def onset_weights(k, c, dt, n_ages, nodes, complements, weights):
    """Step weights for elements whose load starts like ``sqrt(age)``.

    An element that entered the zone at a step boundary ``age = 0`` carries
    ``q = sqrt(age) r(t)`` with ``r = sqrt(k (sigma + s(t)))`` smooth. Interpolating only ``r``
    linearly and integrating the ``sqrt(age)`` factor exactly against the exponential kernel
    keeps the step second order in time from the very first step (a linear interpolant of ``q``
    itself is only order 1.5). Returns ``(w_old, w_new)`` of length ``n_ages`` such that an
    element of age ``m dt`` advances by ``decay U + w_old[m] r(t) + w_new[m] r(t + dt)``.
    """
    w_old = np.empty(n_ages)
    w_new = np.empty(n_ages)
    sqrt_dt = math.sqrt(dt)
    if c == 0.0:
        for m in range(n_ages):
            w_old[m] = 0.0
            w_new[m] = sqrt_dt * math.sqrt(m + 1.0) / k
        return w_old, w_new
    theta = dt / c
    mu = k * theta
    scale = theta * sqrt_dt * phi1(mu)
    n_nodes = nodes.shape[0]
    ys = np.empty(n_nodes)
    one_minus_ys = np.empty(n_nodes)
    for i in range(n_nodes):
        ys[i], one_minus_ys[i] = _exp_map(nodes[i], complements[i], mu)
    smooth = mu <= _SMOOTH_FIRST_INTERVAL
    # The exponential's weights at the Gauss points, normalised like the mapped rule.
    gl_w = np.empty(_GL_X.shape[0])
    for j in range(_GL_X.shape[0]):
        gl_w[j] = _GL_W[j] * math.exp(-mu * _GL_X[j]) / phi1(mu)
    for m in range(n_ages):
        acc_old = 0.0
        acc_new = 0.0
        if smooth and m >= _SMOOTH_ONSET_AGE:
            for j in range(_GL_X.shape[0]):
                root = math.sqrt(m + 1.0 - _GL_X[j])
                acc_old += gl_w[j] * root * _GL_X[j]
                acc_new += gl_w[j] * root * (1.0 - _GL_X[j])
        else:
            for i in range(n_nodes):
                # y = 1 - z is the time left to the end of the step, in steps.
                root = math.sqrt(m + one_minus_ys[i])
                acc_old += weights[i] * root * ys[i]
                acc_new += weights[i] * root * one_minus_ys[i]
        w_old[m] = scale * acc_old
        w_new[m] = scale * acc_new
    return w_old, w_new


#: ``binom(1/2, p)``: ``sqrt(m + u) = sqrt(m) sum_p BINOM_HALF[p] (u/m)^p`` for ``0 <= u <= 1``.
#: Nine terms leave a truncation below 1e-17 relative from age ``ONSET_ASYMPTOTIC_AGE`` on.
BINOM_HALF = np.array([1.0, 0.5, -0.125, 0.0625, -0.0390625, 0.02734375, -0.0205078125,
                       0.01611328125, -0.013092041015625])
ONSET_ASYMPTOTIC_AGE = 64


@njit(cache=True)
def onset_moments(k, c, dt, nodes, complements, weights):
    """``(scale, m_old, m_new)`` that give :func:`onset_weights` at any age without a table.

    For an age ``m`` of many steps ``sqrt(m + u)`` is expanded in ``u/m``; the weights become
    ``scale sqrt(m) sum_p BINOM_HALF[p] m^-p m_old[p]`` (and ``m_new``), with the moments of
    the exponential kernel over the step computed once. Long runs need this: a table per age
    would grow with the number of steps.
    """
    n_terms = BINOM_HALF.shape[0]
    m_old = np.zeros(n_terms)
    m_new = np.zeros(n_terms)
    sqrt_dt = math.sqrt(dt)
    if c == 0.0:
        # w_new = sqrt(dt (m + 1)) / k: every moment of u = 1 is 1.
        for p in range(n_terms):
            m_new[p] = 1.0
        return sqrt_dt / k, m_old, m_new
    theta = dt / c
    mu = k * theta
    for i in range(nodes.shape[0]):
        y, u = _exp_map(nodes[i], complements[i], mu)
        power = 1.0
        for p in range(n_terms):
            m_old[p] += weights[i] * power * y
            m_new[p] += weights[i] * power * u
            power *= u
    return theta * sqrt_dt * phi1(mu), m_old, m_new


@njit(cache=True)
def onset_weight_pair(age, w_on_old, w_on_new, scale, m_old, m_new):
    """Onset weights ``(w_old, w_new)`` of an element ``age`` steps old: from the tables while
    they reach, from the moments of :func:`onset_moments` beyond (the tables must reach
    ``ONSET_ASYMPTOTIC_AGE`` whenever an element can be older than them)."""
    if age < w_on_old.shape[0]:
        return w_on_old[age], w_on_new[age]
    inv = 1.0 / age
    power = 1.0
    acc_old = 0.0
    acc_new = 0.0
    for p in range(BINOM_HALF.shape[0]):
        acc_old += BINOM_HALF[p] * power * m_old[p]
        acc_new += BINOM_HALF[p] * power * m_new[p]
        power *= inv
        if power < 1e-18:  # the remaining terms are below rounding (4 terms from age 2^16)
            break
    root = scale * math.sqrt(age)
    return root * acc_old, root * acc_new


#: :func:`onset_ratio` up to ``z = k age / c = RATIO_Z_LOW 2^RATIO_OCTAVES`` as Chebyshev
#: series: ``k R = 1 - D(sqrt z) / sqrt z`` with ``D`` Dawson's integral is entire in ``z``;
#: one series per octave of ``z`` from ``RATIO_Z_LOW`` (degree 20 leaves ~4e-15, the level of
#: the power series it replaces), and below it ``k R / z`` (degree 12; ``1 - D/sqrt z``
#: cancels there). The power series took 10-80 terms with two divisions each and made the
#: product weights a third of a run's kernel time (0.15-0.45 ms at rtol 1e-6).
RATIO_Z_LOW = 0.5
RATIO_OCTAVES = 11
RATIO_DEGREE = 20
RATIO_NEAR_ZERO_DEGREE = 12


def _ratio_octave_coefficients():
    """Chebyshev coefficients (rows: octaves ``[Z 2^j, Z 2^(j+1)]``, ``Z = RATIO_Z_LOW``) of
    ``1 - D(sqrt z) / sqrt z``, interpolated at Chebyshev points from scipy's ``dawsn``."""
    from numpy.polynomial import chebyshev
    from scipy.special import dawsn

    rows = []
    for j in range(RATIO_OCTAVES):
        low = RATIO_Z_LOW * 2.0 ** j

        def ratio(t, low=low):
            root = np.sqrt(low * (1.5 + 0.5 * t))
            return 1.0 - dawsn(root) / root
        rows.append(chebyshev.chebinterpolate(ratio, RATIO_DEGREE))
    return np.ascontiguousarray(rows)


def _ratio_near_zero_coefficients():
    """Chebyshev coefficients of ``k R / z = exp(-z) sum_n z^n / (n! (n + 3/2))`` on
    ``[0, RATIO_Z_LOW]`` (the positive series, summed to rounding in Python)."""
    from numpy.polynomial import chebyshev

    def series(z):
        total, term, n = 0.0, 1.0, 0
        while term >= 1e-18 * total or n <= z:
            total += term / (n + 1.5)
            n += 1
            term *= z / n
        return math.exp(-z) * total

    return chebyshev.chebinterpolate(
        lambda t: np.array([series(0.5 * RATIO_Z_LOW * (1.0 + x)) for x in np.atleast_1d(t)]),
        RATIO_NEAR_ZERO_DEGREE)


RATIO_CHEBYSHEV = _ratio_octave_coefficients()
RATIO_NEAR_ZERO = _ratio_near_zero_coefficients()


@njit(cache=True)
def _clenshaw(coefficients, t):
    """The Chebyshev series with ``coefficients`` at ``t`` in ``[-1, 1]``."""
    b1 = b2 = 0.0
    for i in range(coefficients.shape[0] - 1, 0, -1):
        b1, b2 = coefficients[i] + 2.0 * t * b1 - b2, b1
    return coefficients[0] + t * b1 - b2


@njit(cache=True)
def _ratio_chebyshev(z):
    """``k R`` at ``RATIO_Z_LOW <= z < RATIO_Z_LOW 2^RATIO_OCTAVES`` (Clenshaw's recurrence on
    the octave's series)."""
    mantissa, exponent = math.frexp(z / RATIO_Z_LOW)  # z / Z = mantissa 2^exponent
    # (mantissa in [0.5, 1) onto [-1, 1))
    return _clenshaw(RATIO_CHEBYSHEV[exponent - 1], 4.0 * mantissa - 3.0)


@njit(cache=True)
def onset_ratio(age, k, c):
    """``U / q`` of an element of the given age whose load grew like ``sqrt(age)``.

    With ``F(age) = (1/c) int_0^age exp(-(k/c)(age - a)) sqrt(a) da`` this is
    ``F(age) / sqrt(age)``: 0 at entry, ``1/k`` once the element has relaxed, with a layer of
    width ``c/k`` in between. With ``z = k age / c``: Chebyshev series (see
    ``RATIO_CHEBYSHEV``) up to ``RATIO_Z_LOW 2^RATIO_OCTAVES``, the asymptotic
    (quasi-static) expansion ``(1/k) sum_n a_n (c / (k age))^n`` beyond.
    """
    if c == 0.0:
        return 1.0 / k
    if k == 0.0:
        return 2.0 * age / (3.0 * c)
    z = k * age / c
    if z < RATIO_Z_LOW:
        # exp(-z) int_0^1 exp(z w) sqrt(w) dw = exp(-z) sum_n z^n / (n! (n + 3/2))
        return age / c * _clenshaw(RATIO_NEAR_ZERO, 2.0 * z / RATIO_Z_LOW - 1.0)
    if z < RATIO_Z_LOW * 2.0 ** RATIO_OCTAVES:
        return _ratio_chebyshev(z) / k
    total = 1.0
    coeff = 1.0
    inv = 1.0 / z
    power = 1.0
    for n in range(30):
        coeff *= -(0.5 - n)
        coeff = -abs(coeff)
        power *= inv
        term = coeff * power
        total += term
        if abs(term) < 1e-17:
            break
    return total / k


# 12-point Gauss-Legendre on [0, 1] for the octaves of the youngest interval.
_GL12_X, _GL12_W = np.polynomial.legendre.leggauss(12)
_GL12_X = 0.5 * (_GL12_X + 1.0)
_GL12_W = 0.5 * _GL12_W


@njit(cache=True)
def _youngest_interval_weights(k, c, dt):
    """``int_0^1 R(z dt) {1 - z, z} dz`` where the relaxation layer ``c / k`` is thinner than
    the step: panels ``[0, w]``, then octaves ``[w, 2w], [2w, 4w], ..`` to 1, ``w = c/(k dt)``.
    ``R`` is entire in the age and, on an octave, no nearer its singular scale than the
    octave's own width, so 12 points per panel reach rounding (measured against a 923-point
    tanh-sinh rule for ``k dt / c`` from 0.6 to 1e8: within 9e-16), with ``12 log2(k dt/c)``
    evaluations instead of 923."""
    if c == 0.0:
        return 0.5 / k, 0.5 / k  # elastic: R = 1/k from the first instant
    acc_y = acc_o = 0.0
    low = 0.0
    high = min(1.0, c / (k * dt))
    if not high > 0.0:
        return 0.5 / k, 0.5 / k  # a layer below the smallest float: R = 1/k at every z > 0
    while low < 1.0:
        width = high - low
        for i in range(_GL12_X.shape[0]):
            z = low + width * _GL12_X[i]
            r = width * _GL12_W[i] * onset_ratio(z * dt, k, c)
            acc_y += r * (1.0 - z)
            acc_o += r * z
        low = high
        high = min(1.0, 2.0 * high)
    return acc_y, acc_o


@njit(cache=True)
def age_interval_weights(k, c, dt, n_ages):
    """Product-integration weights of ``U/q`` between element ages ``m dt`` and ``(m+1) dt``.

    Between neighbouring entered elements ``U/q = g(age) R(age)`` with ``R`` the universal
    :func:`onset_ratio` and ``g`` smooth (close to 1). Interpolating only ``g`` linearly and
    integrating ``R`` exactly keeps the gap integral second order even where the relaxation
    layer ``c/k`` is thinner than a step (a trapezoid on ``U/q`` would leave an error of order
    ``c`` that no step refinement removes until ``dt < c/k``). Returns ``(ratio, w_young,
    w_old)``: ``ratio[m] = R(m dt)`` and ``int_0^1 R((m + z) dt) {1 - z, z} dz``.
    """
    ratio = np.empty(n_ages + 1)
    w_young = np.empty(n_ages)
    w_old = np.empty(n_ages)
    for m in range(n_ages + 1):
        ratio[m] = onset_ratio(m * dt, k, c)
    for m in range(n_ages):
        acc_y = 0.0
        acc_o = 0.0
        if m == 0 and k * dt > _SMOOTH_FIRST_INTERVAL * c:
            acc_y, acc_o = _youngest_interval_weights(k, c, dt)
        else:
            for i in range(_GL_X.shape[0]):
                r = onset_ratio((m + _GL_X[i]) * dt, k, c)
                acc_y += _GL_W[i] * r * (1.0 - _GL_X[i])
                acc_o += _GL_W[i] * r * _GL_X[i]
        w_young[m] = acc_y
        w_old[m] = acc_o
    return ratio, w_young, w_old


@njit(cache=True)
def step_preloaded(sigma, offset, U, q, kt_new, s_new, decay, w_old, w_new):
    """Advance the elements that were inside the zone at ``t = 0`` by one step (in place).

    ``offset = s0 - sigma`` (exact, from the mesh) and ``kt = k t``: ``s - sigma`` is formed as
    their sum, never as a difference of two nearly equal ``s`` and ``sigma``. ``q`` holds each
    element's load at the start of the step and receives the one at its end (the next step's
    start, and what the gap integral divides by: one square root per element and step, not
    three; see :func:`cache_loads`).
    """
    for i in range(sigma.shape[0]):
        q_new = math.sqrt((offset[i] + kt_new) * (s_new + sigma[i]))
        U[i] = decay * U[i] + w_old * q[i] + w_new * q_new
        q[i] = q_new


@njit(cache=True)
def step_entered(sigma, U, r, j_first, n_born, age_base, s_new, k, decay, w_old, w_new):
    """Advance entered elements ``j_first .. n_born - 1``, born on consecutive steps, by one
    step (in place): element ``j`` is ``age_base - j`` steps old, within the tables. ``r``:
    ``sqrt(k (sigma + s))`` at the start of the step in, at its end out (see
    :func:`cache_loads`). This loop is all there is in a run without a budget; kept free of
    branches, it vectorises."""
    # Views from j_first and an index from 0: written as a loop over j from j_first, LLVM
    # does not vectorise it (measured 5 ns against 1.2 ns per element).
    sig_tail = sigma[j_first:n_born]
    U_tail = U[j_first:n_born]
    r_tail = r[j_first:n_born]
    top = age_base - j_first
    for i in range(n_born - j_first):
        age = top - i
        r_new = math.sqrt(k * (sig_tail[i] + s_new))
        U_tail[i] = decay * U_tail[i] + w_old[age] * r_tail[i] + w_new[age] * r_new
        r_tail[i] = r_new


@njit(cache=True)
def step_entered_aged(born, sigma, U, r, j_stop, step, s_new, k, decay, w_old, w_new, scale,
                      m_old, m_new):
    """Advance entered elements ``0 .. j_stop - 1`` by one step (in place): those left apart
    by thinning or older than the tables. Element ``j`` entered at step ``born[j]``; ages
    beyond the tables use :func:`onset_weight_pair`'s expansion. ``r`` as in
    :func:`step_entered`."""
    for j in range(j_stop):
        wo, wn = onset_weight_pair(step - born[j], w_old, w_new, scale, m_old, m_new)
        r_new = math.sqrt(k * (sigma[j] + s_new))
        U[j] = decay * U[j] + wo * r[j] + wn * r_new
        r[j] = r_new


@njit(cache=True)
def cache_loads(sig_pre, offset_pre, q, sig_born, r, n_born, k, kt, s):
    """The loads at ``s`` (``kt = k t``) that the step kernels carry from one step to the
    next: ``q`` of the preloaded elements, ``r = sqrt(k (sigma + s))`` of the entered ones,
    by the very expressions those kernels use, so that a run is the same to the bit whether
    a step recomputes its start's load or takes it from the step before."""
    for i in range(sig_pre.shape[0]):
        q[i] = math.sqrt((offset_pre[i] + kt) * (s + sig_pre[i]))
    for j in range(n_born):
        r[j] = math.sqrt(k * (sig_born[j] + s))


@njit(cache=True)
def interval_width(sigma_a, sigma_b):
    """``x_b - x_a`` for ``x = sqrt(1 + sigma^2)``, without cancellation for thin zones."""
    return (sigma_b - sigma_a) * (sigma_b + sigma_a) / (
        math.sqrt(1.0 + sigma_a * sigma_a) + math.sqrt(1.0 + sigma_b * sigma_b))


@njit(cache=True)
def cubic_interval_weights(d_left, d, d_right, out):
    """Weights on ``v`` at four nodes ``x0 < x1 < x2 < x3`` that integrate over ``[x1, x2]``
    the cubic through them; ``d_left = x1 - x0``, ``d = x2 - x1``, ``d_right = x3 - x2``.
    A zero ``d_left`` (or ``d_right``) means that node is missing: the quadratic through the
    other three, with a zero weight for it. Written into ``out[0:4]``. Two-point
    Gauss-Legendre on ``[x1, x2]`` is exact for cubics."""
    xs = np.array([-d_left, 0.0, d, d + d_right])
    present = np.array([d_left > 0.0, True, True, d_right > 0.0])
    half = 0.5 * d
    offset = d / (2.0 * math.sqrt(3.0))
    for i in range(4):
        out[i] = 0.0
    for p in range(2):
        z = half + (offset if p == 0 else -offset)
        for i in range(4):
            if not present[i]:
                continue
            basis = 1.0
            for m in range(4):
                if m != i and present[m]:
                    basis *= (z - xs[m]) / (xs[i] - xs[m])
            out[i] += half * basis


@njit(cache=True)
def preloaded_state(s0, n, k, c):
    """The zone loaded at ``t = 0`` on ``n`` nodes uniform in angle, ``sigma = s0 cos(theta)``
    (ascending from 0, clustered toward ``b(0)``): ``(sigma, offset = s0 - sigma (exact), U,
    dx)``, where ``dx[i]`` is the width in ``x`` of the interval ending at node ``i`` (the
    last one ending at ``s0``, the oldest entered element) and ``U`` is 0 for a solid with a
    damper (it cannot move at once) or the elastic displacement under the load at ``t = 0``.
    One compiled call: it runs once per level, and as numpy it was a fifth of a short run."""
    if s0 <= 0.0:
        return np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(1)
    sigma = np.empty(n)
    offset = np.empty(n)
    U = np.zeros(n)
    dx = np.zeros(n + 1)
    for i in range(n):
        angle = (n - i) * (0.5 * math.pi / n)
        sigma[i] = s0 * math.cos(angle) if i > 0 else 0.0
        offset[i] = 2.0 * s0 * math.sin(0.5 * angle) ** 2
        if c == 0.0:
            U[i] = math.sqrt(offset[i] * (s0 + sigma[i])) / k
    for i in range(1, n + 1):
        right = sigma[i] if i < n else s0
        dx[i] = interval_width(sigma[i - 1], right)
    return sigma, offset, U, dx


@njit(cache=True)
def preloaded_cubic_weights(dx_pre):
    """:func:`cubic_interval_weights` of every interval of the preloaded nodes (the last one
    ending at the oldest entered element): row ``i`` weighs ``v`` at nodes ``i-2 .. i+1``."""
    n = dx_pre.shape[0]
    out = np.zeros((n, 4))
    for i in range(1, n):
        d_left = dx_pre[i - 1] if i >= 2 else 0.0
        d_right = dx_pre[i + 1] if i + 1 < n else 0.0
        cubic_interval_weights(d_left, dx_pre[i], d_right, out[i])
    return out


@njit(cache=True)
def displacement_integral(sig_pre, offset_pre, U_pre, dx_pre, pre_w, born, sig_born, U_born,
                          dx_born, thin_w, n_born, step, S, kt, k_dt, ratio, w_young, w_old,
                          scratch, q_pre):
    """``int_1^b U(x) / sqrt(b^2 - x^2) dx`` over the free zone (units of ``delta``).

    The field is written ``U = sqrt(b^2 - x^2) v(x)``, so no quadrature node sits on the
    singular end point and the elastic limit (``v = 1/k``) is integrated exactly. Elements
    loaded since ``t = 0`` (ascending ``sigma < s0``) and the oldest entered one use a
    trapezoid on ``v`` in ``x``, or, when ``pre_w`` has a row per interval
    (:func:`preloaded_cubic_weights`, for a mesh that no longer refines with the step), the
    cubic through four neighbours. Entered elements born on consecutive steps, younger than the
    tables of :func:`age_interval_weights`, use those weights (the relaxation layer next to
    ``b``); pairs born on consecutive steps but older than the tables use the trapezoid on
    ``v``; pairs further apart (after :func:`thin_entered`) integrate the cubic through four
    neighbours with the weights ``thin_w[j]`` on ``v`` at elements ``j-2 .. j+1``.
    ``dx_pre[i]`` is the width in ``x`` of the interval ending at preloaded node ``i``
    (``dx_pre[n_pre]``: the one ending at the oldest entered element), ``dx_born[j]`` that
    ending at entered element ``j``: node positions never change, so the widths are computed
    once, not every step. ``S - sigma`` comes from exact offsets: ``offset_pre + k t`` for
    preloaded elements, ``k dt age`` for entered ones (``kt``, ``k_dt``); ``born[0]`` is 0.
    """
    if (pre_w.shape[0] != sig_pre.shape[0] + 1 and n_born > 1 and born[n_born - 1] == step
            and step - born[0] == n_born - 1 and step - born[0] < w_young.shape[0]):
        # (a ladder's level: no budget, every element consecutive and within the tables)
        return (_preloaded_trapezoid(U_pre, q_pre, dx_pre, sig_born, U_born, S, kt, scratch)
                + _entered_consecutive(born, sig_born, U_born, dx_born, n_born, step, S, k_dt,
                                       ratio, w_young, w_old, scratch))
    return (_preloaded_integral(U_pre, q_pre, dx_pre, pre_w, sig_born, U_born, n_born, S, kt)
            + _entered_integral(born, sig_born, U_born, dx_born, thin_w, n_born, step, S, k_dt,
                                ratio, w_young, w_old))


@njit(cache=True, error_model="numpy")
def _preloaded_trapezoid(U_pre, q_pre, dx_pre, sig_born, U_born, S, kt, scratch):
    """:func:`_preloaded_integral` with the trapezoid on ``v`` and an entered element beyond
    the oldest (the same operations in the same order): ``v`` first in a loop without
    dependences, which LLVM vectorises (numpy's error model: no division check), then the
    sum."""
    n_pre = U_pre.shape[0]
    for i in range(n_pre):
        scratch[i] = U_pre[i] / q_pre[i]
    scratch[n_pre] = U_born[0] / math.sqrt(kt * (S + sig_born[0]))
    total = 0.0
    for i in range(1, n_pre + 1):
        total += 0.5 * (scratch[i] + scratch[i - 1]) * dx_pre[i]
    return total


@njit(cache=True, error_model="numpy")
def _entered_consecutive(born, sig_born, U_born, dx_born, n_born, step, S, k_dt, ratio,
                         w_young, w_old, scratch):
    """:func:`_entered_integral` where elements ``0 .. n_born - 1`` entered on consecutive
    steps and all are younger than the tables (the same operations in the same order): ``g``
    first in a loop without dependences, which LLVM vectorises, then the sum."""
    top = step - born[0]  # the oldest age; element j is top - j steps old
    n_aged = n_born - 1  # the youngest (age 0) takes g from its older neighbour
    for j in range(n_aged):
        v = U_born[j] / math.sqrt(k_dt * (top - j) * (S + sig_born[j]))
        scratch[j] = v / ratio[top - j]
    scratch[n_aged] = scratch[n_aged - 1]
    total = 0.0
    for j in range(1, n_born):
        age = top - j
        total += dx_born[j] * (scratch[j] * w_young[age] + scratch[j - 1] * w_old[age])
    return total


@njit(cache=True)
def _preloaded_integral(U_pre, q_pre, dx_pre, pre_w, sig_born, U_born, n_born, S, kt):
    """The part of :func:`displacement_integral` over the elements loaded since ``t = 0``
    (their loads ``q_pre`` at ``S``) and the oldest entered one."""
    total = 0.0
    n_pre = U_pre.shape[0]
    cubic = pre_w.shape[0] == n_pre + 1
    v_prev = 0.0
    p1 = p2 = 0.0  # v at i - 3, i - 2 (v_prev is v at i - 1)
    for i in range(n_pre + 1):
        if i < n_pre:
            v = U_pre[i] / q_pre[i]
        elif n_born == 1:
            # The element at s0 is at b: k == 0 (b fixed, U/q the same everywhere) or t = 0.
            v = v_prev
        else:
            v = U_born[0] / math.sqrt(kt * (S + sig_born[0]))
        if cubic:
            if i >= 2:
                w = pre_w[i - 1]
                total += w[0] * p1 + w[1] * p2 + w[2] * v_prev + w[3] * v
        elif i > 0:
            total += 0.5 * (v + v_prev) * dx_pre[i]
        p1, p2 = p2, v_prev
        v_prev = v
    if cubic and n_pre >= 1:
        w = pre_w[n_pre]
        total += w[0] * p1 + w[1] * p2 + w[2] * v_prev
    return total


@njit(cache=True)
def _entered_integral(born, sig_born, U_born, dx_born, thin_w, n_born, step, S, k_dt, ratio,
                      w_young, w_old):
    """The part of :func:`displacement_integral` over the entered elements."""
    total = 0.0
    # Entered elements, youngest (age 0) last; g = v / R(age) is smooth. A thinned interval
    # ending at j - 1 is added at j, once v at its right neighbour is known.
    n_tab = w_young.shape[0]
    g_prev = 0.0
    age_prev = step
    v1 = v2 = v3 = 0.0  # v at j - 3, j - 2, j - 1
    thinned_pending = False
    # A lone entered element (k = 0, or t = 0) was integrated with the preloaded ones.
    for j in range(n_born if n_born > 1 else 0):
        age = step - born[j]
        if age > 0:
            v = U_born[j] / math.sqrt(k_dt * age * (S + sig_born[j]))
            g = v / ratio[age] if age <= n_tab else 0.0
        else:
            g = g_prev  # R(0) = 0: take g from the element one step older
            v = 0.0  # never used: the youngest pairs are always consecutive
        if thinned_pending:
            w = thin_w[j - 1]
            total += w[0] * v1 + w[1] * v2 + w[2] * v3 + w[3] * v
            thinned_pending = False
        if j > 0:
            gap_steps = age_prev - age
            if gap_steps == 1 and age < n_tab:
                total += dx_born[j] * (g * w_young[age] + g_prev * w_old[age])
            elif gap_steps == 1:
                total += 0.5 * dx_born[j] * (v + v3)
            else:
                thinned_pending = True
        g_prev = g
        v1, v2, v3 = v2, v3, v
        age_prev = age
    return total


@njit(cache=True)
def thin_entered(born, sigma, U, dx, thin_w, n_born, step, keep_young, ratio_max):
    """Drop entered elements so that the survivors are graded in age; returns the new count.

    Elements younger than ``keep_young`` steps are all kept (they carry the relaxation layer
    next to ``b`` and its product weights); the oldest element (born at step 0, the neighbour of
    the preloaded zone) is kept. Among the others an element is dropped when its older kept
    neighbour is at most ``ratio_max`` times as old as its younger one, so the gaps grow
    geometrically with age, and the cubic on ``v`` over them keeps a relative error of order
    ``(ratio_max - 1)^4``. Elements do not interact, so dropping one changes nothing but the
    quadrature of the gap integral. Compacts the arrays in place and recomputes ``dx`` and the
    cubic weights ``thin_w`` of every interval whose ends are not consecutive steps.
    """
    if n_born < 3:
        return n_born
    kept = 1
    age_kept = step - born[0]
    for j in range(1, n_born):
        age = step - born[j]
        if age >= keep_young and j + 1 < n_born:
            age_next = step - born[j + 1]
            if age_kept <= ratio_max * age_next:
                continue
        born[kept] = born[j]
        sigma[kept] = sigma[j]
        U[kept] = U[j]
        dx[kept] = interval_width(sigma[kept - 1], sigma[kept])
        age_kept = age
        kept += 1
    for j in range(1, kept):
        if born[j] - born[j - 1] > 1:
            # Cubic through j-2 .. j+1 (quadratic at the oldest interval); the youngest
            # elements are kept consecutive, so j + 1 always exists here.
            d_left = dx[j - 1] if j >= 2 else 0.0
            cubic_interval_weights(d_left, dx[j], dx[j + 1], thin_w[j])
    return kept


@njit(cache=True)
def gap_from_integral(h, S, integral):
    """Gap at ``r = b`` in units of ``delta``: ``(2/pi) [h acos(1/b) - integral]``.

    ``h - (2/pi) h asin(a/b)`` is written as ``(2/pi) h atan(S)`` so that thin zones do not
    subtract two nearly equal numbers.
    """
    return (2.0 / math.pi) * (h * math.atan(S) - integral)


@njit(cache=True)
def crossing_time(t, gap):
    """Time where the gap reaches 1 in the last step of the rows ``t``, ``gap`` (the last
    four, or fewer when the run has fewer; fourth-order local interpolation).

    The cubic through the last four points leaves a location error ``O(dt^4)``: below the
    stepper's own error and below the ``dt^3`` term that its Richardson extrapolation leaves,
    which a quadratic's error (``O(dt^3)``, with a constant that jumps with where in the step
    the crossing falls) would otherwise make irregular. Newton from the linear guess, kept
    inside the step. Compiled: in Python it was ~12 us of a ~100 us level.
    """
    m = min(4, t.shape[0])
    ts = t[t.shape[0] - m:].copy()
    coef = gap[gap.shape[0] - m:].copy()
    t1, t2, g1, g2 = ts[m - 2], ts[m - 1], coef[m - 2], coef[m - 1]
    t_lin = t1 + (1.0 - g1) * (t2 - t1) / (g2 - g1)
    if m < 3:
        return t_lin
    # Newton's divided differences through the points, centred on the step.
    for i in range(m):
        ts[i] -= t2
    for j in range(1, m):
        for i in range(m - 1, j - 1, -1):
            coef[i] = (coef[i] - coef[i - 1]) / (ts[i] - ts[i - j])
    x = t_lin - t2
    for _ in range(30):
        value = coef[m - 1]
        slope = 0.0
        for j in range(m - 2, -1, -1):
            slope = slope * (x - ts[j]) + value
            value = value * (x - ts[j]) + coef[j]
        if slope <= 0.0:
            return t_lin
        x_new = x - (value - 1.0) / slope
        if not t1 - t2 <= x_new <= 0.0:
            return t_lin
        if abs(x_new - x) <= 1e-15 * (abs(t2) + abs(x_new)):
            return t2 + x_new
        x = x_new
    return t2 + x


#: Return codes of :func:`march`.
MARCH_STOPPED = 0
MARCH_CROSSED = 1
MARCH_FULL = 2


@njit(cache=True)
def march(sig_pre, offset_pre, U_pre, dx_pre, pre_w, born, sig_born, U_born, dx_born, thin_w,
          n_born, j_consecutive, step,
          step_stop, k, c, h0, dt, decay, w_pre_old, w_pre_new, w_on_old, w_on_new, onset_scale,
          onset_m_old, onset_m_new, ratio, w_young, w_old, t_out, gap_out, row0):
    """Advance the foundation from step ``step`` until the gap reaches 1 or ``step_stop``.

    A new element is placed at ``b`` after every step (``sigma = s(t)``), so element entries
    always fall on step boundaries (see :func:`displacement_integral` for ``dx_pre``/
    ``dx_born``). ``t_out``/``gap_out`` receive the time and gap after each step at row
    ``step - row0`` and must reach ``step_stop - row0``. Elements from ``j_consecutive`` on
    were born on consecutive steps (thinning only removes older ones). Returns
    ``(step, n_born, code)``:
    ``MARCH_CROSSED`` when the gap reached 1, ``MARCH_FULL`` when the element arrays are full
    (thin them with :func:`thin_entered` and call again), ``MARCH_STOPPED`` at ``step_stop``.
    """
    capacity = sig_born.shape[0]
    n_tab = w_on_old.shape[0]
    scratch = np.empty(max(sig_pre.shape[0] + 1, capacity))
    q_pre = np.empty(sig_pre.shape[0])
    r_born = np.empty(capacity)
    cache_loads(sig_pre, offset_pre, q_pre, sig_born, r_born, n_born, k, k * (step * dt),
                k * (h0 + step * dt) + c)
    while step < step_stop:
        if k > 0.0 and n_born >= capacity:
            return step, n_born, MARCH_FULL
        t_new = (step + 1) * dt
        s_new = k * (h0 + t_new) + c
        step_preloaded(sig_pre, offset_pre, U_pre, q_pre, k * t_new, s_new, decay, w_pre_old,
                       w_pre_new)
        # Ages fall with j: thinned elements and those older than the tables come first.
        j_split = j_consecutive
        while j_split < n_born and step - born[j_split] >= n_tab:
            j_split += 1
        step_entered_aged(born, sig_born, U_born, r_born, j_split, step, s_new, k, decay,
                          w_on_old, w_on_new, onset_scale, onset_m_old, onset_m_new)
        if j_split < n_born:
            step_entered(sig_born, U_born, r_born, j_split, n_born,
                         step - born[j_split] + j_split, s_new, k, decay, w_on_old, w_on_new)
        step += 1
        if k > 0.0:
            born[n_born] = step
            sig_born[n_born] = s_new
            U_born[n_born] = 0.0
            r_born[n_born] = math.sqrt(k * (s_new + s_new))  # its load at the next start
            dx_born[n_born] = interval_width(sig_born[n_born - 1], s_new)
            n_born += 1
        integral = displacement_integral(sig_pre, offset_pre, U_pre, dx_pre, pre_w, born,
                                         sig_born, U_born, dx_born, thin_w, n_born, step, s_new,
                                         k * t_new, k * dt, ratio, w_young, w_old, scratch,
                                         q_pre)
        g = gap_from_integral(h0 + t_new, s_new, integral)
        t_out[step - row0] = t_new
        gap_out[step - row0] = g
        if g >= 1.0:
            return step, n_born, MARCH_CROSSED
    return step, n_born, MARCH_STOPPED


# --------------------------------------------------------------------------------------------
# A moving contact edge (MODEL.md section 6): the foundation on fixed positions in x.
#
# Positions are offsets ``xi = x - 1`` from the initial contact radius (units of the punch
# radius), so ``b^2 - x^2 = (xi_b - xi)(2 + xi_b + xi)`` keeps full precision in thin zones.
# Free elements sit in ``xi[lo:hi]`` (ascending); bonded ones (``x < a``) all follow the punch
# and are not stored. Loads are ``q = sqrt(b^2 - x^2)`` inside the zone, 0 beyond it.
