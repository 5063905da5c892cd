"""A flat punch pulled through a machine spring, before its onset: the lift is one scalar ODE.

Dimensionless as :mod:`.problem` (lengths in ``a``, lift in ``delta``, time ``T = t v /
delta``). While the bond radius is pinned, the whole line load is a function of the bonded
elements' load ``L = 4 (G h + eta dh/dt)`` alone: the edge condition gives the zone
``S = sqrt(b^2 - a^2)/a = L / (2 sigma_c a)``, and the force on the punch is

    F_total = 2 sigma_c a^2 Phi(S),   Phi(S) = S + (1 + S^2) atan(S)

(contact ``4 sigma_c a^2 S`` plus the zone's ``sigma_c [pi b^2 - 2 a sqrt(b^2 - a^2) - 2 b^2
asin(a/b)]``). The spring of stiffness ``k_m`` holds it: ``kappa (T - H) = Phi(S)`` with
``kappa = k_m delta / (2 sigma_c a^2)`` (the driver at ``T``, the spring relaxed at ``T = 0``),
and ``S = k H + c dH/dT``. So ``c dH/dT = Phi^-1(kappa (T - H)) - k H``: the lift, and with it
the zone ``S(T)``, before any element's history is known. The onset's quadrature then takes
``S(T)`` from here instead of the rigid pull's ``k (H0 + T) + c``.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
from ..kernels import quadrature as kernels
from .frozen import frozen_detach_time, frozen_memory, zone_ratio
from .problem import Problem

#: Chebyshev-Lobatto intervals of the lift's first and largest collocation.
_FIRST_NODES = 16
_MAX_NODES = 1024


def zone_force(S):
    """``Phi(S) = S + (1 + S^2) atan(S)``: ``F_total / (2 sigma_c a^2)``; increasing."""
    return S + (1.0 + S * S) * np.arctan(S)


def zone_of_force(y):
    """``Phi^-1(y)`` (:func:`pulloff.kernels.quadrature.zone_of_force`; ``Phi`` is odd,
    so a compressed spring's ``y < 0`` gives ``-Phi^-1(-y)``: Newton's trial lifts may ask
    for it, and a clipped inverse there stalled Newton on a stiff spring)."""
    y = np.asarray(y, dtype=float)
    out = np.empty(y.shape)
    kernels.zone_of_force(y.reshape(-1), out.reshape(-1))
    return out


@dataclasses.dataclass(frozen=True, eq=False)
class MachinePull(Problem):
    """A :class:`Problem` pulled through a machine spring (``machine_stiffness`` [N/m]), with
    its lift path up to ``span`` (dimensionless): ``path`` rows are the Chebyshev-Lobatto
    nodes of ``sqrt(t / span)``, the lift ``H`` and the zone ``S`` there. Its SI views (lift, zone
    end, forces) follow the path, so results and histories are built as for a rigid pull."""

    machine_stiffness: float = 0.0
    path: np.ndarray = dataclasses.field(default=None, repr=False)
    span: float = 1.0

    def _row(self, row, t):
        if type(t) is float:
            return kernels.path_value(self.path, row, self.span, t)
        t = np.asarray(t, dtype=float)
        out = np.empty(t.shape)
        kernels.lobatto_interpolate(self.path[0], self.path[row],
                                    np.sqrt(np.maximum(t, 0.0) / self.span).ravel(),
                                    out.reshape(-1))
        return out

    def s_of(self, t):
        return self._row(2, t)

    def lift(self, t):
        return self.delta * self._row(1, t)

    def contact_force(self, t):
        """``F_contact = 8 a (G h + eta dh/dt) = 4 sigma_c a^2 S`` [N]."""
        return 4.0 * self.sigma_c * self.a * self.a * self.s_of(t)


def machine_pull(problem: Problem, machine_stiffness: float, t_limit: float,
                 rtol: float = 1e-10):
    """``(MachinePull, t_end, bounded, estimate)``: the lift path from ``T = 0`` past the
    frozen onset, ``t_end`` (``bounded``; it bounds the exact onset from above while the zone
    grows, as on a rigid pull), or to ``t_limit``. ``estimate``: the path's error relative to
    its largest ``S`` (its last change with the nodes doubled), brought below ``1e-3 rtol``
    (at least 1e-13). Raises ValueError where the
    zone stops growing before the end (the quadrature assumes it grows)."""
    k, c = problem.k, problem.c
    kappa = kappa_of(problem, machine_stiffness)
    first = _first_span(problem, kappa)
    span = min(first, t_limit)
    for _ in range(200):
        path, estimate = _path(k, c, kappa, span, max(1e-13, 1e-3 * rtol))
        t_end = _frozen_onset(problem, path, span)
        if t_end is not None and t_end < 0.5 * span:
            # The first span (the rigid pull's) can overshoot a soft spring's onset by orders
            # of magnitude: the path then spends its nodes past the onset (a review found
            # onsets 2-200x early, the estimate ~1e-12). Again on a span that just holds it.
            span = 1.25 * t_end
            continue
        if t_end is not None or span >= t_limit:
            break
        if span > 1e6 * first:
            raise ValueError("no onset within 1e6 times the rigid pull's behind this spring")
        span = min(2.0 * span, t_limit)
    else:
        raise ValueError("the machine's lift found no span holding its onset")
    # (a zone that levels off, as a viscous solid's at the driver's speed, may wobble by
    # the collocation's rounding)
    if np.any(np.diff(path[2]) < -1e-12 * np.max(path[2])):
        raise ValueError("the zone recedes before the onset behind this machine spring")
    pull = MachinePull(**{f.name: getattr(problem, f.name) for f in dataclasses.fields(Problem)},
                       machine_stiffness=machine_stiffness, path=path, span=span)
    return (pull, t_end, True, estimate) if t_end is not None else (pull, span, False, estimate)


def kappa_of(problem: Problem, machine_stiffness: float) -> float:
    """``kappa = k_m delta / (2 sigma_c a^2)``: the spring against the zone's force scale."""
    return machine_stiffness * problem.delta / (2.0 * problem.sigma_c * problem.a ** 2)


def spring_to_solid(problem: Problem, machine_stiffness: float) -> float:
    """The spring's stiffness against the solid's at the start, ``(kappa/2) / k`` (the zone's
    force grows like ``2 S`` there): above ~1 the punch catches up with the driver in a
    layer ``c / (k + kappa/2)`` thinner than the solid's own relaxation ``c / k``; inf for a
    viscous solid (``k = 0``), 0 for an elastic one (no such layer)."""
    if problem.c == 0.0:
        return 0.0
    half = 0.5 * kappa_of(problem, machine_stiffness)
    return half / problem.k if problem.k > 0.0 else math.inf


def _first_span(problem: Problem, kappa: float) -> float:
    """A first span for the path: the rigid pull's frozen onset, plus the spring's stretch
    at its force there (the driver's lead when the punch gets that far), and a quarter."""
    t_rigid = frozen_detach_time(problem)
    if not 0.0 < t_rigid < math.inf:
        return 1.0
    s_rigid = problem.s_of(t_rigid)
    return 1.25 * (t_rigid + float(zone_force(s_rigid)) / kappa)


def _frozen_gap(problem: Problem, T, H, S):
    """The frozen-load gap (every element carrying its current load since ``T = 0``,
    :mod:`.frozen`) along the path: a lower bound of the exact gap while ``S`` grows."""
    return (2.0 / math.pi) * (H * np.arctan(S) - frozen_memory(problem, T) * zone_ratio(S))


def _frozen_onset(problem: Problem, path, span):
    """The first time in ``[0, span]`` where the path's frozen gap reaches 1, or None: first
    node above 1, then bisection on the interpolated path."""
    u, H, S = path
    gaps = _frozen_gap(problem, span * u * u, H, S)
    above = np.nonzero(gaps >= 1.0)[0]
    if above.size == 0:
        return None
    j = int(above[0])
    if j == 0:
        return 0.0
    lo, hi = span * u[j - 1] ** 2, span * u[j] ** 2
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            break
        h, s = (kernels.path_value(path, row, span, mid) for row in (1, 2))
        g = _frozen_gap(problem, np.array([mid]), np.array([h]), np.array([s]))[0]
        lo, hi = (mid, hi) if g < 1.0 else (lo, mid)
    return hi


def _path(k, c, kappa, span, tol):
    """``(path, estimate)``: the lift's ODE by Chebyshev collocation in ``u = sqrt(T /
    span)`` (the lift's relaxation at the start then takes half the nodes it takes in
    ``T``), the nodes doubled from 16 until the solution at the shared nodes changes by at
    most ``tol`` of its largest ``S`` (or :data:`_MAX_NODES`)."""
    n, previous = _FIRST_NODES, None
    while True:
        u, D = _lobatto_differentiation(n)
        T = span * u * u
        # d/dT = (d/du) / (2 span u) on every node but u = 0, where H(0) = 0 is set instead
        D_T = D / np.maximum(2.0 * span * u, 1e-300)[:, None]
        guess = (_first_guess(k, c, kappa, T) if previous is None
                 else np.interp(u, previous[0], previous[1]))
        H = _collocate(k, c, kappa, T, D_T, guess)
        if H is None:  # too few nodes for the spring's start: more nodes, a fresh guess
            if n >= _MAX_NODES:
                raise ValueError("the machine's lift did not converge (collocation)")
            previous, n = None, 2 * n
            continue
        S = zone_of_force(kappa * (T - H))
        # Two checks: the solution at the shared nodes against the half as many nodes' (the
        # ODE's discretisation), and its interpolant through every other node against the
        # rest (the path between nodes: an elastic solid's collocation is exact at every
        # node, and the first check alone passed paths 0.6 % off between them).
        scale = max(np.max(np.abs(S)), 1e-300)
        change = kernels.lobatto_spread(u, S) / scale
        if previous is not None:
            change = max(change, float(np.max(np.abs(S[::2] - previous[2]))) / scale)
            if change <= tol or n >= _MAX_NODES:
                return np.vstack([u, H, S]), change
        previous, n = (u, H, S), 2 * n


def _first_guess(k, c, kappa, T):
    """A first lift for Newton: the quasi-static one (``c = 0``, right for soft springs) or
    the rigid pull's zone ``k T + c`` reached after the spring's relaxation ``c Phi'(c) /
    kappa`` (right for stiff ones), whichever balances the ODE better."""
    quasi = _quasi_static(k, kappa, T)
    zone = (k * T + c) * -np.expm1(-T * kappa / (c * (2.0 + 2.0 * c * math.atan(c)) + 1e-300))
    stiff = T - zone_force(zone) / kappa
    stiff[0] = 0.0
    return min((quasi, stiff), key=lambda H: float(np.max(np.abs(
        zone_of_force(kappa * (T - H)) - k * H - c * np.gradient(H, T)))))


@functools.lru_cache(maxsize=16)
def _lobatto_differentiation(n: int):
    """Chebyshev-Lobatto nodes ``u`` of [0, 1], ascending, and the matrix of ``d/du`` on them
    (Trefethen's ``cheb`` with ``u = (1 - x)/2``)."""
    j = np.arange(n + 1)
    x = np.cos(np.pi * j / n)
    weight = np.where((j == 0) | (j == n), 2.0, 1.0) * (-1.0) ** j
    dx = x[:, None] - x[None, :]
    D = np.outer(weight, 1.0 / weight) / (dx + np.eye(n + 1))
    D -= np.diag(D.sum(axis=1))
    return kernels.lobatto_nodes(n), -2.0 * D


def _collocate(k, c, kappa, T, D, guess):
    """``H`` at the nodes ``T`` (``T[0] = 0``, ``H(0) = 0``) solving ``c D H = Phi^-1(kappa
    (T - H)) - k H`` by Newton from ``guess`` (backtracking on the residual); None where it
    does not converge."""
    H = guess.copy()
    H[0] = 0.0

    def residual(H):
        # (a wild trial lift may overflow: its residual is then not smaller, and halved)
        with np.errstate(over="ignore", invalid="ignore"):
            return c * (D @ H)[1:] - zone_of_force(kappa * (T - H))[1:] + k * H[1:]

    r = residual(H)
    for _ in range(50):
        S = zone_of_force(kappa * (T - H))
        J = c * D[1:, 1:] + np.diag(kappa / (2.0 + 2.0 * S[1:] * np.arctan(S[1:])) + k)
        step = np.linalg.solve(J, r)
        for _ in range(30):
            trial = H.copy()
            trial[1:] -= step
            r_new = residual(trial)
            if np.max(np.abs(r_new)) < np.max(np.abs(r)):
                break
            step *= 0.5
        H, r = trial, r_new
        if np.max(np.abs(step)) <= 1e-15 * max(np.max(np.abs(H)), 1e-300):
            return H
    return None


def _quasi_static(k, kappa, T):
    """The lift of an elastic solid (``c = 0``): ``kappa (T - H) = Phi(k H)``, by bisection
    on the monotone residual (vectorised); ``H = T`` where ``k = 0``."""
    if k == 0.0:
        return T.copy()
    lo, hi = np.zeros_like(T), T.copy()
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        above = zone_force(k * mid) > kappa * (T - mid)
        lo, hi = np.where(above, lo, mid), np.where(above, mid, hi)
    return 0.5 * (lo + hi)
