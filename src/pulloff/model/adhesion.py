"""Cohesive laws between the indenter and the half-space (MODEL.md section 1).

Adding a law is one class here with an :data:`ADHESIONS` row.
"""

from __future__ import annotations

import math
from typing import Literal, Optional

from pydantic import Field, model_validator

from .fields import Num, bad_line, fmt
from .registry import Kind, Registry

ADHESIONS = Registry("adhesion")


@ADHESIONS.register
class Dugdale(Kind):
    """Dugdale law: a uniform tensile stress ``sigma_c`` wherever the gap is below ``delta``;
    any two of sigma_c, delta, gamma, the third follows from gamma = sigma_c*delta."""

    kind: Literal["dugdale"] = Field(description="cohesive law, dugdale")
    sigma_c: Optional[Num] = Field(None, gt=0, description="Dugdale cohesive stress, Pa")
    delta: Optional[Num] = Field(None, gt=0, description="Dugdale range (critical gap), m")
    gamma: Optional[Num] = Field(None, gt=0, description="work of adhesion, J/m^2 = N/m")

    @model_validator(mode="after")
    def _resolve(self) -> Dugdale:
        s, d, g = self.sigma_c, self.delta, self.gamma
        given = [k for k in ("sigma_c", "delta", "gamma") if getattr(self, k) is not None]
        if len(given) < 2:
            missing = [k for k in ("sigma_c", "delta", "gamma") if k not in given]
            raise bad_line(", ".join("{p}" + k for k in missing) + ": missing (give any two of "
                           "sigma_c, delta, gamma" + "".join(
                               f"; got only {{p}}{k} = {fmt(getattr(self, k))}" for k in given) + ")")
        if g is None:
            g = s * d
        elif d is None:
            d = g / s
        elif s is None:
            s = g / d
        elif abs(g - s * d) > 1e-9 * max(g, s * d):
            # the product is rounded for display only: 6e6*1e-8 is 0.060000000000000005
            raise bad_line(f"{{p}}gamma = {fmt(g)}: inconsistent with sigma_c*delta = "
                           f"{fmt(float(f'{s * d:.12g}'))} (sigma_c = {fmt(s)}, delta = {fmt(d)})")
        for k, x in (("sigma_c", s), ("delta", d), ("gamma", g)):
            if k not in given and not (0 < x < math.inf):  # the product/quotient can over/underflow
                raise bad_line(f"{{p}}{k} = {fmt(x)}: derived from the other two, "
                               "not a positive finite float")
        # Given values are kept as written, so a resolved scene re-reads to the same numbers.
        self.sigma_c, self.delta, self.gamma = s, d, g
        return self
