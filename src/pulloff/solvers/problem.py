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

from ..kernels import closed_forms, history as history_kernels
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
        b = self.zone_end(t)
        if type(b) is not float:
            return F_contact, F_contact + analytic.cohesive_force(self.sigma_c, self.a, b)
        # One time, as analytic's scalar form, its 30-term series compiled (the same bits;
        # in Python ~4 us, and an onset run asks at three times).
        a = self.a
        if not b >= a:
            raise ValueError("cohesive_force needs b >= a")
        S = math.sqrt((b - a) * (b + a)) / a
        return F_contact, F_contact + 2.0 * self.sigma_c * a * a * history_kernels.cohesive_bracket(
            S, _COH_SERIES)


def si_history(problem: "Problem", t, gap) -> dict:
    """History columns in SI (:mod:`pulloff.model.outputs`) of the flat punch with its bond
    radius fixed, from dimensionless times and gaps (arrays of one shape). A rigid pull's
    in one compiled pass (:func:`pulloff.kernels.history.flat_punch_columns`, the bits of
    :func:`numpy_si_history`, which a subclass's own lift and zone take)."""
    if type(problem) is not Problem:
        return numpy_si_history(problem, t, gap)
    t = np.asarray(t, dtype=float)
    flat_t = t if t.ndim == 1 and t.flags.c_contiguous else np.ascontiguousarray(t.reshape(-1))
    flat_gap = np.ascontiguousarray(np.asarray(gap, dtype=float).reshape(-1))
    out = np.empty((len(history_kernels.COLUMNS), flat_t.size))
    p = problem
    if not history_kernels.flat_punch_columns(
            flat_t, flat_gap, p.k, p.c, p.h0_scaled, p.time_scale, p.h0, p.v, p.a, p.delta, p.G,
            p.eta, p.sigma_c, _COH_SERIES, out):
        raise ValueError("cohesive_force needs b >= a")
    if t.ndim == 1:  # (the rows as they are: eight reshapes were ~2 us)
        return dict(zip(history_kernels.COLUMNS, out))
    return {name: row.reshape(t.shape) for name, row in zip(history_kernels.COLUMNS, out)}


def numpy_si_history(problem: "Problem", t, gap) -> dict:
    """:func:`si_history` from the problem's own SI views, in numpy."""
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
        "F_total": F_contact + analytic.cohesive_force(problem.sigma_c, problem.a, b),
        "segment": np.zeros(np.shape(t)),  # a pull is one segment
    }


# The closed forms beside a run with their root solves compiled (pulloff.kernels.closed_forms,
# the same bits): in Python the solves were ~10 us of a ~0.3 ms onset run.
_F_SERIES = np.array(analytic._F_SERIES)
_COH_SERIES = np.array(analytic._COH_SERIES)
_G_SERIES = np.array(analytic._G_SERIES)


def compiled_t_star(alpha: float) -> float:
    """:func:`pulloff.model.analytic.seed_t_star` (dimensionless), its bracketed Newton
    compiled; the series (below 1e-4) and fixed point (above 100) stay in Python (cheap,
    and the fixed point's ``(t + 1) ** 2`` is the C library's ``pow``)."""
    if analytic._ALPHA_SERIES_MAX <= alpha <= analytic._ALPHA_FIXED_POINT_MIN:
        return closed_forms.root(closed_forms.SEED, alpha, 0.0, 0.0, math.inf, _F_SERIES)
    return analytic.seed_t_star(alpha)


def compiled_elastic_zone(chi: float) -> float:
    """The elastic onset's ``S`` for ``g(S) = chi > 0`` (dimensionless), compiled."""
    return closed_forms.root(closed_forms.ELASTIC, chi, 0.0, 0.0, math.inf, _G_SERIES)


def predictions(scene) -> dict:
    """:func:`pulloff.model.analytic.predictions` with the compiled root solves (SI)."""
    return analytic.predictions(scene, compiled_t_star, compiled_elastic_zone)
