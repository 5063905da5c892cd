"""Loading protocols: how the indenter is driven (MODEL.md sections 1 and 9).

A protocol is data: the solvers read its segments, they do not contain it. Adding a protocol
(or a segment kind) is one class here with a :data:`LOADINGS` row.
"""

from __future__ import annotations

from typing import Literal, Optional

from pydantic import Field, model_validator

from .fields import Num, bad_line, fmt
from .registry import Kind, Registry

LOADINGS = Registry("loading")


@LOADINGS.register
class ConstantVelocity(Kind):
    """The driver moves as ``h0 + v t``; the indenter follows it rigidly, or through a spring."""

    kind: Literal["constant_velocity"] = Field(description="loading protocol, constant_velocity")
    v: Num = Field(gt=0, description="lift velocity, m/s")
    h0: Num = Field(0.0, ge=0, description="initial lift, m")
    machine_stiffness: Optional[Num] = Field(
        None, gt=0, description="stiffness of the spring between driver and punch, N/m; "
                                "null: a rigid machine")

    @model_validator(mode="after")
    def _spring_starts_relaxed(self) -> ConstantVelocity:
        if self.machine_stiffness is not None and self.h0 != 0:
            raise bad_line(f"{{p}}h0 = {fmt(self.h0)}: with {{p}}machine_stiffness the "
                           "spring starts relaxed at h = 0; a step lift h0 is not defined")
        return self
