"""Numba kernels of the moving-edge stepper: zone loads, element updates, the gap at b.

Lengths in units of the punch radius ``R`` (``xi = x/R - 1``), displacements in ``delta``; see
:mod:`pulloff.solvers.edge`. Kernels that call each other live in this one module.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def zone_load(xi, xi_b):
    """``sqrt(b^2 - x^2)`` for an element at ``xi``; 0 outside the zone."""
    ahead = xi_b - xi
    if ahead <= 0.0:
        return 0.0
    return math.sqrt(ahead * (2.0 + xi_b + xi))


@njit(cache=True)
def zone_loads(xi, lo, hi, xi_b, out):
    """:func:`zone_load` of elements ``lo .. hi - 1`` into ``out``."""
    for j in range(lo, hi):
        out[j] = zone_load(xi[j], xi_b)


@njit(cache=True)
def _angle_from_b(ahead, B):
    """``acos(x/b)`` for an element ``ahead = b - x`` inside the zone, without cancellation."""
    return 2.0 * math.asin(min(1.0, math.sqrt(0.5 * ahead / B)))


@njit(cache=True)
def edge_integral(xi, U_trial, lo, hi, xi_a, U_a, has_edge_node, xi_b):
    """``int_a^b U / sqrt(b^2 - x^2) dx`` with ``U`` linear in ``sqrt(b^2 - x^2)`` between
    nodes, integrated exactly against the weight (product integration: the ``1/sqrt(b - x)``
    end is exact, and a zone end between two nodes is handled by interpolation in ``x``).

    Nodes: ``(xi_a, U_a)`` first when ``has_edge_node`` (an element just released at the
    contact edge), then ``xi[lo:hi]`` with values ``U_trial[lo:hi]`` from the first one at or
    beyond ``a``. Elements beyond ``b`` only serve to interpolate ``U`` at ``b``.
    """
    B = 1.0 + xi_b
    total = 0.0
    have_prev = False
    x_prev = 0.0
    u_prev = 0.0
    if has_edge_node:
        x_prev = xi_a
        u_prev = U_a
        have_prev = True
    for j in range(lo, hi):
        x_j = xi[j]
        if x_j < xi_a:
            continue
        u_j = U_trial[j]
        if have_prev:
            x_end = x_j
            u_end = u_j
            last = False
            if x_j >= xi_b:
                # The zone ends inside this interval: U at b by interpolation.
                span = x_j - x_prev
                u_end = u_prev + (u_j - u_prev) * ((xi_b - x_prev) / span) if span > 0 else u_j
                x_end = xi_b
                last = True
            # U is interpolated linearly in r = sqrt(b^2 - x^2), not in x: a relaxed element
            # near b carries U ~ r, which is then exact (linear in x it would cost a first-
            # order error in the last interval), and a U smooth in x is smooth in r.
            # int U dx / r = int U dr / x = alpha (theta1 - theta2) + beta (x_end - x_prev)
            # for U = alpha + beta r, with theta = acos(x/b) = asin(r/b).
            d1 = xi_b - x_prev
            d2 = xi_b - x_end
            m0 = _angle_from_b(d1, B) - _angle_from_b(d2, B)
            r1 = math.sqrt(d1 * (2.0 * B - d1))
            r2 = math.sqrt(d2 * (2.0 * B - d2)) if d2 > 0.0 else 0.0
            if r1 > r2:
                beta = (u_prev - u_end) / (r1 - r2)
                total += u_end * m0 + beta * ((x_end - x_prev) - r2 * m0)
            if last:
                return total
        x_prev = x_j
        u_prev = u_j
        have_prev = True
    if have_prev and x_prev < xi_b:
        # The zone has grown past the last node: U = 0 at b, where the load is zero and no
        # element has been yet.
        d1 = xi_b - x_prev
        r1 = math.sqrt(d1 * (2.0 * B - d1))
        total += (u_prev / r1) * d1
    return total


@njit(cache=True)
def trial_displacements(base, lo, hi, xi, xi_b, w_new, out):
    """Displacements after one step for a trial zone end ``xi_b`` (into ``out``):
    ``base + w_new q(t + dt)``, the part of the step that does not depend on the new load
    (``base``) being computed once per step by :func:`kv_base` or :func:`maxwell_base`."""
    for j in range(lo, hi):
        out[j] = base[j] + w_new * zone_load(xi[j], xi_b)


@njit(cache=True)
def kv_base(U, q_old, lo, hi, decay, w_old, base):
    """Kelvin-Voigt: ``decay U + w_old q(t)`` of the exact step with the load linear."""
    for j in range(lo, hi):
        base[j] = decay * U[j] + w_old * q_old[j]


@njit(cache=True)
def maxwell_base(E, q_old, lo, hi, phi, gamma_old, k_arms, k_total, E_pred, base):
    """Generalised Maxwell (standard linear solid, Prony series) under a load linear over the
    step: the dashpot displacements advance as ``E_pred = phi E + gamma_old q(t)`` (plus
    ``gamma_new q(t + dt)`` once the new load is known), and ``base = k_arms . E_pred /
    k_total`` is the part of ``U = (q + k_arms . E) / k_total`` that does not depend on it."""
    m = k_arms.shape[0]
    for j in range(lo, hi):
        acc = 0.0
        for i in range(m):
            e = gamma_old[i] * q_old[j]
            for l in range(m):
                e += phi[i, l] * E[j, l]
            E_pred[j, i] = e
            acc += k_arms[i] * e
        base[j] = acc / k_total


@njit(cache=True)
def trial_gap(base, lo, hi, xi, xi_a, has_edge_node, U_a, xi_b, h, ell, w_new, scratch):
    """Gap at ``r = b`` (units of delta) after one step, for a trial contact edge ``xi_a`` and
    zone end ``xi_b``: ``h - (2/pi) [h asin(a/b) + int_a^b U/sqrt(b^2 - x^2) dx]``, written
    with ``acos(a/b) = atan2(sqrt(b^2 - a^2), a)`` (``ell`` is ``sqrt(b^2 - a^2)``)."""
    trial_displacements(base, lo, hi, xi, xi_b, w_new, scratch)
    integral = edge_integral(xi, scratch, lo, hi, xi_a, U_a, has_edge_node, xi_b)
    a = 1.0 + xi_a
    return (2.0 / math.pi) * (h * math.atan2(ell, a) - integral)
