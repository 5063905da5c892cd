"""Independent reference for the moving-edge pull-off of a flat punch (MODEL.md sections 1-3, 6, 8).

``flat_punch_reference`` solves the MDR-Dugdale pull of a rigid flat punch of radius ``R`` from
a linear visco-elastic half-space (elastic, Kelvin-Voigt, standard linear solid / Prony series
of Maxwell arms) through all phases: bonded (``a`` pinned), receding (both ``a`` and ``b``
move) and zone-only (``a = 0``), to complete separation. It imports nothing from the rest of
``pulloff`` and shares no code with the project's solvers.

Method ("history quadrature", no spatial mesh)
----------------------------------------------
Elements do not interact, so the displacement of the element at any ``x`` and time ``t`` is an
explicit functional of the history of the two edge radii. The solver therefore stores *no
element states*: it stores the history of the scalars ``t_k``, ``A_k = a_k^2``,
``B_k = b_k^2`` and ``s_k = q_b(t_k)/(2 sigma_c)`` on a time grid and, whenever the gap at the
zone end is needed, computes the element displacements at the quadrature nodes of the gap
integral *exactly* from that history:

* Opening ``d = u_r - u`` of an element against a reference element that carries the bonded
  load ``q_r`` (so ``u_r = h`` under a rigid machine). Bonded elements have ``d = 0``; an element
  released by the receding edge starts at ``d = 0``; ``d`` obeys the same linear law as ``u``
  driven by ``q_r - q(x, t) = 2 sigma_c (s - sqrt(b^2 - x^2)_+) >= 0``, so it is a sum of
  positive terms (no cancellation even when ``h >> delta``). The gap is
  ``gap(b) = (h - u_r) + (2/pi) int_0^{phi_max} d dphi`` with ``x = b cos(phi)``,
  ``sqrt(b^2 - x^2) = b sin(phi)`` (no ``1/sqrt`` singularity, no cancellation of ``h``).
* Rheology as exponential modes: ``d = alpha0 dq + sum_m w_m z_m``,
  ``z_m' = lambda_m z_m + c_m dq``. Kelvin-Voigt: one mode, ``lambda = -G/eta``; Maxwell arms:
  the eigen-decomposition of the dashpot system; elastic: no mode, ``alpha0 = 1/(4G)``. Each mode
  is integrated exactly over the history: ``int exp(lambda (t - s)) dq(x, s) ds``.
* The history between grid points: on each step the unknown (``A`` in the receding phase,
  ``B`` in the zone-only phase) is the degree-5 polynomial through the six nearest points of
  the same smooth segment (centred once they exist, one-sided for the newest steps), as a
  function of time -- or, where the edge moves fast (near a fold, at the final collapse), time
  as a function of the unknown. Never a chord-length parameter (that would cap the geometric
  order at 4); never across a phase change (onset, a = 0), where the path has weak
  (fractional-power/logarithmic) singularities: steps are graded geometrically (factor 2,
  smallest ~N^-2/3 of the nominal step) away from the start and towards the end of each
  segment. In the bonded phase under a rigid machine ``b(t)`` (external) or ``a(t)``
  (internal) is explicit and used exactly: the onset carries no time-discretisation error.
  Behind a machine spring the internal zone's bonded path is an ODE in ``theta = asin(s/R)``
  (:class:`_SpringPath`; the point-by-point force balance is unstable there), integrated to
  ~1e-13 and interpolated in theta, so its onset or strength limit carries no
  time-discretisation error either; after the strength limit the zone holds the whole face
  (``a = 0``, ``b = R``, ``h = v t - pi R^2 sigma_c/k_m``) until gap(R) = delta.
* Steps are of unit "chord" ``sqrt((dt/dt2)^2 + (dy/dY)^2)`` with ``dt2 = t2/N`` and
  ``dY = min(R^2, 2 (a^2 + s^2)) / N`` (so thin zones keep resolving ``a`` down to the zone
  width); each fixes whichever of ``t`` or ``y`` moves more and solves the scalar condition
  ``gap(b) = delta`` (edge condition built in: ``b^2 = a^2 + s^2``) for the other with a
  safeguarded secant that starts on the extrapolated branch and searches only locally
  (branch continuation); a failed step is retried with half the chord.
* The per-step time integrals use Gauss-Legendre (10 points) where the load
  ``sqrt(b(s)^2 - x^2)`` is far from its zero, and otherwise an adaptive Gauss-Kronrod rule
  that splits at the entry/exit/release instants and removes the square root by
  ``p = p* +- r^2`` (exact onset integration in every step, also when the zero lies just
  outside the step; MODEL.md section 8). The gap integral over ``phi`` is adaptive
  Gauss-Kronrod (21 points) with breakpoints at the kinks of ``d(x)`` (edge positions at the
  phase changes).
* Instability and separation: at the onset (and at a = 0) the sign of d(gap)/d(a^2) (resp.
  d(gap)/d(b^2)) at fixed time decides: if a receding edge (a smaller zone) would open the
  gap further, the state is unstable and the punch comes off at once (an elastic solid at its
  onset). A fold (the branch turning back in time, detected in a step that fixes ``y``) is
  located as the maximum of ``t`` along the interpolated branch: separation by snap-off.
  Otherwise the zone collapses, ``b -> 0`` (the centre gap ``h - u(0)`` reaches delta).
* Convergence: levels ``N = N0 2^l``; the quadrature tolerances are fixed below the
  discretisation error (gap ~1e-11 delta). Observed orders 3 to 6 depending on the scene (about
  5-6 for the thin-zone seed, 3-4 for wide zones and Maxwell solids). The reported values are
  the finest level; ``error_estimate`` is the largest relative change between the two finest
  levels (conservative), ``error_estimate_richardson`` that change over ``2^p - 1``.

Units: SI throughout (m, s, Pa, Pa s, N, N/m).
"""

from __future__ import annotations

import math
import time as _time

import numba as nb
import numpy as np
from scipy.optimize import brentq

__all__ = ["flat_punch_reference", "EdgeRun"]

# --------------------------------------------------------------------------------------------
# Quadrature constants (QUADPACK qk15 / qk21) and Gauss-Legendre on [0, 1]
# --------------------------------------------------------------------------------------------

_K15_X = np.array([0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                   0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                   0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                   0.207784955007898467600689403773245, 0.0])
_K15_W = np.array([0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                   0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                   0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                   0.204432940075298892414161999234649, 0.209482141084727828012999174891714])
_G7_W = np.array([0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                  0.381830050505118944950369775488975, 0.417959183673469387755102040816327])
_K21_X = np.array([0.995657163025808080735527280689003, 0.973906528517171720077964012084452,
                   0.930157491355708226001207180059508, 0.865063366688984510732096688423493,
                   0.780817726586416897063717578345042, 0.679409568299024406234327365114874,
                   0.562757134668604683339000099272694, 0.433395394129247190799265943165784,
                   0.294392862701460198131126603103866, 0.148874338981631210884826001129720,
                   0.0])
_K21_W = np.array([0.011694638867371874278064396062192, 0.032558162307964727478818972459390,
                   0.054755896574351996031381300244580, 0.075039674810919952767043140916190,
                   0.093125454583697605535065465083366, 0.109387158802297641899210590325805,
                   0.123491976262065851077208814520268, 0.134709217311473325928054001771707,
                   0.142775938577060080797094273138717, 0.147739104901338491374841515972068,
                   0.149445554002916905664936468389821])
_G10_W = np.array([0.066671344308688137593568809893332, 0.149451349150580593145776339657697,
                   0.219086362515982043995534934228163, 0.269266719309996355091226921569469,
                   0.295524224714752870173892994651338])

_NG = 10  # Gauss points per step on the fast path
_NC = 6  # polynomial coefficients per step (degree <= 5)
_gx, _gw = np.polynomial.legendre.leggauss(_NG)
_GX = 0.5 * (_gx + 1.0)
_GW = 0.5 * _gw

# step parameterisation codes
_Y_A, _Y_B, _Y_EXT1, _Y_INT1 = 0, 1, 2, 3  # what the interpolated y is
_S_EXACT, _S_INTERP, _S_FROZEN = 0, 1, 2  # how s(t) = q_r/(2 sigma_c) is known


# --------------------------------------------------------------------------------------------
# numba kernels (all private to this file, which also keeps them safe in the disk cache:
# none calls a compiled function of another module)
# --------------------------------------------------------------------------------------------

@nb.njit(cache=True)
def _sq_exact(t, sp):
    """s(t) = q_r(t)/(2 sigma_c) of the bonded track under a rigid machine (h = h0 + v t)."""
    kind = int(sp[0])
    h0 = sp[1]
    v = sp[2]
    sig = sp[3]
    G = sp[4]
    eta = sp[5]
    h = h0 + v * t
    if kind == 0:
        return 2.0 * (G * h + eta * v) / sig
    if kind == 1:
        return 2.0 * G * h / sig
    n = int(sp[6])
    s = G * h
    for i in range(n):
        Gi = sp[7 + 2 * i]
        ti = sp[8 + 2 * i]
        em = -math.expm1(-t / ti)
        s += Gi * (h0 * (1.0 - em) + v * ti * em)
    return 2.0 * s / sig


@nb.njit(cache=True)
def _poly(c, p):
    acc = 0.0
    for j in range(c.size - 1, -1, -1):
        acc = acc * p + c[j]
    return acc


@nb.njit(cache=True)
def _dpoly(c, p):
    acc = 0.0
    for j in range(c.size - 1, 0, -1):
        acc = acc * p + j * c[j]
    return acc


@nb.njit(cache=True)
def _eval(k, p, ymode, smode, tco, yco, sco, sp):
    """(t, dt/dp, A - R^2, B - R^2, s) on step k at parameter p (p may leave [0, 1])."""
    c = tco[k]
    t = _poly(c, p)
    tp = _dpoly(c, p)
    sm = smode[k]
    if sm == 0:
        sq = _sq_exact(t, sp)
    elif sm == 1:
        sq = _poly(sco[k], p)
    else:
        sq = sco[k, 0]
    ym = ymode[k]
    if ym == 0:
        dA = _poly(yco[k], p)
        dB = dA + sq * sq
    elif ym == 1:
        dB = _poly(yco[k], p)
        dA = dB - sq * sq
    elif ym == 2:
        dA = 0.0
        dB = sq * sq
    else:
        dB = 0.0
        dA = -sq * sq
    return t, tp, dA, dB, sq


@nb.njit(cache=True)
def _prep(k0, k1, T, ymode, smode, tco, yco, sco, sp, lam, sigma, gx, gw,
          dBg, Kg, Ok, dBx, stiff):
    """Fast-path data of steps k0..k1-1: Gauss nodes, kernel weights, outside-zone integral."""
    M = lam.size
    for k in range(k0, k1):
        T1 = T[k + 1]
        for m in range(M):
            Ok[k, m] = 0.0
        for g in range(gx.size):
            t, tp, dA, dB, sq = _eval(k, gx[g], ymode, smode, tco, yco, sco, sp)
            dBg[k, g] = dB
            for m in range(M):
                kk = gw[g] * tp * math.exp(lam[m] * (T1 - t))
                Kg[k, m, g] = kk
                Ok[k, m] += kk * 2.0 * sigma * sq
        for j in range(4):
            t, tp, dA, dB, sq = _eval(k, -1.0 + j, ymode, smode, tco, yco, sco, sp)
            dBx[k, j] = dB
        dt = abs(T[k + 1] - T[k])
        st = False
        for m in range(M):
            if abs(lam[m]) * dt > 5.0:
                st = True
        stiff[k] = st


@nb.njit(cache=True)
def _gk15_seg(k, X2, r0, r1, pstar, sgn, T1, ymode, smode, tco, yco, sco, sp, lam, sigma,
              xk, wk, wg, resk, resg):
    """Kronrod-15 and Gauss-7 of the per-mode step integrand over r in [r0, r1].

    p = r (sgn = 0) or p = pstar + sgn r^2 (square root of the load removed at pstar)."""
    M = lam.size
    for m in range(M):
        resk[m] = 0.0
        resg[m] = 0.0
    hl = 0.5 * (r1 - r0)
    cen = 0.5 * (r1 + r0)
    for j in range(15):
        if j < 7:
            r = cen - hl * xk[j]
            wkk = wk[j]
            jj = j
        elif j == 7:
            r = cen
            wkk = wk[7]
            jj = 7
        else:
            jj = 14 - j
            r = cen + hl * xk[jj]
            wkk = wk[jj]
        if sgn == 0:
            p = r
            jac = 1.0
        else:
            p = pstar + sgn * r * r
            jac = 2.0 * abs(r)
        t, tp, dA, dB, sq = _eval(k, p, ymode, smode, tco, yco, sco, sp)
        g = dB - X2
        base = 2.0 * sigma * (sq - (math.sqrt(g) if g > 0.0 else 0.0)) * tp * jac
        isg = (jj % 2 == 1) or jj == 7
        wgg = 0.0
        if isg:
            wgg = wg[(jj - 1) // 2] if jj != 7 else wg[3]
        for m in range(M):
            f = base * math.exp(lam[m] * (T1 - t))
            resk[m] += wkk * f * hl
            if isg:
                resg[m] += wgg * f * hl


@nb.njit(cache=True)
def _adapt_step(k, X2, r0, r1, pstar, sgn, T1, ymode, smode, tco, yco, sco, sp, lam, sigma,
                tol, out, xk, wk, wg):
    M = lam.size
    resk = np.empty(M)
    resg = np.empty(M)
    sa = np.empty(400)
    sb = np.empty(400)
    n = 1
    sa[0] = r0
    sb[0] = r1
    width = r1 - r0
    it = 0
    while n > 0:
        n -= 1
        a = sa[n]
        b = sb[n]
        _gk15_seg(k, X2, a, b, pstar, sgn, T1, ymode, smode, tco, yco, sco, sp, lam, sigma,
                  xk, wk, wg, resk, resg)
        err = 0.0
        for m in range(M):
            e = abs(resk[m] - resg[m])
            if e > err:
                err = e
        it += 1
        if (err <= tol * (b - a) / width or n >= 398 or it > 100 or (b - a) < 1e-15 * width
                or not (err < 1e300)):
            for m in range(M):
                out[m] += resk[m]
        else:
            mid = 0.5 * (a + b)
            sa[n] = a
            sb[n] = mid
            sa[n + 1] = mid
            sb[n + 1] = b
            n += 2


@nb.njit(cache=True)
def _groot(k, X2, lo, hi, glo, ymode, smode, tco, yco, sco, sp):
    """Root of g(p) = B(p) - x^2 in [lo, hi] given a sign change (bisection + secant)."""
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        t, tp, dA, dB, sq = _eval(k, mid, ymode, smode, tco, yco, sco, sp)
        gm = dB - X2
        if (gm > 0.0) == (glo > 0.0):
            lo = mid
            glo = gm
        else:
            hi = mid
    return 0.5 * (lo + hi)


@nb.njit(cache=True)
def _gval(k, p, X2, ymode, smode, tco, yco, sco, sp):
    """g(p) = b(p)^2 - x^2 on step k (the element is loaded where g > 0)."""
    t, tp, dA, dB, sq = _eval(k, p, ymode, smode, tco, yco, sco, sp)
    return dB - X2


@nb.njit(cache=True)
def _slow_step(k, plo, X2, T1, ymode, smode, tco, yco, sco, sp, lam, sigma, tol, out,
               xk, wk, wg):
    """Accumulate int_{plo}^1 exp(lam (T1 - t)) dq(x, p) t'(p) dp per mode into out.

    Splits [plo, 1] at the zeros of g = b(p)^2 - x^2 (entry/exit of the zone) and removes the
    square root of the load by p = p* +- r^2 at every zero of g at or near an end of a
    loaded piece (also at a zero just outside the step: onset integrated in every step)."""
    roots = _zone_crossings(k, plo, X2, ymode, smode, tco, yco, sco, sp)
    tr0, tr1, tps, tsg, nt = _piece_tasks(k, plo, X2, roots, ymode, smode, tco, yco, sco, sp)
    for j in range(nt):
        _adapt_step(k, X2, tr0[j], tr1[j], tps[j], tsg[j], T1, ymode, smode, tco, yco, sco,
                    sp, lam, sigma, tol, out, xk, wk, wg)


@nb.njit(cache=True)
def _zone_crossings(k, plo, X2, ymode, smode, tco, yco, sco, sp):
    """The zeros of g = b(p)^2 - x^2 in [plo, 1] and the nearest one just outside on either
    side (an onset integrated in every step), ascending."""
    ns = 8
    # pass 1: sample g, collect the brackets of its zeros inside [plo, 1] and just outside
    ps = np.empty(ns + 1)
    gs = np.empty(ns + 1)
    for i in range(ns + 1):
        ps[i] = plo + (1.0 - plo) * i / ns
        gs[i] = _gval(k, ps[i], X2, ymode, smode, tco, yco, sco, sp)
    glo_out = _gval(k, plo - 1.0, X2, ymode, smode, tco, yco, sco, sp)
    ghi_out = _gval(k, 2.0, X2, ymode, smode, tco, yco, sco, sp)
    blo = np.empty(ns + 2)
    bhi = np.empty(ns + 2)
    bg = np.empty(ns + 2)
    nr = 0
    # zero before the step (index 0 of the result when present)
    if gs[0] > 0.0 and glo_out <= 0.0:
        blo[nr] = plo - 1.0
        bhi[nr] = plo
        bg[nr] = glo_out
        nr += 1
    for i in range(ns):
        if (gs[i] > 0.0) != (gs[i + 1] > 0.0):
            blo[nr] = ps[i]
            bhi[nr] = ps[i + 1]
            bg[nr] = gs[i]
            nr += 1
    if gs[ns] > 0.0 and ghi_out <= 0.0:
        blo[nr] = 1.0
        bhi[nr] = 2.0
        bg[nr] = gs[ns]
        nr += 1
    roots = np.empty(nr)
    for j in range(nr):
        roots[j] = _groot(k, X2, blo[j], bhi[j], bg[j], ymode, smode, tco, yco, sco, sp)
    return roots


@nb.njit(cache=True)
def _piece_tasks(k, plo, X2, roots, ymode, smode, tco, yco, sco, sp):
    """The pieces of [plo, 1] between the interior zeros, each as a task ``(r0, r1, p*,
    sign)`` of :func:`_adapt_step` (``sign`` 0: no square root to remove); returns the task
    arrays and their count."""
    nr = roots.size
    brk = np.empty(nr + 2)
    nb_ = 0
    brk[nb_] = plo
    nb_ += 1
    for j in range(nr):
        if plo < roots[j] < 1.0:
            brk[nb_] = roots[j]
            nb_ += 1
    brk[nb_] = 1.0
    nb_ += 1
    tr0 = np.empty(2 * nb_)
    tr1 = np.empty(2 * nb_)
    tps = np.empty(2 * nb_)
    tsg = np.empty(2 * nb_, dtype=np.int64)
    nt = 0
    for i in range(nb_ - 1):
        u0 = brk[i]
        u1 = brk[i + 1]
        if u1 <= u0:
            continue
        loaded = _gval(k, 0.5 * (u0 + u1), X2, ymode, smode, tco, yco, sco, sp) > 0.0
        # zeros bounding this piece (interior ones are exact ends, outer ones may lie beyond)
        pL = -1e300
        pR = 1e300
        for j in range(nr):
            if roots[j] <= u0 + 1e-15 and roots[j] > pL:
                pL = roots[j]
            if roots[j] >= u1 - 1e-15 and roots[j] < pR:
                pR = roots[j]
        haveL = loaded and pL > u0 - 1.0 - 1e-12
        haveR = loaded and pR < u1 + 1.0 + 1e-12
        if haveL and haveR:
            mid = 0.5 * (u0 + u1)
            tr0[nt], tr1[nt], tps[nt], tsg[nt] = (math.sqrt(max(u0 - pL, 0.0)),
                                                  math.sqrt(mid - pL), pL, 1)
            nt += 1
            tr0[nt], tr1[nt], tps[nt], tsg[nt] = (math.sqrt(max(pR - u1, 0.0)),
                                                  math.sqrt(pR - mid), pR, -1)
            nt += 1
        elif haveL:
            tr0[nt], tr1[nt], tps[nt], tsg[nt] = (math.sqrt(max(u0 - pL, 0.0)),
                                                  math.sqrt(u1 - pL), pL, 1)
            nt += 1
        elif haveR:
            tr0[nt], tr1[nt], tps[nt], tsg[nt] = (math.sqrt(max(pR - u1, 0.0)),
                                                  math.sqrt(pR - u0), pR, -1)
            nt += 1
        else:
            tr0[nt], tr1[nt], tps[nt], tsg[nt] = u0, u1, 0.0, 0
            nt += 1
    return tr0, tr1, tps, tsg, nt


@nb.njit(cache=True)
def _arel(k, X2, ymode, smode, tco, yco, sco, sp):
    """Release parameter p in step k: A(p) = x^2 (A decreasing through the step)."""
    lo = 0.0
    hi = 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        t, tp, dA, dB, sq = _eval(k, mid, ymode, smode, tco, yco, sco, sp)
        if dA > X2:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@nb.njit(cache=True)
def _element_d(X2, W2, free_start, L, T, DA, DB, SQ, ymode, smode, tco, yco, sco, sp,
               dBg, Kg, Ok, dBx, stiff, E, lam, cw, d0, alpha0, sigma, qscale, qtol,
               xk, wk, wg):
    """Opening d = u_r - u [m] of the element at x (X2 = x^2 - R^2, W2 = b^2 - x^2) at T[L]."""
    M = lam.size
    acc = np.zeros(M)
    tmp = np.zeros(M)
    if free_start:
        kr = 0
        pr = 0.0
    else:
        if DA[0] <= X2:
            kr = 0
            pr = 0.0
        elif DA[L] > X2:
            return 0.0
        else:
            lo = 0
            hi = L  # DA[lo] > X2 >= DA[hi]
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if DA[mid] > X2:
                    lo = mid
                else:
                    hi = mid
            kr = lo
            pr = _arel(lo, X2, ymode, smode, tco, yco, sco, sp)
    ng = dBg.shape[1]
    for k in range(kr, L):
        plo = pr if k == kr else 0.0
        fast = 0
        if plo == 0.0 and not stiff[k]:
            g0 = dBx[k, 0] - X2
            g1 = dBx[k, 1] - X2
            g2 = dBx[k, 2] - X2
            g3 = dBx[k, 3] - X2
            var = max(abs(g2 - g1), max(abs(g1 - g0), abs(g3 - g2)))
            if g0 > 0.0 and g1 > 0.0 and g2 > 0.0 and g3 > 0.0 and min(g1, g2) > 2.5 * var:
                fast = 1
            elif g0 < 0.0 and g1 < 0.0 and g2 < 0.0 and g3 < 0.0 and max(g1, g2) < -2.5 * var:
                fast = 2
        if fast == 2:
            for m in range(M):
                acc[m] += E[k, m] * Ok[k, m]
        elif fast == 1:
            for m in range(M):
                s = 0.0
                for g in range(ng):
                    s += Kg[k, m, g] * math.sqrt(dBg[k, g] - X2)
                acc[m] += E[k, m] * (Ok[k, m] - 2.0 * sigma * s)
        else:
            for m in range(M):
                tmp[m] = 0.0
            tol = qtol * qscale * (abs(T[k + 1] - T[k]) + 1e-300)
            _slow_step(k, plo, X2, T[k + 1], ymode, smode, tco, yco, sco, sp, lam, sigma,
                       tol, tmp, xk, wk, wg)
            for m in range(M):
                acc[m] += E[k, m] * tmp[m]
    d = 0.0
    if alpha0 > 0.0:
        d += alpha0 * 2.0 * sigma * (SQ[L] - math.sqrt(max(W2, 0.0)))
    for m in range(M):
        d += cw[m] * acc[m]
        if free_start:
            d += d0[m] * math.exp(lam[m] * (T[L] - T[0]))
    return d


@nb.njit(cache=True)
def _emat(L, T, lam):
    M = lam.size
    E = np.empty((max(L, 1), M))
    for k in range(L):
        for m in range(M):
            E[k, m] = math.exp(lam[m] * (T[L] - T[k + 1]))
    return E


@nb.njit(cache=True)
def _gap_integral(L, b, dBL, phis, external, T, DA, DB, SQ, ymode, smode, tco, yco, sco, sp,
                  dBg, Kg, Ok, dBx, stiff, lam, cw, d0, alpha0, sigma, qscale, qtol, gtol,
                  xk15, wk15, wg7, xk21, wk21, wg10, stats):
    """int d dphi over [phis[0], phis[-1]] (x = b cos(phi)), adaptive Kronrod-21 per panel."""
    E = _emat(L, T, lam)
    total = 0.0
    sa = np.empty(200)
    sb = np.empty(200)
    fv = np.empty(21)
    span = phis[phis.size - 1] - phis[0]
    nev = 0
    npan = 0
    for ip in range(phis.size - 1):
        n = 1
        sa[0] = phis[ip]
        sb[0] = phis[ip + 1]
        if sb[0] <= sa[0]:
            continue
        while n > 0:
            n -= 1
            a = sa[n]
            bb = sb[n]
            hl = 0.5 * (bb - a)
            cen = 0.5 * (bb + a)
            for j in range(21):
                if j < 10:
                    ph = cen - hl * xk21[j]
                elif j == 10:
                    ph = cen
                else:
                    ph = cen + hl * xk21[20 - j]
                w = b * math.sin(ph)
                W2 = w * w
                X2 = dBL - W2
                fs = external and X2 > 0.0
                fv[j] = _element_d(X2, W2, fs, L, T, DA, DB, SQ, ymode, smode, tco, yco, sco,
                                   sp, dBg, Kg, Ok, dBx, stiff, E, lam, cw, d0, alpha0, sigma,
                                   qscale, qtol, xk15, wk15, wg7)
                nev += 1
            rk = wk21[10] * fv[10]
            rg = 0.0
            for j in range(10):
                jj = 20 - j
                rk += wk21[j] * (fv[j] + fv[jj])
                if j % 2 == 1:
                    rg += wg10[(j - 1) // 2] * (fv[j] + fv[jj])
            rk *= hl
            rg *= hl
            npan += 1
            if (abs(rk - rg) <= gtol * (bb - a) / span or n >= 198 or (bb - a) < 1e-14 * span
                    or npan > 300 or not (abs(rk - rg) < 1e300)):
                total += rk
                stats[1] += 1
            else:
                mid = cen
                sa[n] = a
                sb[n] = mid
                sa[n + 1] = mid
                sb[n + 1] = bb
                n += 2
    stats[0] += nev
    return total


@nb.njit(cache=True)
def _ref_u(L, T, SQ, Ok, lam, cw, alpha0, sigma):
    """Displacement u_r(T[L]) of the reference element (load q_r, u_r(0) = 0)."""
    M = lam.size
    u = alpha0 * 2.0 * sigma * SQ[L]
    for m in range(M):
        s = 0.0
        for k in range(L):
            s += math.exp(lam[m] * (T[L] - T[k + 1])) * Ok[k, m]
        u += cw[m] * s
    return u


# --------------------------------------------------------------------------------------------
# Small helpers
# --------------------------------------------------------------------------------------------

_COH_SERIES = [(-1) ** (n + 1) * 2.0 / ((2 * n - 1) * (2 * n + 1)) for n in range(1, 31)]


def _coh_bracket(S):
    """(1 + S^2) atan(S) - S without cancellation."""
    if S < 0.5:
        s2 = S * S
        acc = 0.0
        for c in reversed(_COH_SERIES):
            acc = acc * s2 + c
        return S * s2 * acc
    return (1.0 + S * S) * math.atan(S) - S


def _forces(A, B, s, sigma):
    """(F_contact, F_total) [N] for bond radius^2 A, zone radius^2 B, s = q_b/(2 sigma_c)."""
    if A <= 0.0:
        return 0.0, sigma * math.pi * max(B, 0.0)
    a = math.sqrt(A)
    Fc = 4.0 * sigma * a * s
    return Fc, Fc + 2.0 * sigma * A * _coh_bracket(s / a)


def _lagrange_coeffs(nodes, vals):
    """Monomial coefficients (length 4) of the polynomial through (nodes, vals)."""
    n = len(nodes)
    V = np.vander(np.asarray(nodes, float), n, increasing=True)
    c = np.linalg.solve(V, np.asarray(vals, float))
    out = np.zeros(4)
    out[:n] = c
    return out


def _modes(G_inf, eta, arms):
    """Exponential modes of the opening law: (alpha0, lam, cw, w) with d = alpha0 dq + sum w z."""
    if arms:
        Gs = np.array([g for g, _ in arms], float)
        taus = np.array([t for _, t in arms], float)
        G0 = G_inf + Gs.sum()
        n = len(arms)
        Mm = (np.outer(np.ones(n), Gs) / G0 - np.eye(n)) / taus[:, None]
        c = 1.0 / (4.0 * G0 * taus)
        lam, V = np.linalg.eig(Mm)
        if np.max(np.abs(np.imag(lam))) > 0:
            raise ValueError("complex relaxation spectrum")
        lam = np.real(lam)
        V = np.real(V)
        cz = np.linalg.solve(V, c)
        w = (Gs / G0) @ V
        return 1.0 / (4.0 * G0), lam, cz * w, w
    if eta > 0.0:
        return 0.0, np.array([-G_inf / eta]), np.array([1.0 / (4.0 * eta)]), np.array([1.0])
    return 1.0 / (4.0 * G_inf), np.zeros(0), np.zeros(0), np.zeros(0)


class _SpringPath:
    """Bonded phase of an internal zone behind a machine spring ``k_m``, in the angle theta:
    ``s = q_b/(2 sigma_c) = R sin(theta)``, ``a = R cos(theta)``.

    Why not the force balance solved point by point on the interpolated load history (as the
    external zone does): that is an Adams-Moulton recursion for ``s``, unstable once
    ``k_m dt`` exceeds the bonded disc's damping ``8 eta a`` (spring and damper in series), and
    ``a -> 0`` at the strength limit makes the ratio unbounded; there, moreover,
    ``a ~ (t_sl - t)^(1/3)``, so no path in time is smooth. In theta the path is analytic up to
    and including ``theta = pi/2`` (``t_sl - t ~ (pi/2 - theta)^3``): with the modes of the
    reference element, ``u_r = alpha0 q + sum_m y_m``, ``y_m' = lam_m y_m + cw_m q``,
    ``q = 2 sigma_c R sin(theta)``, the balance ``k_m (v t - u_r) = F(theta)`` gives

        dy_m/dtheta = (lam_m y_m + cw_m q) dt/dtheta,
        dt/dtheta = (F'(theta) + 2 k_m alpha0 sigma_c R cos(theta)) / (k_m (v - sum_m y_m')),

    ``F = sigma_c R^2 (2 theta + sin(2 theta))`` (the total force), ``F' = 4 sigma_c R^2
    cos^2(theta)``; ``t`` itself comes from the balance (no drift). Integrated to ~1e-13
    (DOP853, dense output); an elastic solid has no modes and ``t(theta)`` in closed form.
    ``theta_end < pi/2`` if ``v - sum y'`` reaches 0 first (the spring would stop stretching:
    not modelled)."""

    def __init__(self, alpha0, lam, cw, sigma, R, v, km):
        self.alpha0, self.lam, self.cw = alpha0, np.asarray(lam), np.asarray(cw)
        self.sigma, self.R, self.v, self.km = sigma, R, v, km
        self.sol = None
        self.theta_end = 0.5 * math.pi
        if self.lam.size:
            self._integrate()

    def force(self, th):
        return self.sigma * self.R ** 2 * (2.0 * th + math.sin(2.0 * th))

    def _rates(self, th, y):
        """(dy/dtheta, v - sum y') [m, m/s] at theta."""
        sR = self.sigma * self.R
        r = self.lam * y + self.cw * (2.0 * sR * math.sin(th))
        nv = self.v - float(np.sum(r))
        c = math.cos(th)
        dt = (4.0 * sR * self.R * c * c + 2.0 * self.km * self.alpha0 * sR * c) / (self.km * nv)
        return r * dt, nv

    def _integrate(self):
        from scipy.integrate import solve_ivp

        def stop(th, y):
            return self._rates(th, y)[1]

        stop.terminal, stop.direction = True, -1
        # length scale of u_r: the spring's stretch plus the relaxed response to 2 sigma_c R
        lam_abs = np.where(self.lam != 0.0, np.abs(self.lam), np.inf)
        ell = self.force(0.5 * math.pi) / self.km + 2.0 * self.sigma * self.R * (
            self.alpha0 + float(np.sum(self.cw / lam_abs)))
        sol = solve_ivp(lambda th, y: self._rates(th, y)[0], (0.0, 0.5 * math.pi),
                        np.zeros(self.lam.size), method="DOP853", rtol=1e-13,
                        atol=1e-16 * ell, dense_output=True, events=stop)
        # a failed integration (dt/dtheta -> inf as v - sum y' -> 0) still holds up to sol.t[-1]
        self.sol = sol.sol
        self.theta_end = float(sol.t[-1])

    def t(self, th):
        """Time [s] at which the bonded path reaches theta."""
        u = self.alpha0 * 2.0 * self.sigma * self.R * math.sin(th)
        if self.sol is not None:
            u += float(np.sum(self.sol(th)))
        return (u + self.force(th) / self.km) / self.v

    def mesh(self, dt1, dth1):
        """Points 0 = theta_0 < ... < theta_n = theta_end of unit chord
        ``sqrt((dt/dt1)^2 + (dtheta/dth1)^2)`` (a smooth grading, ends exactly at theta_end)."""
        th = np.linspace(0.0, self.theta_end, 4097)
        tt = np.array([self.t(x) for x in th])
        dens = np.hypot(np.gradient(tt, th) / dt1, 1.0 / dth1)
        cum = np.concatenate(([0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(th))))
        n = max(4, int(math.ceil(cum[-1])))
        return np.interp(np.linspace(0.0, cum[-1], n + 1), cum, th)


# --------------------------------------------------------------------------------------------
# One resolution
# --------------------------------------------------------------------------------------------

class _NoRoot(Exception):
    pass


class _Seg:
    """A smooth piece of the path (between phase changes): points i0..i1 are interpolated
    together; ``u`` holds their chord coordinates (fallback interpolation variable)."""

    def __init__(self, i0, ymode, smode, exact, dt, dy):
        self.i0 = i0
        self.i1 = None
        self.ym = ymode
        self.sm = smode
        self.exact = exact
        self.dt = dt
        self.dy = dy
        self.u = [0.0]
        self.fix = {}  # point (relative index) -> coordinate held fixed in its solve
        self.by_u = False  # interpolate in u (a smooth path parameter), never in time
        self.deg = None  # degree of the local interpolants (None: EdgeRun.DEG)


class EdgeRun:
    """One run of the reference at a fixed resolution.

    ``N`` sets the steps: the bonded phase uses ``dt = t1_scale/N`` [s]; the receding and
    zone-only phases use steps of (graded) unit chord ``sqrt((dt/dt2)^2 + (dy/dY)^2)`` with
    ``dt2 = t2_scale/N`` [s] and ``dY = y_scale/N`` [m^2] (refined where a^2 + s^2 < y_scale/2;
    ``y = a^2 - R^2`` or ``b^2 - R^2``), so that slow and fast edge motion, folds and the final
    collapse are all resolved. ``run_phase1()``, ``run_propagation()``, then ``results()``.
    Not part of the stable API; see :func:`flat_punch_reference`.
    """

    DEG = 5  # degree of the local interpolants of the path (order of the scheme)

    def __init__(self, *, G_inf, eta, arms, sigma_c, delta, R, v, h0, zone, machine_stiffness,
                 N, t1_scale, t2_scale, y_scale, t_max=None, qtol=1e-13, gtol_rel=1e-10,
                 verbose=False):
        self.G_inf, self.eta, self.arms = float(G_inf), float(eta), tuple(arms)
        self.sigma, self.delta, self.R, self.v, self.h0 = map(float, (sigma_c, delta, R, v, h0))
        self.R2 = self.R * self.R
        if zone not in ("external", "internal"):
            raise ValueError("zone must be 'external' or 'internal'")
        self.external = zone == "external"
        self.km = None if machine_stiffness is None else float(machine_stiffness)
        if self.km is not None and self.h0 != 0.0:
            raise ValueError("a machine spring starts relaxed: h0 must be 0")
        if self.arms and self.eta:
            raise ValueError("Maxwell arms and a Kelvin-Voigt viscosity are not combined")
        if not self.arms and self.eta == 0.0 and self.G_inf <= 0.0:
            raise ValueError("an elastic solid needs G_inf > 0")
        self.alpha0, lam, cw, _w = _modes(self.G_inf, self.eta, self.arms)
        self.lam = np.ascontiguousarray(lam, float)
        self.cw = np.ascontiguousarray(cw, float)
        self.M = self.lam.size
        self.d0 = np.zeros(self.M)
        if not self.arms and self.eta > 0.0:
            self.d0[0] = self.h0  # KV element free from t = 0 (external, x > R): u = 0, d = h0
        kind = 2 if self.arms else (0 if self.eta > 0 else 1)
        sp = [kind, self.h0, self.v, self.sigma, self.G_inf, self.eta, len(self.arms)]
        for g, tau in self.arms:
            sp += [g, tau]
        self.sp = np.array(sp, float)
        self.N = int(N)
        # graded steps at segment ends: the smallest chord is 2^-grade ~ N^(-2/3)
        self.grade = max(3, int(math.ceil(2.0 / 3.0 * math.log2(max(N, 2)))))
        self.ykappa = 2.0  # local y step ~ ykappa (a^2 + s^2)/N (bond) or b^2/N (zone only)
        self.dt1 = t1_scale / N
        self.dt2 = t2_scale / N
        self.dY = y_scale / N
        self.t_max = t_max
        self.qtol = qtol
        self.gtol = gtol_rel * self.delta * math.pi / 2.0
        self.ftol = 0.2 * gtol_rel * self.delta
        self.verbose = verbose
        self.cap = 0
        self._alloc(1024)
        self.L = 0
        self.segs = []
        self.nev = 0
        self.stats = np.zeros(2, np.int64)  # element evaluations, accepted panels
        self.events = {}
        self.breaks_X2 = []
        self.slope = {}

    # ---------------------------------------------------------------- storage
    def _alloc(self, cap):
        M = self.M
        old = self.cap
        spec = {"T": (), "DA": (), "DB": (), "SQ": (), "ymode": ("i",), "smode": ("i",),
                "tco": (_NC,), "yco": (_NC,), "sco": (_NC,), "dBg": (_NG,), "Kg": (M, _NG),
                "Ok": (M,), "dBx": (4,), "stiff": ("b",), "step_seg": ("i",)}
        for name, shp in spec.items():
            if shp == ("i",):
                a = np.zeros(cap, np.int64)
            elif shp == ("b",):
                a = np.zeros(cap, np.bool_)
            else:
                a = np.zeros((cap,) + shp)
            if old:
                a[:old] = getattr(self, name)
            setattr(self, name, a)
        self.cap = cap

    def _ensure(self, idx):
        if idx + 2 >= self.cap:
            self._alloc(2 * self.cap)

    # ---------------------------------------------------------------- points
    def _s_exact(self, t):
        return float(_sq_exact(t, self.sp))

    def _set_point(self, i, t, y, ymode, s):
        self.T[i] = t
        self.SQ[i] = s
        if ymode == _Y_A:
            self.DA[i] = y
            self.DB[i] = y + s * s
        elif ymode == _Y_B:
            self.DB[i] = y
            self.DA[i] = y - s * s
        elif ymode == _Y_EXT1:
            self.DA[i] = 0.0
            self.DB[i] = s * s
        else:
            self.DB[i] = 0.0
            self.DA[i] = -s * s

    def _yval(self, i, ymode):
        return self.DA[i] if ymode == _Y_A else self.DB[i]

    # ---------------------------------------------------------------- path interpolants
    def _stencil(self, seg, k, L):
        """Points of the local interpolant of step k (segment points i0..L, L the newest)."""
        i0 = seg.i0
        D = seg.deg or self.DEG
        if L - i0 <= D:
            return list(range(i0, L + 1))
        st = min(max(k - (D - 1) // 2, i0), L - D)
        return list(range(st, st + D + 1))

    def _fit(self, seg, L, all_steps=False):
        """(Re)fit the steps of segment ``seg`` whose stencil can contain point L."""
        i0 = seg.i0
        n = L - i0
        if n <= 0:
            return
        if seg.exact:
            k = L - 1
            self.tco[k] = 0.0
            self.tco[k, 0] = self.T[k]
            self.tco[k, 1] = self.T[L] - self.T[k]
            _prep(k, L, self.T, self.ymode, self.smode, self.tco, self.yco, self.sco, self.sp,
                  self.lam, self.sigma, _GX, _GW, self.dBg, self.Kg, self.Ok, self.dBx,
                  self.stiff)
            return
        D = self.DEG
        if all_steps or n <= D:
            k0 = i0
        else:
            k0 = max(i0, L - D + (D - 1) // 2)
        us = seg.u
        yv = None
        if seg.ym == _Y_A:
            yv = self.DA
        elif seg.ym == _Y_B:
            yv = self.DB
        for k in range(k0, L):
            idx = self._stencil(seg, k, L)
            # independent variable of the step: time, or y near a fold (never a chord
            # parameter: chord length would limit the geometric order to 4)
            nodes = None
            cands = []
            dTk = self.T[k + 1] - self.T[k]
            if yv is not None:
                dYk = yv[k + 1] - yv[k]
                steep = abs(dYk) / seg.dy > abs(dTk) / seg.dt
                cands = [yv, self.T] if steep else [self.T, yv]
            elif not seg.by_u:
                cands = [self.T]
            for V in cands:
                den = V[k + 1] - V[k]
                if den == 0.0:
                    continue
                nd = np.array([(V[i] - V[k]) / den for i in idx])
                if np.all(np.diff(nd) > 0):
                    nodes = nd
                    break
            if nodes is None:
                uk = us[k - i0]
                h = us[k + 1 - i0] - uk
                nodes = np.array([(us[i - i0] - uk) / h for i in idx])
            V = np.vander(nodes, len(idx), increasing=True)
            # fit differences from the step's start value: keeps the rounding relative to the
            # increments (thin zones need a^2 to ~1e-12 of the zone width)
            for name, vals in (("tco", self.T), ("yco", yv),
                               ("sco", self.SQ if seg.sm == _S_INTERP else None)):
                if vals is None:
                    continue
                v0 = vals[k]
                c = np.linalg.solve(V, np.array([vals[i] - v0 for i in idx]))
                arr = getattr(self, name)
                arr[k] = 0.0
                arr[k, : len(idx)] = c
                arr[k, 0] = v0
            if seg.sm == _S_FROZEN:
                self.sco[k] = 0.0
                self.sco[k, 0] = self.SQ[i0]
        _prep(k0, L, self.T, self.ymode, self.smode, self.tco, self.yco, self.sco, self.sp,
              self.lam, self.sigma, _GX, _GW, self.dBg, self.Kg, self.Ok, self.dBx, self.stiff)

    # ---------------------------------------------------------------- gap
    def _h(self, i, phase3=False):
        if self.km is None:
            return self.h0 + self.v * self.T[i]
        if phase3:
            return self.v * self.T[i] - self.sigma * math.pi * (self.R2 + self.DB[i]) / self.km
        return _ref_u(i, self.T, self.SQ, self.Ok, self.lam, self.cw, self.alpha0, self.sigma)

    def gap(self, L, phase3=False):
        """Gap [m] at the zone end at point L (steps 0..L-1 prepared)."""
        self.nev += 1
        R2 = self.R2
        B = R2 + self.DB[L]
        A = R2 + self.DA[L]
        s = self.SQ[L]
        if B <= 0.0:
            b, B, phimax = 0.0, 0.0, 0.5 * math.pi
        else:
            b = math.sqrt(B)
            phimax = math.atan2(s, math.sqrt(A)) if A > 0.0 else 0.5 * math.pi
        phis = [0.0, phimax]
        if b > 0.0:
            for X2 in self.breaks_X2:
                W2 = self.DB[L] - X2
                if 0.0 < W2 < B:
                    ph = math.asin(min(1.0, math.sqrt(W2) / b))
                    if 1e-12 * phimax < ph < phimax * (1 - 1e-12):
                        phis.append(ph)
        phis = np.array(sorted(phis))
        qscale = 2.0 * self.sigma * max(abs(s), 1e-300)
        I = _gap_integral(L, b, self.DB[L], phis, self.external, self.T, self.DA, self.DB,
                          self.SQ, self.ymode, self.smode, self.tco, self.yco, self.sco, self.sp,
                          self.dBg, self.Kg, self.Ok, self.dBx, self.stiff, self.lam, self.cw,
                          self.d0, self.alpha0, self.sigma, qscale, self.qtol, self.gtol,
                          _K15_X, _K15_W, _G7_W, _K21_X, _K21_W, _G10_W, self.stats)
        g = 2.0 / math.pi * I
        if not math.isfinite(g):
            raise FloatingPointError(f"gap is not finite at point {L}")
        if self.km is not None:
            ur = _ref_u(L, self.T, self.SQ, self.Ok, self.lam, self.cw, self.alpha0, self.sigma)
            g += self._h(L, phase3) - ur
        return g

    def _gap0(self):
        """Gap at t = 0 (no history yet)."""
        B = self.R2 + self.DB[0]
        A = self.R2 + self.DA[0]
        s = self.SQ[0]
        if s == 0.0:
            return 0.0
        b = math.sqrt(B)
        phimax = math.atan2(s, math.sqrt(A)) if A > 0 else 0.5 * math.pi
        from scipy.integrate import quad

        def dfun(ph):
            w = b * math.sin(ph)
            X2 = self.DB[0] - w * w
            d = self.alpha0 * 2.0 * self.sigma * (s - w)
            if self.external and X2 > 0.0:
                d += float(np.sum(self.d0))
            return d

        return 2.0 / math.pi * quad(dfun, 0.0, phimax, epsabs=1e-300, epsrel=1e-13,
                                    limit=200)[0]

    # ---------------------------------------------------------------- trial points
    def _declare(self, L, seg_index):
        seg = self.segs[seg_index]
        self._ensure(L)
        k = L - 1
        self.step_seg[k] = seg_index
        self.ymode[k] = seg.ym
        self.smode[k] = seg.sm

    def trial(self, L, t, y, seg_index, phase3=False):
        """Put trial point L at time t with segment variable y; return gap - delta [m]."""
        seg = self.segs[seg_index]
        self._declare(L, seg_index)
        j = L - seg.i0
        if seg.sm == _S_EXACT:
            s = self._s_exact(t)
        elif seg.sm == _S_FROZEN:
            s = self.SQ[seg.i0]
        else:
            s = self.SQ[L - 1]
        self._set_point(L, t, y, seg.ym, s)
        if seg.exact:
            du = 1.0
        elif seg.ym in (_Y_A, _Y_B):
            du = math.hypot((t - self.T[L - 1]) / seg.dt, (self._yval(L, seg.ym)
                                                          - self._yval(L - 1, seg.ym)) / seg.dy)
        else:
            du = (t - self.T[L - 1]) / seg.dt
        while len(seg.u) <= j:
            seg.u.append(0.0)
        seg.u[j] = seg.u[j - 1] + du
        del seg.u[j + 1:]
        if seg.sm == _S_INTERP:
            self._solve_s(L, seg, y)
        else:
            self._fit(seg, L)
        return self.gap(L, phase3) - self.delta

    def _solve_s(self, L, seg, y):
        """Compliant machine, bonded phases: s at point L from k_m (v t - u_r(t)) = F_total."""
        t = self.T[L]

        def resid(s):
            self._set_point(L, t, y, seg.ym, s)
            self._fit(seg, L)
            ur = _ref_u(L, self.T, self.SQ, self.Ok, self.lam, self.cw, self.alpha0,
                        self.sigma)
            _, Ft = _forces(self.R2 + self.DA[L], self.R2 + self.DB[L], s, self.sigma)
            return self.km * (self.v * t - ur) - Ft

        if not resid(0.0) > 0.0:
            # the driver is behind the reference element even without load: the recursion for
            # s (Adams-Moulton-like) has gone unstable, k_m dt >~ 8 eta a (see _SpringPath)
            raise RuntimeError("force balance behind the spring lost its root (the step is "
                               "long for the spring's relaxation 8 eta a / k_m): not solved "
                               "in this phase")
        s_prev = self.SQ[L - 1]
        hi = max(2.0 * s_prev, 1e-6 * self.R)
        while resid(hi) > 0:
            hi *= 2.0
        s = brentq(resid, 0.0, hi, xtol=1e-300, rtol=8.9e-16, maxiter=200)
        resid(s)

    # ---------------------------------------------------------------- root solving
    def _secant(self, F, x0, slope, xtol, window):
        """Root of an increasing F near x0 (branch continuation).

        Safeguarded secant started with the remembered slope; gives up (``_NoRoot``) when no
        root lies within ``window`` of x0. The last evaluation is left at the returned root."""
        f0 = F(x0)
        if abs(f0) <= self.ftol:
            return x0
        lo = hi = None
        if f0 < 0:
            lo = (x0, f0)
        else:
            hi = (x0, f0)
        if slope is None or not slope > 0:
            x1 = x0 - math.copysign(1e-3 * window, f0)
        else:
            x1 = x0 - f0 / slope
        xp, fp = x0, f0
        for _ in range(60):
            if abs(x1 - x0) > window:
                if lo is not None and hi is not None:
                    x1 = 0.5 * (lo[0] + hi[0])
                else:
                    raise _NoRoot
            f1 = F(x1)
            if f1 < 0:
                lo = (x1, f1) if lo is None or x1 > lo[0] else lo
            else:
                hi = (x1, f1) if hi is None or x1 < hi[0] else hi
            if abs(f1) <= self.ftol or abs(x1 - xp) <= xtol:
                if abs(x1 - xp) <= xtol and abs(f1) > 1e3 * self.ftol and lo and hi \
                        and hi[0] - lo[0] > 4 * xtol:
                    pass  # not converged in f: keep iterating inside the bracket
                else:
                    if f1 != 0.0 and fp != f1:
                        self._last_slope = (f1 - fp) / (x1 - xp) if x1 != xp else None
                    return x1
            if fp != f1 and x1 != xp:
                sl = (f1 - fp) / (x1 - xp)
                self._last_slope = sl
            else:
                sl = 0.0
            x2 = x1 - f1 / sl if sl > 0 else None
            if lo is not None and hi is not None:
                if x2 is None or not (lo[0] < x2 < hi[0]):
                    x2 = 0.5 * (lo[0] + hi[0])
            elif x2 is None:
                x2 = x1 - math.copysign(2.0 * abs(x1 - xp) + 1e-3 * window, f1)
            else:
                # no bracket yet: do not jump further than 4x the last move
                lim = 4.0 * abs(x1 - xp) + 1e-6 * window
                if abs(x2 - x1) > lim:
                    x2 = x1 + math.copysign(lim, x2 - x1)
            xp, fp = x1, f1
            x1 = x2
        raise RuntimeError("secant did not converge")

    # ---------------------------------------------------------------- phase 1 (bonded)
    def run_phase1(self):
        if not self.external and self.km is not None:
            return self._run_phase1_spring()
        ym = _Y_EXT1 if self.external else _Y_INT1
        exact = self.km is None
        sm = _S_EXACT if exact else _S_INTERP
        s0 = self._s_exact(0.0) if exact else 0.0
        self._set_point(0, 0.0, None, ym, s0)
        self.segs = [_Seg(0, ym, sm, exact, self.dt1, None)]
        self.breaks_X2 = [self.DB[0] if self.external else self.DA[0]]
        if not self.external and s0 >= self.R:
            # the bonded line load would exceed 2 sigma_c R: the bond is gone at once
            self.events["strength_limit"] = 0.0
        g0 = self._gap0()
        if g0 >= self.delta:
            self.L = 0
            self.events["onset"] = 0
            self._ft_onset = None
            return
        L = 0
        g_prev, t_prev = g0, 0.0
        while True:
            L += 1
            t = L * self.dt1
            f = self.trial(L, t, None, 0)
            if not exact:
                self.segs[0].fix[L] = "t"
            if (not self.external and self.SQ[L] >= self.R
                    and "strength_limit" not in self.events):
                self.events["strength_limit"] = self._strength_limit_time(L, t, exact)
            if self.verbose and L % 100 == 0:
                print(f"  bonded L={L} t={t:.6g} gap-delta={f:.3e}", flush=True)
            if f >= 0.0:
                break
            g_prev, t_prev = f + self.delta, t
            if self.t_max is not None and t > self.t_max:
                raise RuntimeError("no onset before t_max")
        L = self._land_on_onset(L, t, ym, exact)
        self.L = L
        self.events["onset"] = L
        self._ft_onset = (g_prev, t_prev)
        self.segs[0].i1 = L

    def _run_phase1_spring(self):
        """Internal zone behind a spring: the bonded phase on the theta path (_SpringPath),
        points on its mesh until gap(R) = delta (the onset) or theta = pi/2 (the strength
        limit, then the pinned stage up to gap(R) = delta)."""
        self._spath = _SpringPath(self.alpha0, self.lam, self.cw, self.sigma, self.R, self.v,
                                  self.km)
        seg = _Seg(0, _Y_INT1, _S_INTERP, False, self.dt1, None)
        seg.by_u = True  # u = theta: t(theta) and s(theta) are analytic, t(s) and s(t) are not
        self.segs = [seg]
        self._set_point(0, 0.0, None, _Y_INT1, 0.0)
        self.breaks_X2 = [self.DA[0]]
        ths = self._spath.mesh(self.dt1, 0.5 * math.pi / self.N)
        g_prev = (0.0, 0.0)
        for L in range(1, ths.size):
            f = self._theta_trial(L, float(ths[L]))
            if f >= 0.0:
                L = self._land_theta(L)
                self.L = L
                self.events["onset"] = L
                self._ft_onset = g_prev
                seg.i1 = L
                return
            g_prev = (f + self.delta, self.T[L])
            if self.t_max is not None and self.T[L] > self.t_max:
                raise RuntimeError("no onset before t_max")
        if self._spath.theta_end < 0.5 * math.pi:
            raise RuntimeError("behind the spring the bonded punch stops stretching it before "
                               "the onset (v - dh/dt -> 0): not modelled")
        # theta = pi/2: q_b = 2 sigma_c R, a = 0, F = pi R^2 sigma_c (MODEL.md 6)
        self.events["strength_limit"] = float(self.T[L])
        self._i_sl = L
        seg.i1 = L
        self._run_pinned(L)

    def _theta_trial(self, L, th):
        """Point L of the theta path at theta = th; returns gap - delta [m]."""
        seg = self.segs[0]
        self._declare(L, 0)
        self._set_point(L, self._spath.t(th), None, _Y_INT1, self.R * math.sin(th))
        del seg.u[L - seg.i0:]
        seg.u.append(th)
        self._fit(seg, L)
        return self.gap(L) - self.delta

    def _land_theta(self, L):
        """Make point ``L`` of the theta path the onset (gap = delta inside its step): first on
        the step's truncated interpolants (dense output), then as a proper point (dropping the
        previous point if it is too close); returns the onset's index."""
        seg, k = self.segs[0], L - 1
        th0, th1 = seg.u[k], seg.u[L]
        tco_full, sco_full = self.tco[k].copy(), self.sco[k].copy()

        def dense(x):
            p = (x - th0) / (th1 - th0)
            sc = p ** np.arange(_NC)
            self.tco[k], self.sco[k] = tco_full * sc, sco_full * sc
            self._set_point(L, _poly(tco_full, p), None, _Y_INT1, _poly(sco_full, p))
            _prep(k, L, self.T, self.ymode, self.smode, self.tco, self.yco, self.sco, self.sp,
                  self.lam, self.sigma, _GX, _GW, self.dBg, self.Kg, self.Ok, self.dBx,
                  self.stiff)
            return self.gap(L) - self.delta

        x = brentq(dense, th0, th1, xtol=1e-300, rtol=8.9e-16, maxiter=200)
        if x - th0 < 0.2 * (th1 - th0) and L >= 2:
            L -= 1  # a step much shorter than its neighbours would spoil the interpolants
        prev = seg.u[L - 1]
        lo, hi = prev + 0.5 * (x - prev), min(th1, x + 0.5 * (th1 - th0))
        G = lambda y: self._theta_trial(L, y)
        while G(hi) < 0.0 and hi < self._spath.theta_end:
            hi = min(hi + 0.5 * (th1 - th0), self._spath.theta_end)
        while G(lo) > 0.0 and lo > prev + 1e-3 * (th1 - th0):
            lo = prev + 0.5 * (lo - prev)
        G(brentq(G, lo, hi, xtol=1e-300, rtol=8.9e-16, maxiter=200))
        return L

    def _run_pinned(self, L):
        """After the strength limit behind a spring: ``a = 0``, the zone fills the face
        (``b = R``), ``F = pi R^2 sigma_c`` and the lift ``h = v t - F/k_m`` is explicit; the
        reference element keeps its load ``2 sigma_c R`` (frozen: continuous at t_sl; the gap
        adds ``h - u_r``). The path is exactly linear in time here (one-step interpolants), so
        the steps only bound the per-step quadrature (|lam| dt <= 1); the point where
        gap(R) = delta becomes the "onset" index, the zone-only phase starts there."""
        seg = _Seg(L, _Y_B, _S_FROZEN, False, self.dt2, self.dY)
        seg.deg = 1
        self.segs.append(seg)
        si = len(self.segs) - 1
        rate = float(np.max(np.abs(self.lam))) if self.M else 0.0
        dt = min(self.dt2, 1.0 / rate) if rate > 0 else self.dt2
        i = L
        while True:
            t = self.T[i] + dt
            if self.trial(i + 1, t, 0.0, si, True) >= 0.0:
                break
            i += 1
            if self.t_max is not None and t > self.t_max:
                raise RuntimeError("no onset (gap(R) = delta) before t_max")
        t0 = self.T[i]
        lo = t0 + 1e-9 * dt  # a zero-length step has no interpolant
        G = lambda tt: self.trial(i + 1, tt, 0.0, si, True)
        ton = lo if G(lo) >= 0.0 else brentq(G, lo, t, xtol=1e-300, rtol=8.9e-16, maxiter=200)
        G(ton)
        self.L = i + 1
        self.events["onset"] = i + 1
        self._ft_onset = None
        seg.i1 = i + 1

    def _strength_limit_time(self, L, t, exact):
        """Internal zone: when the bonded line load reaches 2 sigma_c R inside step ``L``
        (a = 0, F = pi R^2 sigma_c); the zone then stays pinned at b = R until gap(R) =
        delta."""
        if exact:
            return brentq(lambda tt: self._s_exact(tt) - self.R, self.T[L - 1], t,
                          xtol=1e-300, rtol=8.9e-16)
        ps = brentq(lambda pp: _poly(self.sco[L - 1], pp) - self.R, 0.0, 1.0,
                    xtol=1e-300, rtol=8.9e-16)
        return float(_poly(self.tco[L - 1], ps))

    def _land_on_onset(self, L, t, ym, exact):
        """Make point ``L`` the onset (gap = delta), which lies inside the step ending at
        ``t``; returns its index (a point too close before it is dropped)."""
        t0 = self.T[L - 1]
        k = L - 1
        tco_full = self.tco[k].copy()
        sco_full = self.sco[k].copy()
        u_full = self.segs[0].u[L]

        def F(tt):
            # the onset lies inside step k: truncate its interpolant (dense output), no refit
            p = (tt - t0) / (t - t0)
            sc = p ** np.arange(_NC)
            self.tco[k] = tco_full * sc
            self.sco[k] = sco_full * sc
            s_ = self._s_exact(tt) if exact else float(_poly(sco_full, p))
            self._set_point(L, tt, None, ym, s_)
            self.segs[0].u[L] = self.segs[0].u[L - 1] + p * (u_full - self.segs[0].u[L - 1])
            _prep(k, L, self.T, self.ymode, self.smode, self.tco, self.yco, self.sco, self.sp,
                  self.lam, self.sigma, _GX, _GW, self.dBg, self.Kg, self.Ok, self.dBx,
                  self.stiff)
            return self.gap(L) - self.delta

        ton = brentq(F, t0, t, xtol=1e-300, rtol=8.9e-16, maxiter=200)
        F(ton)
        if not exact:
            # dense output does not satisfy the force balance exactly at t_on: re-solve the
            # onset as a proper point (drop the previous grid point if it is too close)
            if ton - self.T[L - 1] < 0.2 * self.dt1 and L >= 2:
                L -= 1
            self.segs[0].u = self.segs[0].u[:L]

            def G(tt):
                return self.trial(L, tt, None, 0)

            lo, hi = self.T[L - 1] + 0.5 * (ton - self.T[L - 1]), min(t, ton + 0.5 * self.dt1)
            while G(hi) < 0.0:
                hi = hi + 0.5 * self.dt1
            while G(lo) > 0.0 and lo > self.T[L - 1] + 1e-3 * self.dt1:
                lo = self.T[L - 1] + 0.5 * (lo - self.T[L - 1])
            ton = brentq(G, lo, hi, xtol=1e-300, rtol=8.9e-16, maxiter=200)
            G(ton)
        return L

    # ---------------------------------------------------------------- propagation
    def _forces_at(self, i):
        return _forces(self.R2 + self.DA[i], self.R2 + self.DB[i], self.SQ[i], self.sigma)

    def _tangent(self, seg, L):
        """(dt/du, dy/du) at the last point of the segment from its last step polynomial."""
        k = L - 1
        h = seg.u[L - seg.i0] - seg.u[L - 1 - seg.i0]
        return _dpoly(self.tco[k], 1.0) / h, _dpoly(self.yco[k], 1.0) / h

    def run_propagation(self):
        """Receding phase (y = a^2 - R^2) and zone-only phase (y = b^2 - R^2) to separation."""
        L = self.L
        sm = _S_EXACT if self.km is None else _S_INTERP
        self.breaks_X2 += [self.DA[L], self.DB[L]]
        self.slope = {}
        if self.R2 + self.DA[L] <= 0.0:
            # strength-limited internal zone: the bond is already gone, zone-only from here
            self.events["a_zero"] = L
            tang = self._open_zone_only(L, None)
            if tang is None:
                return
            return self._march(L, len(self.segs) - 1, 3, tang)
        self.segs.append(_Seg(L, _Y_A, sm, False, self.dt2, self.dY))
        si = len(self.segs) - 1
        # stability of the onset: lower A at fixed time
        yA = self.DA[L]
        eps = 1e-4 * self.dY
        f_0 = self.trial(L + 1, self.T[L], yA - 1e-3 * eps, si)
        f_eps = self.trial(L + 1, self.T[L], yA - eps, si)
        fA = (f_0 - f_eps) / (0.999 * eps)  # d(gap)/dA at the onset, fixed time
        self.events["dgap_dA_onset"] = fA
        if not fA > 0.0:
            # a receding edge would open the gap further: the crack is unstable
            self.events["separation"] = ("unstable_onset", self.T[L])
            return
        if self._ft_onset is not None and self.T[L] > self._ft_onset[1]:
            ft = (self.delta - self._ft_onset[0]) / (self.T[L] - self._ft_onset[1])
        else:
            ft = fA * self.dY / self.dt2
        self.slope = {"y": fA, "t": ft}
        return self._march(L, si, 2, (1.0, -ft / fA))

    def _open_zone_only(self, L, prev_seg):
        """Open the zone-only segment at point L; None if it is unstable (punch snaps off)."""
        smode = _S_EXACT if self.km is None else _S_FROZEN
        if prev_seg is not None:
            dtu, dyu = self._tangent(prev_seg, L)
            tang = (dtu, dyu if self.km is not None
                    else dyu + 2.0 * self.SQ[L] * self._sdot(L) * dtu)
        else:
            tang = (1.0, -self.dY / self.dt2)
        self.breaks_X2.append(self.DB[L])
        self.segs.append(_Seg(L, _Y_B, smode, False, self.dt2, self.dY))
        si = len(self.segs) - 1
        # a root with d(gap)/dB <= 0 at fixed time is unstable (a larger zone would close
        # further): the punch snaps off
        yB = self.DB[L]
        eps = 1e-4 * min(self.dY, self.R2 + yB)
        f_0 = self.trial(L + 1, self.T[L], yB - 1e-3 * eps, si, True)
        f_eps = self.trial(L + 1, self.T[L], yB - eps, si, True)
        fB = (f_0 - f_eps) / (0.999 * eps)
        self.events["dgap_dB_a_zero"] = fB
        if not fB > 0.0:
            self.events["separation"] = ("snap_at_a_zero", self.T[L])
            return None
        self.slope["y"] = fB
        return tang

    def _march(self, L, si, phase, tang):
        while True:
            seg = self.segs[si]
            ym = seg.ym
            phase3 = phase == 3
            y_end = -self.R2
            yL = self._yval(L, ym)
            n = L - seg.i0
            if self.t_max is not None and self.T[L] > self.t_max:
                self.events["separation"] = ("t_max", self.T[L])
                return
            # local y step: the nominal dY, refined where the bond is small compared with R
            # (thin-zone scenes end with a of the order of the zone width)
            if ym == _Y_A:
                yloc = self.R2 + yL + self.SQ[L] ** 2
            else:
                yloc = self.R2 + self.DB[seg.i0]
            dyl = min(self.dY, self.ykappa * yloc / self.N)
            # step length (chord, in units of the nominal step): geometric grading away from
            # the start of a segment and towards its end, where the path has weak
            # (fractional-power / logarithmic) singularities at the phase changes
            c = min(1.0, 2.0 ** (-self.grade + min(max(n - 1, 0), self.grade)))
            if n >= 1:
                k = L - 1
                dtp, dyp = _dpoly(self.tco[k], 1.0), _dpoly(self.yco[k], 1.0)
                chord_per_p = math.hypot(dtp / self.dt2, dyp / dyl)
                if dyp < 0 and chord_per_p > 0:
                    rem = (yL - y_end) / (-dyp) * chord_per_p  # chord left to y = y_end
                    if rem < 2.0 * c:
                        c = max(0.5 * rem, 2.0 ** (-self.grade))
            status = None
            for _attempt in range(12):
                status = self._advance(L, si, seg, c, dyl, tang, y_end, phase3)
                if status != "retry":
                    break
                c *= 0.5
            if status in ("fold", "retry"):
                self._locate_fold(L, si, failed=status == "retry")
                return
            fix_y = status == "y"
            L += 1
            self.L = L
            seg.fix[L - seg.i0] = "y" if fix_y else "t"
            if self.internal_b_check(L):
                raise RuntimeError("the zone would grow beyond the punch rim (b > R): "
                                   "not modelled")
            if self.verbose and (L % 100 == 0):
                print(f"  phase{phase} L={L} t={self.T[L]:.10g} A={self.R2 + self.DA[L]:.6e} "
                      f"B={self.R2 + self.DB[L]:.6e} nev={self.nev}", flush=True)
            if self._yval(L, ym) <= y_end:
                seg.i1 = L
                if phase == 2:
                    self.events["a_zero"] = L
                    tang = self._open_zone_only(L, seg)
                    if tang is None:
                        return
                    si = len(self.segs) - 1
                    phase = 3
                else:
                    self.events["separation"] = ("collapse", self.T[L])
                    return

    def internal_b_check(self, L):
        """True if an internal zone would reach beyond the rim (b > R) after the onset."""
        return (not self.external) and self.DB[L] > 1e-12 * self.R2

    def _predict_chord(self, seg, L, c, dyl, tang):
        """(t, y) a chord c ahead of point L: quadratic through the last three points in the
        chord parameter (robust on graded steps), or the tangent at the segment start."""
        ym = seg.ym
        n = L - seg.i0
        if n < 2:
            dtn, dyn = tang
            nrm = math.hypot(dtn / self.dt2, dyn / dyl)
            return self.T[L] + c * dtn / nrm, self._yval(L, ym) + c * dyn / nrm
        idx = tuple(range(L - min(n, 4), L + 1))
        xs = np.array([self.T[i] / self.dt2 for i in idx])
        ys = np.array([self._yval(i, ym) / dyl for i in idx])
        dch = np.hypot(np.diff(xs), np.diff(ys))
        # cubic through four nearly uniform chords, else a quadratic through the last three
        if len(dch) < 4 or not (0.6 < dch[-1] / dch[-2] < 1.7 and 0.6 < dch[-2] / dch[-3] < 1.7
                                and c < 1.7 * dch[-1]):
            xs, ys, dch = xs[-3:], ys[-3:], dch[-2:]
        else:
            xs, ys, dch = xs[-4:], ys[-4:], dch[-3:]
        ch = np.concatenate(([0.0], np.cumsum(dch)))
        at = ch[-1] + c
        out = []
        for vals in (xs, ys):
            cf = _lagrange_coeffs(ch - ch[-1], vals - vals[-1])
            out.append(vals[-1] + _poly(cf, at - ch[-1]))
        return out[0] * self.dt2, out[1] * dyl

    def _advance(self, L, si, seg, c, dyl, tang, y_end, phase3):
        """Solve for point L+1 a chord ~c ahead. Returns "t" / "y" (the coordinate held
        fixed), "fold" (the branch turned back in time) or "retry" (no root near)."""
        ym = seg.ym
        yL = self._yval(L, ym)
        t_pred, y_pred = self._predict_chord(seg, L, c, dyl, tang)
        Dt = (t_pred - self.T[L]) / self.dt2
        Dy = (y_pred - yL) / dyl
        fix_y = abs(Dy) > abs(Dt) or t_pred <= self.T[L]
        if y_pred <= y_end or (Dy < 0 and yL - y_end < 1.05 * abs(y_pred - yL)):
            fix_y = True
            if y_pred != yL:
                t_pred = self.T[L] + (t_pred - self.T[L]) * (y_end - yL) / (y_pred - yL)
            y_pred = y_end
        try:
            if not fix_y:
                try:
                    y_new = self._secant(
                        lambda y: self.trial(L + 1, t_pred, y, si, phase3), y_pred,
                        self.slope.get("y"), 1e-14 * dyl, 3.0 * abs(y_pred - yL) + dyl)
                    self.slope["y"] = getattr(self, "_last_slope", self.slope.get("y"))
                    if ym == _Y_A and y_new > yL:
                        raise RuntimeError("crack arrest (a would grow): not modelled")
                    if y_new < y_end:
                        fix_y = True
                        y_pred = y_end
                except _NoRoot:
                    fix_y = True
            if fix_y:
                t_new = self._secant(
                    lambda t: self.trial(L + 1, t, y_pred, si, phase3), t_pred,
                    self.slope.get("t"), 1e-14 * self.dt2,
                    3.0 * abs(t_pred - self.T[L]) + c * self.dt2)
                self.slope["t"] = getattr(self, "_last_slope", self.slope.get("t"))
                if t_new < self.T[L]:
                    return "fold"
        except _NoRoot:
            return "retry"
        return "y" if fix_y else "t"

    def _sdot(self, L):
        t = self.T[L]
        e = 1e-6 * max(t, self.dt2)
        return (self._s_exact(t + e) - self._s_exact(t - e)) / (2 * e)

    def _locate_fold(self, L, si, failed=False):
        """The branch turns back in time between points L-1 and the trial L+1: t_f = max t(u)."""
        seg = self.segs[si]
        best = (self.T[L], 0.0, L - 1)
        if not failed:
            for k in (L - 1, L):
                if k < seg.i0:
                    continue
                c = self.tco[k]
                dp = np.polynomial.Polynomial(c).deriv()
                roots = dp.roots() if np.any(dp.coef != 0) else []
                cand = [0.0, 1.0] + [r.real for r in roots if abs(r.imag) < 1e-9
                                     and 0.0 <= r.real <= 1.0]
                for p in cand:
                    tv = _poly(c, p)
                    if tv > best[0]:
                        best = (tv, p, k)
        tf, pf, kf = best
        t, tp, dA, dB, s = _eval(kf, pf, self.ymode, self.smode, self.tco, self.yco, self.sco,
                                 self.sp)
        self.events["separation"] = ("fold" if not failed else "lost_branch", float(tf))
        self.events["fold_state"] = (self.R2 + dA, self.R2 + dB, s)

    # ---------------------------------------------------------------- probes (tests, diagnostics)
    def state_at(self, t):
        """(a^2, b^2, s) [m^2, m^2, m] at time t [s] from the accepted path (after the onset)."""
        on = self.events["onset"]
        for k in range(on, self.L):
            t0, t1 = self.T[k], self.T[k + 1]
            if min(t0, t1) <= t <= max(t0, t1) and t0 != t1:
                lo, hi = 0.0, 1.0
                up = _poly(self.tco[k], 1.0) > _poly(self.tco[k], 0.0)
                for _ in range(200):
                    m = 0.5 * (lo + hi)
                    if (_poly(self.tco[k], m) < t) == up:
                        lo = m
                    else:
                        hi = m
                _, _, dA, dB, s = _eval(k, 0.5 * (lo + hi), self.ymode, self.smode, self.tco,
                                        self.yco, self.sco, self.sp)
                return self.R2 + dA, self.R2 + dB, s
        raise ValueError("t outside the propagation")

    def probe_gap(self, i, B):
        """Gap [m] at the time of accepted zone-only point i if the zone radius^2 were B.

        A zero-duration step from point i in a scratch segment (the accepted interpolants are
        left alone): elements keep their states; a Maxwell solid responds instantly to the
        changed load. Uses the storage slot i + 1; call after :meth:`results`."""
        seg_i = self.segs[int(self.step_seg[i - 1])]
        scratch = _Seg(i, _Y_B, seg_i.sm, False, self.dt2, self.dY)
        self.segs.append(scratch)
        saved = {(n, j): getattr(self, n)[j].copy() for n, j in
                 [(n, i + 1) for n in ("T", "DA", "DB", "SQ")]
                 + [(n, i) for n in ("ymode", "smode", "tco", "yco", "sco", "dBg", "Kg",
                                     "Ok", "dBx", "stiff", "step_seg")]}
        try:
            if B == self.R2 + self.DB[i]:
                return self.gap(i, True)
            return self.trial(i + 1, self.T[i], B - self.R2, len(self.segs) - 1, True) \
                + self.delta
        finally:
            self.segs.pop()
            for (n, j), v in saved.items():
                getattr(self, n)[j] = v

    # ---------------------------------------------------------------- outputs
    def results(self):
        L = self.L
        # refit the accepted path (the last trial may have been beyond the end)
        for seg in self.segs:
            if seg.i0 < L and not seg.exact:
                end = seg.i1 if seg.i1 is not None else L
                self._fit(seg, end)
        on = self.events["onset"]
        Fc_on, Ft_on = self._forces_at(on)
        t_on = float(self.T[on])
        if "strength_limit" in self.events:
            # the bond went at q_b = 2 sigma_c R: that instant is the onset (MODEL.md 6)
            t_on = float(self.events["strength_limit"])
            Fc_on, Ft_on = 0.0, self.sigma * math.pi * self.R2
        sep_kind, t_sep = self.events["separation"]
        best_t = (Ft_on, t_on)
        best_c = (Fc_on, t_on)
        for i in range(on, L + 1):
            Fc, Ft = self._forces_at(i)
            if Ft > best_t[0]:
                best_t = (Ft, float(self.T[i]))
            if Fc > best_c[0]:
                best_c = (Fc, float(self.T[i]))
        best_t = self._refine_peak(best_t, True)
        best_c = self._refine_peak(best_c, False)
        if not self.external and self.km is None:
            best_c = max(best_c, self._bonded_contact_peak(float(self.T[on])),
                         key=lambda x: x[0])
        if "fold_state" in self.events:
            A, B, s = self.events["fold_state"]
            Fc, Ft = _forces(A, B, s, self.sigma)
            if Ft > best_t[0]:
                best_t = (Ft, t_sep)
            if Fc > best_c[0]:
                best_c = (Fc, t_sep)
        R2 = self.R2
        h = np.array([self._h_out(i) for i in range(L + 1)])
        A = R2 + self.DA[: L + 1]
        B = R2 + self.DB[: L + 1]
        Ft = np.array([self._forces_at(i)[1] for i in range(L + 1)])
        return dict(t_onset=t_on, F_onset_total=float(Ft_on),
                    F_onset_contact=float(Fc_on), t_separation=float(t_sep),
                    separation_kind=sep_kind,
                    F_peak_total=float(best_t[0]), t_peak_total=float(best_t[1]),
                    F_peak_contact=float(best_c[0]), t_peak_contact=float(best_c[1]),
                    t_a_zero=float(self.T[self.events["a_zero"]]) if "a_zero" in self.events
                    else float("nan"),
                    t=self.T[: L + 1].copy(), h=h, a=np.sqrt(np.clip(A, 0.0, None)),
                    b=np.sqrt(np.clip(B, 0.0, None)), F_total=Ft, n_points=L + 1,
                    gap_evaluations=self.nev, element_evaluations=int(self.stats[0]))

    def _h_out(self, i):
        if self.km is None:
            return self.h0 + self.v * self.T[i]
        a0 = getattr(self, "_i_sl", self.events.get("a_zero"))  # explicit lift from a = 0 on
        if a0 is not None and i > a0:
            return self._h(i, True)
        return _ref_u(i, self.T, self.SQ, self.Ok, self.lam, self.cw, self.alpha0, self.sigma)

    def _force_on_step(self, k, p, total):
        t, tp, dA, dB, s = _eval(k, p, self.ymode, self.smode, self.tco, self.yco, self.sco,
                                 self.sp)
        Fc, Ft = _forces(self.R2 + dA, self.R2 + dB, s, self.sigma)
        return (Ft if total else Fc), t

    def _bonded_contact_peak(self, t_end):
        """``(F, t)`` of the largest contact force ``4 sigma a s`` (``a^2 = R^2 - s^2``) of the
        internal zone's pinned phase up to ``t_end`` under a rigid pull (its path exact):
        where ``s = R / sqrt(2)``, or at ``t = 0`` where ``s`` is past it already. (Before a
        face's strength limit the contact force falls back to 0; the onset's is not its
        largest.)"""
        half = math.sqrt(0.5 * self.R2)
        if self._s_exact(0.0) >= half:
            t = 0.0
        elif self._s_exact(t_end) <= half:
            t = t_end
        else:
            lo, t = 0.0, t_end
            for _ in range(200):
                mid = 0.5 * (lo + t)
                lo, t = (mid, t) if self._s_exact(mid) < half else (lo, mid)
        s = min(self._s_exact(t), math.sqrt(self.R2))
        return _forces(self.R2 - s * s, self.R2, s, self.sigma)[0], t

    def _refine_peak(self, best, total):
        """Maximise the force along the interpolated path in the steps next to the best point."""
        L = self.L
        on = self.events["onset"]
        i0 = on + int(np.argmin(np.abs(self.T[on: L + 1] - best[1])))
        cand = best
        gr = (math.sqrt(5.0) - 1.0) / 2.0
        for k in range(max(i0 - 2, on), min(i0 + 2, L)):
            ps = np.linspace(0.0, 1.0, 33)
            vals = [self._force_on_step(k, p, total)[0] for p in ps]
            j = int(np.argmax(vals))
            a_, b_ = ps[max(j - 1, 0)], ps[min(j + 1, 32)]
            c_, d_ = b_ - gr * (b_ - a_), a_ + gr * (b_ - a_)
            fc, fd = self._force_on_step(k, c_, total)[0], self._force_on_step(k, d_, total)[0]
            for _ in range(90):
                if fc > fd:
                    b_, d_, fd = d_, c_, fc
                    c_ = b_ - gr * (b_ - a_)
                    fc = self._force_on_step(k, c_, total)[0]
                else:
                    a_, c_, fc = c_, d_, fd
                    d_ = a_ + gr * (b_ - a_)
                    fd = self._force_on_step(k, d_, total)[0]
            p = 0.5 * (a_ + b_)
            # golden section locates the maximum only to ~sqrt(eps): polish with Newton on
            # central differences of the (polynomial) path
            hh = 1e-4
            for _ in range(6):
                fm = self._force_on_step(k, p - hh, total)[0]
                f0 = self._force_on_step(k, p, total)[0]
                fp = self._force_on_step(k, p + hh, total)[0]
                d2 = (fp - 2.0 * f0 + fm) / (hh * hh)
                if not d2 < 0.0:
                    break
                dp = -((fp - fm) / (2.0 * hh)) / d2
                if abs(dp) > 0.1:
                    break
                p = min(max(p + dp, 0.0), 1.0)
                if abs(dp) < 1e-15:
                    break
            F, t = self._force_on_step(k, p, total)
            if F > cand[0]:
                cand = (float(F), float(t))
        return cand


# --------------------------------------------------------------------------------------------
# Public driver
# --------------------------------------------------------------------------------------------

_SCALARS = ("t_onset", "F_onset_total", "F_onset_contact", "t_separation", "F_peak_total",
            "t_peak_total", "F_peak_contact", "t_peak_contact")


def _elastic_guess(G, sigma_c, delta, R, v, h0, external):
    """Onset time [s] of an elastic solid with modulus G (closed form), a scale for dt."""
    chi = math.pi * G * delta / (sigma_c * R)
    if external:
        # g(S) = S atan S - (sqrt(1+S^2) - 1) = chi
        f = lambda S: S * math.atan(S) - S * S / (1.0 + math.sqrt(1.0 + S * S)) - chi
        hi = 1.0
        while f(hi) < 0:
            hi *= 2.0
        S = brentq(f, 0.0, hi, xtol=1e-300, rtol=1e-12)
    else:
        f = lambda th: th * math.sin(th) - 2.0 * math.sin(0.5 * th) ** 2 - chi
        S = math.sin(brentq(f, 0.0, 0.5 * math.pi)) if f(0.5 * math.pi) > 0 else 1.0
    h = sigma_c * R * S / (2.0 * G)
    return max(h - h0, 0.0) / v


def _one_level(params, N, scales, t_max, verbose):
    run = EdgeRun(**params, N=N, t1_scale=scales[0], t2_scale=scales[1], y_scale=scales[2],
                  t_max=t_max, verbose=verbose)
    run.run_phase1()
    run.run_propagation()
    return run.results()


def flat_punch_reference(*, G_inf, eta=0.0, arms=(), sigma_c, delta, R, v, h0=0.0,
                         zone="external", machine_stiffness=None, rtol=1e-7, t_max=None,
                         level=None, N0=16, min_level=0, max_level=6, scales=None,
                         time_budget=None, verbose=False):
    """Reference solution of the MDR-Dugdale pull-off of a flat punch (MODEL.md 1-3, 6, 8).

    Parameters (SI)
    ---------------
    G_inf : float [Pa]
        Relaxed (long-time) shear modulus; the elastic modulus without ``eta`` and ``arms``.
    eta : float [Pa s]
        Kelvin-Voigt viscosity (``G(t) = G_inf + eta delta(t)``); not combined with ``arms``.
    arms : tuple of (G_i [Pa], tau_i [s])
        Maxwell arms (standard linear solid: one arm; Prony series: several).
    sigma_c : float [Pa]
        Dugdale stress.
    delta : float [m]
        Dugdale range (work of adhesion ``sigma_c delta``).
    R : float [m]
        Punch radius: the bond radius before the onset (external zone) or the largest zone
        radius (internal zone, ``b <= R``).
    v : float [m/s]
        Lift (driver) speed, ``h = h0 + v t`` under a rigid machine.
    h0 : float [m]
        Initial lift (must be 0 with a machine spring).
    zone : "external" | "internal"
        Cohesive zone outside the bond (seed) or on the punch face.
    machine_stiffness : float [N/m] or None
        Machine spring ``k_m``: the punch lift solves ``k_m (v t - h) = F_total``.
    rtol : float
        Target relative accuracy of the scalar outputs; levels ``N = N0 2^l`` are added until
        the estimated error is below it (at least three levels, at most ``max_level + 1``).
    t_max : float [s] or None
        Give up (``RuntimeError`` before the onset; ``separation_kind = "t_max"`` after it).
    level : int or None
        Run this one resolution only (``N = N0 2^level``; no convergence ladder, so
        ``error_estimate`` is nan).
    N0, min_level, max_level : the ladder ``N = N0 2^l``, ``l = min_level..max_level``.
    scales : (t1 [s], t2 [s], y [m^2]) or None
        Step scales (bonded phase, propagation, a^2/b^2); by default from a coarse pilot run
        (``t1`` = onset time, ``t2`` = duration of the propagation, ``y = R^2``).
    time_budget : float [s] or None
        Do not start a level whose predicted wall time (from the growth of the previous ones)
        would exceed what is left of this budget.

    Returns
    -------
    dict with
      ``t_onset`` [s], ``F_onset_total`` [N], ``F_onset_contact`` [N]: first gap = delta at
      the zone end (internal zone: or the instant ``q_b = 2 sigma_c R`` if earlier, with the
      strength-limit force ``pi R^2 sigma_c``);
      ``t_separation`` [s] and ``separation_kind``: ``"collapse"`` (zone-only phase ends with
      ``b -> 0``, the centre gap reaching delta), ``"fold"`` (the quasi-static branch turns
      back in time: snap-off; the time of the turning point), ``"unstable_onset"`` (a
      receding edge would open the gap further: the crack runs at once, e.g. elastic),
      ``"snap_at_a_zero"`` (the zone-only state is unstable when ``a`` reaches 0),
      ``"lost_branch"`` (no root near the branch, last accepted time), ``"t_max"``;
      ``F_peak_total``/``t_peak_total``, ``F_peak_contact``/``t_peak_contact`` [N], [s]: largest
      force of the whole run (onset included);
      ``t_a_zero`` [s]: when the bond radius reached 0 (nan if never);
      ``error_estimate``: largest relative change of the scalars between the two finest levels
      (nan with ``level`` given), ``error_estimates`` per scalar, ``error_estimate_richardson``
      (the same divided by ``2^p - 1`` with the observed order ``p``), ``observed_order``
      (median over t_separation, t_a_zero and the peak forces of the last three levels);
      ``levels``: per-level scalars and their ``N``; ``t, h, a, b, F_total``: the finest
      history [s, m, m, m, N] at the accepted points.
    """
    params = dict(G_inf=G_inf, eta=eta, arms=tuple(tuple(float(v_) for v_ in x) for x in arms),
                  sigma_c=sigma_c, delta=delta, R=R, v=v, h0=h0, zone=zone,
                  machine_stiffness=machine_stiffness)
    if scales is None:
        scales = _pilot_scales(params, t_max)
    scales = tuple(float(x) for x in scales)
    lv = [level] if level is not None else range(min_level, max_level + 1)
    tstart = _time.time()
    results, levels, estimates = _ladder(
        params, scales, lv, N0, rtol, t_max, level is None, time_budget, tstart, verbose)
    return _assemble(results, levels, estimates, scales, N0, tstart)


def _assemble(results, levels, estimates, scales, N0, tstart) -> dict:
    """The finest level's outputs with the ladder's estimates, levels and scales."""
    est, rich, order, per = estimates
    out = dict(results[-1])
    out["error_estimate"] = est if len(results) >= 2 else float("nan")
    out["error_estimate_richardson"] = rich
    out["observed_order"] = order
    out["error_estimates"] = per
    out["levels"] = levels
    out["scales"] = dict(t1_scale=scales[0], t2_scale=scales[1], y_scale=scales[2], N0=N0)
    out["wall_time_total"] = _time.time() - tstart
    return out


def _pilot_scales(params, t_max):
    """Step scales ``(t1, t2, y)`` from a coarse pilot run: the onset time, the duration of
    the propagation and ``R^2``."""
    R = params["R"]
    t1 = _elastic_guess(params["G_inf"], params["sigma_c"], params["delta"], R, params["v"],
                        params["h0"], params["zone"] == "external")
    if not t1 > 0:
        t1 = params["delta"] / params["v"]
    pilot = err = None
    for n_pilot in (8, 16):
        try:
            pilot = _one_level(params, n_pilot, (t1, t1, R * R), t_max, False)
        except (RuntimeError, _NoRoot, FloatingPointError, np.linalg.LinAlgError) as e:
            err = e
            continue
        if pilot["separation_kind"] != "lost_branch":
            break
    if pilot is None:
        raise RuntimeError(f"pilot run failed: {err}") from err
    t_on = pilot["t_onset"]
    t1s = t_on if t_on > 0 else t1
    t2s = pilot["t_separation"] - t_on
    if not t2s > 1e-6 * t1s:
        t2s = t1s
    return (t1s, t2s, R * R)


def _ladder(params, scales, lv, N0, rtol, t_max, converge, time_budget, tstart, verbose):
    """Run the levels ``N = N0 2^l`` for ``l`` in ``lv`` until (``converge``) the estimate is
    below ``rtol`` with at least three levels, or the time budget would be overrun; returns
    the per-level results, their scalars and ``_estimate``'s tuple."""
    levels, results = [], []
    estimate = (float("nan"), float("nan"), float("nan"), {})
    for l in lv:
        N = N0 * 2 ** l
        if time_budget is not None and len(results) >= 1 and converge:
            last = results[-1]["wall_time"]
            growth = max(2.0, last / max(results[-2]["wall_time"], 1e-3)) if len(results) >= 2 \
                else 4.0
            if _time.time() - tstart + growth * last > time_budget and len(results) >= 3:
                break
        t0 = _time.time()
        res = _one_level(params, N, scales, t_max, verbose)
        res["N"] = N
        res["wall_time"] = _time.time() - t0
        results.append(res)
        levels.append({k: res[k] for k in _SCALARS + ("N", "wall_time", "t_a_zero",
                                                     "separation_kind", "n_points")})
        if verbose:
            print(f"level {l} N={N}: " + " ".join(f"{k}={res[k]:.12g}" for k in _SCALARS)
                  + f"  [{res['wall_time']:.1f} s]", flush=True)
        if len(results) >= 2:
            estimate = _estimate(results)
            if converge and len(results) >= 3 and estimate[0] < rtol:
                break
    return results, levels, estimate


def _estimate(results):
    """(max relative change between the two finest levels, Richardson estimate, order, per-key).

    Relative to the finest value; the peak times relative to the separation time (a flat
    maximum locates its time only to ~sqrt(noise) of the force)."""
    a, b = results[-2], results[-1]
    per = {}
    for k in _SCALARS:
        if k.startswith("t_peak"):
            scale = max(abs(b["t_separation"]), abs(b["t_onset"]), 1e-300)
        else:
            scale = max(abs(b[k]), 1e-300)
        per[k] = abs(b[k] - a[k]) / scale
    est = max(per.values())
    order = float("nan")
    if len(results) >= 3:
        c = results[-3]
        ords = []
        for k in ("t_separation", "t_a_zero", "F_peak_total", "F_peak_contact"):
            d1 = abs(a[k] - c[k])
            d2 = abs(b[k] - a[k])
            # only quantities that carry a discretisation error (not a peak at the onset)
            if (math.isfinite(d1) and math.isfinite(d2) and d2 > 0
                    and d1 > 1e-12 * abs(b[k])):
                ords.append(math.log2(d1 / d2))
        if ords:
            order = float(np.median(ords))
    p = order if math.isfinite(order) and order > 1 else 1.0
    rich = est / (2.0 ** p - 1.0)
    return est, rich, order, per
