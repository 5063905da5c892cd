"""A flat-punch pull reduced to numbers, and the scales both flat-punch solvers share.

Lengths along the foundation in units of the punch radius ``a``, displacements, lift and gap in
``delta``, time in ``T = delta / v``. Then the Kelvin-Voigt element reads
``k U + c dU/dt = q`` with ``k = 2 G delta / (sigma_c a)``, ``c = 2 eta v / (sigma_c a)`` and
``q`` the line load in units of ``2 sigma_c a``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..kernels import history as history_kernels
from ..model import analytic


@dataclass(frozen=True)
class Problem:
    """A flat-punch pull (SI in the fields, dimensionless through the properties; the
    scalar ones computed once: an onset run reads them ~20 times)."""

    G: float  # Pa (the relaxed modulus G_inf of a Maxwell solid)
    eta: float  # Pa s
    sigma_c: float  # Pa
    delta: float  # m
    a: float  # m
    v: float  # m/s
    h0: float = 0.0  # m
    #: Maxwell arms ``((G_i [Pa], tau_i [s]), ...)`` of a standard linear solid or Prony
    #: series; ``G`` is then the relaxed modulus ``G_inf`` and ``eta`` is 0.
    arms: tuple = ()

    @classmethod
    def from_scene(cls, scene) -> "Problem":
        spectrum = scene.material.spectrum()
        return cls(G=spectrum.G_inf, eta=spectrum.eta, sigma_c=scene.adhesion.sigma_c,
                   delta=scene.adhesion.delta, a=scene.geometry.radius, v=scene.loading.v,
                   h0=scene.loading.h0, arms=tuple(spectrum.arms))

    @property
    def arm_stiffness(self) -> np.ndarray:
        """Dimensionless ``k_i = 2 G_i delta / (sigma_c a)`` of the Maxwell arms."""
        return np.array([2.0 * G * self.delta / (self.sigma_c * self.a) for G, _ in self.arms])

    @property
    def arm_times(self) -> np.ndarray:
        """Dimensionless relaxation times ``tau_i v / delta`` of the Maxwell arms."""
        return np.array([tau / self.time_scale for _, tau in self.arms])

    @functools.cached_property
    def k(self) -> float:
        """Dimensionless foundation stiffness ``2 G delta / (sigma_c a)``."""
        return 2.0 * self.G * self.delta / (self.sigma_c * self.a)

    @functools.cached_property
    def c(self) -> float:
        """Dimensionless foundation damping ``2 eta v / (sigma_c a)``."""
        return 2.0 * self.eta * self.v / (self.sigma_c * self.a)

    @functools.cached_property
    def time_scale(self) -> float:
        """``T = delta / v`` [s]: the time to lift the punch by one Dugdale length."""
        return self.delta / self.v

    @functools.cached_property
    def h0_scaled(self) -> float:
        return self.h0 / self.delta

    @property
    def groups(self) -> dict:
        """The seed's ``alpha``, ``chi``, ``V`` (MODEL.md section 4)."""
        return analytic.dimensionless_groups(self.G, self.eta, self.sigma_c, self.delta, self.a,
                                             self.v)

    def s_of(self, t):
        """``sqrt(b^2 - a^2) / a`` at dimensionless time ``t`` (edge condition)."""
        return self.k * (self.h0_scaled + t) + self.c

    # --- SI views of a dimensionless time -------------------------------------------------
    def lift(self, t):
        """Punch lift ``h`` [m] at dimensionless time ``t``."""
        # (a float stays one: the same operations without numpy, every level's outputs)
        t = t if type(t) is float else np.asarray(t, dtype=float)
        return self.h0 + self.v * self.time_scale * t

    def zone_end(self, t):
        """Cohesive-zone end ``b`` [m] at dimensionless time ``t``."""
        scalar = type(t) is float
        s = self.s_of(t if scalar else np.asarray(t, dtype=float))
        return self.a * (math.sqrt if scalar else np.sqrt)(1.0 + s * s)

    def contact_force(self, t):
        """``F_contact = 8 a (G h + eta dh/dt)`` [N] (eq. 48)."""
        return 8.0 * self.a * (self.G * self.lift(t) + self.eta * self.v)

    def total_force(self, t):
        """``F_contact`` plus the cohesive zone's own force [N] (MODEL.md section 3)."""
        return self.forces(t)[1]

    def forces(self, t):
        """``(F_contact, F_total)`` [N] at dimensionless time ``t``: the contact force computed
        once for both (an onset run wants both at three times)."""
        F_contact = self.contact_force(t)
        return F_contact, F_contact + analytic.cohesive_force(self.sigma_c, self.a,
                                                              self.zone_end(t))


def si_history(problem: "Problem", t, gap) -> dict:
    """History columns in SI (:mod:`pulloff.model.outputs`) of the flat punch with its bond
    radius fixed, from dimensionless times and gaps."""
    b = problem.zone_end(t)
    F_contact = problem.contact_force(t)
    return {
        "t": t * problem.time_scale,
        "h": problem.lift(t),
        "a": np.full(np.shape(t), problem.a),
        "b": b,
        "gap": gap * problem.delta,
        "F_contact": F_contact,
        # (total_force's own sum, without computing b and F_contact again)
        "F_total": F_contact + analytic.cohesive_force(problem.sigma_c, problem.a, b,
                                                       horner=compiled_horner),
        "segment": np.zeros(np.shape(t)),  # a pull is one segment
    }


#: Coefficient lists of :func:`compiled_horner` as arrays, by ``id`` (with the list itself, so
#: that an id is never reused for another list while it is here).
_COEFFICIENT_ARRAYS: dict = {}


def compiled_horner(coeffs, x) -> np.ndarray:
    """:func:`pulloff.model.analytic._horner` compiled (:func:`pulloff.kernels.history.horner`:
    the same operations, so the same bits): ``sum_j coeffs[j] x^j`` for an array ``x``."""
    entry = _COEFFICIENT_ARRAYS.get(id(coeffs))
    if entry is None or entry[0] is not coeffs:
        entry = _COEFFICIENT_ARRAYS[id(coeffs)] = (coeffs, np.array(coeffs, dtype=float))
    x = np.ascontiguousarray(x, dtype=float)
    out = np.empty(x.shape)
    history_kernels.horner(entry[1], x.reshape(-1), out.reshape(-1))
    return out
