"""Rigid axisymmetric indenters (MODEL.md sections 3, 6 and 9).

An indenter is its surface ``z = h + f(r)`` and, through MDR, its 1D profile
``g(x) = |x| int_0^|x| f'(r) / sqrt(x^2 - r^2) dr``. Adding an indenter is one class here with a
:data:`GEOMETRIES` row.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Literal, Optional

import numpy as np
from pydantic import Field, ValidationInfo, model_serializer, model_validator
from pydantic_core import PydanticCustomError

from .fields import Num, bad, bad_line, fmt
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


def _read_table(path: Path) -> tuple[list, list]:
    """Two numeric columns ``r [m], f [m]`` from a CSV/whitespace file (``#`` comments and one
    header line allowed); a bad line is an error naming the file and the line."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as e:
        raise bad(f"cannot read {path} ({getattr(e, 'strerror', None) or e})") from None
    r, f = [], []
    for number, line in enumerate(lines, 1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        cells = [c for c in re.split(r"[,;\s]+", text) if c]
        try:
            values = [float(c) for c in cells]
        except ValueError:
            if not r and number == next(i for i, ln in enumerate(lines, 1)
                                         if ln.split("#", 1)[0].strip()):
                continue  # a header line
            raise bad(f"{path}, line {number}: {text!r} is not two numbers (r [m], f [m])") \
                from None
        if len(values) != 2 or not all(math.isfinite(v) for v in values):
            raise bad(f"{path}, line {number}: {text!r} is not two finite numbers "
                      "(r [m], f [m])")
        r.append(values[0])
        f.append(values[1])
    return r, f


def _check_table(r: list, f: list, where: str) -> None:
    if len(r) < 2:
        raise bad(f"{where}: needs at least two points (r, f)")
    if r[0] != 0.0 or f[0] != 0.0:
        raise bad(f"{where}: the first point must be r = 0, f = 0 (the tip), not "
                  f"({fmt(r[0])}, {fmt(f[0])})")
    for i in range(1, len(r)):
        if not r[i] > r[i - 1]:
            raise bad(f"{where}: r must increase strictly; point {i + 1} has r = {fmt(r[i])} "
                      f"after {fmt(r[i - 1])}")
        if f[i] < 0.0:
            raise bad(f"{where}: point {i + 1} has f = {fmt(f[i])} < 0 (the tip is the lowest "
                      "point)")


@GEOMETRIES.register
class Profile(Geometry):
    """A measured tip: ``f(r)`` tabulated (linear in between, the last slope beyond), from a
    file (``path``: two columns r [m], f [m]) or given inline (``r``, ``f``)."""

    kind: Literal["profile"] = Field(description="indenter: profile (a tabulated tip)")
    path: Optional[str] = Field(None, min_length=1,
                                description="file with two columns r [m], f [m], relative to "
                                            "the scene file, text")
    r: Optional[list[Num]] = Field(None, description="radii of the table, m")
    f: Optional[list[Num]] = Field(None, description="heights of the table above the tip, m")

    @model_validator(mode="before")
    @classmethod
    def _load(cls, data, info: ValidationInfo):
        if not isinstance(data, dict) or data.get("path") is None:
            return data
        if data.get("r") is not None or data.get("f") is not None:
            raise bad_line("{p}path: give either a file or r and f, not both")
        base = (info.context or {}).get("base") if info is not None else None
        path = Path(data["path"])
        if not path.is_absolute() and base is not None:
            path = Path(base) / path
        try:
            r, f = _read_table(path)
            _check_table(r, f, str(path))
        except PydanticCustomError as e:
            raise bad_line(f"{{p}}path = {fmt(data['path'])}: {e.context['reason']}") from None
        return {**data, "r": r, "f": f}

    @model_validator(mode="after")
    def _table(self) -> Profile:
        if self.r is None or self.f is None:
            raise bad_line("{p}r, {p}f: missing (give path: FILE, or r: [...] and f: [...])")
        if len(self.r) != len(self.f):
            raise bad_line(f"{{p}}r, {{p}}f: {len(self.r)} and {len(self.f)} values; need as "
                           "many of each")
        try:
            _check_table(self.r, self.f, "the table")
        except PydanticCustomError as e:
            raise bad_line("{p}r, {p}f: " + e.context["reason"]) from None
        return self

    @model_serializer(mode="wrap")
    def _inline(self, handler):
        # The resolved scene carries the table itself, so a result file reproduces itself.
        data = handler(self)
        data["path"] = None
        return data

    def ramps(self) -> tuple[np.ndarray, np.ndarray]:
        """``(knots [m], slope changes)``: ``f = sum_j s_j (r - r_j)_+`` (the last slope continues
        beyond the table)."""
        r, f = np.asarray(self.r, dtype=float), np.asarray(self.f, dtype=float)
        slopes = np.diff(f) / np.diff(r)
        jumps = np.diff(np.concatenate([[0.0], slopes]))
        keep = jumps != 0.0
        return r[:-1][keep], jumps[keep]

    def f_of(self, r):
        """Profile height ``f(r)`` [m] of the interpolant."""
        k, s = self.ramps()
        r = np.asarray(r, dtype=float)
        return np.maximum(r[..., None] - k, 0.0) @ s
