"""Independent high-accuracy reference for the exact model of MODEL.md section 3.

The simulator time-steps a discretised foundation; this module instead evaluates the exact
("history: exact") solution by nested adaptive quadrature of the explicit element solutions
(``scipy.integrate.quad``) and locates detachment with ``scipy.optimize.brentq``.  It imports
nothing from the rest of ``pulloff`` on purpose, so that it can serve as an independent check.

Dimensionless formulation (used internally for conditioning)
------------------------------------------------------------
Lengths along the surface in ``a``, displacements/lift/gap in ``delta``, time in ``delta/v``::

    x' = x/a,  b' = b/a,  U = u/delta,  H = h/delta = H0 + T,  T = t v/delta,
    k = 2 G delta/(sigma_c a),  c = 2 eta v/(sigma_c a).

Dividing the edge condition ``4 G h + 4 eta v = 2 sigma_c sqrt(b^2 - a^2)`` by ``2 sigma_c a``
gives ``S(T) = k H(T) + c`` with ``S = sqrt(b'^2 - 1)``: S grows linearly in T.  Each free
element is labelled by ``sigma = sqrt(x'^2 - 1)``, so that ``b'^2 - x'^2 = S^2 - sigma^2`` holds
without cancellation even for thin zones, and its ODE becomes ``k U + c dU/dT = sqrt(S^2 -
sigma^2)``.  Changing the time variable to ``S' = S(T')`` (valid for k > 0)::

    U(sigma, T) = 1/(c k) int_{max(S0, sigma)}^{S} exp(-(S - S')/c) sqrt(S'^2 - sigma^2) dS'

and the gap (``acos(a/b) = atan(S)`` removes the cancellation of ``h - h asin(a/b)``)::

    gap/delta = (2/pi) [ H atan(S) - I ],
    I = int_0^S U(sigma) sigma / (sqrt(1 + sigma^2) sqrt(S^2 - sigma^2)) dsigma.

Detachment always happens for ``v > 0`` and ``G + eta > 0``: the "frozen history" displacement
``sqrt(S^2 - sigma^2) (1 - exp(-k T/c))/k`` bounds ``U`` from above (loads only grow), so its
closed-form gap bounds the exact gap from below and its root is a rigorous upper bound on the
detachment time; ``I >= 0`` gives a rigorous lower bound.  brentq runs inside that bracket
(this assumes, as checked in the tests, that the gap increases with t once the zone exists).

Verified accuracy (tests/test_reference.py and the development checks behind them): the gap
agrees with an independent 20-30 digit mpmath evaluation in the original variables (x, t') to
~1e-16 relative; element displacements agree with solve_ivp (DOP853/Radau/LSODA at rtol 1e-13)
to ~3e-13; eta = 0 and G = 0 reproduce the closed forms to ~1e-15; the eta -> 0 and G -> 0
corrections follow eps (A ln(1/eps) + B) to ~1e-11 of t at eps = 1e-7..1e-10; rtol 1e-8, 1e-10
and 1e-12 agree to < 1e-11 on t_detach over random scenes with chi 1e-10..1e2, alpha 1e-8..1e12.
"""

from __future__ import annotations

import math
import sys

from scipy import integrate, optimize

__all__ = ["reference_gap", "reference_detachment", "reference_displacement"]

# The memory kernel exp(-w) is cut at w = _W_CUT: e^-80 ~ 2e-35 stays far below any rtol even
# after multiplication by the largest possible ratio of kernel support to layer width.
_W_CUT = 80.0
# Breakpoints (in kernel e-folds w) that let QAGP resolve the exponential boundary layer of the
# inner integral without blind bisection.
_W_POINTS = (1.0, 4.0, 16.0)
# Breakpoints for the outer integral, in units of (S - sigma)/c: the recently entered elements
# (entered less than a few eta/G ago) still lag their quasi-static value there.
_LAYER_POINTS = (0.25, 1.0, 4.0, 16.0, 64.0)
_QUAD_LIMIT = 400
# QUADPACK refuses epsrel < 50 eps when epsabs = 0.
_MIN_EPSREL = 1e-13
_BRENT_RTOL = 4.0 * sys.float_info.epsilon


def _quad(f, lo, hi, epsrel, points=None):
    # full_output=1 keeps QUADPACK's round-off diagnostics (expected near 1e-12) from spamming
    # warnings; accuracy is established by the independent checks in tests/test_reference.py,
    # not by these flags.
    pts = None
    if points:
        pts = sorted(p for p in points if lo < p < hi)
        pts = pts or None
    res = integrate.quad(f, lo, hi, epsabs=0.0, epsrel=max(epsrel, _MIN_EPSREL),
                         limit=_QUAD_LIMIT, points=pts, full_output=1)
    return res[0]


class _Scene:
    """Dimensionless scene (see module docstring)."""

    def __init__(self, G, eta, sigma_c, delta, a, v, h0):
        G, eta, sigma_c, delta, a, v, h0 = (float(z) for z in (G, eta, sigma_c, delta, a, v, h0))
        if not (a > 0 and sigma_c > 0 and delta > 0 and v > 0):
            raise ValueError("need a > 0, sigma_c > 0, delta > 0 and v > 0")
        if not (G >= 0 and eta >= 0):
            raise ValueError("need G >= 0 and eta >= 0")
        self.G, self.eta, self.sigma_c, self.delta, self.a, self.v, self.h0 = (
            G, eta, sigma_c, delta, a, v, h0)
        self.k = 2.0 * G * delta / (sigma_c * a)
        self.c = 2.0 * eta * v / (sigma_c * a)
        self.H0 = h0 / delta
        self.S0 = self.k * self.H0 + self.c

    def S(self, T):
        return max(self.k * (self.H0 + T) + self.c, 0.0)

    # ---- rigorous bounds on the gap (closed form) -------------------------------------------
    def gap_upper(self, T):
        """(2/pi) H atan(S): the gap with I = 0, an upper bound."""
        S = self.S(T)
        return 2.0 / math.pi * (self.H0 + T) * math.atan(S)

    def _frozen_factor(self, T):
        # (1 - exp(-k T/c))/k with its two limits; expm1 keeps it exact for k T/c -> 0.
        k, c = self.k, self.c
        if c == 0.0:
            return 1.0 / k
        if k == 0.0:
            return T / c
        return -math.expm1(-k * T / c) / k

    def gap_frozen(self, T):
        """Frozen-history gap, a lower bound of the exact gap."""
        S = self.S(T)
        wid = S * S / (1.0 + math.sqrt(1.0 + S * S))  # sqrt(1+S^2) - 1 without cancellation
        return 2.0 / math.pi * ((self.H0 + T) * math.atan(S) - self._frozen_factor(T) * wid)

    # ---- element solution ---------------------------------------------------------------------
    def U_inner(self, sig, Y, p2, eps):
        """Dimensionless displacement U of element sigma at the current time.

        With y = S - S' (kernel argument times c) the element solution reads::

            U = 1/(c k) int_0^Y exp(-y/c) sqrt((s^2 - y)(s^2 + 2 sigma - y)) dy,

        s^2 = S - sigma, Y = S - max(S0, sigma) (how far S has grown since the element was first
        loaded) and p2 = s^2 - Y = max(S0 - sigma, 0).  Y and p2 are passed in because the
        callers know them without cancellation: Y can be 1e-16 of s^2 (G -> 0) and the kernel
        width c can be 1e-16 of Y (eta -> 0), so neither may be formed as a difference here.
        Near y = 0 (the exponential layer) y itself is the variable; near y = Y, where the load
        has its sqrt(t' - t_entry) onset when p2 = 0, y = Y - z^2 makes the integrand smooth.
        """
        if Y <= 0.0:
            return 0.0
        k, c = self.k, self.c
        s2 = Y + p2
        t2 = s2 + 2.0 * sig
        if c == 0.0:  # elastic: no memory
            return math.sqrt(s2 * t2) / k
        sqrt, exp = math.sqrt, math.exp
        y_m = 0.5 * Y
        ycut = min(y_m, _W_CUT * c)

        def f1(y):
            return exp(-y / c) * sqrt((s2 - y) * (t2 - y))

        total = _quad(f1, 0.0, ycut, eps, [w * c for w in _W_POINTS])
        if y_m < _W_CUT * c:
            zmax = sqrt(Y - y_m)
            zlo = sqrt(Y - _W_CUT * c) if Y > _W_CUT * c else 0.0
            q2 = p2 + 2.0 * sig  # t2 - Y

            def f2(z):
                zz = z * z
                return 2.0 * z * exp(-(Y - zz) / c) * sqrt((p2 + zz) * (q2 + zz))

            pts = [sqrt(Y - w * c) for w in _W_POINTS if w * c < Y]
            total += _quad(f2, zlo, zmax, eps, pts)
        return total / (c * k)

    # ---- gap ----------------------------------------------------------------------------------
    def I_integral(self, T, eps_out, eps_in):
        """I(T) = int_0^S U sigma/(sqrt(1+sigma^2) sqrt(S^2-sigma^2)) dsigma, with s = sqrt(S-sigma).

        In s the 1/sqrt(S - sigma) end-point singularity disappears:
        dsigma/sqrt(S^2 - sigma^2) = 2 ds/sqrt(2S - s^2).
        """
        S = self.S(T)
        if S <= 0.0 or T <= 0.0:
            return 0.0
        k, c = self.k, self.c
        sqrt = math.sqrt
        rootS = sqrt(S)

        if k == 0.0 or c == 0.0:
            # Elastic (U = sqrt(S^2-sig^2)/k) or purely viscous (S = c fixed, U = T sqrt(.)/c):
            # no entry history, only the outer quadrature is left.
            coef = 1.0 / k if c == 0.0 else T / c

            def g(s):
                sig = S - s * s
                return coef * s * sqrt(s * s + 2.0 * sig) * sig / sqrt(1.0 + sig * sig) \
                    * 2.0 / sqrt(2.0 * S - s * s)

            return _quad(g, 0.0, rootS, eps_out)

        S0c = max(self.S0, 0.0)
        # S - S0c without cancellation (k T when the zone existed at t = 0): elements with
        # sigma > S0c entered after t = 0.
        Ys0 = k * T if self.S0 >= 0.0 else S
        s0 = sqrt(Ys0)
        total = 0.0

        # Region 1: s in (0, s0), sigma in (S0c, S): elements that entered at T_e > 0.  The
        # boundary layer (recently entered elements, S - sigma ~ c) sits near s = 0.
        if s0 > 0.0:
            def g1(s):
                sig = S0c + (s0 - s) * (s0 + s)
                U = self.U_inner(sig, s * s, 0.0, eps_in)
                return U * sig / sqrt(1.0 + sig * sig) * 2.0 / sqrt(2.0 * S - s * s)

            pts = [sqrt(w * c) for w in _LAYER_POINTS]
            total += _quad(g1, 0.0, s0, eps_out, pts)

        # Region 2: sigma in (0, S0c), loaded since t = 0.  U has a one-sided (S0 - sigma)^(3/2)
        # kink at sigma = S0; s = s0 + r^2 turns it into r^3.
        if S0c > 0.0:
            rmax = sqrt(S0c / (rootS + s0))  # sqrt(sqrt(S) - s0) without cancellation

            def g2(r):
                s = s0 + r * r
                p2 = r * r * (s + s0)  # S0 - sigma
                sig = max(S0c - p2, 0.0)
                U = self.U_inner(sig, Ys0, p2, eps_in)
                return 2.0 * r * U * sig / sqrt(1.0 + sig * sig) * 2.0 / sqrt(2.0 * S - s * s)

            total += _quad(g2, 0.0, rmax, eps_out)
        return total

    def gap(self, T, rtol):
        """Dimensionless gap (units of delta) at dimensionless time T."""
        S = self.S(T)
        if S <= 0.0:
            return 0.0
        eps_out = rtol
        eps_in = 0.1 * rtol
        I = self.I_integral(T, eps_out, eps_in)
        return 2.0 / math.pi * ((self.H0 + T) * math.atan(S) - I)

    # ---- forces -------------------------------------------------------------------------------
    def forces(self, T):
        h = self.delta * (self.H0 + T)
        S = self.S(T)
        F_contact = 8.0 * self.a * (self.G * h + self.eta * self.v)
        return F_contact, F_contact + self.sigma_c * 2.0 * self.a ** 2 * _zone_bracket(S)


def _zone_bracket(S):
    """(1 + S^2) atan(S) - S, i.e. [pi b^2 - 2 a sqrt(b^2-a^2) - 2 b^2 asin(a/b)]/(2 a^2).

    The two terms cancel to O(S^3) for thin zones, so small S uses the series
    sum_{n>=1} (-1)^(n+1) 2 S^(2n+1)/((2n-1)(2n+1)).
    """
    if S <= 0.0:
        return 0.0
    if S > 0.1:
        return (1.0 + S * S) * math.atan(S) - S
    S2 = S * S
    total, term, n = 0.0, S * S2, 1
    while True:
        add = (1.0 if n % 2 else -1.0) * 2.0 * term / ((2 * n - 1) * (2 * n + 1))
        total += add
        if abs(add) <= 1e-18 * abs(total):
            return total
        term *= S2
        n += 1


def reference_displacement(x, t, G, eta, sigma_c, delta, a, v, h0=0.0, rtol=1e-12):
    """Displacement u(x, t) [m] of the free element at x > a [m], time t >= 0 [s].

    Solution of ``4 G u + 4 eta du/dt = 2 sigma_c sqrt(max(b(t)^2 - x^2, 0))``, ``u(x,0) = 0``
    by quadrature.  G, eta in Pa and Pa s, sigma_c in Pa, delta, a, h0 in m, v in m/s.
    For x <= a the element is bonded and ``h(t)`` is returned.
    """
    sc = _Scene(G, eta, sigma_c, delta, a, v, h0)
    T = float(t) * v / delta
    xr = float(x) / a
    if xr <= 1.0:
        return sc.delta * (sc.H0 + T)
    sig = math.sqrt((xr - 1.0) * (xr + 1.0))
    S = sc.S(T)
    if sig >= S or T <= 0.0:
        return 0.0
    if sc.k == 0.0:
        return sc.delta * T * math.sqrt((S - sig) * (S + sig)) / sc.c
    S0c = max(sc.S0, 0.0)
    if sig >= S0c:  # entered after t = 0
        return sc.delta * sc.U_inner(sig, S - sig, 0.0, rtol)
    Ys0 = sc.k * T if sc.S0 >= 0.0 else S
    return sc.delta * sc.U_inner(sig, Ys0, S0c - sig, rtol)


def reference_gap(t, G, eta, sigma_c, delta, a, v, h0=0.0, rtol=1e-11):
    """Gap [m] at the end r = b of the cohesive zone at time t [s] (MODEL.md section 3).

    G [Pa], eta [Pa s], sigma_c [Pa], delta [m], a [m], v [m/s], h0 [m] (lift h = h0 + v t).
    rtol is the relative tolerance of the outer quadrature (the inner one runs 10x tighter).
    """
    sc = _Scene(G, eta, sigma_c, delta, a, v, h0)
    return sc.delta * sc.gap(float(t) * v / delta, rtol)


def _root_bracket(f, T_start=1.0):
    """Some T with f(T) >= 0 and a T_prev < T with f(T_prev) < 0 (or 0), by doubling/halving."""
    T = T_start
    if f(T) >= 0.0:
        while T > 1e-300:
            Tp = 0.5 * T
            if f(Tp) < 0.0:
                return Tp, T
            T = Tp
        return 0.0, T
    for _ in range(4000):
        Tn = 2.0 * T
        if f(Tn) >= 0.0:
            return T, Tn
        T = Tn
    raise RuntimeError("no root found in bracket search")


def reference_detachment(G, eta, sigma_c, delta, a, v, h0=0.0, rtol=1e-10, t_max=None):
    """Detachment of the flat punch for the exact model (MODEL.md section 3).

    Parameters: G [Pa], eta [Pa s], sigma_c [Pa], delta [m], a [m], v [m/s] (> 0), h0 [m];
    rtol: requested relative accuracy of t_detach (the gap quadrature runs at rtol/10);
    t_max [s]: give up after this time.  Default None means no limit: for v > 0 and G + eta > 0
    the frozen-history root is a rigorous finite upper bound of t_detach, so the search always
    terminates; only G = eta = 0 (b stays at a, gap stays 0) never detaches.

    Returns dict(detached: bool, t_detach [s], h_detach [m], b_detach [m], F_contact [N],
    F_total [N]); all values nan when not detached.  t_detach = 0 if gap(0) >= delta.
    """
    sc = _Scene(G, eta, sigma_c, delta, a, v, h0)
    nan = float("nan")
    none = dict(detached=False, t_detach=nan, h_detach=nan, b_detach=nan,
                F_contact=nan, F_total=nan)
    T_max = math.inf if t_max is None else float(t_max) * v / delta
    eps_gap = 0.1 * rtol

    def result(T):
        S = sc.S(T)
        Fc, Ft = sc.forces(T)
        return dict(detached=True, t_detach=T * delta / v, h_detach=delta * (sc.H0 + T),
                    b_detach=a * math.sqrt(1.0 + S * S), F_contact=Fc, F_total=Ft)

    # U(0) = 0 for eta > 0 (a damper cannot move instantly), so the gap with I = 0 is the
    # exact gap(0); an elastic solid (eta = 0) carries U = q/(4G) at once: the frozen gap.
    gap0 = sc.gap_frozen(0.0) if sc.c == 0.0 < sc.k else sc.gap_upper(0.0)
    if gap0 >= 1.0:
        return result(0.0)
    if sc.k == 0.0 and sc.c == 0.0:
        return none

    # Rigorous bracket from the closed-form bounds: gap_frozen <= gap <= gap_upper.
    lo_a, lo_b = _root_bracket(lambda T: sc.gap_upper(T) - 1.0)
    T_lo = optimize.brentq(lambda T: sc.gap_upper(T) - 1.0, lo_a, lo_b, xtol=1e-300,
                           rtol=_BRENT_RTOL)
    hi_a, hi_b = _root_bracket(lambda T: sc.gap_frozen(T) - 1.0, T_lo)
    if hi_a > 0.0 and sc.gap_frozen(hi_a) < 1.0:
        T_hi = optimize.brentq(lambda T: sc.gap_frozen(T) - 1.0, hi_a, hi_b, xtol=1e-300,
                               rtol=_BRENT_RTOL)
    else:
        T_hi = hi_b
    T_hi = max(T_hi, T_lo)
    if T_lo > T_max:
        return none

    def F(T):
        return sc.gap(T, eps_gap) - 1.0

    if T_hi > T_max:
        if F(T_max) < 0.0:
            return none
        T_hi = T_max
    f_lo, f_hi = F(T_lo), F(T_hi)
    # The bounds can be tight (elastic and viscous limits are exact), so quadrature noise may
    # put both ends on one side: nudge outwards.
    j = 0
    while f_hi < 0.0:
        j += 1
        if j > 60:
            raise RuntimeError("detachment bracket failed (gap not reaching delta)")
        T_hi *= 1.0 + 1e-12 * 4.0 ** j
        if T_hi > T_max:
            return none
        f_hi = F(T_hi)
    j = 0
    while f_lo > 0.0:
        j += 1
        if j > 60:
            raise RuntimeError("detachment bracket failed (gap above delta at lower bound)")
        T_lo *= 1.0 - 1e-12 * 4.0 ** j
        f_lo = F(T_lo)
    if f_lo == 0.0:
        return result(T_lo)
    if f_hi == 0.0:
        return result(T_hi)
    T_d = optimize.brentq(F, T_lo, T_hi, xtol=1e-300 + 1e-3 * rtol * T_lo,
                          rtol=max(_BRENT_RTOL, 1e-3 * rtol), maxiter=200)
    return result(T_d)
