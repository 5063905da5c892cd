"""Rigid axisymmetric indenters (MODEL.md sections 3, 6 and 9).

An indenter is its surface ``z = h + f(r)`` and, through MDR, its 1D profile
``g(x) = |x| int_0^|x| f'(r) / sqrt(x^2 - r^2) dr``. Adding an indenter is one class here with a
:data:`GEOMETRIES` row.
"""

from __future__ import annotations

from typing import Literal

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
