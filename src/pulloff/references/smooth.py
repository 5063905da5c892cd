"""Independent fixed-mesh reference for a sphere pressed into and pulled from an SLS half-space.

``sphere_path_reference`` is a brute-force, careful time stepper for the MDR-Dugdale model of
MODEL.md sections 1, 2, 6 and 9: a rigid sphere (``f = r^2/(2R)``, MDR profile ``g = x^2/R``)
under displacement control (rigid machine) approaches a linear visco-elastic half-space from
``h0`` at speed ``v_in`` until the total force reaches ``-F_target`` (compressive), then
retracts at ``v_out`` until complete separation; or (``force_rate``) retracts under force
control, ``F(t) = -F_target + force_rate (t - t_turn)``, to the force-controlled pull-off. It
imports nothing from the rest of ``pulloff`` and shares no code with the project's solvers.

Units: SI throughout (m, s, Pa, N, N/m).

Method
------
* Rheology: shear relaxation modulus ``G(t) = G_inf + sum_i G_i exp(-t/tau_i)``. One MDR element
  per unit length carries the line load ``f = 4 (G_inf u + sum_i s_i)`` with the arm variables
  ``s_i' = G_i u' - s_i/tau_i`` (Pa). Over a step ``dt`` the arms are updated exactly for a
  displacement that is linear in time:
  ``s_i <- e_i s_i + G_i c_i (u_new - u_old)``, ``e_i = exp(-dt/tau_i)``,
  ``c_i = tau_i (1 - e_i)/dt`` (``c_i = 1`` for ``dt = 0``: a jump sees ``G_inf + sum G_i``).
  Hence ``f_new = 4 (Geff u_new - hist)`` with ``Geff = G_inf + sum G_i c_i`` and
  ``hist = sum_i (G_i c_i u_old - e_i s_i)``.
* Space: a fixed grid of ``n_elements + 1`` nodes on ``[0, x_max]`` carries ``u`` and ``s_i``
  exactly at the nodes. Two extra *moving* nodes at the current contact radius ``a`` and zone end
  ``b`` carry the states there, so that the kinks of the state field at ``a`` and ``b`` are
  represented exactly; between nodes ``hist`` is interpolated linearly. Everything else is
  analytic: contact elements ``u = h + g(x)``, the Dugdale part ``q/(4 Geff)`` of the free
  displacement, and the gap integral ``(2/pi) int u/sqrt(b^2 - x^2)`` of the piecewise linear
  ``hist`` (product integration, exact for linear segments).
* At each step ``(a, b)`` solve the edge condition (gives ``b(a)`` explicitly:
  ``b^2 = a^2 + (f_edge(a)/(2 sigma_c))^2``) and ``gap(b) = delta`` (one scalar equation).
  All phases are one continuous 1D path parameter ``p``: ``p <= 0`` zone only with
  ``b = b_touch + p`` (``b_touch`` = zone end at which the free centre touches the sphere),
  ``p > 0`` contact with ``a = p``; ``p = -b_touch`` is "no zone". The stable state is an
  up-crossing of ``Phi(p) = gap - delta`` (or ``p = p_lo`` with ``Phi > 0``: apart).
  The root is continued in a small window around the previous one; if it is not found the step
  is halved; below ``1e-10`` of the nominal step the branch has ended (fold) and the solution
  jumps (scan to the next up-crossing in the direction given by the sign of ``Phi``) with the
  material responding with its instantaneous modulus (the jump step has ``dt -> 0``).
* The force target at the turn is hit exactly (root in the step size). ``F_pulloff`` is the
  largest tensile force of the retraction, refined by a parabola through the three samples
  around the largest one.

Force-controlled retraction (``force_rate``)
--------------------------------------------
* Same model, grid, moving nodes and arm update; the lift ``h`` is an extra unknown of each
  step. For a step ``dt`` (history fixed) the states are parametrised by the contact radius
  ``a``: the edge condition gives the lift explicitly, ``h(a, b) = (sigma sqrt(b^2 - a^2)/2 +
  hist(a))/Geff - a^2/R``, and ``gap(b) = delta`` (``-delta`` at ``b = a``, increasing) fixes
  ``b(a)``; so ``F(a)`` is one smooth function. The step's state is the root of
  ``F(a) = F_prescribed(t + dt)`` on the stable side (``dF/da < 0``) nearest the last ``a``:
  Newton on ``(a, b)`` from a linear predictor (accepted only on the stable side, within a
  window), else a walk from the last ``a`` with bracketing (Brent).
* Fold (pull-off): if the walk passes the local maximum of ``F(a)`` (refined by bounded
  Brent) and it is below the prescribed force, no state carries it within this step. The fold
  time is then the root ``dt*`` in ``[0, dt]`` of ``S(dt) = max_a F(a; dt) - F_prescribed(dt)``
  (Brent, ``xtol`` 1e-15 of the time; ``S(0) > 0`` as the last state is stable). This is the
  same as maximising over ``a`` the time at which ``a`` balances the prescribed force.
  ``F_pulloff`` is the prescribed force at ``t_turn + dt*``; ``h_pulloff``/``a_pulloff`` are of
  the maximising state (a flat maximum: ~1e-8 relative, the force to round-off).
* Step control: nominal ``dt = dF/force_rate``; edges may move at most ``kappa`` zone widths
  per step, ``kappa = dt/min(tau_i)`` (no limit when elastic), also for the fold step, so the
  fold is closed in on with shrinking steps (last step ~1e-6 s at dt = 6e-5 s). Only
  contact states are followed (an error if the contact is lost before the fold).
"""
from __future__ import annotations

import math
import time as _time

import numpy as np
from scipy.optimize import brentq, minimize_scalar

__all__ = ["sphere_path_reference"]


class _Model:
    def __init__(self, G_inf, arms, sigma_c, delta, R):
        self.G_inf = float(G_inf)
        self.Gi = np.array([float(g) for g, _ in arms])
        self.taui = np.array([float(t) for _, t in arms])
        self.sigma = float(sigma_c)
        self.delta = float(delta)
        self.R = float(R)

    def coeffs(self, dt):
        if dt <= 0.0:
            e = np.ones_like(self.taui)
            c = np.ones_like(self.taui)
        else:
            k = dt / self.taui
            e = np.exp(-k)
            c = np.where(k > 1e-8, -np.expm1(-k) / np.where(k > 0, k, 1.0), 1.0 - 0.5 * k)
        return e, c


def _theta_r(x, b):
    r = np.sqrt(np.maximum((b - x) * (b + x), 0.0))
    return np.arctan2(r, x), r


class _Step:
    """Everything for one step from state (X, U, S) to time t+dt at lift h."""

    def __init__(self, model, Xm, Um, Sm, h, dt, tol_x):
        m = model
        self.m = m
        self.h = h
        e, c = m.coeffs(dt)
        self.e, self.c = e, c
        self.Geff = m.G_inf + float(np.dot(m.Gi, c))
        self.Xm = Xm
        if len(m.Gi):
            self.Hm = ((m.Gi * c)[:, None] * Um[None, :] - e[:, None] * Sm).sum(axis=0)
        else:
            self.Hm = np.zeros_like(Xm)
        self.elastic = not len(m.Gi)
        self.hist0 = self.Hm[0]
        self.b_t = 2.0 * (self.Geff * h - self.hist0) / m.sigma
        self.p_lo = -self.b_t if self.b_t > 0 else 0.0
        self.tol_x = tol_x
        self.xmax = Xm[-1]

    def hist_at(self, x):
        if self.elastic:
            return 0.0
        return float(np.interp(x, self.Xm, self.Hm))

    def Hint(self, a, b):
        """int_a^b hist(x)/sqrt(b^2-x^2) dx for piecewise linear hist."""
        if self.elastic or b <= a:
            return 0.0
        Xm, Hm = self.Xm, self.Hm
        i0 = np.searchsorted(Xm, a + self.tol_x, side="right")
        i1 = np.searchsorted(Xm, b - self.tol_x, side="left")
        xs = np.concatenate(([a], Xm[i0:i1], [b]))
        hs = np.concatenate(([self.hist_at(a)], Hm[i0:i1], [self.hist_at(b)]))
        th, r = _theta_r(xs, b)
        dx = np.diff(xs)
        I0 = th[:-1] - th[1:]
        I1 = r[:-1] - r[1:]
        w0 = (xs[1:] * I0 - I1) / dx
        w1 = (I1 - xs[:-1] * I0) / dx
        return float(np.dot(hs[:-1], w0) + np.dot(hs[1:], w1))

    def ab(self, p):
        """(a, b) for path parameter p."""
        if p < 0.0:
            return 0.0, max(self.b_t + p, 0.0)
        a = p
        L = 4.0 * (self.Geff * (self.h + a * a / self.m.R) - self.hist_at(a))
        if L <= 0.0:
            return a, a
        return a, math.hypot(a, L / (2.0 * self.m.sigma))

    def phi(self, p):
        m = self.m
        h = self.h
        a, b = self.ab(p)
        if b <= 0.0:
            return h - self.hist0 / self.Geff - m.delta
        if b <= a:
            return -m.delta
        th_a, r_a = (math.atan2(math.sqrt(max((b - a) * (b + a), 0.0)), a),
                     math.sqrt(max((b - a) * (b + a), 0.0)))
        asin_ab = 0.5 * math.pi - th_a
        C = h * asin_ab + (0.5 * b * b * asin_ab - 0.5 * a * r_a) / m.R
        u3d = (2.0 / math.pi) * (C + (0.5 * m.sigma * (b - a) + self.Hint(a, b)) / self.Geff)
        return h + 0.5 * b * b / m.R - u3d - m.delta

    def force(self, a, b):
        m = self.m
        h = self.h
        F = 0.0
        if a > 0.0:
            Fc = self.Geff * (h * a + a ** 3 / (3.0 * m.R))
            if not self.elastic:
                i1 = np.searchsorted(self.Xm, a - self.tol_x, side="left")
                xs = np.concatenate((self.Xm[:i1], [a]))
                hs = np.concatenate((self.Hm[:i1], [self.hist_at(a)]))
                Fc -= float(np.sum(0.5 * (hs[1:] + hs[:-1]) * np.diff(xs)))
            F += 8.0 * Fc
        if b > a:
            r_a = math.sqrt(max((b - a) * (b + a), 0.0))
            th_a = math.atan2(r_a, a)
            F += 2.0 * m.sigma * (b * b * th_a - a * r_a)
        return F

    # --- force control: the lift as an unknown (contact states, a > 0) -----------------------
    def h_edge(self, a, b):
        """Lift at which the contact edge a carries the zone b (edge condition solved for h)."""
        return ((0.5 * self.m.sigma * math.sqrt(max((b - a) * (b + a), 0.0)) + self.hist_at(a))
                / self.Geff - a * a / self.m.R)

    def gap_at(self, a, b, h):
        """``gap(b) - delta`` for contact radius a, zone end b and lift h (``phi`` with h given)."""
        m = self.m
        if b <= a:
            return -m.delta
        r_a = math.sqrt(max((b - a) * (b + a), 0.0))
        asin_ab = 0.5 * math.pi - math.atan2(r_a, a)
        C = h * asin_ab + (0.5 * b * b * asin_ab - 0.5 * a * r_a) / m.R
        u3d = (2.0 / math.pi) * (C + (0.5 * m.sigma * (b - a) + self.Hint(a, b)) / self.Geff)
        return h + 0.5 * b * b / m.R - u3d - m.delta

    def hist_integral(self, a):
        """int_0^a hist dx (exact for the piecewise linear hist), via a cumulative table."""
        if self.elastic:
            return 0.0
        if not hasattr(self, "_cum"):
            self._cum = np.concatenate(([0.0], np.cumsum(0.5 * (self.Hm[1:] + self.Hm[:-1])
                                                         * np.diff(self.Xm))))
        i = int(np.searchsorted(self.Xm, a, side="right")) - 1
        i = min(max(i, 0), len(self.Xm) - 2)
        x0 = self.Xm[i]
        return float(self._cum[i] + 0.5 * (self.Hm[i] + self.hist_at(a)) * (a - x0))

    def force_at(self, a, b, h):
        """Total force [N] of the contact state (a, b) at lift h (``force`` with h given)."""
        m = self.m
        F = 8.0 * (self.Geff * (h * a + a ** 3 / (3.0 * m.R)) - self.hist_integral(a))
        if b > a:
            r_a = math.sqrt(max((b - a) * (b + a), 0.0))
            F += 2.0 * m.sigma * (b * b * math.atan2(r_a, a) - a * r_a)
        return F


class _Fail(Exception):
    pass


class _Solver:
    def __init__(self, model, X):
        self.m = model
        self.X = X
        self.dx = X[1] - X[0] if len(X) > 1 else X[-1]
        self.dxmin = float(np.min(np.diff(X)))
        self.tol_x = 1e-9 * self.dxmin
        n = len(X)
        na = len(model.Gi)
        self.U = np.zeros(n)
        self.S = np.zeros((na, n))
        self.mov = []  # list of (x, u, s)
        self.mode = "none"  # none | zone | contact
        self.a = 0.0
        self.b = 0.0
        self.dp_prev = 0.0

    # --- state helpers -------------------------------------------------------------------
    def merged(self):
        X, U, S = self.X, self.U, self.S
        if not self.mov:
            return X, U, S
        Xl, Ul, Sl = [X], [U], [S]
        xs = []
        for (x, u, s) in self.mov:
            j = np.searchsorted(X, x)
            if (j < len(X) and abs(X[j] - x) <= self.tol_x) or (j > 0 and abs(X[j - 1] - x) <= self.tol_x):
                continue
            if any(abs(x - y) <= self.tol_x for y in xs):
                continue
            xs.append(x)
            Xl.append(np.array([x]))
            Ul.append(np.array([u]))
            Sl.append(np.asarray(s).reshape(-1, 1))
        Xc = np.concatenate(Xl)
        o = np.argsort(Xc, kind="stable")
        return Xc[o], np.concatenate(Ul)[o], np.concatenate(Sl, axis=1)[:, o]

    def p_old(self, st):
        if self.mode == "none":
            return st.p_lo
        if self.mode == "zone":
            return max(min(self.b - st.b_t, 0.0), st.p_lo)
        return max(self.a, 0.0)

    # --- root finding ----------------------------------------------------------------------
    def _bracket_root(self, st, pa, fa, pb, fb):
        if fa == 0.0:
            return pa
        if fb == 0.0:
            return pb
        return brentq(st.phi, min(pa, pb), max(pa, pb), xtol=1e-15 * self.X[-1], rtol=1e-15,
                      maxiter=200)

    def local_root(self, st, p0):
        """Up-crossing root of phi within a window around p0, or raise _Fail.

        From p0 walk (growing steps) in the direction in which phi should change sign; if
        |phi| starts growing again before a sign change, minimise |phi| on the last interval
        (a narrow dip near a fold); no sign change there means the branch has ended.
        """
        scale = max(self.b, abs(st.b_t), 1e-6 * self.X[-1])
        W = min(4.0 * self.dx, 0.02 * scale) + 2.0 * abs(self.dp_prev)
        f0 = st.phi(p0)
        if f0 == 0.0:
            return p0
        sg = 1.0 if f0 > 0.0 else -1.0
        dirn = -sg
        if sg > 0 and p0 <= st.p_lo:
            return st.p_lo
        lim = p0 + dirn * W
        lim = max(lim, st.p_lo) if dirn < 0 else min(lim, self.X[-1])
        step = 1.2 * abs(self.dp_prev) + W / 64.0
        pts = [(p0, sg * f0)]
        while True:
            pp = pts[-1][0]
            pn = pp + dirn * step
            pn = max(pn, lim) if dirn < 0 else min(pn, lim)
            fn = st.phi(pn)
            sfn = sg * fn
            if sfn <= 0.0:
                return self._bracket_root(st, pp, sg * pts[-1][1], pn, fn)
            if dirn < 0 and pn <= st.p_lo:
                return st.p_lo  # separated (no zone)
            if sfn > pts[-1][1]:  # |phi| grows again: look for a dip between
                pa = pts[-2][0] if len(pts) > 1 else pp
                lo, hi = min(pa, pn), max(pa, pn)
                if lo == hi:
                    raise _Fail
                res = minimize_scalar(lambda x: sg * st.phi(x), bounds=(lo, hi), method="bounded",
                                      options={"xatol": 1e-14 * self.X[-1]})
                if res.fun < 0.0:
                    # up-crossing nearest p0: between the p0-side point and the minimum
                    pside = pa if len(pts) > 1 else pp
                    return self._bracket_root(st, pside, sg * st.phi(pside), res.x, sg * res.fun)
                raise _Fail
            pts.append((pn, sfn))
            if pn == lim:
                raise _Fail
            step *= 2.0

    def global_root(self, st, p0):
        """Jump: scan from p0 to the next up-crossing in the direction given by phi's sign."""
        f0 = st.phi(p0)
        ds = max(0.5 * self.dx, 1e-5 * self.X[-1])
        pp, fp = p0, f0
        if f0 < 0.0:
            while True:
                pn = pp + ds
                if pn > self.X[-1]:
                    raise RuntimeError("jump target beyond x_max; increase x_max")
                fn = st.phi(pn)
                if fn > 0.0:
                    return self._bracket_root(st, pp, fp, pn, fn)
                pp, fp = pn, fn
        else:
            while True:
                pn = max(pp - ds, st.p_lo)
                fn = st.phi(pn)
                if fn < 0.0:
                    return self._bracket_root(st, pn, fn, pp, fp)
                if pn <= st.p_lo:
                    return st.p_lo
                pp, fp = pn, fn

    # --- one step ----------------------------------------------------------------------------
    def trial(self, h, dt, jump=False):
        Xm, Um, Sm = self.merged()
        st = _Step(self.m, Xm, Um, Sm, h, dt, self.tol_x)
        p0 = self.p_old(st)
        p = self.global_root(st, p0) if jump else self.local_root(st, p0)
        a, b = st.ab(p)
        if p <= st.p_lo and st.phi(st.p_lo) > 0.0:
            mode, a, b = "none", 0.0, 0.0
        elif p < 0.0:
            mode = "zone"
        else:
            mode = "contact"
        F = st.force(a, b)
        return dict(st=st, p=p, p0=p0, a=a, b=b, mode=mode, F=F, Xm=Xm, Um=Um, Sm=Sm, h=h, dt=dt)

    def commit(self, tr):
        st = tr["st"]
        m = self.m
        a, b, h = tr["a"], tr["b"], tr["h"]
        e, c, Geff = st.e, st.c, st.Geff
        Xm, Um, Sm = tr["Xm"], tr["Um"], tr["Sm"]

        def new_u(x, histx):
            u = histx / Geff
            inz = (x > a) & (x < b)
            u = np.where(inz, (0.5 * m.sigma * np.sqrt(np.maximum(b * b - x * x, 0.0)) + histx) / Geff, u)
            u = np.where(x <= a, h + x * x / m.R, u) if a > 0 else u
            return u

        X = self.X
        if len(m.Gi):
            histX = ((m.Gi * c)[:, None] * self.U[None, :] - e[:, None] * self.S).sum(axis=0)
        else:
            histX = np.zeros_like(X)
        Un = new_u(X, histX)
        if a > 0:
            Un = np.where(X <= a, h + X * X / m.R, Un)
        Sn = e[:, None] * self.S + (m.Gi * c)[:, None] * (Un - self.U)[None, :]
        mov = []
        for x in ([a] if a > 0 else []) + ([b] if b > 0 else []):
            if x >= X[-1]:
                raise RuntimeError("zone end beyond x_max; increase x_max")
            uo = float(np.interp(x, Xm, Um))
            so = np.array([np.interp(x, Xm, Sm[i]) for i in range(Sm.shape[0])])
            hx = float(np.dot(m.Gi * c, np.full_like(c, uo)) - np.dot(e, so)) if len(m.Gi) else 0.0
            if x == a and a > 0:
                un = h + x * x / m.R
            else:
                un = hx / Geff
            sn = e * so + m.Gi * c * (un - uo)
            mov.append((x, un, sn))
        self.U, self.S, self.mov = Un, Sn, mov
        self.dp_prev = tr["p"] - tr["p0"] if tr["mode"] == self.mode else 0.0
        self.mode, self.a, self.b = tr["mode"], a, b


def _default_xmax(G_inf, sigma_c, delta, R, F_target):
    # elastic (softest modulus) estimates: zone-only jump radius and Maugis-Dugdale sizes
    gamma = sigma_c * delta
    E = 4.0 * G_inf
    b_zone = 2.0 * sigma_c * R / (math.pi * G_inf)
    a_load = (3.0 * R * (F_target + 3.0 * math.pi * gamma * R) / (4.0 * E)) ** (1.0 / 3.0) * 2.0
    return 1.3 * max(b_zone, a_load) + 4.0 * a_load


def _march(sol, h0, segments, delta, F_target, max_steps):
    """Step the approach and the retraction (``segments``: (speed [m/s], nominal step [s])),
    resolving folds as jumps; the history (lists) and the jumps."""
    rec = dict(t=[0.0], h=[h0], F=[0.0], a=[0.0], b=[0.0], mode=["none"], segment=[0])
    jumps = []

    def record(t, tr, seg):
        rec["t"].append(t)
        rec["h"].append(tr["h"])
        rec["F"].append(tr["F"])
        rec["a"].append(tr["a"])
        rec["b"].append(tr["b"])
        rec["mode"].append(tr["mode"])
        rec["segment"].append(seg)

    t = 0.0
    h = h0
    nsteps = 0
    for seg, (v, dtn) in enumerate(segments):
        dtry = dtn
        dt_min = 1e-10 * dtn
        # edge-speed limit per step, refined with the nominal step
        kappa = v * dtn / delta
        done = False
        while not done:
            nsteps += 1
            if nsteps > max_steps:
                raise RuntimeError("too many steps")
            try:
                tr = sol.trial(h + v * dtry, dtry)
                # accuracy control: the edges may move at most kappa zone widths per step
                if tr["mode"] == sol.mode and sol.mode != "none":
                    w = max(sol.b - sol.a, 1e-300)
                    ell = max(abs(tr["a"] - sol.a), abs(tr["b"] - sol.b)) / (kappa * w)
                    if ell > 1.5 and dtry > dt_min:
                        dtry = max(dtry * min(0.5, 0.8 / ell), dt_min)
                        continue
                    grow = min(2.0, 0.9 / ell) if ell > 0 else 2.0
                else:
                    grow = 2.0
            except _Fail:
                if dtry > dt_min:
                    dtry *= 0.5
                    continue
                # fold: the branch ends here -> jump (dt -> 0 step, instantaneous response)
                before = dict(t=t, h=h, F=rec["F"][-1], a=sol.a, b=sol.b, mode=sol.mode)
                tr = sol.trial(h + v * dtry, dtry, jump=True)
                grow = 2.0
                jumps.append(dict(before=before, after=dict(t=t + dtry, h=tr["h"], F=tr["F"], a=tr["a"],
                                                            b=tr["b"], mode=tr["mode"]), segment=seg))
            # turn at the force target
            if seg == 0 and tr["mode"] != "none" and tr["F"] <= -F_target:
                def fres(d):
                    return sol.trial(h + v * d, d)["F"] + F_target
                lo, hi = 0.0, tr["dt"]
                if fres(lo) < 0.0:
                    lo = hi  # already past (should not happen)
                dstar = brentq(fres, lo, hi, xtol=1e-14 * hi, rtol=1e-15) if lo < hi else hi
                tr = sol.trial(h + v * dstar, dstar)
                done = True
            sol.commit(tr)
            t += tr["dt"]
            h = tr["h"]
            record(t, tr, seg)
            if seg == 1 and tr["mode"] == "none":
                done = True
            dtry = min(max(grow, 0.5) * tr["dt"], dtn) if tr["dt"] > 0 else dtn
    return rec, jumps


class _ContactStates:
    """Contact states of one force-controlled step (fixed ``dt``, hence fixed history): for a
    contact radius ``a`` the zone end ``b`` solves ``gap(b) = delta`` with the lift given by the
    edge condition at ``a``, ``h = (sigma sqrt(b^2 - a^2)/2 + hist(a))/Geff - a^2/R``; returns
    ``(b, h, F)`` (cached)."""

    def __init__(self, st, w_guess, xmax):
        self.st = st
        self.w = max(w_guess, 1e-9 * xmax)
        self.xmax = xmax
        self.cache = {}

    def __call__(self, a):
        v = self.cache.get(a)
        if v is None:
            st = self.st

            def g(b):
                return st.gap_at(a, b, st.h_edge(a, b))

            lo, w = a, 0.25 * self.w  # g(a) = -delta
            while True:
                hi = a + w
                if hi >= self.xmax:
                    raise RuntimeError("zone end beyond x_max; increase x_max")
                if g(hi) > 0.0:
                    break
                lo, w = hi, 2.0 * w
            b = brentq(g, lo, hi, xtol=1e-15 * self.xmax, rtol=1e-15, maxiter=200)
            h = st.h_edge(a, b)
            v = (b, h, st.force_at(a, b, h))
            self.cache[a] = v
        return v


def _force_newton(st, Ft, a_pred, b_pred, a0, W, xmax):
    """Newton (chord) solve of ``gap = delta`` and ``F = Ft`` for ``(a, b)`` from a predictor,
    the lift from the edge condition; ``(a, b)`` on the stable branch (``dF/da < 0`` along
    ``gap = delta``) within ``W`` of ``a0``, or None (then the walk decides)."""
    Fs = abs(Ft) + 2.0 * st.m.sigma * st.m.delta * st.m.R  # force scale of the residual

    def res(a, b):
        if not 0.0 < a < b < xmax:
            raise _Fail
        h = st.h_edge(a, b)
        return np.array([st.gap_at(a, b, h) / st.m.delta, (st.force_at(a, b, h) - Ft) / Fs])

    def jac(a, b, r):
        e = 1e-7 * (b - a)
        ra = res(a + e, b)
        rb = res(a, b + e)
        return np.column_stack(((ra - r) / e, (rb - r) / e))

    try:
        a, b = a_pred, b_pred
        r = res(a, b)
        J = jac(a, b, r)
        tol = 1e-14 * a0
        for it in range(16):
            if it == 8:
                J = jac(a, b, r)
            da, db = np.linalg.solve(J, -r)
            a, b = a + da, b + db
            r = res(a, b)
            if abs(da) <= tol and abs(db) <= tol:
                break
        else:
            return None
        J = jac(a, b, r)
    except (_Fail, np.linalg.LinAlgError):
        return None
    if abs(a - a0) > W or not np.all(np.isfinite(J)):
        return None
    if J[1, 0] - J[1, 1] * J[0, 0] / J[0, 1] >= 0.0:
        return None  # unstable side of the fold
    return float(a), float(b)


def _force_max(ev, a0, step, W):
    """Local maximum of ``F(a) = ev(a)[2]`` nearest ``a0`` (walk uphill with doubling steps,
    then bounded Brent on the bracketing triple): ``(a_m, F_m)``; ``_Fail`` beyond ``W``."""
    def f(a):
        if a <= 0.0:
            raise NotImplementedError("contact lost before the force-controlled pull-off")
        return ev(a)[2]

    f0 = f(a0)
    d = -1.0
    f1 = f(a0 - step)
    walk = True
    if f1 < f0:
        d = 1.0
        f1 = f(a0 + step)
        if f1 <= f0:
            lo, hi = a0 - step, a0 + step
            walk = False
    if walk:
        pp, ap, fp = a0, a0 + d * step, f1
        while True:
            step *= 2.0
            an = ap + d * step
            if abs(an - a0) > W:
                raise _Fail
            fn = f(an)
            if fn <= fp:
                lo, hi = min(pp, an), max(pp, an)
                break
            pp, ap, fp = ap, an, fn
    res = minimize_scalar(lambda x: -f(x), bounds=(lo, hi), method="bounded",
                          options={"xatol": 1e-13 * a0})
    return float(res.x), float(-res.fun)


def _force_step(ev, Ft, a0, step, W, xtol):
    """Stable contact state (``dF/da < 0``) nearest ``a0`` carrying the force ``Ft``:
    ``("ok", a)``, or ``("fold", a_m, F_m)`` if the local maximum ``F_m`` of ``F(a)`` is below
    ``Ft``; ``_Fail`` if neither is found within ``W`` of ``a0``."""
    def g(a):
        if a <= 0.0:
            raise NotImplementedError("contact lost before the force-controlled pull-off")
        return ev(a)[2] - Ft

    def root(lo, hi):
        return ("ok", brentq(g, lo, hi, xtol=xtol, rtol=1e-15, maxiter=200))

    g0 = g(a0)
    if g0 == 0.0:
        return ("ok", a0)
    d = step
    if g0 > 0.0:  # too much tension at a0: the contact grows (F decreases with a)
        pp, gp = a0, g0
        while True:
            an = pp + d
            if an - a0 > W:
                raise _Fail
            gn = g(an)
            if gn <= 0.0:
                return root(pp, an)
            if gn > gp:
                raise _Fail
            pp, gp, d = an, gn, 2.0 * d
    pts = [(a0, g0)]
    while True:  # the contact shrinks until F reaches Ft, or F passes its maximum
        an = pts[-1][0] - d
        if a0 - an > W:
            raise _Fail
        gn = g(an)
        if gn >= 0.0:
            return root(an, pts[-1][0])
        if gn < pts[-1][1]:
            break
        pts.append((an, gn))
        d *= 2.0
    a_m, F_m = _force_max(ev, pts[-1][0], step, W)
    if F_m < Ft:
        return ("fold", a_m, F_m)
    above = [a for a, _ in pts if a > a_m]
    if not above:
        raise _Fail
    return root(a_m, min(above))


def _fold_in_step(make, Fpres, w, a0, step, W, dtry, t_end):
    """The fold inside a step of ``dtry``: the root of ``S(dt) = max_a F(a; dt) -
    F_prescribed(dt)`` on ``[0, dtry]``; returns the step, its states, the fold's ``a`` and the
    step length."""
    def S(dt):
        return _force_max(make(dt, w)[1], a0, step, W)[1] - Fpres(dt)

    dts = 0.0 if S(0.0) <= 0.0 else brentq(S, 0.0, dtry, xtol=1e-15 * t_end, rtol=1e-15,
                                           maxiter=200)
    st, ev = make(dts, w)
    return st, ev, _force_max(ev, a0, step, W)[0], dts


def _retract_force(sol, rec, F_target, rate, dtn, kappa, max_steps):
    """Force-controlled retraction ``F = -F_target + rate (t - t_turn)`` from the turn to the
    fold (pull-off); appends to ``rec``; returns the fold (dict)."""
    t_turn = rec["t"][-1]
    if sol.mode != "contact":
        raise RuntimeError("force control needs contact at the turn")
    xmax = sol.X[-1]
    s = 0.0  # time since the turn
    dtry = dtn
    dt_min = 1e-10 * dtn
    da_prev = 0.0
    merged = sol.merged()
    nsteps = 0
    pred = None  # (da, db, dt) of the last step: the Newton predictor

    def make(dt, w):
        st = _Step(sol.m, *merged, 0.0, dt, sol.tol_x)
        return st, _ContactStates(st, w, xmax)

    def Fpres(dt):
        return -F_target + rate * (s + dt)

    while True:
        nsteps += 1
        if nsteps > max_steps:
            raise RuntimeError("too many steps")
        a0, b0 = sol.a, sol.b
        w = b0 - a0
        step = 1.2 * abs(da_prev) + w / 64.0
        W = 4.0 * sol.dx + 8.0 * w + 4.0 * abs(da_prev)
        xtol = 1e-15 * xmax
        st, ev = make(dtry, w)
        nw = None
        if pred is not None:
            q = dtry / pred[2]
            nw = _force_newton(st, Fpres(dtry), a0 + q * pred[0], b0 + q * pred[1], a0, W, xmax)
        if nw is not None:
            res = ("ok", nw[0])
        else:
            try:
                res = _force_step(ev, Fpres(dtry), a0, step, W, xtol)
            except _Fail:
                if dtry > dt_min:
                    dtry *= 0.5
                    continue
                raise RuntimeError("force-controlled step failed (no state near the last one)")
        fold = res[0] == "fold"
        if fold:
            st, ev, a, dt_step = _fold_in_step(make, Fpres, w, a0, step, W, dtry,
                                               t_turn + s + dtry)
            b, h, F = ev(a)
        elif nw is not None:
            a, b = nw
            dt_step = dtry
            h = st.h_edge(a, b)
            F = st.force_at(a, b, h)
        else:
            a = res[1]
            dt_step = dtry
            b, h, F = ev(a)
        ell = max(abs(a - a0), abs(b - b0)) / (kappa * w) if math.isfinite(kappa) else 0.0
        if ell > 1.5 and dt_step > dt_min:
            # edges may move at most kappa zone widths per step (also when closing on the fold)
            dtry = max(dt_step * min(0.5, 0.8 / ell), dt_min)
            continue
        grow = min(2.0, 0.9 / ell) if ell > 0 else 2.0
        sol.commit(dict(st=st, p=a, p0=a0, a=a, b=b, mode="contact", F=F, Xm=merged[0],
                        Um=merged[1], Sm=merged[2], h=h, dt=dt_step))
        s += dt_step
        for key, val in (("t", t_turn + s), ("h", h), ("F", F), ("a", a), ("b", b),
                         ("mode", "contact"), ("segment", 1)):
            rec[key].append(val)
        if fold:
            return dict(s=s, t=t_turn + s, F=-F_target + rate * s, F_state=F, h=h, a=a, b=b,
                        t_turn=t_turn, last_step=dt_step, n_steps=nsteps)
        merged = sol.merged()
        da_prev = a - a0
        pred = (a - a0, b - b0, dt_step) if dt_step > 0.0 else None
        dtry = min(max(grow, 0.5) * dt_step, dtn)


def _summary(out, jumps) -> dict:
    """Pull-off (parabola-refined), jump out, contact loss, jump in and extent (SI)."""
    res = {}
    seg = out["segment"]
    F = out["F"]
    hh = out["h"]
    idx = np.nonzero(seg == 1)[0]
    k = idx[np.argmax(F[idx])]
    Fp, hp = F[k], hh[k]
    if idx[0] < k < idx[-1]:
        x0, x1, x2 = hh[k - 1], hh[k], hh[k + 1]
        y0, y1, y2 = F[k - 1], F[k], F[k + 1]
        if out["mode"][k - 1] == out["mode"][k] == out["mode"][k + 1] == "contact":
            d01 = (y1 - y0) / (x1 - x0)
            d12 = (y2 - y1) / (x2 - x1)
            c2 = (d12 - d01) / (x2 - x0)
            if c2 < 0:
                xv = 0.5 * (x0 + x1) - d01 / (2 * c2)
                if x0 <= xv <= x2:
                    hp = xv
                    Fp = y0 + d01 * (xv - x0) + c2 * (xv - x0) * (xv - x1)
    res["F_pulloff"] = float(Fp)
    res["h_pulloff"] = float(hp)
    jo = [j for j in jumps if j["segment"] == 1 and j["before"]["mode"] == "contact"
          and j["after"]["mode"] != "contact"]
    if jo:
        res["F_jump_out"] = float(jo[0]["before"]["F"])
        res["h_jump_out"] = float(jo[0]["before"]["h"])
        res["a_jump_out"] = float(jo[0]["before"]["a"])
        res["F_after_jump_out"] = float(jo[0]["after"]["F"])
    else:
        res["F_jump_out"] = res["h_jump_out"] = res["a_jump_out"] = res["F_after_jump_out"] = float("nan")
    kc = [k for k in idx if out["mode"][k] == "contact"]
    res["h_contact_lost"] = float(hh[kc[-1]]) if kc else float("nan")  # last contact sample
    res["F_contact_lost"] = float(F[kc[-1]]) if kc else float("nan")
    ji = [j for j in jumps if j["segment"] == 0]
    res["h_jump_in"] = float(ji[0]["before"]["h"]) if ji else float("nan")
    res["h_turn"] = float(hh[idx[0] - 1])
    res["h_separation"] = float(hh[-1])
    res["b_max"] = float(np.max(out["b"]))
    return res


def sphere_path_reference(*, G_inf, arms=(), sigma_c, delta, R, h0, v_in, F_target, v_out=None,
                          n_elements, dt=None, dt_in=None, dh=None, x_max=None,
                          max_steps=10_000_000, force_rate=None, dF=None):
    """Approach-retract cycle of a rigid sphere on an MDR-Dugdale visco-elastic half-space.

    Parameters (SI units)
    ---------------------
    G_inf : float          relaxed shear modulus [Pa] (E* = 4 G, incompressible).
    arms : tuple of (G_i [Pa], tau_i [s])   Maxwell arms; ``()`` is elastic with ``G_inf``.
    sigma_c : float        Dugdale stress [Pa];  delta : float  Dugdale range [m].
    R : float              sphere radius [m] (``f = r^2/(2R)``, MDR ``g = x^2/R``).
    h0 : float             initial lift [m] (> delta: starts apart).
    v_in, v_out : float    approach / retraction speeds [m/s] (> 0).
    F_target : float       compressive force [N] at which the approach turns (``F = -F_target``).
    n_elements : int       number of grid cells on ``[0, x_max]`` (uniform).
    dt : float             retraction time step [s]; ``dt_in`` approach step [s] (default: the
                           same indenter displacement per step, ``dt * v_out / v_in``).
    dh : float             alternative: indenter displacement per step [m] (both segments).
    x_max : float          grid length [m] (default from elastic estimates with ``G_inf``).

    Returns a dict with arrays ``t`` [s], ``h`` [m], ``F`` [N, tensile > 0], ``a``, ``b`` [m],
    ``mode`` and ``segment`` (0 approach, 1 retract), the list ``jumps`` and the summary
    ``F_pulloff`` (largest tensile force of the retraction, parabola-refined) and
    ``h_pulloff`` (lift there), ``F_jump_out``/``h_jump_out`` (last contact state before the
    jump out of contact; NaN if contact is lost continuously), ``F_after_jump_out``,
    ``a_jump_out``, ``h_contact_lost``/``F_contact_lost`` (last contact sample), ``h_jump_in``, ``h_separation``, ``h_turn``, ``wall_time`` [s].

    Force-controlled retraction
    ---------------------------
    force_rate : float     [N/s] (> 0). Given, ``v_out`` must be None: after the approach the
                           force is prescribed, ``F(t) = -F_target + force_rate (t - t_turn)``
                           (rigid indenter, no machine spring), and the lift is the extra unknown.
    dF : float             force per retraction step [N] (nominal ``dt = dF/force_rate``; or give
                           ``dt``). The approach step is ``dh/v_in`` (or ``dt_in``).
    The retraction stops at the fold where no state carries the prescribed force any more (see
    the module docstring). The result then has the arrays (``segment`` 1 = force-controlled,
    the fold state is the last sample), ``jumps`` (of the approach), ``F_pulloff`` (prescribed
    force at the fold time), ``t_pulloff`` (time since the start), ``h_pulloff``, ``a_pulloff``,
    ``b_pulloff``, ``F_pulloff_state`` (the force of the fold state, = ``F_pulloff`` to
    round-off), ``last_step`` [s], ``h_jump_in``, ``h_turn``, ``t_turn``, ``b_max``, ``x_max``,
    ``n_steps``, ``wall_time``.
    """
    if force_rate is not None:
        if v_out is not None:
            raise ValueError("give either v_out (displacement control) or force_rate")
        return _force_path(G_inf=G_inf, arms=arms, sigma_c=sigma_c, delta=delta, R=R, h0=h0,
                           v_in=v_in, F_target=F_target, force_rate=force_rate,
                           n_elements=n_elements, dt=dt, dt_in=dt_in, dh=dh, dF=dF, x_max=x_max,
                           max_steps=max_steps)
    if v_out is None:
        raise ValueError("v_out (or force_rate) is required")
    t_wall = _time.perf_counter()
    model = _Model(G_inf, arms, sigma_c, delta, R)
    if x_max is None:
        # elastic pre-run with the relaxed modulus (no grid dependence when elastic)
        x0 = _default_xmax(G_inf, sigma_c, delta, R, F_target)
        pre = sphere_path_reference(G_inf=G_inf, arms=(), sigma_c=sigma_c, delta=delta, R=R, h0=h0,
                                    v_in=v_in, F_target=F_target, v_out=v_out, n_elements=64,
                                    dh=delta / 5.0, x_max=x0)
        x_max = 1.5 * pre["b_max"]
    X = np.linspace(0.0, x_max, int(n_elements) + 1)
    sol = _Solver(model, X)
    if dh is not None:
        dt_out = dh / v_out
        dt_inn = dh / v_in
    else:
        dt_out = float(dt)
        dt_inn = float(dt_in) if dt_in is not None else dt * v_out / v_in

    rec, jumps = _march(sol, h0, ((-v_in, dt_inn), (v_out, dt_out)), delta, F_target,
                        max_steps)
    out = {k: np.array(vv) for k, vv in rec.items()}
    out["jumps"] = jumps
    out.update(_summary(out, jumps))
    out["x_max"] = float(x_max)
    out["n_steps"] = int(len(out["F"]))
    out["wall_time"] = _time.perf_counter() - t_wall
    return out


def _step_length(increment, rate, dt, missing):
    """A time step [s]: ``increment / rate`` (a lift or force increment at its rate), else
    ``dt``."""
    if increment is not None:
        return increment / rate
    if dt is not None:
        return float(dt)
    raise ValueError(f"force control: {missing}")


def _force_path(*, G_inf, arms, sigma_c, delta, R, h0, v_in, F_target, force_rate, n_elements,
                dt, dt_in, dh, dF, x_max, max_steps):
    """Displacement-controlled approach, then force-controlled retraction to the pull-off."""
    t_wall = _time.perf_counter()
    if not force_rate > 0.0:
        raise ValueError("force_rate must be > 0")
    dt_inn = _step_length(dh, v_in, dt_in, "give dh or dt_in for the approach")
    dtn = _step_length(dF, force_rate, dt, "give dF (or dt) for the retraction")
    model = _Model(G_inf, arms, sigma_c, delta, R)
    if x_max is None:
        # elastic approach with the relaxed modulus: the largest zone of the path is at the turn
        x0 = _default_xmax(G_inf, sigma_c, delta, R, F_target)
        pre = _Solver(_Model(G_inf, (), sigma_c, delta, R), np.linspace(0.0, x0, 65))
        rec0, _ = _march(pre, h0, ((-v_in, delta / 5.0 / v_in),), delta, F_target, max_steps)
        x_max = 1.5 * max(rec0["b"])
    X = np.linspace(0.0, x_max, int(n_elements) + 1)
    sol = _Solver(model, X)
    rec, jumps = _march(sol, h0, ((-v_in, dt_inn),), delta, F_target, max_steps)
    kappa = dtn / float(np.min(model.taui)) if len(model.taui) else math.inf
    fold = _retract_force(sol, rec, F_target, force_rate, dtn, kappa, max_steps)
    out = {k: np.array(vv) for k, vv in rec.items()}
    out["jumps"] = jumps
    ji = [j for j in jumps if j["segment"] == 0]
    out.update(F_pulloff=float(fold["F"]), t_pulloff=float(fold["t"]), h_pulloff=float(fold["h"]),
               a_pulloff=float(fold["a"]), b_pulloff=float(fold["b"]),
               F_pulloff_state=float(fold["F_state"]), last_step=float(fold["last_step"]),
               h_jump_in=float(ji[0]["before"]["h"]) if ji else float("nan"),
               h_turn=float(out["h"][np.nonzero(out["segment"] == 1)[0][0] - 1]),
               t_turn=float(fold["t_turn"]), b_max=float(np.max(out["b"])), x_max=float(x_max),
               n_steps=int(len(out["F"])))
    out["wall_time"] = _time.perf_counter() - t_wall
    return out
