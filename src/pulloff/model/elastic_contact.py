"""Exact elastic references for the adhesive contact of rigid axisymmetric indenters.

Closed forms, or closed forms up to one scalar root per state, for the *elastic* MDR-Dugdale
model of MODEL.md section 9 and for the classical theories it has to reproduce: Maugis-Dugdale
for the sphere, JKR for any power-law indenter, DMT.  numpy/scipy only and independent of the
project's solvers, so that their tests can use these as exact references.

Conventions (MODEL.md sections 1 and 9)
---------------------------------------
SI throughout: lengths [m], moduli and stresses [Pa], work of adhesion [J/m^2 = N/m], forces [N].
Indenter surface ``z = h + f(r)``, ``f(0) = 0``; ``h`` is the lift, ``h < 0`` presses in.
Incompressible half-space of shear modulus ``G``: ``E* = 4 G``.  Forces are positive in tension.
Dugdale law: tensile stress ``sigma_c`` wherever the gap is below ``delta``; ``gamma = sigma_c
delta``; every MDR function takes any two of the three.  Maugis (1992) and JKR count the load
``P`` positive in compression and the indentation ``Delta = -h``; the ``maugis_*`` functions keep
his convention (``P = -F_total``) and say so.

The elastic MDR-Dugdale state (section 9) and the form it is solved in
----------------------------------------------------------------------
Contact ``|x| < a``: ``u = h + g(x)``, ``q = 4 G u``; zone ``a < |x| < b``: ``q = 2 sigma_c
sqrt(b^2 - x^2)``, ``u = q / (4 G)``.  With ``c = sqrt(b^2 - a^2) = a S``:

* edge condition (``q`` continuous at ``a``): ``h = -g(a) + sigma_c c / (2 G)``;
* ``gap(b) = h + f(b) - u3D(b) = delta``.  With the inverse MDR transform
  ``f(b) = (2/pi) int_0^b g(x) / sqrt(b^2 - x^2) dx`` and the edge condition this is exactly

      (2/pi) J(a, b) + (sigma_c a / (pi G)) [S atan S - (sqrt(1 + S^2) - 1)] = delta,
      J(a, b) = int_a^b (g(x) - g(a)) / sqrt(b^2 - x^2) dx  (>= 0 when g is non-decreasing),

  whose left side increases with ``S`` for a non-decreasing ``g``: for every ``a > 0`` there is
  exactly one zone, found by a bracketed root in ``log S`` (``b - a`` of thin zones is never
  formed; ``J`` is evaluated without cancellation, see :class:`PowerLawProfile`).  With ``g = 0``
  it is the flat punch of MODEL.md section 5;
* forces: ``F_contact = 2 int_0^a q dx = 4 sigma_c a c - 8 G M(a)`` with
  ``M(a) = a g(a) - int_0^a g dx = int_0^a x g'(x) dx``, and the zone adds
  ``2 int_a^b q dx = 2 sigma_c a^2 [(1 + S^2) atan S - S]``.

Zone-only states (``a = 0``): ``u = q/(4G)`` everywhere, ``u3D(b) = sigma_c b / (pi G)``, so
``h = delta + sigma_c b / (pi G) - f(b)`` and ``F_total = 2 int_0^b 2 sigma_c sqrt(b^2 - x^2) dx
= pi sigma_c b^2``.  The zone touches at the centre (gap ``h - sigma_c b / (2G) = 0``) at the
*join* radius ``b0``, where it meets the contact branch's ``a -> 0`` end; ``b -> 0`` gives
``h = delta``, the free state.  Contact branch (``a`` from large to 0), zone-only branch (``b``
from ``b0`` to 0) and the free state (``h > delta``, ``F = 0``) form one connected curve.

Which point is "pull-off"
-------------------------
Load control: the largest tension on the curve.  Displacement control (rigid machine): the
point where a quasi-static lift *leaves* the curve, i.e. the first maximum of ``h`` met when the
curve is followed from large contact towards separation; on the contact branch that is the
largest ``a`` with ``dh/da = 0`` (``d(indentation)/da = 0``), otherwise it is on the zone-only
branch (``dh/db = 0``) or at the join.  The maximum tension *along* a displacement-controlled
pull is the load-control value (that point is passed on the stable side), so it is not repeated.
For the sphere the departure is on the contact branch for ``lambda > 0.93795`` and on the
zone-only branch below (:data:`MAUGIS_LAMBDA_ZONE_DEPARTURE`).

Checks (tests/test_elastic_contact.py)
--------------------------------------
* MDR-Dugdale sphere = Maugis (1992): identical term by term (edge condition -> his Delta, gap
  condition -> his eq. for m, forces -> his P); numerically <= 6e-15 along the whole curve,
  pull-offs 3e-15 (load) and 1e-11 (displacement).
* JKR is the limit ``sigma_c -> inf`` at fixed gamma for every power law; states and pull-offs
  approach it as ``sigma_c^-2`` (``lambda^-2``): the zone width is ``O(1/sigma_c)`` but both
  first corrections are ``O(sigma_c^-2)`` relative.
* DMT (rigid) limit ``G -> inf``: pull-off error ``O(1/G)``, i.e. ``O(lambda^(3/2))``.

Sources: D. Maugis, J. Colloid Interface Sci. 150 (1992) 243; K. L. Johnson, K. Kendall,
A. D. Roberts, Proc. R. Soc. Lond. A 324 (1971) 301; B. V. Derjaguin, V. M. Muller,
Yu. P. Toporov, J. Colloid Interface Sci. 53 (1975) 314; V. L. Popov, M. Hess, Method of
Dimensionality Reduction in Contact Mechanics and Friction (Springer 2015); F. M. Borodich,
B. A. Galanov, M. M. Suarez-Alvarez, J. Mech. Phys. Solids 68 (2014) 14; K. L. Johnson,
J. A. Greenwood, J. Colloid Interface Sci. 192 (1997) 326.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq, minimize_scalar
from scipy.special import betaincc, gammaln, roots_legendre
from scipy.special import beta as beta_fn

__all__ = [
    "mdr_kappa",
    "PowerLawProfile",
    "TabulatedProfile",
    "mdr_profile_power_law",
    "mdr_profile_tabulated",
    "sphere_profile",
    "cone_profile",
    "ContactState",
    "ZoneOnlyState",
    "PullOff",
    "equilibrium_at_contact_radius",
    "zone_only_state",
    "zone_only_at_lift",
    "join_radius",
    "equilibrium_curve",
    "rigid_lift_cycle",
    "mdr_dugdale_pulloff",
    "jkr_state",
    "jkr_pulloff_power_law",
    "jkr_pulloff",
    "dmt_sphere",
    "dmt_pulloff_power_law",
    "maugis_lambda",
    "maugis_units",
    "tabor_parameter",
    "maugis_parametric",
    "maugis_at_contact_radius",
    "maugis_zone_only",
    "maugis_force",
    "maugis_indentation",
    "maugis_pulloff",
    "maugis_pulloff_force",
    "MAUGIS_LAMBDA_ZONE_DEPARTURE",
]

_EPS = np.finfo(float).eps
_RTOL = 4.0 * _EPS  # the smallest rtol brentq accepts
_YTOL = 1e-15  # absolute tolerance on log(S) or log(a): a relative tolerance on S or a
_GL_X, _GL_W = roots_legendre(24)


def _out(x):
    """A Python float for 0-d input, the array otherwise."""
    x = np.asarray(x, dtype=float)
    return float(x) if x.ndim == 0 else x


def _cohesive(sigma_c, delta, gamma):
    """(sigma_c [Pa], delta [m], gamma [J/m^2]) from any two of them (MODEL.md section 1)."""
    given = [v is not None for v in (sigma_c, delta, gamma)]
    if sum(given) < 2:
        raise ValueError("give two of sigma_c, delta, gamma")
    if sigma_c is None:
        sigma_c = gamma / delta
    elif delta is None:
        delta = gamma / sigma_c
    elif gamma is None:
        gamma = sigma_c * delta
    elif not math.isclose(gamma, sigma_c * delta, rel_tol=1e-12):
        raise ValueError("gamma != sigma_c * delta")
    if not (sigma_c > 0 and delta > 0):
        raise ValueError("need sigma_c > 0 and delta > 0")
    return float(sigma_c), float(delta), float(gamma)


# ---------------------------------------------------------------------------------------------
# MDR profiles
# ---------------------------------------------------------------------------------------------


def mdr_kappa(n):
    """``kappa_n = sqrt(pi) Gamma(n/2 + 1) / Gamma(n/2 + 1/2)`` [-]: the MDR factor of
    ``f = A r^n -> g = kappa_n A |x|^n`` (Popov & Hess, *Method of Dimensionality Reduction in
    Contact Mechanics and Friction*, 2015).  Log-gamma keeps it finite for large ``n``
    (``kappa_n ~ sqrt(pi n / 2)``; relative rounding grows with n: 4e-10 at n = 1e6)."""
    n = np.asarray(n, dtype=float)
    return _out(np.sqrt(np.pi) * np.exp(gammaln(n / 2 + 1) - gammaln(n / 2 + 0.5)))


def _flat_gap(S):
    """``S atan S - (sqrt(1+S^2) - 1)`` [-], the flat-punch part of the gap condition; the
    second term written without cancellation."""
    return S * np.arctan(S) - S * S / (1.0 + np.sqrt(1.0 + S * S))


def _zone_force(S):
    """``(1 + S^2) atan S - S`` [-]: the zone's line-load integral over ``2 sigma_c a^2``.
    For small ``S`` its alternating series ``sum (-1)^(k-1) 2 S^(2k+1) / ((2k-1)(2k+1))``
    (k >= 1) replaces the cancelling closed form."""
    S = np.asarray(S, dtype=float)
    out = (1.0 + S * S) * np.arctan(S) - S
    small = S < 0.1
    if np.any(small):
        s = S[small]
        ser = np.zeros_like(s)
        for k in range(8, 0, -1):  # S^17 < 1e-17: converged
            ser = ser + (-1) ** (k - 1) * 2.0 / ((2 * k - 1) * (2 * k + 1)) * s ** (2 * k + 1)
        out = np.where(small, 0.0, out)
        out[small] = ser
    return out


class PowerLawProfile:
    """Rigid power-law indenter ``f(r) = A r^n`` [m] (``A`` [m^(1-n)], ``n > 0``) and its MDR
    profile ``g(x) = kappa_n A |x|^n`` [m].  ``A = 0`` is the flat plane (``g = 0``).

    Sphere ``f = r^2/(2R)``: ``A = 1/(2R)``, ``n = 2``, ``g = x^2/R``.  Cone ``f = r tan(theta)``:
    ``A = tan(theta)``, ``n = 1``, ``g = (pi/2) tan(theta) |x|``.  Calling the profile gives
    ``g``.
    """

    monotone = True  # g non-decreasing on x >= 0: one zone per contact radius

    def __init__(self, coefficient, exponent):
        self.coefficient, self.exponent = float(coefficient), float(exponent)
        if not (self.exponent > 0 and self.coefficient >= 0):
            raise ValueError("need exponent > 0 and coefficient >= 0")
        self.kappa = mdr_kappa(self.exponent)
        # int_a^b x^n / sqrt(b^2 - x^2) dx = b^n (B/2) betaincc((n+1)/2, 1/2, a^2/b^2)
        self._half_beta = 0.5 * beta_fn(0.5, 0.5 * (self.exponent + 1.0))

    def __repr__(self):
        return f"PowerLawProfile(coefficient={self.coefficient!r}, exponent={self.exponent!r})"

    def f(self, r):
        """Indenter profile ``f(r)`` [m] at radius r [m]."""
        return _out(self.coefficient * np.abs(np.asarray(r, float)) ** self.exponent)

    def df(self, r):
        """Slope ``f'(r)`` [-] at r [m] > 0."""
        n = self.exponent
        return _out(n * self.coefficient * np.asarray(r, float) ** (n - 1.0))

    def g(self, x):
        """MDR profile ``g(x)`` [m] at x [m]."""
        return _out(self.kappa * self.coefficient * np.abs(np.asarray(x, float)) ** self.exponent)

    __call__ = g

    def dg(self, x):
        """Slope ``g'(x)`` [-] at x [m] > 0."""
        n = self.exponent
        return _out(n * self.kappa * self.coefficient * np.asarray(x, float) ** (n - 1.0))

    def moment(self, a):
        """``M(a) = int_0^a x g'(x) dx = a g(a) - int_0^a g dx`` [m^2] for a [m]."""
        n = self.exponent
        return _out(self.kappa * self.coefficient * n / (n + 1.0) * np.asarray(a, float) ** (n + 1))

    def excess(self, a, S):
        """``J = int_a^b (g(x) - g(a)) / sqrt(b^2 - x^2) dx`` [m] with ``b = a sqrt(1 + S^2)``.

        Thin zones (``S < 1/2``): ``x = b cos(theta)``, ``J = int_0^atan(S) (g(b cos) - g(a))``,
        the integrand ``a^n expm1(n log(x/a))`` with ``log(x/a) = (log1p(S^2) + log1p(-sin^2))/2``
        (no cancellation, relative accuracy ~eps although ``J ~ S^3``); 24 Gauss-Legendre nodes
        on ``theta <= 0.464``, analytic out to ``pi/2``, converge to rounding.  Wider zones: the
        incomplete-beta closed form, whose two terms no longer cancel.
        """
        a, S = np.broadcast_arrays(np.asarray(a, float), np.asarray(S, float))
        n = self.exponent
        out = np.empty(a.shape)
        thin = S < 0.5
        if np.any(thin):
            s, an = S[thin], a[thin] ** n
            th_a = np.arctan(s)
            th = th_a[:, None] * (0.5 * (_GL_X + 1.0))
            logx = 0.5 * (np.log1p(s * s)[:, None] + np.log1p(-np.sin(th) ** 2))
            out[thin] = an * 0.5 * th_a * (np.expm1(n * logx) @ _GL_W)
        wide = ~thin
        if np.any(wide):
            s, aw = S[wide], a[wide]
            bn = aw**n * (1.0 + s * s) ** (0.5 * n)
            full = bn * self._half_beta * betaincc(0.5 * (n + 1.0), 0.5, 1.0 / (1.0 + s * s))
            out[wide] = full - aw**n * np.arctan(s)
        return _out(self.kappa * self.coefficient * out)


class TabulatedProfile:
    """Rigid indenter tabulated as ``f(r_i)`` [m] at ``r_i`` [m], linear in between and continued
    with the last slope beyond the table; ``r_0 = 0``, ``f_0 = 0``, ``r`` strictly increasing.

    Written as a sum of ramps, ``f(r) = sum_j ds_j (r - r_j)_+`` (``ds_j`` the slope change at
    knot ``r_j``), every MDR quantity is a sum of exact per-ramp closed forms, so it is exact
    for the interpolant (no quadrature): ramp ``(r - r_j)_+`` has ``g_j(x) = x acos(r_j / x)``
    for ``x > r_j`` (eq. 6 of MODEL.md section 9 with ``f' = 1`` on ``r > r_j``).

    Accuracy: ``J`` (:meth:`excess`) is a difference of terms of size ``S g(a)`` and has size
    ``S^3 g(a)``: relative error ~``eps / S^2`` for zones thinner than ``S = sqrt(b^2-a^2)/a``;
    use :class:`PowerLawProfile` for thin-zone (JKR-limit) studies.

    The interpolant is faceted, and every interior knot is a small conical edge: ``g'`` has an
    integrable ``(x - r_j)^(-1/2)`` spike just outside each knot.  So ``g`` of a sampled smooth
    profile converges only as ``N^(-3/2)`` (N table points), and the lift ``h(a)`` of the
    equilibria is a fine sawtooth whose slope between knots is off by ``~sqrt(dr/a)``:
    displacement-control pull-off points of a table are those of the facets (they converge
    slowly and erratically to the smooth profile's), load-control ones are robust.
    """

    def __init__(self, r, f):
        r, f = np.asarray(r, float), np.asarray(f, float)
        if r.ndim != 1 or r.shape != f.shape or r.size < 2:
            raise ValueError("r and f: 1-D arrays of equal length >= 2")
        if r[0] != 0.0 or f[0] != 0.0 or np.any(np.diff(r) <= 0):
            raise ValueError("need r[0] = 0, f[0] = 0 and r strictly increasing")
        slopes = np.diff(f) / np.diff(r)
        jumps = np.diff(np.concatenate([[0.0], slopes]))
        keep = jumps != 0.0
        self.r_table, self.f_table = r, f
        self.knots, self.jumps = r[:-1][keep], jumps[keep]
        # g non-decreasing if every slope change is >= 0 (convex f): each ramp's g_j grows
        self.monotone = bool(np.all(self.jumps >= 0.0))

    def __repr__(self):
        return f"TabulatedProfile({self.r_table.size} points up to r = {self.r_table[-1]!r})"

    def _ramps(self, x):
        x = np.asarray(x, float)
        return x, x[..., None], np.broadcast_to(self.knots, x.shape + self.knots.shape)

    def f(self, r):
        """Interpolated profile ``f(r)`` [m] at r [m] >= 0."""
        r, rr, k = self._ramps(r)
        return _out(np.maximum(rr - k, 0.0) @ self.jumps)

    def df(self, r):
        """Slope ``f'(r)`` [-] at r [m] (right-continuous at knots)."""
        r, rr, k = self._ramps(r)
        return _out((rr >= k) @ self.jumps)

    def g(self, x):
        """MDR profile ``g(x) = sum_j ds_j x acos(r_j/x)`` [m] (x > r_j terms) at x [m]."""
        x, xx, k = self._ramps(np.abs(np.asarray(x, float)))
        on = xx > k
        rho = np.sqrt(np.where(on, (xx - k) * (xx + k), 0.0))  # sqrt(x^2 - r_j^2), no cancellation
        return _out(np.where(on, xx * np.arctan2(rho, k), 0.0) @ self.jumps)

    __call__ = g

    def dg(self, x):
        """Slope ``g'(x) = sum_j ds_j [acos(r_j/x) + r_j / sqrt(x^2 - r_j^2)]`` [-] at x [m]
        (infinite just right of an interior knot: the kink of ``f`` becomes a square root)."""
        x, xx, k = self._ramps(x)
        on = xx > k
        rho = np.sqrt(np.where(on, (xx - k) * (xx + k), 1.0))
        return _out(np.where(on, np.arctan2(rho, k) + k / rho, 0.0) @ self.jumps)

    def moment(self, a):
        """``M(a) = int_0^a x g'(x) dx`` [m^2]: per ramp ``(a^2/2) acos(r_j/a) + (r_j/2)
        sqrt(a^2 - r_j^2)`` (from ``M = int_0^a f'(r) r^2 / sqrt(a^2 - r^2) dr``)."""
        a, aa, k = self._ramps(a)
        on = aa > k
        rho = np.sqrt(np.where(on, (aa - k) * (aa + k), 0.0))
        per = np.where(on, 0.5 * aa * aa * np.arctan2(rho, k) + 0.5 * k * rho, 0.0)
        return _out(per @ self.jumps)

    def excess(self, a, S):
        """``J = int_a^b (g(x) - g(a)) / sqrt(b^2 - x^2) dx`` [m], ``b = a sqrt(1 + S^2)``.

        Per ramp: ``(pi/2)(b - r_j)`` if ``a <= r_j < b`` (inverse MDR transform), 0 beyond
        ``b``, and for ``r_j < a``, with ``c = a S``, ``rho = sqrt(a^2 - r_j^2)``:
        ``(pi/2)(c - r_j) + Phi(r_j) - a acos(r_j/a) atan S``, where
        ``Phi(r) = r atan(rho/c) - c asin(r/a) + b atan(c r / (b rho))`` is the antiderivative of
        ``atan(sqrt(a^2 - r^2)/c)`` that ``int_0^a g / sqrt(b^2 - x^2) dx = int_0^a f'(r)
        atan(sqrt(a^2 - r^2)/c) dr`` needs (order of integration exchanged).
        """
        a, S = np.broadcast_arrays(np.asarray(a, float), np.asarray(S, float))
        aa, ss = a[..., None], S[..., None]
        k = np.broadcast_to(self.knots, a.shape + self.knots.shape)
        b, c = aa * np.sqrt(1.0 + ss * ss), aa * ss
        inside = k < aa
        rho = np.sqrt(np.where(inside, (aa - k) * (aa + k), 0.0))
        phi = k * np.arctan2(rho, c) - c * np.arctan2(k, rho) + b * np.arctan2(c * k, b * rho)
        j_in = 0.5 * np.pi * (c - k) + phi - aa * np.arctan2(rho, k) * np.arctan(ss)
        j_out = 0.5 * np.pi * np.maximum(b - k, 0.0)
        return _out(np.where(inside, j_in, j_out) @ self.jumps)


def mdr_profile_power_law(coefficient, exponent):
    """MDR profile of ``f(r) = coefficient r^exponent``: ``g(x) = kappa_n coefficient |x|^n``
    (callable; also ``f``, ``df``, ``dg``, ``moment``, ``excess``).  coefficient [m^(1-n)]."""
    return PowerLawProfile(coefficient, exponent)


def mdr_profile_tabulated(r, f):
    """MDR profile of a tabulated ``f(r)`` [m] at ``r`` [m] (piecewise linear, exact for the
    interpolant: ``g(x) = x int_0^x f'(r) / sqrt(x^2 - r^2) dr``).  Callable: ``g(x)``."""
    return TabulatedProfile(r, f)


def sphere_profile(R):
    """Sphere (paraboloid) of radius R [m]: ``f = r^2/(2R)``, ``g = x^2/R``."""
    return PowerLawProfile(0.5 / float(R), 2.0)


def cone_profile(slope):
    """Cone ``f = slope r`` (slope = tan of the angle between face and plane) [-]:
    ``g = (pi/2) slope |x|``."""
    return PowerLawProfile(slope, 1.0)


# ---------------------------------------------------------------------------------------------
# Elastic MDR-Dugdale: states
# ---------------------------------------------------------------------------------------------


class ContactState(NamedTuple):
    """An equilibrium with contact: lift h [m], zone end b [m], forces [N] (tension > 0)."""

    h: float
    b: float
    F_total: float
    F_contact: float


class ZoneOnlyState(NamedTuple):
    """Surfaces apart, the zone ``r < b`` pulling: lift h [m], b [m], F_total [N], and the gap at
    the centre [m] (the smallest gap for a non-decreasing ``f``; contact needs it >= 0)."""

    h: float
    b: float
    F_total: float
    centre_gap: float


class PullOff(NamedTuple):
    """A pull-off point: force F [N] (tension > 0), lift h [m], contact radius a [m], zone end b
    [m] and on which branch it lies ("contact", "zone-only", "join")."""

    F: float
    h: float
    a: float
    b: float
    branch: str


def _gap_lhs(profile, a, S, G, sigma_c):
    """Left side of the gap condition [m] (module docstring); increasing in S for monotone g."""
    return 2.0 / np.pi * profile.excess(a, S) + sigma_c * a / (np.pi * G) * _flat_gap(S)


def _solve_S(profile, a, G, sigma_c, delta):
    """Zone ratio ``S = sqrt(b^2 - a^2)/a`` [-] of the equilibrium at contact radius a [m]: the
    smallest root of the gap condition (the only one when ``g`` is non-decreasing)."""

    def resid(y):
        return _gap_lhs(profile, a, math.exp(y), G, sigma_c) - delta

    k = sigma_c * a / (np.pi * G)
    # the flat-punch root: J >= 0 puts the root below it for monotone g (start of the search)
    y_hi = math.log(max(math.sqrt(2.0 * delta / k), delta / (k * (0.5 * math.pi - 1.0))))
    while resid(y_hi) <= 0.0:
        y_hi += 2.0
    y_lo = y_hi - 2.0
    while resid(y_lo) >= 0.0:
        y_lo -= 2.0
    if not profile.monotone:
        # several roots possible: the first crossing of an upward scan from a point below delta
        y_lo -= 20.0
        ys = np.linspace(y_lo, y_hi, 400)
        r = np.array([resid(y) for y in ys])
        i = int(np.argmax(r > 0.0))
        y_lo, y_hi = ys[i - 1], ys[i]
    return math.exp(brentq(resid, y_lo, y_hi, xtol=_YTOL, rtol=_RTOL, maxiter=300))


def _state_from_S(profile, a, S, G, sigma_c):
    c = a * S
    h = sigma_c * c / (2.0 * G) - profile.g(a)
    F_contact = 4.0 * sigma_c * a * c - 8.0 * G * profile.moment(a)
    F_total = F_contact + 2.0 * sigma_c * a * a * float(_zone_force(S))
    return ContactState(float(h), a * math.sqrt(1.0 + S * S), float(F_total), float(F_contact))


def equilibrium_at_contact_radius(a, profile, G, *, sigma_c=None, delta=None, gamma=None):
    """Elastic MDR-Dugdale equilibrium with contact radius a [m] > 0 (array or scalar).

    profile: a :class:`PowerLawProfile` or :class:`TabulatedProfile`; G [Pa] shear modulus
    (``E* = 4G``); two of sigma_c [Pa], delta [m], gamma [J/m^2].  Returns
    :class:`ContactState` ``(h [m], b [m], F_total [N], F_contact [N])``, forces positive in
    tension, ``h < 0`` pressing in.  For a non-decreasing ``g`` (power laws, convex tables) the
    zone end ``b`` is unique; otherwise the smallest ``b > a`` with ``gap(b) = delta`` is taken
    (the gap first reaches ``delta`` there, so the zone holds no point further than ``delta``).
    Several states per *lift* (JKR-like S-curves) appear as several ``a`` with the same ``h``.
    """
    sigma_c, delta, _ = _cohesive(sigma_c, delta, gamma)
    a_arr = np.asarray(a, float)
    if np.any(a_arr <= 0) or G <= 0:
        raise ValueError("need a > 0 and G > 0 (a = 0: zone_only_state)")
    states = []
    for ai in map(float, a_arr.ravel()):
        S = _solve_S(profile, ai, G, sigma_c, delta)
        states.append(_state_from_S(profile, ai, S, G, sigma_c))
    if a_arr.ndim == 0:
        return states[0]
    cols = np.array(states, dtype=float).T.reshape((4,) + a_arr.shape)
    return ContactState(*cols)


def zone_only_state(b, profile, G, *, sigma_c=None, delta=None, gamma=None):
    """Zone-only equilibrium (a = 0) with zone radius b [m] >= 0, explicit in b.

    ``h = delta + sigma_c b / (pi G) - f(b)`` [m] (``gap(b) = delta`` with ``u3D(b) = sigma_c b /
    (pi G)``), ``F_total = pi sigma_c b^2`` [N] (``2 int_0^b 2 sigma_c sqrt(b^2 - x^2) dx``),
    ``centre_gap = h - sigma_c b / (2G)`` [m] (``u(0) = q(0)/(4G)``).  Valid while
    ``centre_gap >= 0``, i.e. ``b <= join_radius(...)``; ``b = 0`` is the free state at
    ``h = delta``.  Returns :class:`ZoneOnlyState`, vectorised over b.
    """
    sigma_c, delta, _ = _cohesive(sigma_c, delta, gamma)
    b = np.asarray(b, float)
    h = delta + sigma_c * b / (np.pi * G) - np.asarray(profile.f(b))
    return ZoneOnlyState(_out(h), _out(b), _out(np.pi * sigma_c * b * b),
                         _out(h - sigma_c * b / (2.0 * G)))


def join_radius(profile, G, *, sigma_c=None, delta=None, gamma=None):
    """Zone radius b0 [m] where the zone-only branch touches (centre gap 0) and meets the contact
    branch's ``a -> 0`` end: ``f(b0) + sigma_c b0 (1/(2G) - 1/(pi G)) = delta`` (increasing in b0
    for a non-decreasing ``f``: one root)."""
    sigma_c, delta, _ = _cohesive(sigma_c, delta, gamma)
    k = sigma_c * (0.5 - 1.0 / np.pi) / G

    def resid(y):
        b = math.exp(y)
        return float(profile.f(b)) + k * b - delta

    y_hi = math.log(delta / k) + 1e-9  # just above the f = 0 root: an upper bound
    y_lo = y_hi - 2.0
    while resid(y_lo) >= 0.0:
        y_lo -= 2.0
    return math.exp(brentq(resid, y_lo, y_hi, xtol=_YTOL, rtol=_RTOL))


def zone_only_at_lift(h, profile, G, *, sigma_c=None, delta=None, gamma=None, branch="stable"):
    """Zone-only state at lift h [m]: ``b`` solves ``delta + sigma_c b/(pi G) - f(b) = h`` on
    ``0 < b <= b0``.  Up to two roots for a sphere: ``branch="stable"`` is the largest root with
    ``dh/db < 0`` (``f'(b) > sigma_c/(pi G)``: the state a rigid lift follows, reached from the
    contact branch), ``"nucleus"`` the smallest root (a growing zone, unstable under a rigid
    lift).  Returns :class:`ZoneOnlyState`, or None if no such state exists at this h."""
    sigma_c, delta, gamma = _cohesive(sigma_c, delta, gamma)
    kw = dict(sigma_c=sigma_c, delta=delta)
    b0 = join_radius(profile, G, **kw)
    bs = b0 * np.linspace(0.0, 1.0, 513)
    r = np.asarray(zone_only_state(bs, profile, G, **kw).h) - h
    idx = np.nonzero(np.sign(r[:-1]) * np.sign(r[1:]) <= 0)[0]
    roots = []
    for i in idx:
        if r[i] == 0.0:
            roots.append(bs[i])
        elif r[i + 1] != 0.0:
            roots.append(brentq(lambda b: float(zone_only_state(b, profile, G, **kw).h) - h,
                                bs[i], bs[i + 1], xtol=1e-300, rtol=_RTOL))
    roots = sorted(set(float(x) for x in roots) | ({b0} if r[-1] == 0.0 else set()))
    if branch == "nucleus":
        pick = roots[:1]
    elif branch == "stable":
        pick = [b for b in roots[::-1] if b > 0 and profile.df(b) > sigma_c / (np.pi * G)][:1]
    else:
        raise ValueError("branch: 'stable' or 'nucleus'")
    return zone_only_state(pick[0], profile, G, **kw) if pick else None


# ---------------------------------------------------------------------------------------------
# Elastic MDR-Dugdale: the whole curve, rigid-lift paths, pull-off
# ---------------------------------------------------------------------------------------------


def equilibrium_curve(profile, G, *, sigma_c=None, delta=None, gamma=None, a_max, a_min=None,
                      n_contact=200, n_zone=100):
    """The connected elastic equilibrium curve, ordered from indentation to separation.

    Contact branch at ``n_contact`` radii from a_max [m] down to a_min [m] (geometric; default
    ``1e-6 a_max``), then the zone-only branch from the join radius ``b0`` down to ``b = 0``
    (``h = delta``, where the free state ``h >= delta, F = 0`` continues it).  Returns a dict of
    arrays: ``h`` [m], ``F_total`` [N], ``F_contact`` [N], ``a`` [m], ``b`` [m] and ``branch``
    (0 contact, 1 zone-only).  A rigid lift follows the curve where ``h`` grows along it
    (stable under displacement control), see :func:`rigid_lift_cycle`.
    """
    sigma_c, delta, gamma = _cohesive(sigma_c, delta, gamma)
    kw = dict(sigma_c=sigma_c, delta=delta)
    a_min = 1e-6 * a_max if a_min is None else a_min
    a = np.geomspace(a_max, a_min, n_contact)
    cs = equilibrium_at_contact_radius(a, profile, G, **kw)
    b0 = join_radius(profile, G, **kw)
    # geometric towards b = 0 (the nucleus end), then b = 0 itself
    bz = np.concatenate([b0 * np.geomspace(1.0, 1e-6, n_zone - 1), [0.0]])
    zs = zone_only_state(bz, profile, G, **kw)
    zs.h[0] = sigma_c * b0 / (2.0 * G)  # exact at the join (the general form cancels there)
    return dict(
        h=np.concatenate([cs.h, zs.h]),
        F_total=np.concatenate([cs.F_total, zs.F_total]),
        F_contact=np.concatenate([cs.F_contact, np.zeros_like(bz)]),
        a=np.concatenate([a, np.zeros_like(bz)]),
        b=np.concatenate([cs.b, bz]),
        branch=np.concatenate([np.zeros(a.size, int), np.ones(bz.size, int)]),
    )


def _follow(h, F):
    """Walk a sampled curve with a rigid, monotonically increasing lift: advance while ``h``
    grows; at a maximum of ``h`` jump (same ``h``) to the first later sample pair where ``h``
    crosses that value upwards, or to the free state (F = 0) if there is none.  Returns the
    path (h, F) and the list of jumps ``(h, F_before, F_after)``."""
    H, P, jumps, i, n = [h[0]], [F[0]], [], 0, len(h)
    while i < n - 1:
        if h[i + 1] >= h[i]:
            i += 1
            H.append(h[i]), P.append(F[i])
            continue
        up = np.nonzero((h[i + 1:-1] <= h[i]) & (h[i + 2:] > h[i]))[0]
        if up.size == 0:
            jumps.append((h[i], F[i], 0.0))
            H.append(h[i]), P.append(0.0)
            break
        k = i + 1 + int(up[0])
        w = (h[i] - h[k]) / (h[k + 1] - h[k])
        F_land = F[k] + w * (F[k + 1] - F[k])
        jumps.append((h[i], F[i], F_land))
        H.append(h[i]), P.append(F_land)
        i = k + 1
        H.append(h[i]), P.append(F[i])
    return np.array(H), np.array(P), jumps


def rigid_lift_cycle(curve):
    """Quasi-static approach and retraction under displacement control (rigid machine) on a
    curve from :func:`equilibrium_curve` (resolution: its sampling).

    Retract: from the most indented sample, lift increasing.  Approach: from the free state at
    ``h = delta`` (the surfaces first feel each other when the centre gap reaches ``delta``),
    lift decreasing, the curve walked backwards.  Returns ``dict(retract=(h, F),
    approach=(h, F), retract_jumps=[...], approach_jumps=[...])`` with jumps as ``(h [m],
    F_before [N], F_after [N])``; the first retract jump is the displacement-control pull-off
    (jump-out), the first approach jump the jump-in.  The energy a cycle dissipates [J] is
    ``int F dh`` along the retraction plus along the approach, each in its own direction
    (tension > 0, lift up; the free-state parts carry no force).
    """
    h, F = np.asarray(curve["h"]), np.asarray(curve["F_total"])
    hr, Fr, jr = _follow(h, F)
    ha, Fa, ja = _follow(-h[::-1], F[::-1])
    ja = [(-x, y, z) for x, y, z in ja]
    return dict(retract=(hr, Fr), approach=(-ha, Fa), retract_jumps=jr, approach_jumps=ja)


def _dlog(fun, x, eps=1e-3):
    """``d fun / d log x`` by the 5-point stencil (error ~eps^4 plus rounding/eps)."""
    f = [fun(x * math.exp(k * eps)) for k in (-2, -1, 1, 2)]
    return (f[0] - 8.0 * f[1] + 8.0 * f[2] - f[3]) / (12.0 * eps)


def _first_turn(v, scale):
    """Index i of the first local maximum of the sampled v (``v[i+1] < v[i]`` by more than the
    rounding of v, ~1e-13 ``scale``), or None."""
    down = np.nonzero(np.diff(v) < -1e-13 * scale[:-1])[0]
    return int(down[0]) if down.size else None


def _refine(fun, lo, hi, fallback):
    """Root of fun in [lo, hi] if it changes sign there, else ``fallback`` (a grid point)."""
    f_lo, f_hi = fun(lo), fun(hi)
    if f_lo == 0.0:
        return lo
    if f_lo * f_hi > 0.0:
        return fallback
    return brentq(fun, lo, hi, xtol=1e-13, rtol=_RTOL)


def _faceted_peak(fun, lo, hi, knots, per_facet=8):
    """Radius [m] of the largest ``fun`` on [lo, hi] for a faceted (tabulated) profile: ``fun``
    is smooth on each facet but kinked at the knots, so a derivative root is not the maximum
    (a local one at best). Every knot and ``per_facet`` points inside each facet are sampled;
    the best sample's neighbouring facets are then maximised as the smooth pieces they are."""
    inside = knots[(knots > lo) & (knots < hi)]
    edges = np.concatenate([[lo], inside, [hi]])
    t = np.linspace(0.0, 1.0, per_facet + 2)[:-1]
    xs = np.append((edges[:-1, None] + np.outer(np.diff(edges), t)).ravel(), hi)
    vals = np.array([fun(x) for x in xs])
    k = int(np.nanargmax(vals))
    best_x, best_v = xs[k], vals[k]
    j = min(np.searchsorted(edges, xs[k], side="right") - 1, edges.size - 2)
    for m in (j - 1, j, j + 1):
        if 0 <= m < edges.size - 1:
            r = minimize_scalar(lambda x: -fun(x), bounds=(edges[m], edges[m + 1]),
                                method="bounded", options={"xatol": 1e-12 * edges[m + 1]})
            if -r.fun > best_v:
                best_x, best_v = float(r.x), -float(r.fun)
    return best_x


def _contact_scale(profile, G, gamma, b0):
    """Largest radius [m] worth sampling: 4x the larger of the join radius and the JKR zero-force
    radius (where ``sqrt(8 pi E* gamma a^3) = 2 E* M(a)``; beyond it the contact is in
    compression and far from pull-off)."""
    E = 4.0 * G
    a = b0
    for _ in range(200):
        if math.sqrt(8.0 * math.pi * E * gamma * a**3) < 2.0 * E * float(profile.moment(a)):
            return 4.0 * max(a, b0)
        a *= 2.0
    raise ValueError("no compressive contact found: a flat profile has no pull-off radius scale")


def mdr_dugdale_pulloff(profile, G, *, sigma_c=None, delta=None, gamma=None, control="load",
                        a_max=None, n=160, machine_stiffness=None):
    """Pull-off of the elastic MDR-Dugdale model for any (monotone) profile: :class:`PullOff`
    ``(F [N], h [m], a [m], b [m], branch)``, G [Pa], two of sigma_c [Pa], delta [m], gamma
    [J/m^2].

    control="load": the largest tension on the whole curve (contact branch, or its ``a -> 0``
    end, the join, since the zone-only force ``pi sigma_c b^2`` is largest there).
    control="displacement": where a rigid lift leaves the curve (module docstring): the largest
    ``a`` with ``dh/da = 0``; if ``h`` rises all the way to the join, the zone-only branch is
    followed while ``f'(b) > sigma_c/(pi G)`` and left where that fails (``dh/db = 0``), at the
    join if it fails there already, or at ``b = 0`` (``F = 0``, a continuous release).
    Behind a machine spring of ``machine_stiffness`` [N/m] (displacement control) it is the
    driver ``h + F/k`` that turns: the spring and the curve lose stability together, where
    ``dF/dh = -k`` (nan if that happens beyond the contact branch).
    The contact branch is sampled at ``n`` radii from a_max (default: :func:`_contact_scale`)
    down to 1e-6 of the smaller of the JKR and join scales, then refined by a root of the
    5-point derivative in ``log a`` (each point an exact equilibrium): measured agreement with
    Maugis' analytic derivatives 3e-15 (load) and 1e-11 (displacement) for the sphere.  For a
    :class:`TabulatedProfile` the load-control point is the largest over every facet and knot
    (:func:`_faceted_peak`: a derivative root on a faceted curve finds a local maximum) and the
    displacement-control point is a facet's (see there).
    """
    sigma_c, delta, gamma = _cohesive(sigma_c, delta, gamma)
    kw = dict(sigma_c=sigma_c, delta=delta)
    b0 = join_radius(profile, G, **kw)
    a_max = _contact_scale(profile, G, gamma, b0) if a_max is None else a_max
    a = np.geomspace(a_max, 1e-6 * min(a_max / 4.0, b0), n)
    cs = equilibrium_at_contact_radius(a, profile, G, **kw)
    # at the join h = sigma_c b0/(2G) exactly; delta + sigma_c b0/(pi G) - f(b0) would cancel
    # when f(b0) ~ delta (stiff solids)
    join = ZoneOnlyState(sigma_c * b0 / (2.0 * G), b0, math.pi * sigma_c * b0 * b0, 0.0)

    def state(x):
        return equilibrium_at_contact_radius(x, profile, G, **kw)

    def at(x, branch):
        s = state(x)
        return PullOff(s.F_total, s.h, x, s.b, branch)

    def refine(i, quantity):
        lo = math.log(a[i + 1]) if i + 1 < n else math.log(a[i]) - 7.0
        y = _refine(lambda y: _dlog(lambda x: quantity(state(x)), math.exp(y)),
                    lo, math.log(a[i - 1]), math.log(a[i]))
        return at(math.exp(y), "contact")

    if control == "load":
        F = np.append(cs.F_total, join.F_total)
        i = int(np.argmax(F))
        if i == 0:
            raise ValueError("largest tension at a_max: raise a_max")
        if i == n:
            return PullOff(join.F_total, join.h, 0.0, b0, "join")
        if isinstance(profile, TabulatedProfile):
            lo, hi = a[min(i + 2, n - 1)], a[max(i - 2, 0)]
            return at(_faceted_peak(lambda x: state(x).F_total, lo, hi, profile.r_table),
                      "contact")
        return refine(i, lambda s: s.F_total)
    if control != "displacement":
        raise ValueError("control: 'load' or 'displacement'")
    # h = sigma_c c/(2G) - g(a) is rounded at ~eps (|h| + 2 g(a)); near the join
    # h - h_join = O(a^2) for a sphere sinks below that, hence the tolerance
    compliance = 0.0 if machine_stiffness is None else 1.0 / machine_stiffness

    def driver(s):
        return s.h + compliance * s.F_total

    h = np.append(driver(cs), driver(join))
    i = _first_turn(h, np.abs(h) + 2.0 * np.append(profile.g(a), 0.0))
    if i == 0:
        raise ValueError("lift already falls at a_max: raise a_max")
    if i is not None and i < n:
        return refine(i, driver)
    if compliance:
        return PullOff(math.nan, math.nan, math.nan, math.nan, "beyond contact")
    return _zone_only_departure(profile, G, sigma_c, delta, b0)


def _zone_only_departure(profile, G, sigma_c, delta, b0):
    """Where a rigid lift leaves the zone-only branch entered at the join b0 [m]: the largest
    ``b <= b0`` with ``f'(b) = sigma_c/(pi G)`` (``dh/db = 0``), see mdr_dugdale_pulloff."""
    kw = dict(sigma_c=sigma_c, delta=delta)
    crit = sigma_c / (np.pi * G)
    bs = b0 * np.geomspace(1.0, 1e-9, 400)
    stable = np.asarray(profile.df(bs)) > crit
    if not stable[0]:
        b, branch = b0, "join"
    elif stable.all():
        b, branch = 0.0, "zone-only"
    else:
        j = int(np.argmin(stable))
        b = brentq(lambda x: float(profile.df(x)) - crit, bs[j], bs[j - 1], xtol=1e-300, rtol=_RTOL)
        branch = "zone-only"
    z = zone_only_state(b, profile, G, **kw)
    return PullOff(z.F_total, z.h, 0.0, b, branch)


# ---------------------------------------------------------------------------------------------
# JKR (sigma_c -> inf at fixed gamma) and DMT
# ---------------------------------------------------------------------------------------------


def jkr_state(a, profile, E_star, gamma):
    """JKR state at contact radius a [m] for any MDR profile: ``(h [m], F [N])``, tension > 0.

    MDR route (Popov & Hess 2015): contact elements ``u = h + g(x)``, line load
    ``E* u``; the JKR edge condition is that the boundary element is stretched by
    ``u(a) = sqrt(2 pi a gamma / E*)`` (Griffith balance of the 1D foundation).  So
    ``h = -g(a) + sqrt(2 pi a gamma / E*)`` and ``F = 2 E* int_0^a u dx =
    sqrt(8 pi E* gamma a^3) - 2 E* M(a)``, ``M(a) = int_0^a x g'(x) dx``.  Sphere:
    ``F = sqrt(8 pi E* gamma a^3) - 4 E* a^3 / (3R)`` (JKR 1971).  E_star [Pa], gamma [J/m^2].
    """
    a = np.asarray(a, float)
    w = np.sqrt(2.0 * np.pi * gamma * a / E_star)
    h = w - np.asarray(profile.g(a))
    F = 2.0 * E_star * a * w - 2.0 * E_star * np.asarray(profile.moment(a))
    return _out(h), _out(F)


def jkr_pulloff_power_law(coefficient, exponent, E_star, gamma, control="load"):
    """JKR pull-off of ``f = A r^n`` (n > 1/2, A [m^(1-n)] > 0): :class:`PullOff` (b = a).

    With ``w = sqrt(2 pi gamma / E*)``, ``K = kappa_n A``: ``h = w sqrt(a) - K a^n``,
    ``F = 2 E* w a^(3/2) - 2 E* K n a^(n+1) / (n+1)``.
    load (``dF/da = 0``): ``a^(n-1/2) = 3 w / (2 n K)``,
    ``F = 2 E* w a^(3/2) (2n-1) / (2(n+1))``, ``h = w sqrt(a) (2n-3)/(2n)``;
    displacement (``dh/da = 0``): ``a^(n-1/2) = w / (2 n K)`` (``a`` is ``3^(-2/(2n-1))`` times
    the above), ``F = 2 E* w a^(3/2) (2n+1) / (2(n+1))``, ``h = w sqrt(a) (2n-1)/(2n)``.
    Sphere: ``F = (3/2) pi gamma R`` at ``a^3 = 9 pi gamma R^2 / (8 E*)``, and ``(5/6) pi gamma
    R`` at ``a^3 = pi gamma R^2 / (8 E*)``; cone (slope t): ``(54/pi) gamma^2 / (E* t^3)`` and
    ``(6/pi) gamma^2 / (E* t^3)``.  Derived here by the MDR route and checked as the
    ``sigma_c -> inf`` limit of the MDR-Dugdale model; the frictionless power-law JKR problem is
    also treated by Borodich, Galanov & Suarez-Alvarez, J. Mech. Phys. Solids 68 (2014) 14.
    For n <= 1/2 the JKR force has no maximum: ValueError.
    """
    n, A = float(exponent), float(coefficient)
    if not (n > 0.5 and A > 0):
        raise ValueError("JKR pull-off needs exponent > 1/2 and coefficient > 0")
    K = mdr_kappa(n) * A
    w = math.sqrt(2.0 * math.pi * gamma / E_star)
    if control == "load":
        a = (3.0 * w / (2.0 * n * K)) ** (2.0 / (2.0 * n - 1.0))
        F = 2.0 * E_star * w * a**1.5 * (2.0 * n - 1.0) / (2.0 * (n + 1.0))
        h = w * math.sqrt(a) * (2.0 * n - 3.0) / (2.0 * n)
    elif control == "displacement":
        a = (w / (2.0 * n * K)) ** (2.0 / (2.0 * n - 1.0))
        F = 2.0 * E_star * w * a**1.5 * (2.0 * n + 1.0) / (2.0 * (n + 1.0))
        h = w * math.sqrt(a) * (2.0 * n - 1.0) / (2.0 * n)
    else:
        raise ValueError("control: 'load' or 'displacement'")
    return PullOff(F, h, a, a, "contact")


def jkr_pulloff(profile, E_star, gamma, control="load"):
    """JKR pull-off of any MDR profile by a root of ``dF/da`` (load: ``a g'(a) = (3/2) w
    sqrt(a)``) or ``dh/da`` (displacement: ``g'(a) = w / (2 sqrt a)``), ``w = sqrt(2 pi gamma
    / E*)``; the largest root, i.e. the first met while the contact shrinks.  :class:`PullOff`.
    For a :class:`TabulatedProfile` ``g'`` has spikes at the knots: the displacement-control
    root is then a facet's, found to the 400-point search grid.
    """
    w = math.sqrt(2.0 * math.pi * gamma / E_star)
    if control == "load":
        def d(a):
            return 1.5 * w * math.sqrt(a) - a * float(profile.dg(a))
    elif control == "displacement":
        def d(a):
            return 0.5 * w / math.sqrt(a) - float(profile.dg(a))
    else:
        raise ValueError("control: 'load' or 'displacement'")
    a_hi = _contact_scale(profile, E_star / 4.0, gamma, 1e-300 + w * w)
    grid = np.geomspace(a_hi, 1e-8 * a_hi, 400)
    vals = np.array([d(x) for x in grid])
    j = int(np.argmax(vals > 0.0))
    if vals[0] > 0.0 or vals[j] <= 0.0:
        raise ValueError("no JKR pull-off found in the sampled range")
    a = brentq(d, grid[j], grid[j - 1], xtol=1e-300, rtol=_RTOL)
    h, F = jkr_state(a, profile, E_star, gamma)
    return PullOff(F, h, a, a, "contact")


def dmt_sphere(a, R, E_star, gamma):
    """DMT sphere (Derjaguin, Muller & Toporov 1975, as used by Maugis 1992): Hertz contact
    plus the constant adhesive force ``2 pi gamma R``: ``h = -a^2/R`` [m],
    ``F = 2 pi gamma R - 4 E* a^3 / (3R)`` [N] (tension > 0).  Pull-off ``2 pi gamma R`` at
    ``a = 0``, ``h = 0`` (the same under load and displacement control in this limit)."""
    a = np.asarray(a, float)
    return _out(-a * a / R), _out(2.0 * np.pi * gamma * R - 4.0 * E_star * a**3 / (3.0 * R))


def dmt_pulloff_power_law(coefficient, exponent, *, sigma_c=None, delta=None, gamma=None):
    """Rigid (G -> inf, Maugis' lambda -> 0) limit of the MDR-Dugdale pull-off of
    ``f = A r^n`` [N]: the zone of a touching, undeformed indenter, ``pi sigma_c r_d^2`` with
    ``A r_d^n = delta``, i.e. ``pi sigma_c (delta / A)^(2/n)``.  Only for the sphere (n = 2) is
    it ``2 pi gamma R`` whatever the law (Derjaguin's approximation); otherwise it depends on
    sigma_c and delta separately, not on gamma alone."""
    sigma_c, delta, _ = _cohesive(sigma_c, delta, gamma)
    return math.pi * sigma_c * (delta / float(coefficient)) ** (2.0 / float(exponent))


# ---------------------------------------------------------------------------------------------
# Maugis-Dugdale sphere (Maugis, J. Colloid Interface Sci. 150 (1992) 243), in his variables
# ---------------------------------------------------------------------------------------------
#
# K = (4/3) E* = 16 G / 3; lambda = 2 sigma_0 (R / (pi w K^2))^(1/3); A = a / (pi w R^2/K)^(1/3);
# m = c/a (c: the zone end, our b); P-bar = P / (pi w R);
# Delta-bar = Delta / (pi^2 w^2 R/K^2)^(1/3), P compressive positive, Delta the indentation.
# With s = sqrt(m^2 - 1) (our S):
#   (lambda A^2/2) [s + (m^2 - 2) atan s] + (4 lambda^2 A/3) [s atan s - m + 1] = 1      (i)
#   P-bar = A^3 - lambda A^2 [s + m^2 atan s]                                          (ii)
#   Delta-bar = A^2 - (4/3) A lambda s                                                 (iii)
# Everything is written in s: m = sqrt(1 + s^2) as a float cannot resolve thin zones (m - 1).


def maugis_lambda(R, G, sigma_c, gamma):
    """Maugis' transition parameter ``lambda = 2 sigma_c (R / (pi gamma K^2))^(1/3)`` [-],
    ``K = (4/3) E* = 16 G / 3``; R [m], G [Pa], sigma_c [Pa], gamma [J/m^2].  JKR is
    ``lambda -> inf``, DMT ``lambda -> 0``; see also :func:`tabor_parameter`."""
    K = 16.0 * G / 3.0
    return 2.0 * sigma_c * (R / (math.pi * gamma * K * K)) ** (1.0 / 3.0)


def tabor_parameter(R, G, gamma, z0):
    """Tabor's ``mu = (R gamma^2 / (E*^2 z0^3))^(1/3)`` [-] (E* = 4G) for an equilibrium spacing
    z0 [m].  A Dugdale law with the Lennard-Jones peak stress ``sigma_c = 16 gamma / (9 sqrt(3)
    z0)`` has ``lambda = 1.1570 mu`` (Johnson & Greenwood, J. Colloid Interface Sci. 192 (1997)
    326)."""
    return (R * gamma * gamma / ((4.0 * G) ** 2 * z0**3)) ** (1.0 / 3.0)


def maugis_units(R, G, gamma):
    """Maugis' units ``(a_unit [m], P_unit [N], Delta_unit [m]) = ((pi gamma R^2/K)^(1/3),
    pi gamma R, (pi^2 gamma^2 R / K^2)^(1/3))``, ``K = 16 G / 3``: ``a = A a_unit`` etc."""
    K = 16.0 * G / 3.0
    return ((math.pi * gamma * R * R / K) ** (1.0 / 3.0), math.pi * gamma * R,
            (math.pi**2 * gamma**2 * R / K**2) ** (1.0 / 3.0))


def _maugis_pq(s):
    """``p = s + (s^2 - 1) atan s`` (series ``sum (-1)^(j-1) 4j s^(2j+1)/(4j^2-1)`` below
    s = 0.1, where the closed form cancels to ``4 s^3/3``) and ``q = s atan s - (m - 1)``."""
    s = np.asarray(s, float)
    p = s + (s * s - 1.0) * np.arctan(s)
    small = s < 0.1
    if np.any(small):
        t = s[small]
        ser = sum((-1) ** (j - 1) * 4.0 * j / (4.0 * j * j - 1.0) * t ** (2 * j + 1)
                  for j in range(8, 0, -1))
        p = np.where(small, 0.0, p)
        p[small] = ser
    q = _flat_gap(s)
    return p, q


def _maugis_branch(lam, s):
    """A, P-bar, Delta-bar and their s-derivatives on the contact branch (eqs. i-iii)."""
    s = np.asarray(s, float)
    p, q = _maugis_pq(s)
    at, m = np.arctan(s), np.sqrt(1.0 + s * s)
    al, be = 0.5 * lam * p, 4.0 * lam * lam / 3.0 * q
    # the positive root of al A^2 + be A = 1, in the form that does not cancel
    A = 2.0 / (be + np.sqrt(be * be + 4.0 * al))
    dal = 0.5 * lam * (2.0 * s * s / (1.0 + s * s) + 2.0 * s * at)
    dbe = 4.0 * lam * lam / 3.0 * (at + s / (1.0 + s * s) - s / m)
    dA = -(dal * A * A + dbe * A) / (2.0 * al * A + be)
    Q, dQ = s + m * m * at, 2.0 + 2.0 * s * at
    P = A**3 - lam * A * A * Q
    dP = 3.0 * A * A * dA - lam * (2.0 * A * dA * Q + A * A * dQ)
    D = A * A - 4.0 / 3.0 * lam * A * s
    dD = 2.0 * A * dA - 4.0 / 3.0 * lam * (dA * s + A)
    return A, P, D, dA, dP, dD


def maugis_parametric(lam, m=None, *, s=None):
    """Maugis' parametric solution: ``(A, P-bar, Delta-bar)`` at ``m = c/a > 1`` (or at
    ``s = sqrt(m^2 - 1)``, exact for thin zones) for lambda [-]; A from eq. (i), a quadratic.
    P-bar is compressive positive (our ``F_total = -P-bar pi gamma R``)."""
    if (m is None) == (s is None):
        raise ValueError("give m or s")
    s = np.sqrt(np.asarray(m, float) ** 2 - 1.0) if s is None else np.asarray(s, float)
    A, P, D = _maugis_branch(lam, s)[:3]
    return _out(A), _out(P), _out(D)


def maugis_at_contact_radius(A, lam):
    """``(m, P-bar, Delta-bar)`` at Maugis contact radius A > 0 (array or scalar): eq. (i) is
    increasing in s, one root in ``log s``."""
    A_arr = np.asarray(A, float)
    out = []
    for Ai in A_arr.ravel():
        def resid(y):
            p, q = _maugis_pq(math.exp(y))
            return 0.5 * lam * Ai * Ai * float(p) + 4.0 * lam * lam * Ai / 3.0 * float(q) - 1.0
        lo, hi = -2.0, 2.0
        while resid(lo) > 0:
            lo -= 4.0
        while resid(hi) < 0:
            hi += 4.0
        s = math.exp(brentq(resid, lo, hi, xtol=_YTOL, rtol=_RTOL, maxiter=300))
        _, P, D = maugis_parametric(lam, s=s)
        out.append((math.sqrt(1.0 + s * s), P, D))
    cols = np.array(out).T.reshape((3,) + A_arr.shape)
    return tuple(_out(c) for c in cols)


def maugis_zone_only(c_bar, lam):
    """Zone-only (a = 0) states in Maugis' variables at zone radius ``c_bar = b / a_unit``:
    ``P-bar = -(pi lambda / 2) c_bar^2``, ``Delta-bar = -2/(pi lambda) - (8 lambda/(3 pi)) c_bar
    + c_bar^2 / 2`` (our ``h = delta + sigma_c b/(pi G) - b^2/(2R)`` with ``delta = 2/(pi
    lambda)`` and ``sigma_c/(pi G) = 8 lambda/(3 pi)`` in these units).  Returns (P-bar,
    Delta-bar), and the join (contact at the centre) is at ``c0 = 2/(be + sqrt(be^2 + pi
    lambda))``, ``be = (4 lambda^2/3)(pi/2 - 1)``: the ``A -> 0`` limit of eq. (i)."""
    c = np.asarray(c_bar, float)
    return (_out(-0.5 * math.pi * lam * c * c),
            _out(-2.0 / (math.pi * lam) - 8.0 * lam / (3.0 * math.pi) * c + 0.5 * c * c))


def _maugis_join(lam):
    be = 4.0 * lam * lam / 3.0 * (0.5 * math.pi - 1.0)
    return 2.0 / (be + math.sqrt(be * be + math.pi * lam))


def maugis_force(a, R, G, sigma_c, gamma):
    """Maugis load P [N] (compressive positive: ``P = -F_total``) at contact radius a [m]."""
    a_u, P_u, _ = maugis_units(R, G, gamma)
    return _out(np.asarray(maugis_at_contact_radius(np.asarray(a) / a_u,
                                                    maugis_lambda(R, G, sigma_c, gamma))[1]) * P_u)


def maugis_indentation(a, R, G, sigma_c, gamma):
    """Maugis indentation Delta [m] (``= -h``) at contact radius a [m]."""
    a_u, _, d_u = maugis_units(R, G, gamma)
    return _out(np.asarray(maugis_at_contact_radius(np.asarray(a) / a_u,
                                                    maugis_lambda(R, G, sigma_c, gamma))[2]) * d_u)


#: Below this lambda the contact radius of a sphere under a rigid lift shrinks to zero without
#: instability and the zone-only branch is followed: ``c* = 8 lambda/(3 pi) < c0`` (the zone-only
#: turning point lies before the join) exactly when ``16 (pi - 1) lambda^3 / (9 pi) < 1``.
MAUGIS_LAMBDA_ZONE_DEPARTURE = (9.0 * math.pi / (16.0 * (math.pi - 1.0))) ** (1.0 / 3.0)


class MaugisPullOff(NamedTuple):
    """A Maugis pull-off point in his variables: P-bar (< 0 in tension), Delta-bar, A, s =
    sqrt(m^2 - 1) (inf on the zone-only branch), c_bar = zone radius / a_unit, branch."""

    P: float
    Delta: float
    A: float
    s: float
    c_bar: float
    branch: str


def maugis_pulloff(lam, control="load"):
    """Maugis-Dugdale pull-off of a sphere as a function of lambda [-], in Maugis' variables.

    load: the minimum of P-bar over the contact branch (interior for every lambda; it tends to
    -3/2 as lambda -> inf and to -2 as lambda -> 0).  displacement: where a rigid lift leaves
    the curve (module docstring).  For ``lambda > MAUGIS_LAMBDA_ZONE_DEPARTURE`` (= 0.93795) that
    is the first ``dDelta/dA = 0`` on the contact branch met as A decreases (tends to -5/6 as
    lambda -> inf).  Below it ``Delta`` keeps decreasing all the way to A = 0 (near the join
    ``Delta = Delta_0 + O(A^2)``), the lift continues on the zone-only branch and leaves it at
    its turning point ``c* = 8 lambda / (3 pi)``: ``P-bar = -(32/(9 pi)) lambda^3``, which tends
    to 0 with lambda -- the DMT-like sphere is released without a jump.  The two forms meet at
    ``P-bar = -2/(pi - 1)``.  Returns :class:`MaugisPullOff`; analytic s-derivatives are used
    for the roots.
    """
    c0 = _maugis_join(lam)
    # from far beyond pull-off (A >> 1) to A ~ 1e-6 c0 (where Delta - Delta_join ~ A^2 is still
    # far above rounding)
    s = np.geomspace(1e-3 * min(1.0, 1.0 / lam), 1e6 * max(1.0, c0), 1500)
    A, P, D, dA, dP, dD = _maugis_branch(lam, s)

    def point(si, branch="contact"):
        Ai, Pi, Di = _maugis_branch(lam, si)[:3]
        return MaugisPullOff(float(Pi), float(Di), float(Ai), float(si), float(Ai * si), branch)

    def root(k, i):  # root of the k-th output (an s-derivative) between s[i-1] and s[i]
        fun = lambda y: float(_maugis_branch(lam, math.exp(y))[k])  # noqa: E731
        y = _refine(fun, math.log(s[i - 1]), math.log(s[i]), None)
        return None if y is None else math.exp(y)

    if control == "load":
        # P falls while A shrinks (dP/ds < 0) down to its minimum; the sign change of the
        # analytic derivative locates it even where P is flat to rounding (lambda -> 0)
        up = np.nonzero(dP >= 0.0)[0]
        P_j, D_j = maugis_zone_only(c0, lam)
        si = root(4, int(up[0])) if up.size and up[0] > 0 else None
        if si is not None and point(si).P <= P_j:
            return point(si)
        # lambda < ~1e-5: the interior minimum is within rounding of the join value (their
        # difference is O(lambda^3)), and dP/ds is noise there
        return MaugisPullOff(P_j, D_j, 0.0, math.inf, c0, "join")
    if control != "displacement":
        raise ValueError("control: 'load' or 'displacement'")
    # stable while Delta falls as A falls (dD/ds < 0).  Near the join dD/ds = O(A^2/s) comes
    # from cancelling terms of size A/s; a sign below their rounding is not a turn (it matters
    # only within ~1e-4 of lambda_c, where a turn and the join give the same force to 1e-12)
    noise = 1e-13 * (np.abs(2.0 * A * dA) + 4.0 / 3.0 * lam * (np.abs(dA) * s + A))
    turn = np.nonzero(dD > noise)[0]
    if turn.size:
        i = int(turn[0])
        if i == 0:
            raise ValueError("grid starts beyond the turning point")
        si = root(5, i)
        return point(s[i] if si is None else si)
    c_star = 8.0 * lam / (3.0 * math.pi)
    c = min(c_star, c0)
    P_z, D_z = maugis_zone_only(c, lam)
    return MaugisPullOff(P_z, D_z, 0.0, math.inf, c, "zone-only" if c_star < c0 else "join")


def maugis_pulloff_force(R, G, sigma_c, gamma, control="load"):
    """Maugis-Dugdale pull-off force of a sphere [N] as a *tension* (``-P-bar pi gamma R``);
    R [m], G [Pa], sigma_c [Pa], gamma [J/m^2]; see :func:`maugis_pulloff`."""
    lam = maugis_lambda(R, G, sigma_c, gamma)
    return -maugis_pulloff(lam, control).P * math.pi * gamma * R
