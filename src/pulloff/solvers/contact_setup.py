"""A scene reduced to the contact stepper's dimensionless numbers.

Scales: lengths along the surface in ``L`` (the punch radius, or where a smooth profile rises by
``delta``: ``f(L) = delta``), displacements, lifts and gaps in ``delta``, time in ``T`` (``delta``
over the first speed of the loading), line loads in ``2 sigma_c L`` and forces in
``sigma_c L^2``. Then a free element carries ``Q = sqrt(beta^2 - xi^2)``, an elastic one obeys
``Q = kappa U`` with ``kappa = 2 G delta / (sigma_c L)``, and ``F = 4 int_0^inf Q dxi``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..kernels import contact as K

#: Kinds of indenter the stepper distinguishes.
FLAT_EXTERNAL, FLAT_INTERNAL, SMOOTH = "flat_external", "flat_internal", "smooth"


@dataclass(frozen=True)
class Law:
    """The element law in state-space form (see :mod:`pulloff.kernels.contact`): modes
    ``dY/dt = lam Y + z Q``, ``U = ctil . Y + d Q``; plus what a contact element needs: the
    Kelvin-Voigt ``kappa``, ``c`` or the Maxwell arms ``kappa_arms``, ``tau_arms`` with
    ``V`` (arm dashpots ``E = V Y``)."""

    kappa_inf: float
    c: float
    kappa_arms: np.ndarray
    tau_arms: np.ndarray
    lam: np.ndarray
    z: np.ndarray
    ctil: np.ndarray
    d: float
    V: np.ndarray
    V_inv: np.ndarray

    @property
    def n_modes(self) -> int:
        return self.lam.size

    @property
    def maxwell(self) -> bool:
        return self.kappa_arms.size > 0

    @cached_property
    def fastest_decay(self) -> float:
        """The rate the fastest mode decays at [1 / time unit]; 0 without memory."""
        return max(-float(np.min(self.lam)), 0.0)

    @cached_property
    def slowest_decay(self) -> float:
        """The rate the slowest mode decays at [1 / time unit]; 0 where one never decays (a
        Maxwell fluid's zero mode comes out of the eigensolver as ~ -1e-14)."""
        slowest = -float(np.max(self.lam))
        return slowest if slowest > 1e-12 * self.fastest_decay else 0.0

    @cached_property
    def V_kernel(self) -> np.ndarray:
        """``V`` in C order, as the kernels take it: the eigensolver's comes in Fortran order
        with two arms or more, and numba compiled the step's kernels once more for that (15 s
        from an empty cache where a Prony series ran after a standard linear solid). Python
        keeps ``V`` itself: a product with the other layout rounds differently."""
        return np.ascontiguousarray(self.V)

    @property
    def kappa_instant(self) -> float:
        return self.kappa_inf + float(np.sum(self.kappa_arms))

    @classmethod
    def from_spectrum(cls, spectrum, stiffness: float, T: float) -> "Law":
        """``stiffness = 2 delta / (sigma_c L)`` turns a modulus [Pa] into ``kappa``."""
        k_inf = spectrum.G_inf * stiffness
        c = spectrum.eta * stiffness / T
        k_arms = np.array([G * stiffness for G, _ in spectrum.arms])
        taus = np.array([tau / T for _, tau in spectrum.arms])
        empty = np.zeros(0)
        if k_arms.size:
            k_tot = k_inf + k_arms.sum()
            A = (np.outer(1.0 / taus, k_arms) / k_tot) - np.diag(1.0 / taus)
            b = 1.0 / (k_tot * taus)
            lam, V = np.linalg.eig(A)
            order = np.argsort(lam.real)
            lam, V = lam.real[order], V.real[:, order]
            V_inv = np.linalg.inv(V)
            return cls(k_inf, 0.0, k_arms, taus, lam, V_inv @ b, V.T @ (k_arms / k_tot),
                       1.0 / k_tot, V, V_inv)
        if c > 0.0:
            one = np.ones((1, 1))
            return cls(k_inf, c, empty, empty, np.array([-k_inf / c]), np.array([1.0 / c]),
                       np.array([1.0]), 0.0, one, one)
        # Elastic: no state. One idle mode keeps every array two-dimensional.
        one = np.ones((1, 1))
        return cls(k_inf, 0.0, empty, empty, np.zeros(1), np.zeros(1), np.zeros(1),
                   1.0 / k_inf, one, one)


@dataclass(frozen=True)
class Indenter:
    """``f = A_f xi^n``, ``g = C xi^n`` in units of ``delta`` over ``xi`` in ``L`` (a flat punch:
    ``C = 0`` with its face ending at ``xi = 1``), or a tabulated tip as ramps
    ``f = sum_j jumps_j (xi - knots_j)_+``."""

    kind: str
    A_f: float = 0.0
    C: float = 0.0
    n: float = 0.0
    knots: np.ndarray = field(default_factory=lambda: np.zeros(0))
    jumps: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def table(self):
        return self.knots, self.jumps

    def f(self, xi):
        if self.knots.size:
            return K.table_f(self.knots, self.jumps, float(xi))
        return self.A_f * xi ** self.n if self.A_f else 0.0

    def g(self, xi):
        if self.knots.size:
            if np.ndim(xi):
                return np.array([K.table_g(self.knots, self.jumps, float(x)) for x in xi])
            return K.table_g(self.knots, self.jumps, float(xi))
        return self.C * np.abs(xi) ** self.n if self.C else 0.0 * xi

    def g_integral(self, alpha):
        """``int_0^alpha g dxi``."""
        if self.knots.size:
            return K.table_g_integral(self.knots, self.jumps, alpha)
        return self.C * alpha ** (self.n + 1.0) / (self.n + 1.0) if self.C else 0.0


@dataclass(frozen=True)
class Drive:
    """One segment of the loading in the stepper's units: ``speed`` (lift per ``T``) or
    ``force_rate`` (force per ``T``) or a ``hold``; its end as ``(name, value)`` with name one of
    lift, force, time (all relative to the path's start: lift and force absolute, time a
    duration), onset, separation."""

    kind: str  # speed | force_rate | hold
    rate: float
    end: tuple
    index: int


@dataclass
class Setup:
    """Everything the stepper needs, dimensionless; ``L`` [m], ``T`` [s], ``delta`` [m] and
    ``F0`` [N] convert back."""

    L: float
    T: float
    delta: float
    F0: float
    law: Law
    indenter: Indenter
    drives: list
    control: str  # displacement | force
    machine: float | None  # k_m delta / (sigma_c L^2)
    h0: float
    until: str  # detach | separation (constant_velocity), or path
    t_max: float
    notes: list = field(default_factory=list)

    @property
    def flat(self) -> bool:
        return self.indenter.kind != SMOOTH


def _indenter(geometry, delta):
    if geometry.kind == "flat_punch":
        kind = FLAT_INTERNAL if geometry.cohesive_zone == "internal" else FLAT_EXTERNAL
        return geometry.radius, Indenter(kind)
    if geometry.kind == "profile":
        knots, jumps = geometry.ramps()
        L = _where_f_reaches(knots, jumps, delta)
        return L, Indenter(SMOOTH, knots=knots / L, jumps=jumps * L / delta)
    A, n = geometry.power_law()
    L = (delta / A) ** (1.0 / n)  # f(L) = delta
    from ..model.geometry import kappa_n

    return L, Indenter(SMOOTH, A * L ** n / delta, kappa_n(n) * A * L ** n / delta, n)


def _where_f_reaches(knots, jumps, height):
    """The radius where a tip written as ramps rises by ``height`` (its last slope continues
    beyond the table)."""
    from scipy.optimize import brentq

    f = lambda r: float(np.maximum(r - knots, 0.0) @ jumps) - height  # noqa: E731
    hi = max(float(knots[-1]) if knots.size else 1.0, 1e-300)
    while f(hi) < 0.0:
        hi *= 2.0
    return brentq(f, 0.0, hi, xtol=1e-14 * hi)


def _drives(loading, delta, T, F0):
    if loading.kind == "constant_velocity":
        return [Drive("speed", loading.v * T / delta, ("event", "end"), 0)]
    out = []
    for i, seg in enumerate(loading.segments):
        if seg.drive == "hold":
            out.append(Drive("hold", 0.0, ("time", seg.hold / T), i))
            continue
        rate = seg.speed * T / delta if seg.drive == "speed" else seg.force_rate * T / F0
        end = seg.until
        value = {"lift": lambda x: x / delta, "force": lambda x: x / F0,
                 "time": lambda x: x / T, "event": lambda x: x}[end.name](end.value)
        out.append(Drive(seg.drive, rate, (end.name, value), i))
    return out


def _time_scale(scene, delta, F0):
    loading = scene.loading
    if loading.kind == "constant_velocity":
        return delta / loading.v
    for seg in loading.segments:
        if seg.speed:
            return delta / abs(seg.speed)
    for seg in loading.segments:
        if seg.force_rate:
            return F0 / abs(seg.force_rate)
    taus = scene.material.spectrum().relaxation_times
    return min(taus) if taus else loading.segments[0].hold


def setup(scene, t_max_default: float = 100.0) -> Setup:
    """The stepper's numbers for ``scene``; ``t_max_default`` in units of ``T`` (a pull's end
    when the scene gives no ``numerics.t_max``)."""
    delta, sigma_c = scene.adhesion.delta, scene.adhesion.sigma_c
    L, indenter = _indenter(scene.geometry, delta)
    F0 = sigma_c * L * L
    T = _time_scale(scene, delta, F0)
    law = Law.from_spectrum(scene.material.spectrum(), 2.0 * delta / (sigma_c * L), T)
    loading = scene.loading
    k_m = loading.machine_stiffness
    machine = None if k_m is None else k_m * delta / F0
    control = "displacement" if loading.kind == "constant_velocity" else loading.control
    t_max = math.inf if scene.numerics.t_max is None else scene.numerics.t_max / T
    until = scene.model.until if loading.kind == "constant_velocity" else "path"
    return Setup(L, T, delta, F0, law, indenter, _drives(loading, delta, T, F0), control,
                 machine, loading.h0 / delta, until, t_max)
