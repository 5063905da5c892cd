"""Rigid axisymmetric indenters (MODEL.md sections 3, 6 and 9).

An indenter is its surface ``z = h + f(r)`` and, through MDR, its 1D profile
``g(x) = |x| int_0^|x| f'(r) / sqrt(x^2 - r^2) dr``. Adding an indenter is one class here with a
:data:`GEOMETRIES` row.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from pydantic import Field

from .fields import Num
from .registry import Kind, Registry

GEOMETRIES = Registry("geometry")


class Geometry(Kind):
    """A rigid indenter."""


@GEOMETRIES.register
class FlatPunch(Geometry):
    """Rigid flat punch bonded over the disc r < radius (``f = 0`` on the face)."""

    kind: Literal["flat_punch"] = Field(description="indenter: flat_punch")
    radius: Num = Field(gt=0, description="punch (contact) radius a, m")
    cohesive_zone: Literal["external", "internal"] = Field(
        "external", description="cohesive zone outside the punch (the seed's virtual crack) or "
                                "on its face (b <= radius), no unit")


def kappa_n(n: float) -> float:
    """MDR factor of a power-law profile: ``g = kappa_n A x^n`` for ``f = A r^n``,
    ``kappa_n = sqrt(pi) Gamma(n/2 + 1) / Gamma(n/2 + 1/2)`` (MODEL.md section 9)."""
    return math.sqrt(math.pi) * math.exp(math.lgamma(n / 2.0 + 1.0) - math.lgamma(n / 2.0 + 0.5))


class PowerLawShape(Geometry):
    """A smooth indenter ``f = A r^n`` (sphere, cone, power law); subclasses say ``A`` and
    ``n``."""

    def power_law(self) -> tuple[float, float]:
        """``(A [m^(1-n)], n)`` of ``f = A r^n``."""
        raise NotImplementedError

    def f(self, r):
        """Profile height ``f(r)`` [m] above the tip."""
        A, n = self.power_law()
        return A * np.abs(np.asarray(r, dtype=float)) ** n

    def g(self, x):
        """MDR profile ``g(x)`` [m]."""
        A, n = self.power_law()
        return kappa_n(n) * A * np.abs(np.asarray(x, dtype=float)) ** n


@GEOMETRIES.register
class Sphere(PowerLawShape):
    """A sphere (paraboloid) of radius ``R``: ``f = r^2 / (2 R)``."""

    kind: Literal["sphere"] = Field(description="indenter: sphere")
    radius: Num = Field(gt=0, description="sphere radius R, m")

    def power_law(self):
        return 0.5 / self.radius, 2.0


@GEOMETRIES.register
class Cone(PowerLawShape):
    """A cone: ``f = slope r`` (slope = tan of the angle between flank and surface)."""

    kind: Literal["cone"] = Field(description="indenter: cone")
    slope: Num = Field(gt=0, le=100.0, description="tan of the flank angle, dimensionless")

    def power_law(self):
        return self.slope, 1.0


@GEOMETRIES.register
class PowerLaw(PowerLawShape):
    """``f = coefficient r^exponent`` (SI: the coefficient has units m^(1 - exponent))."""

    kind: Literal["power_law"] = Field(description="indenter: power_law")
    coefficient: Num = Field(gt=0, description="A of f = A r^n, m^(1-n)")
    exponent: Num = Field(ge=0.5, le=20.0, description="n of f = A r^n, dimensionless")

    def power_law(self):
        return self.coefficient, self.exponent
