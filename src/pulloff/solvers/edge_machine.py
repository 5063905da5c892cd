"""The lift of a flat punch pulled through a machine spring past its onset, for the edge
quadrature (:mod:`.edge_quadrature`): a Kelvin-Voigt (or elastic) solid, the zone outside
(the spring starts relaxed at no lift: a scene refuses ``loading.h0`` with it).

In the kernels' units (lengths in ``R``, the lift ``H`` in ``delta``, time in ``delta / v``,
the bonded load ``ell = L / (2 sigma_c R)``, which the edge condition makes
``sqrt(b^2 - a^2)``) the spring, its driver at ``t``, holds the whole line load,

    kappa (t - H) = f(a, ell) = a ell + b^2 atan2(ell, a),      b^2 = a^2 + ell^2

(``F_total = 2 sigma_c R^2 f``, ``kappa = k_m delta / (2 sigma_c R^2)``), and the bonded
elements follow the punch: ``ell = k H + c dH/dt``.

- **Before the onset** the lift and ``ell`` are :mod:`.machine_lift`'s path.
- **While the bond recedes** (``a`` marched) the lift is the exponential integral over the
  last step, ``H_n = e^(-k dt/c) H_(n-1) + (1/c) int e^(-k (t_n - s)/c) ell(s) ds``, with
  ``ell`` the history's interpolant through the trial node: an Adams-Moulton rule with the
  solid's own relaxation exact, zero-stable for any ratio of steps (differentiating the lift
  instead, as a BDF rule does, is not at degree 5 with the march's doubling steps). One
  scalar Newton on ``ell_n`` with the force balance.
- **The zone alone** (``a = 0``) holds the punch by its stress only, so the punch moves with
  it: ``H = t - (pi/2) b^2 / kappa``. The gap's formula then needs only some virtual
  element's load history (the bonded load until ``a = 0``); frozen there, as the moving-edge
  reference does, the gap gains ``H - U_r``, with ``U_r`` that element's creep under it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..kernels import quadrature as kernels
from .machine_lift import machine_pull, spring_to_solid
from .problem import Problem

#: Gauss points of the last step's exponential integral (the interpolant is of degree 5).
_GAUSS = np.polynomial.legendre.leggauss(8)
_GX, _GW = 0.5 * (_GAUSS[0] + 1.0), 0.5 * _GAUSS[1]


@dataclass
class Machine:
    """A pull through a machine spring in the kernels' units: ``kappa``, the lift law
    ``ell = k H + c dH/dt`` and the lift path before the onset (rows: nodes, ``H``, ``ell``
    on ``sqrt(t / span)``), with the spring's stiffness [N/m] and the path's estimate."""

    kappa: float
    k: float
    c: float
    path: np.ndarray
    span: float
    stiffness: float  # N/m
    path_error: float  # the lift path's estimate, relative (machine_lift.machine_pull)

    @classmethod
    def from_scene(cls, scene, t_limit: float) -> "Machine":
        """The machine and the lift path to past the onset (``ValueError`` where
        :func:`.machine_lift.machine_pull` finds none)."""
        problem = Problem.from_scene(scene)
        stiffness = scene.loading.machine_stiffness
        pull, _, _, path_error = machine_pull(problem, stiffness, t_limit,
                                              min(scene.numerics.rtol, 1e-6))
        kappa = stiffness * problem.delta / (2.0 * problem.sigma_c * problem.a ** 2)
        return cls(kappa, problem.k, problem.c, pull.path, pull.span, stiffness, path_error)

    def law_array(self) -> np.ndarray:
        """The kernels' ``rh`` for ``ell`` before the onset (:func:`kernels.ell_of`)."""
        return np.concatenate(([math.nan, self.span, self.path.shape[1]], self.path.ravel()))

    def lift_before(self, t: float) -> float:
        return kernels.path_value(self.path, 1, self.span, t)

    def lift_alone(self, t: float, b2: float) -> float:
        """The lift while the zone alone holds the punch (``b2 = b^2``)."""
        return t - 0.5 * math.pi * b2 / self.kappa

    def virtual_lift(self, t: float, t_zero: float, lift_zero: float, ell_zero: float) -> float:
        """``U_r``: the displacement of an element that followed the punch until
        ``t_zero`` and then kept its load ``ell_zero``."""
        if self.c == 0.0:
            return lift_zero
        if self.k == 0.0:  # (a viscous solid creeps at a constant rate)
            return lift_zero + ell_zero * (t - t_zero) / self.c
        rest = ell_zero / self.k
        return rest + (lift_zero - rest) * math.exp(-self.k * (t - t_zero) / self.c)

    def receding(self, hist: np.ndarray, lifts: np.ndarray, first: int, i: int) -> tuple:
        """``(ell, H)`` at trial node ``i`` of the receding bond (``hist`` rows 0-2 set
        there, ``ell`` and ``H`` at the piece's earlier nodes from ``first``):
        :func:`kernels.receding_lift`."""
        return kernels.receding_lift(hist, lifts, first, i, self.kappa, self.k, self.c,
                                     _GX, _GW)


def problems(scene, limit: float) -> list:
    """Why the edge quadrature cannot pull this scene through its machine spring (empty:
    it can): ``(key, value, reason)``."""
    out = []
    kind = scene.material.kind
    if kind not in ("elastic", "kelvin_voigt"):
        out.append(("material.kind", kind, "behind a machine spring the edge quadrature "
                    "takes an elastic or Kelvin-Voigt solid"))
    if scene.geometry.cohesive_zone != "external":
        out.append(("geometry.cohesive_zone", scene.geometry.cohesive_zone,
                    "behind a machine spring the edge quadrature puts the zone outside"))
    if not out:
        ratio = spring_to_solid(Problem.from_scene(scene), scene.loading.machine_stiffness)
        if ratio > limit:
            out.append(("loading.machine_stiffness", scene.loading.machine_stiffness,
                        f"the spring is {ratio:.2g} times stiffer than the solid at the "
                        f"start ({limit:g} at most for the edge quadrature)"))
    return out
