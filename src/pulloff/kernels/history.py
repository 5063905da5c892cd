"""Numba kernels of the SI history columns that the flat-punch onset solvers share
(:func:`pulloff.solvers.problem.si_history`).

A history of a few hundred rows costs ~0.7 us per numpy operation whatever its size; the
cohesive force's 30-term series (:func:`pulloff.model.analytic.cohesive_force`) took ~60 of
them, ~45 us of a ~0.4 ms onset run. Compiled, it is the same multiplications and additions
in the same order (no fused multiply-add: numba does not contract them), so bit for bit.
"""

from __future__ import annotations

from numba import njit


@njit(cache=True)
def horner(coeffs, x, out):
    """``out[i] = sum_j coeffs[j] x[i]^j`` by Horner's rule from the highest coefficient,
    the operations of :func:`pulloff.model.analytic._horner` in its order (1-d arrays).
    Coefficient by coefficient over all of ``x``, as numpy does: the inner loop runs in
    SIMD lanes (5x faster than element by element, each element's sum a chain of 30)."""
    top = coeffs.size - 1
    for i in range(x.size):
        out[i] = coeffs[top]
    for j in range(top - 1, -1, -1):
        c = coeffs[j]
        for i in range(x.size):
            out[i] = out[i] * x[i] + c
