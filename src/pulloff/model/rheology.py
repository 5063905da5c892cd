"""Rheologies of the half-space: each maps element by element in MDR (MODEL.md section 6).

A rheology is its shear relaxation modulus ``G(t) = G_inf + eta delta(t) + sum_i G_i
exp(-t/tau_i)`` (:class:`Spectrum`). Every foundation element of width ``dx`` then obeys
``q = 4 int G(t - s) du(s)`` (a line load per unit length). Two element laws cover every kind:
Kelvin-Voigt (``eta``, no arms; elastic is ``eta = 0``) and the generalised Maxwell solid (arms,
no ``eta``). Adding a rheology is one class here with a :data:`RHEOLOGIES` row; it need only
say what its spectrum is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np
from pydantic import Field, model_validator
from scipy.optimize import brentq

from .fields import Num, bad_line
from .registry import Kind, Registry

RHEOLOGIES = Registry("material")


@dataclass(frozen=True)
class Spectrum:
    """``G(t) = G_inf + eta delta(t) + sum G_i exp(-t/tau_i)``; SI (Pa, Pa s, s)."""

    G_inf: float  # Pa, relaxed modulus
    eta: float = 0.0  # Pa s, Kelvin-Voigt damper
    arms: tuple = ()  # ((G_i [Pa], tau_i [s]), ...), Maxwell arms

    @property
    def instantaneous_modulus(self) -> float:
        """``G(0+)`` [Pa]: what a step in displacement meets first (inf behind a damper)."""
        if self.eta > 0.0:
            return math.inf
        return self.G_inf + sum(G for G, _ in self.arms)

    @property
    def law(self) -> str:
        """The element law that integrates this spectrum: ``kelvin_voigt`` or ``maxwell``."""
        return "maxwell" if self.arms else "kelvin_voigt"

    @property
    def relaxation_times(self) -> tuple:
        """Every time scale of the spectrum [s] (``eta/G_inf`` for Kelvin-Voigt)."""
        if self.arms:
            return tuple(tau for _, tau in self.arms)
        if self.eta > 0.0 and self.G_inf > 0.0:
            return (self.eta / self.G_inf,)
        return ()

    def creep(self) -> tuple:
        """The shear creep compliance ``J(t) = J(0) + int_0^t J'`` (``J * G = t``), as
        ``(J(0) [1/Pa], rates [1/s], weights [1/(Pa s)])`` with ``J'(t) = sum_k weights_k
        exp(-rates_k t)``. Its rates are the roots of ``s G^(s) = 0`` on the negative axis, one
        between each two arms' rates, one below the slowest (``G_inf > 0``), one above the
        fastest behind a damper; a viscous solid (``G_inf = 0``) creeps at the rate 0."""
        if not self.arms:
            if self.eta == 0.0:
                return 1.0 / self.G_inf, np.zeros(0), np.zeros(0)
            return 0.0, np.array([self.G_inf / self.eta]), np.array([1.0 / self.eta])
        G = np.array([g for g, _ in self.arms])
        mu = np.array([1.0 / tau for _, tau in self.arms])
        G, mu = G[np.argsort(mu)], np.sort(mu)

        def s_modulus(lam):  # s G^(s) at s = -lam, between the poles -mu_i
            return self.G_inf - float(np.sum(G * lam / (mu - lam)))

        rates = []
        below = 0.0
        for m in mu:
            # s G^(s) runs from +inf (or G_inf at 0) down to -inf between two poles
            gap = 1e-14 * m
            rates.append(brentq(s_modulus, below + (gap if below else 0.0), m - gap,
                                xtol=1e-300, rtol=4.0 * np.finfo(float).eps))
            below = m
        rates = np.array(rates)
        slope = np.array([np.sum(G * mu / (mu - lam) ** 2) for lam in rates])
        return 1.0 / self.instantaneous_modulus, rates, 1.0 / slope

    def modulus(self, t):
        """``G(t)`` [Pa] for ``t > 0`` (the damper's delta excluded)."""
        t = np.asarray(t, dtype=float)
        return self.G_inf + sum(G * np.exp(-t / tau) for G, tau in self.arms)


class Rheology(Kind):
    """A half-space material (incompressible: ``E* = 4 G``)."""

    def spectrum(self) -> Spectrum:
        raise NotImplementedError


@RHEOLOGIES.register
class Elastic(Rheology):
    """Linear elastic half-space."""

    kind: Literal["elastic"] = Field(description="rheology: elastic")
    example: ClassVar[dict] = {"G": 1e6}
    G: Num = Field(gt=0, description="shear modulus, Pa")

    def spectrum(self) -> Spectrum:
        return Spectrum(self.G)


@RHEOLOGIES.register
class KelvinVoigt(Rheology):
    """Spring ``G`` parallel to a damper ``eta`` (the seed's solid)."""

    kind: Literal["kelvin_voigt"] = Field(description="rheology: kelvin_voigt")
    example: ClassVar[dict] = {"G": 1e6, "eta": 1e3}
    G: Num = Field(ge=0, description="shear modulus, Pa")
    eta: Num = Field(ge=0, description="shear viscosity, Pa s")

    @model_validator(mode="after")
    def _has_stiffness(self) -> KelvinVoigt:
        if self.G == 0 and self.eta == 0:
            raise bad_line("{p}G = 0.0, {p}eta = 0.0: both zero "
                           "(need G > 0 or eta > 0; a half-space with neither has no stiffness)")
        return self

    def spectrum(self) -> Spectrum:
        return Spectrum(self.G, self.eta)


@RHEOLOGIES.register
class StandardLinearSolid(Rheology):
    """Relaxed spring ``G_inf`` parallel to one Maxwell arm (spring ``G_1``, time ``tau_1``)."""

    kind: Literal["standard_linear_solid"] = Field(description="rheology: standard_linear_solid")
    example: ClassVar[dict] = {"G_inf": 1e6, "G_1": 9e6, "tau_1": 1e-3}
    G_inf: Num = Field(gt=0, description="relaxed (long-time) shear modulus, Pa")
    G_1: Num = Field(gt=0, description="shear modulus of the Maxwell arm, Pa")
    tau_1: Num = Field(gt=0, description="relaxation time of the Maxwell arm, s")

    def spectrum(self) -> Spectrum:
        return Spectrum(self.G_inf, 0.0, ((self.G_1, self.tau_1),))


class PronyTerm(Kind):
    """One Maxwell arm of a Prony series: a spring G in series with a damper G tau."""

    G: Num = Field(gt=0, description="shear modulus of the arm, Pa")
    tau: Num = Field(gt=0, description="relaxation time of the arm, s")


@RHEOLOGIES.register
class Prony(Rheology):
    """Generalised Maxwell solid: ``G_inf`` and any number of arms."""

    kind: Literal["prony"] = Field(description="rheology: prony")
    example: ClassVar[dict] = {"G_inf": 1e6, "terms": [{"G": 4e6, "tau": 1e-4},
                                                       {"G": 5e6, "tau": 1e-2}]}
    G_inf: Num = Field(gt=0, description="relaxed (long-time) shear modulus, Pa")
    terms: list[PronyTerm] = Field(min_length=1,
                                   description="Maxwell arms of the Prony series, list of {G, tau}")

    def spectrum(self) -> Spectrum:
        return Spectrum(self.G_inf, 0.0, tuple((term.G, term.tau) for term in self.terms))
