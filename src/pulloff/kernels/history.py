"""Numba kernel of the SI history columns that the flat-punch onset solvers share
(:func:`pulloff.solvers.problem.si_history`).

A history of a few hundred rows cost ~0.7 us per numpy operation whatever its size: its
eight columns took ~40 numpy passes and the cohesive force's 30-term series
(:func:`pulloff.model.analytic.cohesive_force`) ~60 more, 25-50 us of a ~0.3 ms onset run.
Here all of them are one pass, row by row, with the same multiplications and additions in
the same order as the Python forms (``math.atan`` is the C library's in both; numba
contracts no multiply-add), so bit for bit: the tests compare them.
"""

from __future__ import annotations

import math

from numba import njit

#: Rows of :func:`flat_punch_columns`' output, in the order of the output table's history.
COLUMNS = ("t", "h", "a", "b", "gap", "F_contact", "F_total", "segment")
#: ``S`` below which the cohesive force is its series (``analytic._COH_SERIES_MAX_S``).
COH_SERIES_MAX_S = 0.5


@njit(cache=True)
def cohesive_bracket(S, coh_series):
    """``(1 + S^2) atan(S) - S`` for one ``S >= 0`` (``analytic._cohesive_force_scalar``):
    below ``S = 0.5`` its series (``coh_series``, in powers of ``S^2`` from ``S^3`` on,
    summed by Horner's rule from the highest term), where the direct form cancels."""
    if S < COH_SERIES_MAX_S:
        s2 = S * S
        acc = coh_series[coh_series.size - 1]
        for j in range(coh_series.size - 2, -1, -1):
            acc = acc * s2 + coh_series[j]
        return S * s2 * acc
    return (1.0 + S * S) * math.atan(S) - S


@njit(cache=True)
def flat_punch_columns(t, gap, k, c, h0_scaled, time_scale, h0, v, a, delta, G, eta,
                       sigma_c, coh_series, out):
    """The history of a flat punch with its bond radius fixed, in SI, into the rows of
    ``out`` (shape ``(8, t.size)``, rows :data:`COLUMNS`) from dimensionless times ``t`` and
    gaps ``gap``: the expressions of :class:`pulloff.solvers.problem.Problem`'s ``lift``,
    ``zone_end``, ``contact_force`` and of ``cohesive_force``, grouped as there. False where a
    zone end lies inside the bond (``b < a``: the caller raises as ``cohesive_force``)."""
    lift_rate = v * time_scale  # (as lift's v * T * t: the scalar product first)
    viscous = eta * v
    contact_scale = 8.0 * a
    zone_scale = 2.0 * sigma_c * a * a
    ok = True
    for i in range(t.size):
        h = h0 + lift_rate * t[i]
        s = k * (h0_scaled + t[i]) + c
        b = a * math.sqrt(1.0 + s * s)
        F_contact = contact_scale * (G * h + viscous)
        if b < a:  # (as cohesive_force's test: a nan passes)
            ok = False
        S = math.sqrt((b - a) * (b + a)) / a
        out[0, i] = t[i] * time_scale
        out[1, i] = h
        out[2, i] = a
        out[3, i] = b
        out[4, i] = gap[i] * delta
        out[5, i] = F_contact
        out[6, i] = F_contact + zone_scale * cohesive_bracket(S, coh_series)
        out[7, i] = 0.0
    return ok
