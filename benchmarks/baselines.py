"""Two baselines for the foundation stepper of :mod:`pulloff.solver`, for the benchmarks only.

Both solve the same dimensionless model as :mod:`pulloff.kernels` (lengths along the foundation
in units of the contact radius ``a``, displacements, lift and gap in ``delta``, time in
``delta / v``; ``sigma = sqrt(x^2 - 1)``, ``s(t) = k (h0 + t) + c``):

- :func:`mol_detachment`: the method of lines. The displacements of a *fixed* mesh of free
  elements are one ODE system ``k U + c dU/dt = sqrt(max(s^2 - sigma^2, 0))`` handed to
  :func:`scipy.integrate.solve_ivp` (LSODA or Radau) with an event at ``gap = 1``. This is what
  one would write without the stepper's tricks: the mesh cannot follow ``b(t)``, the sqrt onset
  of every element is left to the adaptive integrator, and the gap is a plain trapezoid.
- :func:`march_numpy`: the stepper's own algorithm (exact exponential steps, onset weights per
  age, age-interval weights for the gap; see :func:`pulloff.kernels.march`) in plain numpy,
  vectorised over the elements of each step. The weight tables are built once per run by the
  same numba functions as the product, so the comparison isolates the per-step work.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse
from scipy.integrate import solve_ivp

from pulloff.kernels import onset as kernels
from pulloff.solvers.onset import Problem, frozen_detach_time, preloaded_mesh, step_weights


# --------------------------------------------------------------------------------------------
# Baseline 1: method of lines with scipy's solve_ivp.

def mol_mesh(problem: Problem, n_elements: int, t_ref: float) -> np.ndarray:
    """Fixed element positions ``sigma`` (ascending, dimensionless) on ``[0, s(t_ref)]``.

    The split mirrors the stepper's mesh, which measured 2-8x more accurate here than nodes
    clustered toward both ends at equal size: the part loaded at ``t = 0``, ``[0, s0]``, is
    uniform in angle and clustered toward ``s0`` (where ``U`` has its ``(s0 - sigma)^1.5``
    kink); the rest is uniform in ``sigma``, because ``b`` sweeps it at constant speed
    ``ds/dt = k``.
    """
    s0 = problem.s_of(0.0)
    s_max = problem.s_of(t_ref)
    n_pre = max(4, round(n_elements * s0 / s_max)) if s0 > 0.0 else 0
    n_entered = max(4, n_elements - n_pre)
    preloaded, _ = preloaded_mesh(s0, n_pre)
    entered = s0 + (s_max - s0) * np.arange(n_entered + 1) / n_entered
    return np.concatenate([preloaded, entered])


@dataclass
class MolRun:
    """Outcome of one method-of-lines solve (dimensionless)."""

    t_detach: float  # nan if the event was not reached
    n_elements: int
    n_steps: int  # accepted steps of the integrator


def mol_detachment(problem: Problem, n_elements: int, rtol: float,
                   method: str = "LSODA") -> MolRun:
    """Detachment time by the method of lines on a fixed mesh (see module docstring).

    ``rtol`` is solve_ivp's relative tolerance; the absolute one is ``rtol`` times the lift at
    the frozen-history detachment time (``t_ref``, in ``delta``), the size of the displacements
    that matter for the gap. The Jacobian ``-k/c`` is constant and diagonal and is passed
    exactly (sparse for Radau, bandwidth 0 for LSODA), so neither method spends time on
    finite-difference Jacobians. ``c = 0`` would make the system algebraic: not supported.
    """
    k, c, h0 = problem.k, problem.c, problem.h0_scaled
    if not c > 0.0:
        raise ValueError("the method of lines needs c > 0 (eta > 0); c = 0 is a DAE")
    t_ref = frozen_detach_time(problem)
    sigma = mol_mesh(problem, n_elements, t_ref)
    x = np.sqrt(1.0 + sigma * sigma)
    # Trapezoid lengths in x between neighbouring nodes, written without cancellation.
    dx = (sigma[1:] - sigma[:-1]) * (sigma[1:] + sigma[:-1]) / (x[1:] + x[:-1])
    relax = k / c

    def rhs(t, U):
        s = k * (h0 + t) + c
        q = np.sqrt(np.maximum((s - sigma) * (s + sigma), 0.0))
        return q / c - relax * U

    def gap_minus_one(t, U):
        # gap = (2/pi) [h atan(S) - int U / sqrt(b^2 - x^2) dx] with U = sqrt(b^2 - x^2) v:
        # trapezoid of v in x over the nodes inside the zone, plus the partial interval to b,
        # where v = U/q -> 0 (the element at b has just entered and has not moved yet).
        S = k * (h0 + t) + c
        # Nodes with sigma < S: at least the one at sigma = 0, since S >= s0 >= c > 0.
        m = int(np.searchsorted(sigma, S))
        sg = sigma[:m]
        v = U[:m] / np.sqrt((S - sg) * (S + sg))
        integral = 0.5 * np.dot(v[1:] + v[:-1], dx[:m - 1])
        b = math.sqrt(1.0 + S * S)
        integral += 0.5 * v[-1] * (S - sg[-1]) * (S + sg[-1]) / (b + x[m - 1])
        return (2.0 / math.pi) * ((h0 + t) * math.atan(S) - integral) - 1.0

    gap_minus_one.terminal = True
    gap_minus_one.direction = 1.0
    n = sigma.size
    if method == "Radau":
        jac_options = {"jac": scipy.sparse.diags(np.full(n, -relax), format="csc")}
    elif method == "LSODA":
        banded = np.full((1, n), -relax)
        jac_options = {"jac": lambda t, U: banded, "lband": 0, "uband": 0}
    else:
        raise ValueError(f"method must be LSODA or Radau, got {method!r}")
    # The frozen time bounds detachment from above; the margin only covers rounding.
    sol = solve_ivp(rhs, (0.0, 1.01 * t_ref), np.zeros(n), method=method, rtol=rtol,
                    atol=rtol * (h0 + t_ref), events=gap_minus_one, dense_output=False,
                    **jac_options)
    events = sol.t_events[0]
    return MolRun(float(events[0]) if events.size else math.nan, n, int(sol.t.size - 1))


# --------------------------------------------------------------------------------------------
# Baseline 2: the stepper's algorithm in numpy.

def march_numpy(problem: Problem, dt: float, n_stop: int,
                n_preloaded: int | None = None) -> float:
    """Dimensionless detachment time by the stepper's algorithm, per-step work in numpy.

    Same mesh, weights, update and gap quadrature as :func:`pulloff.solver.run_foundation`
    with :func:`pulloff.kernels.march` (so the same ``t_detach`` up to rounding), but each step
    is a handful of vectorised numpy operations over the elements instead of numba loops.
    Returns ``nan`` if the gap does not reach 1 within ``n_stop`` steps. Needs ``k > 0`` (the
    stepper's ``k = 0`` limit places no new elements and is not reproduced here).
    """
    k, c, h0 = problem.k, problem.c, problem.h0_scaled
    if not k > 0.0:
        raise ValueError("march_numpy needs k > 0 (G > 0)")
    s0 = problem.s_of(0.0)
    # Mesh of the elements loaded at t = 0: the rule of run_foundation, verbatim.
    s_ref = problem.s_of(n_stop * dt)
    n_pre = n_preloaded or max(8, int(math.ceil(n_stop * s0 / s_ref)))
    sig_pre, _ = preloaded_mesh(s0, n_pre)
    capacity = n_stop + 2
    # Entered element j sits at s(j dt): placed at b after step j (j = 0 is the one at s0).
    # Positions are known in advance, so their geometry is computed once, with the kernel's
    # own floating-point expression for s.
    steps = np.arange(capacity)
    sig_born = k * (h0 + steps * dt) + c
    sig_born[0] = s0
    U_born = np.zeros(capacity)
    x_born = np.sqrt(1.0 + sig_born * sig_born)
    dx_born = (sig_born[1:] - sig_born[:-1]) * (sig_born[1:] + sig_born[:-1]) \
        / (x_born[1:] + x_born[:-1])
    # Part 1 of the gap integral runs over the preloaded elements and then the element at s0;
    # U_pre is a view into the head of that buffer so that no step has to concatenate.
    sig_1 = np.append(sig_pre, s0)
    x_1 = np.sqrt(1.0 + sig_1 * sig_1)
    dx_1 = (sig_1[1:] - sig_1[:-1]) * (sig_1[1:] + sig_1[:-1]) / (x_1[1:] + x_1[:-1])
    U_1 = np.zeros(sig_1.size)
    U_pre = U_1[:-1]

    (decay, w_pre_old, w_pre_new, w_on_old, w_on_new, _, _, _, ratio, w_young,
     w_old) = step_weights(k, c, dt, capacity)
    if capacity > w_on_old.size:
        raise ValueError(f"march_numpy reads weight tables by age: at most {w_on_old.size} "
                         f"steps, not {n_stop}")
    t_out = np.zeros(capacity)
    gap_out = np.zeros(capacity)
    gap_out[0] = kernels.gap_from_integral.py_func(h0, s0, 0.0)
    if gap_out[0] >= 1.0:
        return 0.0

    n_born = 1
    for step in range(n_stop):
        t_new = (step + 1) * dt
        s_old = k * (h0 + step * dt) + c
        s_new = k * (h0 + t_new) + c
        # Preloaded elements: load linear over the step.
        q_old = np.sqrt(np.maximum((s_old - sig_pre) * (s_old + sig_pre), 0.0))
        q_new = np.sqrt(np.maximum((s_new - sig_pre) * (s_new + sig_pre), 0.0))
        U_pre *= decay
        U_pre += w_pre_old * q_old + w_pre_new * q_new
        # Entered elements j = 0..step have ages step..0: the weight tables read backwards.
        sb = sig_born[:n_born]
        ub = U_born[:n_born]
        ub *= decay
        ub += w_on_old[step::-1] * np.sqrt(k * (sb + s_old)) \
            + w_on_new[step::-1] * np.sqrt(k * (sb + s_new))
        n_born += 1  # the new element at b = s_new, U = 0
        U_1[-1] = U_born[0]
        integral = _displacement_integral(sig_1, U_1, dx_1, sig_born, U_born, dx_born, n_born,
                                          s_new, ratio, w_young, w_old)
        g = (2.0 / math.pi) * ((h0 + t_new) * math.atan(s_new) - integral)
        t_out[step + 1] = t_new
        gap_out[step + 1] = g
        if g >= 1.0:
            return kernels.crossing_time(t_out[:step + 2], gap_out[:step + 2])
    return math.nan


def _displacement_integral(sig_1, U_1, dx_1, sig_born, U_born, dx_born, n_born, S, ratio,
                           w_young, w_old):
    """:func:`pulloff.kernels.displacement_integral` for ``n_born >= 2``, vectorised.

    ``sig_1``/``U_1``: the preloaded elements followed by the entered element at ``s0``;
    ``dx_1``/``dx_born``: x-lengths between neighbours of ``sig_1`` and of ``sig_born``.
    """
    # Part 1: trapezoid of v = U / q in x.
    v = U_1 / np.sqrt((S - sig_1) * (S + sig_1))
    total = 0.5 * np.dot(v[1:] + v[:-1], dx_1)
    # Part 2: entered elements, oldest first; g = v / R(age) is interpolated linearly and R is
    # integrated exactly per age interval. The youngest (age 0, R = 0) borrows g from the next.
    # Element j has age youngest - j, so the age-indexed tables are read backwards.
    youngest = n_born - 1
    sb = sig_born[:youngest]
    g = np.empty(n_born)
    g[:youngest] = U_born[:youngest] / np.sqrt((S - sb) * (S + sb)) / ratio[youngest:0:-1]
    g[youngest] = g[youngest - 1]
    ages = slice(youngest - 1, None, -1)
    total += np.dot(dx_born[:youngest], g[1:] * w_young[ages] + g[:-1] * w_old[ages])
    return total
