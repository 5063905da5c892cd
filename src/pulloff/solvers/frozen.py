"""The seed's frozen load history (its eq. 31): a closed form, nothing to discretise.

Every free element carries the *current* load since ``t = 0`` (MODEL.md section 3, item 2).
:func:`frozen_detach_time` also bounds the exact onset from above, which the steppers use to
size their runs.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..kernels import closed_forms
from .base import Solver, flat_punch_pull, problem as problem_line
from .problem import Problem, predictions, si_history
from .result import Result


def zone_ratio(s):
    """``(b - a)/a = sqrt(1 + s^2) - 1`` without cancellation for thin zones."""
    if type(s) is float:  # (math: the same bits without numpy's scalar arithmetic)
        return s * s / (1.0 + math.sqrt(1.0 + s * s))
    return s * s / (1.0 + np.sqrt(1.0 + s * s))


def frozen_memory(problem: Problem, t):
    """``U / q`` of the frozen-load model at dimensionless time ``t``: ``(1 - exp(-k t/c)) / k``
    with its exact limits ``1/k`` (``c = 0``) and ``t/c`` (``k = 0``); scalars or arrays."""
    k, c = problem.k, problem.c
    t = np.asarray(t, dtype=float)
    if c == 0.0:
        return np.full_like(t, 1.0 / k)
    if k == 0.0:
        return t / c
    return -np.expm1(-k * t / c) / k


def frozen_gap(problem: Problem, t):
    """Dimensionless gap of the seed's frozen-load model, without linearisation in ``b - a``.

    Every element carries the current load since ``t = 0``: ``U = q`` :func:`frozen_memory`,
    so ``int U / sqrt(b^2 - x^2) dx = (b - 1)`` times that factor. Scalars or arrays.
    """
    s = problem.s_of(np.asarray(t, dtype=float))
    return (2.0 / math.pi) * ((problem.h0_scaled + t) * np.arctan(s)
                              - zone_ratio(s) * frozen_memory(problem, t))


def frozen_detach_time(problem: Problem, t_limit: float = math.inf) -> float:
    """First dimensionless time with ``frozen_gap = 1`` (``inf`` if none before ``t_limit``).

    It bounds the exact detachment time from above: loads only grow, so the exact displacement
    is never larger than the frozen one and the exact gap reaches 1 no later. Newton inside a
    doubled bracket, compiled (:func:`pulloff.kernels.closed_forms.root`: in Python
    it cost ~10 us of every onset run).
    """
    return closed_forms.root(closed_forms.FROZEN, problem.k, problem.c, problem.h0_scaled,
                             float(t_limit), _NO_SERIES)


_NO_SERIES = np.empty(0)  # (the frozen gap has none)


class FrozenSolver(Solver):
    """``model.history: frozen``: the seed's eq. 31 on a Kelvin-Voigt (or elastic) flat punch
    pulled to the onset, without linearisation in ``b - a``."""

    name = "frozen"
    summary = "the seed's frozen load history (eq. 31), closed form"

    def unsupported(self, scene) -> list[str]:
        out = []
        if scene.model.history != "frozen":
            # The rest is listed too: routing names the problems of the closest solver.
            out.append(problem_line("model.history", scene.model.history,
                                    "the frozen solver is the closed form of history: frozen"))
        why = ("the seed's frozen load history (eq. 31) is a closed form of a Kelvin-Voigt "
               "flat punch pulled to the onset; use history: exact")
        out += [line.split(": ", 1)[0] + ": " + why
                for line in flat_punch_pull(scene, "frozen")]
        if scene.model.history == "frozen" and scene.material.kind not in ("kelvin_voigt", "elastic"):
            out.append(problem_line("model.history", "frozen", f"{why} for a "
                                    f"{scene.material.kind}"))
        if scene.model.until != "detach":
            out.append(problem_line("model.until", scene.model.until, why))
        for key in ("steps", "max_elements"):
            value = getattr(scene.numerics, key)
            if value is not None:
                out.append(problem_line(f"numerics.{key}", value, "nothing is stepped with "
                                        "model.history = frozen (a closed form); remove it"))
        if scene.numerics.method is not None:
            out.append(problem_line("numerics.method", scene.numerics.method, "the frozen "
                                    "history is a closed form, neither stepped nor integrated; "
                                    "remove it"))
        if scene.output.every is not None:
            out.append(problem_line("output.every", scene.output.every, "nothing is stepped "
                                    "with model.history = frozen; its history has "
                                    "output.history_rows rows"))
        return out

    def solve(self, scene, observers) -> Result:
        wall_start = time.perf_counter()
        problem = Problem.from_scene(scene)
        T = problem.time_scale
        t_limit = math.inf if scene.numerics.t_max is None else scene.numerics.t_max / T
        t_frozen = frozen_detach_time(problem, t_limit)
        t_end = min(t_frozen, t_limit)
        detached = t_frozen <= t_limit
        t = np.linspace(0.0, t_end, max(2, observers.history_rows)) if t_end > 0 else np.zeros(1)
        snapshots = []
        for ts in observers.snapshot_times:
            if ts / T <= t_end:
                s = problem.s_of(ts / T)
                sig = s * np.cos(np.linspace(0.5 * np.pi, 0.0, 65))
                q = np.sqrt(np.maximum((s - sig) * (s + sig), 0.0))
                snapshots.append((ts, problem.a * np.sqrt(1.0 + sig * sig),
                                  problem.delta * q * frozen_memory(problem, ts / T)))
        summary = {"detached": detached, "solver": self.name, "history": "frozen",
                   "until": scene.model.until, "cohesive_zone": scene.geometry.cohesive_zone,
                   # The root is found to rounding (Newton stops at a step below 4 ulp).
                   "error_estimate": 4e-16 * 8, "n_elements": 0, "n_steps": 0,
                   "t_end": float(t[-1] * T), **problem.groups}
        if detached:
            td = t_frozen
            summary.update(t_detach=td * T, h_detach=float(problem.lift(td)),
                           b_detach=float(problem.zone_end(td)),
                           zone_ratio_detach=float(zone_ratio(problem.s_of(td))),
                           F_contact_detach=float(problem.contact_force(td)),
                           F_total_detach=float(problem.total_force(td)))
        summary["wall_time"] = time.perf_counter() - wall_start
        return Result.build(summary, predictions(scene),
                            si_history(problem, t, frozen_gap(problem, t)), snapshots=snapshots,
                            notes=observers.skipped_snapshots(t[-1] * T), problem=problem)
