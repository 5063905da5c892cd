"""The seed's onset by quadrature: the gap as one integral over the load history
(:mod:`pulloff.kernels.quadrature`), its root, and the history as an interpolant.

Each Gauss rule of :data:`_RULES` integrates the gap to a known accuracy (measured on the
work-precision scenes and the hard cases against the reference: the errors of
:data:`_RULE_ERRORS`). A run takes the cheapest rule expected to be well within ``rtol``,
solves ``gap = 1`` with it and with the next rule, and reports the finer root; the estimate is
the two roots' difference (that of the coarser rule, so a cautious one). The history is the
polynomial interpolant of the gap in ``u = sqrt(t / t_end)`` (the gap has a ``t^2 log t`` term
at ``t = 0``, smooth in ``u``) on Chebyshev-Lobatto nodes, doubled until the interpolant of
half the nodes is within ``rtol`` of the other half: its nodes bracket the first crossing.
Behind a machine spring the lift and the zone come from :mod:`.machine_lift` instead of the
rigid pull's ``H0 + T``.
"""

from __future__ import annotations

import functools
import math
import sys
import time
from dataclasses import dataclass

import numpy as np

from ..kernels import quadrature as kernels
from .base import Solver, problem as problem_line
from .frozen import frozen_detach_time
from .machine_lift import kappa_of, machine_pull, spring_to_solid
from .onset import FoundationRun, assemble, seed_onset_problems
from .problem import Problem

#: Gauss-Legendre points per panel and panels graded toward the newest load, coarsest first.
_RULES = ((4, 3), (6, 4), (8, 6), (10, 8), (12, 10), (16, 14))
#: The largest relative error of each rule's detachment time over the four work-precision
#: scenes and the hard cases (against the reference at rtol 1e-12, whose own floor is ~1e-12;
#: ``/tmp`` study, the table in the README).
_RULE_ERRORS = (2e-6, 2e-8, 5e-11, 2e-13, 2e-15, 1e-16)
#: The first rule is expected this far within rtol: the next one then checks it cheaply.
_RULE_MARGIN = 10.0
#: Chebyshev-Lobatto intervals of the history's first and largest interpolant.
_FIRST_NODES = 16
_MAX_NODES = 1024
#: A nearly elastic solid's relaxation layer at ``t = 0`` thinner than this fraction of the
#: pull is left out of the interpolant (:class:`Span`).
_LAYER_FRACTION = 1e-3
#: Behind a spring, the largest ratio of the spring's to the solid's stiffness at the start
#: (:func:`.machine_lift.spring_to_solid`) the quadrature takes.
_MAX_SPRING_TO_SOLID = 10.0
#: The lift path of a rigid pull: none (the kernels' linear ``H0 + T``).
RIGID = np.zeros((3, 0))
#: Rows of the history at most (``output.history_rows`` may ask for fewer): uniform in time, of
#: an interpolant of 17-65 nodes (up to 1025 where a note says it missed rtol), so more rows
#: draw the same curve and cost ~0.1 ms per 1000 (the SI columns and the closed forms of each
#: row); a run at rtol 1e-6 costs ~0.3 ms.
HISTORY_ROWS = 257


@functools.lru_cache(maxsize=None)
def _rule(m: int):
    """``(graded panels, nodes, weights)`` of rule ``m`` on [0, 1]."""
    n, graded = _RULES[m]
    x, w = np.polynomial.legendre.leggauss(n)
    return graded, 0.5 * (x + 1.0), 0.5 * w


@functools.lru_cache(maxsize=64)
def first_rule(rtol: float) -> int:
    """The cheapest rule expected to be :data:`_RULE_MARGIN` within ``rtol`` (the last but
    one at most: the last checks it)."""
    for m, error in enumerate(_RULE_ERRORS[:-1]):
        if error * _RULE_MARGIN <= rtol:
            return m
    return len(_RULES) - 2


class QuadratureRun:
    """The gap of one problem under one rule: evaluations counted."""

    def __init__(self, problem: Problem, m: int):
        self.k, self.c, self.H0 = problem.k, problem.c, problem.h0_scaled
        # The lift: a rigid pull's is linear; behind a spring, a path (machine_lift).
        path = getattr(problem, "path", None)
        self.lift = (RIGID, 1.0) if path is None else (path, problem.span)
        self.m = m
        self.rule = _rule(m)
        self.evaluations = 0

    def nodes_per_gap(self, t: float) -> int:
        return kernels.nodes_per_gap(self.k, self.c, self.H0, *self.lift, t, *self.rule)

    def gaps(self, t: np.ndarray) -> np.ndarray:
        self.evaluations += t.size
        return kernels.gaps(self.k, self.c, self.H0, *self.lift,
                            np.ascontiguousarray(t, dtype=float), *self.rule)

    def root_in(self, lo, hi, g_lo, g_hi):
        """``(root, slope)`` in a bracket whose gaps minus 1 are ``g_lo < 0 <= g_hi``."""
        root, slope, n = kernels.detach_time(self.k, self.c, self.H0, *self.lift, lo, hi,
                                             g_lo, g_hi, *self.rule)
        self.evaluations += n
        return root, slope

    def root_near(self, t0, slope, lo, hi, bounded=False):
        """The root near ``t0`` (secants), or in ``[lo, hi]`` if they do not settle there;
        nan if ``[lo, hi]`` brackets none. ``bounded``: the gap is at least 1 at ``hi``
        (whatever its rounding says, see :func:`_crossing`)."""
        root, n = kernels.secant_root(self.k, self.c, self.H0, *self.lift, t0, slope,
                                      *self.rule)
        self.evaluations += n
        if bounded and root > hi:
            return hi
        if not lo <= root <= hi:
            g = self.gaps(np.array([lo, hi])) - 1.0
            if bounded:
                g[1] = max(g[1], 0.0)
            if not (g[0] < 0.0 <= g[1]):
                return math.nan
            root, _ = self.root_in(lo, hi, g[0], g[1])
        return root


@dataclass(frozen=True)
class Span:
    """The interpolant's interval ``[start, end]`` (dimensionless), with ``t = start + (end -
    start) u^2``. ``start`` is 0, or past the relaxation layer of a nearly elastic solid lifted
    at ``t = 0`` (its dampers let the preloaded elements catch up in ~``c / k``: a layer far
    thinner than a row of the history, which no polynomial resolves; the rows before it are
    evaluated one by one)."""

    start: float
    end: float

    @classmethod
    def for_problem(cls, problem: Problem, t_end: float) -> "Span":
        k, c = problem.k, problem.c
        layer = 0.0
        if k > 0.0 and c > 0.0 and problem.h0_scaled > 0.0:
            layer = kernels.DECAYS * c / k
        elif c > 0.0 and getattr(problem, "path", None) is not None:
            # behind a spring: the punch catching up with the driver (machine_lift)
            layer = kernels.DECAYS * c / (k + 0.5 * kappa_of(problem, problem.machine_stiffness))
        if 0.0 < layer < _LAYER_FRACTION * t_end:
            return cls(layer, t_end)
        return cls(0.0, t_end)

    def times(self, u: np.ndarray) -> np.ndarray:
        return self.start + (self.end - self.start) * u * u

    def time(self, u: float) -> float:
        """:meth:`times` of one node, in floats (the same bits)."""
        return self.start + (self.end - self.start) * u * u

    def nodes(self, t: np.ndarray) -> np.ndarray:
        """The nodes ``u`` of ascending times ``t`` (0 before ``start``)."""
        if self.start == 0.0 and t[0] >= 0.0:
            # (ascending times from 0: no shift, nothing to clip; the same bits in two
            # numpy passes of the four)
            u = t / self.end
            return np.sqrt(u, out=u)
        return np.sqrt(np.maximum(t - self.start, 0.0) / (self.end - self.start))


def history_interpolant(run: QuadratureRun, span: Span, rtol: float):
    """``(u nodes, gaps, estimate)``: the gap at Chebyshev-Lobatto nodes in ``u`` (see
    :class:`Span`), doubled until the interpolant through every other node is within ``rtol``
    (in ``delta``) at the rest, or :data:`_MAX_NODES`; ``estimate`` is that largest
    difference."""
    n = _FIRST_NODES
    u = kernels.lobatto_nodes(n)
    values = run.gaps(span.times(u))
    while True:
        estimate = kernels.lobatto_spread(u, values)
        if estimate <= rtol or n >= _MAX_NODES:
            return u, values, estimate
        n *= 2
        u_new = kernels.lobatto_nodes(n)
        merged = np.empty(n + 1)
        merged[::2] = values
        merged[1::2] = run.gaps(span.times(u_new[1::2]))
        u, values = u_new, merged


def _relative_change(a, b) -> float:
    """Largest ``|a - b| / |b|`` over the outputs (``|b| = 0`` judged absolutely; nan if any
    is). In floats, one by one: numpy's five passes over three values cost ~10 us a run."""
    changes = [abs(x - y) / (abs(y) if y != 0.0 else 1.0) for x, y in zip(a, b)]
    return math.nan if any(math.isnan(c) for c in changes) else float(max(changes))


def _detach_values(problem: Problem, t: float) -> tuple:
    """:func:`.onset.detach_outputs` as a tuple of floats: ``(t, F_contact, F_total)``."""
    return (t, *problem.forces(t))


def _rounding(problem: Problem, t: float, slope: float) -> float:
    """The relative error of an onset time ``t`` that the gap's rounding alone leaves: the
    gap is a difference of terms of size ``(2/pi) h atan(s)``, whose last bits move the root
    by their size over the slope. Large only where the onset comes right after ``t = 0`` (a
    lift just short of the one that detaches at once): there no rule refines it."""
    size = (2.0 / math.pi) * problem.lift(t) / problem.delta * math.atan(problem.s_of(t))
    return 4.0 * sys.float_info.epsilon * size / (abs(slope) * t) if slope and t > 0 else 0.0


def _crossing(problem: Problem, m: int, span: Span, bounded: bool, rtol: float):
    """One try at rule ``m``: ``(t_detach or nan, estimate, history, runs)`` where
    ``history = (u nodes, gaps, interpolation estimate)`` and ``runs`` the two rules'
    :class:`QuadratureRun` (for their counts). ``bounded``: ``span.end`` is the frozen onset,
    where the exact gap is at least 1."""
    coarse, fine = QuadratureRun(problem, m), QuadratureRun(problem, m + 1)
    u, values, spread = history_interpolant(coarse, span, rtol)
    history, runs = (u, values, spread), (coarse, fine)
    if bounded and values[-1] < 1.0:
        # The bound holds exactly, its rounding does not: an elastic solid (whose gap is the
        # frozen one) reaches 1 within an ulp of the end, on either side.
        values[-1] = 1.0
    above = np.nonzero(values >= 1.0)[0]
    if above.size == 0:
        # No crossing before the end: what is controlled is the gap there.
        end = fine.gaps(np.array([span.end]))
        return math.nan, _relative_change(values[-1:], end), history, runs
    j = int(above[0])
    if j == 0:
        # The gap at the start within rounding of 1 where the frozen bound put it below: the
        # onset is there. (A relaxation layer before a later start only lowers the gap.)
        return span.start, 0.0, history, runs
    lo, hi = span.time(float(u[j - 1])), span.time(float(u[j]))
    t_coarse, slope = coarse.root_in(lo, hi, values[j - 1] - 1.0, values[j] - 1.0)
    last = j == u.size - 1
    t_fine = fine.root_near(t_coarse, slope, lo, hi, bounded and last)
    if math.isnan(t_fine):
        # The finer rule's root left the bracket (a root on a node): the widest bracket the
        # history allows.
        wide = span.times(u[[max(j - 2, 0), min(j + 1, u.size - 1)]])
        t_fine = fine.root_near(t_coarse, slope, wide[0], wide[1],
                                bounded and j + 1 >= u.size - 1)
    if math.isnan(t_fine):
        return t_coarse, math.inf, history, runs
    estimate = _relative_change(_detach_values(problem, t_coarse),
                                _detach_values(problem, t_fine))
    return t_fine, max(estimate, _rounding(problem, t_fine, slope)), history, runs


def _rows(problem: Problem, run: QuadratureRun, span: Span, history, t_last: float, rows: int):
    """``(t, gap)`` of the history: ``rows`` times uniform on ``[0, t_last]``, the gap from
    the interpolant, or evaluated where a row lies before the interpolant's start."""
    u, values, _ = history
    t = _uniform(t_last, max(2, rows))
    gap = np.empty(t.size)
    kernels.lobatto_interpolate(u, values, span.nodes(t), gap)
    if span.start > 0.0:  # (rows start at t = 0: none lies before a span from 0)
        early = t < span.start
        if np.any(early):
            gap[early] = run.gaps(t[early])
    return t, gap


def _uniform(end: float, n: int) -> np.ndarray:
    """``np.linspace(0.0, end, n)`` bit for bit (``n >= 2``): its ``arange * step`` with the
    end exact, without its ~5 us of Python (its own path where the step underflows)."""
    step = end / (n - 1)
    if step == 0.0:
        return np.linspace(0.0, end, n)
    t = np.arange(n, dtype=float)
    t *= step
    t[-1] = end
    return t


def quadrature_onset(problem: Problem, t_end: float, bounded: bool, rtol: float, rows: int):
    """The onset before ``t_end`` (dimensionless; ``bounded``: the frozen onset, see
    :func:`_crossing`): ``(FoundationRun, estimate, notes)``.

    Rules from :func:`first_rule` up, until two consecutive ones agree within ``rtol / 2``;
    the finer one's root is reported, the history (``rows`` rows, uniform in time, to the
    onset or ``t_end``) is the coarser one's interpolant."""
    if t_end == 0.0:
        gap0 = float(kernels.gap(problem.k, problem.c, problem.h0_scaled, RIGID, 1.0, 0.0,
                                 *_rule(0)))
        return (FoundationRun(math.nan, np.zeros(1), np.array([gap0]), 0.0, 0, 0), 0.0, [])
    span = Span.for_problem(problem, t_end)
    m = first_rule(rtol)
    while True:
        t_detach, estimate, history, runs = _crossing(problem, m, span, bounded, rtol)
        if estimate <= 0.5 * rtol or m + 2 >= len(_RULES):
            break
        m += 1
    notes = []
    if history[2] > rtol:
        notes.append(f"history: the gap's interpolant is within {history[2]:.2g} of delta "
                     f"(not {rtol:g}) at {history[0].size} nodes")
    t_last = t_end if math.isnan(t_detach) else t_detach
    t, gap = _rows(problem, runs[0], span, history, t_last, rows)
    run = FoundationRun(math.nan, t, gap, t_detach, runs[1].nodes_per_gap(t_last),
                        sum(r.evaluations for r in runs))
    return run, estimate, notes


class OnsetQuadratureSolver(Solver):
    """The seed scene to its onset by quadrature over the load history (Kelvin-Voigt or
    elastic, flat punch, zone outside, a rigid pull or one through a machine spring), without
    steps: the default where a scene asks for no fixed steps, snapshots or ``output.every``."""

    name = "onset_quadrature"
    method = "quadrature"
    kernel = "quadrature.secant_root"  # compiled last
    summary = ("seed onset by quadrature over the load history (flat punch, external zone, "
               "Kelvin-Voigt, rigid or through a machine spring; no steps)")

    def unsupported(self, scene) -> list[str]:
        out = seed_onset_problems(scene, "quadrature onset", machine=True)
        why = "the quadrature onset has no steps or element fields; the stepper has" + (
            ": remove it, or numerics.method = quadrature"
            if scene.numerics.method == "quadrature" else "")
        if scene.numerics.method == "stepper":
            out.append(problem_line("numerics.method", "stepper", "asks for the stepper"))
        if scene.numerics.steps is not None:  # (max_elements comes only with steps)
            out.append(problem_line("numerics.steps", scene.numerics.steps, why))
        if scene.output.every is not None:
            out.append(problem_line("output.every", scene.output.every, why))
        if scene.output.snapshots:
            out.append(problem_line("output.snapshots", scene.output.snapshots, why))
        machine = getattr(scene.loading, "machine_stiffness", None)
        if machine is not None and not out:
            ratio = spring_to_solid(Problem.from_scene(scene), machine)
            if ratio > _MAX_SPRING_TO_SOLID:
                # A review's random scan (400 scenes, rtol 1e-8): where the spring's stiffness
                # dominates the solid's at the start (or the solid has none, G = 0) the lift's
                # collocation failed on 16 scenes; below this ratio none failed, 293 of 302
                # met rtol and the other 9 said they did not (notes).
                out.append(problem_line(
                    "loading.machine_stiffness", machine, f"the spring is {ratio:.2g} times "
                    f"the solid's stiffness at the start (the quadrature onset takes "
                    f"{_MAX_SPRING_TO_SOLID:g} at most: a start layer it does not resolve); "
                    "the contact solver steps it"))
        return out

    def solve(self, scene, observers):
        wall_start = time.perf_counter()
        problem = Problem.from_scene(scene)
        t_limit = (math.inf if scene.numerics.t_max is None
                   else scene.numerics.t_max / problem.time_scale)
        machine = scene.loading.machine_stiffness
        if machine is None:
            t_frozen = frozen_detach_time(problem, t_limit)
            t_end, bounded, path_error = min(t_frozen, t_limit), t_frozen <= t_limit, 0.0
        else:
            problem, t_end, bounded, path_error = machine_pull(problem, machine, t_limit,
                                                               scene.numerics.rtol)
        run, estimate, notes = quadrature_onset(problem, t_end, bounded, scene.numerics.rtol,
                                                min(observers.history_rows, HISTORY_ROWS))
        estimate = max(estimate, path_error)
        if not estimate <= scene.numerics.rtol:
            notes.append(f"not converged: error estimate {estimate:.2g} above rtol "
                         f"{scene.numerics.rtol:g} with the finest rule")
        peaks = {}
        if machine is not None and not math.isnan(run.t_detach):
            # The zone grows until the onset (machine_pull checks it), and every force with it.
            td = run.t_detach
            peaks = dict(t_peak_contact=td * problem.time_scale,
                         t_peak_total=td * problem.time_scale,
                         F_peak_contact=float(problem.contact_force(td)),
                         F_peak_total=float(problem.total_force(td)))
        return assemble(scene, problem, run, estimate, math.nan, observers,
                        time.perf_counter() - wall_start, notes, False, solver=self.name,
                        extra=peaks)
