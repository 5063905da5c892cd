"""Numba kernels of the MDR foundation: exponential step weights, element updates, gap integral.

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
# A finer rule for the one scalar per run whose integrand has a layer as thin as c/(k dt).
TS_FINE_NODES, TS_FINE_COMPLEMENTS, TS_FINE_WEIGHTS = _tanh_sinh_rule(step=1.0 / 128.0,
                                                                      half_width=3.6)


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
    for m in range(n_ages):
        acc_old = 0.0
        acc_new = 0.0
        for i in range(n_nodes):
            # y = 1 - z is the time left to the end of the step, in steps.
            root = math.sqrt(m + one_minus_ys[i])
            acc_old += weights[i] * root * ys[i]
            acc_new += weights[i] * root * one_minus_ys[i]
        w_old[m] = scale * acc_old
        w_new[m] = scale * acc_new
    return w_old, w_new


@njit(cache=True)
def onset_ratio(age, k, c):
    """``U / q`` of an element of the given age whose load grew like ``sqrt(age)``.

    With ``F(age) = (1/c) int_0^age exp(-(k/c)(age - a)) sqrt(a) da`` this is
    ``F(age) / sqrt(age)``: 0 at entry, ``1/k`` once the element has relaxed, with a layer of
    width ``c/k`` in between. Positive series below 40 relaxation times, the asymptotic
    (quasi-static) expansion ``(1/k) sum_n a_n (c / (k age))^n`` beyond.
    """
    if c == 0.0:
        return 1.0 / k
    if k == 0.0:
        return 2.0 * age / (3.0 * c)
    z = k * age / c
    if z <= 40.0:
        # exp(-z) int_0^1 exp(z w) sqrt(w) dw = exp(-z) sum_n z^n / (n! (n + 3/2))
        total = 0.0
        term = 1.0
        n = 0
        while True:
            total += term / (n + 1.5)
            n += 1
            term *= z / n
            if term < 1e-17 * total and n > z:
                break
        return age / c * math.exp(-z) * total
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
        if abs(term) < 1e-17 or n + 1 > 0.5 * z:
            break
    return total / k


# 8-point Gauss-Legendre on [0, 1]: ages older than one step see a smooth U/q.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)
_GL_X = 0.5 * (_GL_X + 1.0)
_GL_W = 0.5 * _GL_W


@njit(cache=True)
def age_interval_weights(k, c, dt, n_ages, nodes, complements, weights):
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
        if m == 0:
            # The layer sits inside the youngest interval: tanh-sinh clusters at age 0.
            for i in range(nodes.shape[0]):
                r = onset_ratio(nodes[i] * dt, k, c)
                acc_y += weights[i] * r * complements[i]
                acc_o += weights[i] * r * nodes[i]
        else:
            for i in range(_GL_X.shape[0]):
                r = onset_ratio((m + _GL_X[i]) * dt, k, c)
                acc_y += _GL_W[i] * r * (1.0 - _GL_X[i])
                acc_o += _GL_W[i] * r * _GL_X[i]
        w_young[m] = acc_y
        w_old[m] = acc_o
    return ratio, w_young, w_old


@njit(cache=True)
def step_preloaded(sigma, offset, U, kt_old, kt_new, s_old, s_new, decay, w_old, w_new):
    """Advance the elements that were inside the zone at ``t = 0`` by one step (in place).

    ``offset = s0 - sigma`` (exact, from the mesh) and ``kt = k t``: ``s - sigma`` is formed as
    their sum, never as a difference of two nearly equal ``s`` and ``sigma``.
    """
    for i in range(sigma.shape[0]):
        sg = sigma[i]
        q_old = math.sqrt((offset[i] + kt_old) * (s_old + sg))
        q_new = math.sqrt((offset[i] + kt_new) * (s_new + sg))
        U[i] = decay * U[i] + w_old * q_old + w_new * q_new


@njit(cache=True)
def step_entered(sigma, U, n_born, step, s_old, s_new, k, decay, w_old, w_new):
    """Advance the elements that entered the zone at step boundaries by one step (in place).

    Element ``j`` entered at step ``j``; at step ``step`` its age is ``step - j`` steps.
    """
    for j in range(n_born):
        age = step - j
        sg = sigma[j]
        r_old = math.sqrt(k * (sg + s_old))
        r_new = math.sqrt(k * (sg + s_new))
        U[j] = decay * U[j] + w_old[age] * r_old + w_new[age] * r_new


@njit(cache=True)
def interval_width(sigma_a, sigma_b):
    """``x_b - x_a`` for ``x = sqrt(1 + sigma^2)``, without cancellation for thin zones."""
    return (sigma_b - sigma_a) * (sigma_b + sigma_a) / (
        math.sqrt(1.0 + sigma_a * sigma_a) + math.sqrt(1.0 + sigma_b * sigma_b))


@njit(cache=True)
def displacement_integral(sig_pre, offset_pre, U_pre, dx_pre, sig_born, U_born, dx_born,
                          n_born, S, kt, k_dt, ratio, w_young, w_old):
    """``int_1^b U(x) / sqrt(b^2 - x^2) dx`` over the free zone (units of ``delta``).

    The field is written ``U = sqrt(b^2 - x^2) v(x)``, so no quadrature node sits on the
    singular end point and the elastic limit (``v = 1/k``) is integrated exactly. Elements
    loaded since ``t = 0`` (ascending ``sigma < s0``) and the oldest entered one use a
    trapezoid on ``v`` in ``x``; the other entered ones (the last at ``b``, age 0) use
    :func:`age_interval_weights`. ``dx_pre[i]`` is the width in ``x`` of the interval ending
    at preloaded node ``i`` (``dx_pre[n_pre]``: the one ending at the oldest entered element),
    ``dx_born[j]`` that ending at entered element ``j``: node positions never change, so the
    widths are computed once, not every step. ``S - sigma`` comes from exact offsets:
    ``offset_pre + k t`` for preloaded elements, ``k dt age`` for entered ones (``kt``, ``k_dt``).
    """
    total = 0.0
    n_pre = sig_pre.shape[0]
    v_prev = 0.0
    for i in range(n_pre + 1):
        if i < n_pre:
            sg = sig_pre[i]
            u = U_pre[i]
            ahead = offset_pre[i] + kt
        else:
            sg = sig_born[0]
            u = U_born[0]
            ahead = kt
        if i == n_pre and n_born == 1:
            # The element at s0 is at b: k == 0 (b fixed, U/q the same everywhere) or t = 0.
            v = v_prev
        else:
            v = u / math.sqrt(ahead * (S + sg))
        if i > 0:
            total += 0.5 * (v + v_prev) * dx_pre[i]
        v_prev = v
    # Entered elements, youngest (age 0) last; g = v / R(age) is smooth.
    youngest = n_born - 1
    g_old = 0.0
    for j in range(n_born):
        age = youngest - j
        if j < youngest:
            g = U_born[j] / math.sqrt(k_dt * age * (S + sig_born[j])) / ratio[age]
        else:
            g = g_old  # R(0) = 0: take g from the element one step older
        if j > 0:
            total += dx_born[j] * (g * w_young[age] + g_old * w_old[age])
        g_old = g
    return total


@njit(cache=True)
def gap_from_integral(h, S, integral):
    """Gap at ``r = b`` in units of ``delta``: ``(2/pi) [h acos(1/b) - integral]``.

    ``h - (2/pi) h asin(a/b)`` is written as ``(2/pi) h atan(S)`` so that thin zones do not
    subtract two nearly equal numbers.
    """
    return (2.0 / math.pi) * (h * math.atan(S) - integral)


@njit(cache=True)
def march(sig_pre, offset_pre, U_pre, dx_pre, sig_born, U_born, dx_born, n_born, step,
          step_stop, k, c, h0, dt, decay, w_pre_old, w_pre_new, w_on_old, w_on_new, ratio,
          w_young, w_old, t_out, gap_out):
    """Advance the foundation from step ``step`` until the gap reaches 1 or ``step_stop``.

    ``sig_born``/``U_born``/``dx_born`` must have room for ``step_stop + 1`` elements (see
    :func:`displacement_integral` for ``dx_pre``/``dx_born``); a new element is
    placed at ``b`` after every step (``sigma = s(t)``), so element entries always fall on step
    boundaries. ``t_out``/``gap_out`` receive the time and gap after each step, indexed by
    step number. Returns ``(step, n_born, crossed)``.
    """
    while step < step_stop:
        t_old = step * dt
        t_new = (step + 1) * dt
        s_old = k * (h0 + t_old) + c
        s_new = k * (h0 + t_new) + c
        step_preloaded(sig_pre, offset_pre, U_pre, k * t_old, k * t_new, s_old, s_new, decay,
                       w_pre_old, w_pre_new)
        step_entered(sig_born, U_born, n_born, step, s_old, s_new, k, decay, w_on_old, w_on_new)
        step += 1
        if k > 0.0:
            sig_born[n_born] = s_new
            U_born[n_born] = 0.0
            dx_born[n_born] = interval_width(sig_born[n_born - 1], s_new)
            n_born += 1
        integral = displacement_integral(sig_pre, offset_pre, U_pre, dx_pre, sig_born, U_born,
                                         dx_born, n_born, s_new, k * t_new, k * dt, ratio,
                                         w_young, w_old)
        g = gap_from_integral(h0 + t_new, s_new, integral)
        t_out[step] = t_new
        gap_out[step] = g
        if g >= 1.0:
            return step, n_born, True
    return step, n_born, False
