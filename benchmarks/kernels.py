"""Cost of the numba kernels per element, and how whole runs grow with accuracy and steps.

    python benchmarks/kernels.py

For each kernel of :mod:`pulloff.kernels` that does per-step or per-run work it reports the
warm time per element (ns per element-step, or per table entry for the weight tables) at
1e2 .. 1e5 elements, as the median and interquartile range over repeated samples, and the
fitted exponent of time against size (1 means linear). Then it measures how a whole
``simulate`` run grows with the requested rtol and how ``run_foundation`` grows with the
number of steps, and how a level of the moving-edge (contact) stepper grows with its steps
and elements (``--contact-only``: that section alone, to results/kernels_contact.txt).
Single thread; writes results/kernels.txt with the same text.

The arguments are those of a real run: the scene alpha = 1, chi = 1e-4 (thin zone, the
seed's regime) with the step of a run of N steps per frozen detachment time, N = size.
"""

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import math  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from common import loglog_slope, machine_summary, scene_for_groups, time_call  # noqa: E402
from pulloff.kernels import onset as kernels  # noqa: E402
from pulloff.model.analytic import predictions  # noqa: E402
from pulloff.solvers import simulate  # noqa: E402
from pulloff.solvers.onset import (Problem, frozen_detach_time, preloaded_mesh,  # noqa: E402
                                   run_foundation, step_weights)

RESULTS = Path(__file__).resolve().parent / "results"
SIZES = [100, 1_000, 10_000, 100_000]
# march's work grows like steps^2: 1e4 steps (~1.5e4 elements at the end) is ~1 s per sample.
MARCH_STEPS = [100, 300, 1_000, 3_000, 10_000]
RTOLS = [10.0**-e for e in np.arange(3.0, 9.01, 0.5)]
STEPS = [100 * 2**j for j in range(8)]  # 100 .. 12800
SCENE = (1.0, 1e-4)  # alpha, chi
CONTACT_CONFIGS = ("separation_kv", "sls_finite_punch", "seed_flat_punch")
CONTACT_LEVELS = [16, 32, 64, 128, 256]
MIN_REPEATS = 15  # samples per point, enough for a meaningful interquartile range
MIN_TOTAL = 0.3  # s per point

_lines = []


def out(text=""):
    """Print and keep the line for results/kernels.txt."""
    print(text, flush=True)
    _lines.append(text)


def setup(problem: Problem, n: int):
    """Arrays of a run with ``n`` steps per frozen detachment time, mid-way through the pull:
    ``n`` elements loaded since t = 0 and ``n`` entered ones, with displacements of the right
    size (half the quasi-static ``q / k``; the kernels' cost does not depend on the values)."""
    k, c = problem.k, problem.c
    t_ref = frozen_detach_time(problem)
    dt = t_ref / n
    s0 = problem.s_of(0.0)
    sig_pre, offset_pre = preloaded_mesh(s0, n)
    steps = np.arange(n + 1)
    sig_born = k * (problem.h0_scaled + steps * dt) + c
    S = sig_born[-1] + k * dt
    U_pre = 0.5 * np.sqrt((S - sig_pre) * (S + sig_pre)) / k
    U_born = 0.5 * np.sqrt((S - sig_born) * (S + sig_born)) / k
    return dict(k=k, c=c, dt=dt, S=S, sig_pre=sig_pre, offset_pre=offset_pre, U_pre=U_pre,
                sig_born=sig_born, U_born=U_born)


def kernel_calls(problem: Problem, n: int):
    """``{kernel: (call, elements or table entries per call)}`` at size ``n``."""
    a = setup(problem, n)
    k, c, dt, S = a["k"], a["c"], a["dt"], a["S"]
    decay, w_old, w_new = kernels.linear_load_weights(k, c, dt)
    tables = (kernels.TS_NODES, kernels.TS_COMPLEMENTS, kernels.TS_WEIGHTS)
    w_on_old, w_on_new = kernels.onset_weights(k, c, dt, n + 2, *tables)
    ratio, w_young, w_aged = kernels.age_interval_weights(k, c, dt, n + 2)
    moments = kernels.onset_moments(k, c, dt, *tables)
    born = np.arange(n + 1, dtype=np.int64)  # element j entered at step j
    no_cubic = np.zeros((1, 4))  # trapezoid/product weights, as in a run without a budget
    scratch = np.empty(2 * n + 2)
    sig_pre, U_pre = a["sig_pre"], a["U_pre"]
    sig_born, U_born = a["sig_born"][:n], a["U_born"][:n]
    # For the gap integral: half the elements preloaded, half entered (n in total).
    half = n // 2
    sig_p, U_p = a["sig_pre"][::2][:half], a["U_pre"][::2][:half]
    off_p = a["offset_pre"][::2][:half]
    t_now = (S - c) / k - problem.h0_scaled  # the time at which s = S
    # The loads carried from step to step (kernels.onset.cache_loads), at the step's start.
    q_pre = np.sqrt((a["offset_pre"] + k * (t_now - dt)) * (S - k * dt + sig_pre))
    r_born = np.sqrt(k * (a["sig_born"][:n] + S - k * dt))
    q_p = np.sqrt((off_p + k * t_now) * (S + sig_p))  # the carried loads at S
    nodes_p = np.append(sig_p, a["sig_born"][0])
    dx_p = np.append(0.0, [kernels.interval_width(x, y) for x, y in zip(nodes_p[:-1],
                                                                        nodes_p[1:])])
    dx_b = np.append(0.0, [kernels.interval_width(x, y) for x, y in zip(a["sig_born"][:-1],
                                                                        a["sig_born"][1:])])
    return {
        "step_preloaded": (lambda: kernels.step_preloaded(
            sig_pre, a["offset_pre"], U_pre, q_pre, k * t_now, S, decay, w_old, w_new), n),
        "step_entered": (lambda: kernels.step_entered(
            sig_born, U_born, r_born, 0, n, n - 1, S, k, decay, w_on_old, w_on_new), n),
        "step_entered_aged": (lambda: kernels.step_entered_aged(
            born[:n], sig_born, U_born, r_born, n, n - 1, S, k, decay, w_on_old[:64],
            w_on_new[:64], *moments), n),
        "displacement_integral": (lambda: kernels.displacement_integral(
            sig_p, off_p, U_p, dx_p, no_cubic, born, a["sig_born"], a["U_born"], dx_b,
            no_cubic, n - half, n - half - 1, S, k * t_now, k * dt, ratio, w_young, w_aged,
            scratch, q_p),
            n),
        "onset_weights": (lambda: kernels.onset_weights(k, c, dt, n, *tables), n),
        "age_interval_weights": (lambda: kernels.age_interval_weights(k, c, dt, n), n),
    }


def march_call(problem: Problem, n_steps: int):
    """A call of ``kernels.march`` over ``n_steps`` steps from t = 0, set up as run_foundation
    does, with the step chosen so that the gap stays below 1 (no early stop). Returns the call,
    its number of element-steps and the number of elements at the end."""
    k, c, h0 = problem.k, problem.c, problem.h0_scaled
    t_ref = frozen_detach_time(problem)
    # Half the frozen detachment time: the exact gap is still well below delta there.
    dt = 0.5 * t_ref / n_steps
    s0 = problem.s_of(0.0)
    n_pre = max(8, int(math.ceil(n_steps * s0 / problem.s_of(n_steps * dt))))
    sig_pre0, offset_pre0 = preloaded_mesh(s0, n_pre)
    nodes = np.append(sig_pre0, s0)
    dx_pre = np.append(0.0, [kernels.interval_width(x, y) for x, y in zip(nodes[:-1],
                                                                          nodes[1:])])
    capacity = n_steps + 2
    weights = step_weights(k, c, dt, capacity)
    no_cubic = np.zeros((1, 4))

    def call():
        # Fresh state per call: march advances U and places elements in place.
        U_pre = np.zeros(n_pre)
        sig_born = np.zeros(capacity)
        sig_born[0] = s0
        U_born = np.zeros(capacity)
        dx_born = np.zeros(capacity)
        born = np.zeros(capacity, dtype=np.int64)
        t_out = np.zeros(capacity)
        gap_out = np.zeros(capacity)
        step, n_born, code = kernels.march(
            sig_pre0, offset_pre0, U_pre, dx_pre, no_cubic, born, sig_born, U_born, dx_born,
            no_cubic, 1, 0, 0, n_steps, k, c, h0, dt, *weights, t_out, gap_out, 0)
        assert step == n_steps and code == kernels.MARCH_STOPPED
        return n_born

    # Step m (from 0) advances n_pre + m + 1 elements (and integrates over them and the new
    # one at b): the same count as in report_run_foundation.
    element_steps = n_steps * n_pre + n_steps * (n_steps + 1) / 2
    return call, element_steps, n_pre + n_steps + 1


def fmt_spread(timing, units):
    """'median (IQR q1-q3)' in ns per unit."""
    scale = 1e9 / units
    return f"{timing.median * scale:9.2f} ({timing.q1 * scale:7.2f}-{timing.q3 * scale:7.2f})"


def report_kernels(problem: Problem):
    out("== Per-element cost of the kernels: ns per element-step (per table entry for the "
        "weight tables),\n   median (interquartile range) over >= 15 samples; exponent of "
        "time vs size over all sizes and\n   over the top two; fixed cost per call")
    names = list(kernel_calls(problem, SIZES[0]))
    per_size = {}
    for n in SIZES:
        per_size[n] = {}
        for name, (call, units) in kernel_calls(problem, n).items():
            call()  # compile or load from the cache
            timing, _ = time_call(call, min_repeats=MIN_REPEATS, min_total=MIN_TOTAL)
            per_size[n][name] = (timing, units)
    out(f"  {'kernel':<22}" + "".join(f"{'n = ' + format(n, ','):>22}" for n in SIZES)
        + f"{'exponent':>9}{'top two':>8}{'fixed':>9}")
    comments = []
    for name in names:
        cells, times = [], []
        for n in SIZES:
            timing, units = per_size[n][name]
            scale = 1e9 / units
            cells.append(f"{timing.median * scale:8.2f} ({timing.q1 * scale:.2f}-"
                         f"{timing.q3 * scale:.2f})")
            times.append(timing.median)
        p_all = loglog_slope(SIZES, times)
        p_big = loglog_slope(SIZES[-2:], times[-2:])
        # Time = fixed + per_element n: the fixed part (numba dispatch, loop set-up, the
        # allocation of the returned tables) is what is left at the smallest size once the
        # per-element cost of the largest size is taken off.
        fixed = times[0] - SIZES[0] * times[-1] / SIZES[-1]
        out(f"  {name:<22}" + "".join(f"{c:>22}" for c in cells)
            + f"{p_all:9.3f}{p_big:8.3f}{1e6 * fixed:6.2f} us")
        top = f"{SIZES[-2]:.0e}..{SIZES[-1]:.0e}"
        if abs(p_big - 1.0) > 0.1:
            comments.append(f"{name}: exponent {p_big:.2f} over {top}, NOT ~1")
        elif abs(p_all - 1.0) > 0.1:
            comments.append(f"{name}: ~1 (linear) over {top}; {p_all:.2f} over all sizes "
                            f"because a fixed {1e6 * fixed:.2f} us per call weighs on the "
                            f"small sizes")
        else:
            comments.append(f"{name}: ~1 (linear) at every size")
    for line in comments:
        out(f"  - {line}")
    return per_size


def exponent_comment(p: float, expected: float) -> str:
    if abs(p - expected) <= 0.1:
        return f"~{expected:g} as expected"
    return f"NOT ~{expected:g}"


def report_march(problem: Problem):
    out("\n== march (the whole step loop in one call): ns per element-step")
    out(f"  {'steps':>7} {'elements':>9} {'element-steps':>14} {'median ms':>10} "
        f"{'ns/elem-step (IQR)':>30}")
    rows = []
    for n_steps in MARCH_STEPS:
        call, element_steps, elements = march_call(problem, n_steps)
        call()
        timing, _ = time_call(call, min_repeats=5 if n_steps >= 3000 else MIN_REPEATS,
                              min_total=MIN_TOTAL)
        rows.append((n_steps, element_steps, timing))
        out(f"  {n_steps:7d} {elements:9d} {element_steps:14.3g} {1e3 * timing.median:10.3f} "
            f"{fmt_spread(timing, element_steps):>30}")
    steps = [r[0] for r in rows]
    work = [r[1] for r in rows]
    times = [r[2].median for r in rows]
    p_work = loglog_slope(work, times)
    p_steps = loglog_slope(steps, times)
    p_top = loglog_slope(steps[-3:], times[-3:])
    out(f"  exponent of time vs element-steps: {p_work:.3f} ({exponent_comment(p_work, 1.0)});"
        f" vs steps: {p_steps:.3f} over all, {p_top:.3f} over the last three")
    # Cost of one numba dispatch of march with its 24 arguments (a call that does no step).
    k, c, h0 = problem.k, problem.c, problem.h0_scaled
    z = np.zeros(4)
    z2 = np.zeros((1, 4))
    zi = np.zeros(4, dtype=np.int64)
    weights = step_weights(k, c, 1.0, 4)

    def no_step():
        return kernels.march(z, z, z, z, z2, zi, z, z, z, z2, 1, 0, 0, 0, k, c, h0, 1.0, *weights,
                             z, z, 0)

    no_step()
    timing, _ = time_call(no_step, min_repeats=MIN_REPEATS, min_total=MIN_TOTAL)
    out(f"  dispatch of one march call that does no step: {1e6 * timing.median:.2f} us "
        f"(run_foundation calls march once per 2048 steps or 1/50 of the run, whichever is "
        f"longer, for its progress bar and Ctrl-C)")
    return rows


def report_simulate(alpha, chi):
    out(f"\n== simulate: warm time against the requested rtol (scene alpha = {alpha:g}, "
        f"chi = {chi:g})")
    out(f"  {'rtol':>8} {'steps':>7} {'elements':>9} {'estimate':>9} {'median ms':>10} "
        f"{'IQR ms':>16}")
    simulate(scene_for_groups(alpha, chi, rtol=1e-3))
    rows = []
    for rtol in RTOLS:
        scene = scene_for_groups(alpha, chi, rtol=rtol)
        timing, res = time_call(lambda: simulate(scene))
        rows.append((rtol, res, timing))
        out(f"  {rtol:8.1e} {res.n_steps:7d} {res.n_elements:9d} {res.error_estimate:9.2e} "
            f"{1e3 * timing.median:10.3f} {1e3 * timing.q1:7.3f}-{1e3 * timing.q3:<8.3f}")
    inv = [1.0 / r[0] for r in rows]
    times = [r[2].median for r in rows]
    p_all = loglog_slope(inv, times)
    tight = [i for i, r in enumerate(rows) if r[0] <= 1e-6]
    p_tight = loglog_slope([inv[i] for i in tight], [times[i] for i in tight])
    steps = [r[1].n_steps for r in rows]
    p_steps = loglog_slope(inv, steps)
    out(f"  exponent of time vs 1/rtol: {p_all:.3f} over rtol 1e-3..1e-9, {p_tight:.3f} over "
        f"rtol <= 1e-6 (design: 1, since time ~ N^2 and N ~ rtol^-1/2); steps ~ "
        f"(1/rtol)^{p_steps:.3f} (design 0.5)")
    out("  Time is a staircase in rtol: N doubles until the Richardson estimate is below "
        "rtol/2, so each\n  doubling of N (4x in time) covers a factor ~4 in rtol; at loose "
        "rtol the fixed costs of a run\n  flatten the curve. Fixed costs inside every "
        "simulate call:")
    scene = scene_for_groups(alpha, chi)
    problem = Problem.from_scene(scene)
    t_ref = frozen_detach_time(problem)
    for label, call in (
            ("closed forms beside the result (model.analytic.predictions)",
             lambda: predictions(scene)),
            ("frozen detachment time (solver.frozen_detach_time)",
             lambda: frozen_detach_time(problem)),
            ("weight tables of one 200-step level (onset + age-interval)",
             lambda: (kernels.onset_weights(problem.k, problem.c, t_ref / 200, 227,
                                            kernels.TS_NODES, kernels.TS_COMPLEMENTS,
                                            kernels.TS_WEIGHTS),
                      kernels.age_interval_weights(problem.k, problem.c, t_ref / 200,
                                                   227)))):
        call()
        timing, _ = time_call(call, min_repeats=MIN_REPEATS, min_total=MIN_TOTAL)
        out(f"    {label:<62} {1e3 * timing.median:7.3f} ms")
    return rows


def report_run_foundation(problem: Problem):
    out("\n== run_foundation: warm time against the number of steps (dt = t_frozen / N, "
        "N + N/8 steps allowed)")
    out(f"  {'N':>6} {'steps':>7} {'elements':>9} {'median ms':>10} {'IQR ms':>18} "
        f"{'ns per elem-step':>17}")
    t_ref = frozen_detach_time(problem)
    run_foundation(problem, t_ref / 100, 112)
    rows = []
    for N in STEPS:
        timing, run = time_call(lambda: run_foundation(problem, t_ref / N, N + N // 8))
        # Step m touches every element present: the preloaded ones plus the m entered so far.
        n_pre = run.n_elements - run.n_steps - 1
        element_steps = run.n_steps * n_pre + run.n_steps * (run.n_steps + 1) / 2
        rows.append((N, run, timing, element_steps))
        out(f"  {N:6d} {run.n_steps:7d} {run.n_elements:9d} {1e3 * timing.median:10.3f} "
            f"{1e3 * timing.q1:8.3f}-{1e3 * timing.q3:<9.3f} "
            f"{1e9 * timing.median / element_steps:17.2f}")
    steps = [r[1].n_steps for r in rows]
    times = [r[2].median for r in rows]
    p_all = loglog_slope(steps, times)
    p_top = loglog_slope(steps[-3:], times[-3:])
    # time = a N + b N^2: the linear part is per-step and per-table-entry work.
    A = np.column_stack([steps, np.square(steps)]).astype(float)
    (lin, quad), *_ = np.linalg.lstsq(A / np.array(times)[:, None],
                                      np.ones(len(times)), rcond=None)
    out(f"  exponent of time vs steps: {p_all:.3f} over all, {p_top:.3f} over the last three "
        f"({exponent_comment(p_top, 2.0)} at large N)")
    out(f"  fit time = a n + b n^2 (relative least squares): a = {1e6 * lin:.2f} us per step, "
        f"b = {1e9 * quad:.2f} ns per step^2; the two terms are equal at n = {lin / quad:.0f}")
    out("  Why ~2: every step places one new element at the zone end b, so step m advances and "
        "integrates\n  n_pre + m elements and a run of n steps costs n n_pre + n^2/2 "
        "element-steps (the preloaded\n  count n_pre also grows with n). Below a few hundred "
        "steps the per-step and per-table-entry\n  costs (numba dispatch, weight tables) "
        "dominate and the exponent is closer to 1.")
    return rows


def contact_level(scene, n):
    """``(seconds, steps, evaluations, element-evaluations, elements at the end, most live
    elements)`` of one warm level of the moving-edge stepper (live: not archived behind a
    receding zone); every trial evaluation is counted by wrapping
    :meth:`pulloff.solvers.contact_step.Step._evaluate` for the duration."""
    from pulloff.solvers import contact, contact_step

    counted, live = [], [0]
    original = contact_step.Step._evaluate

    def counting(self, alpha, beta, H_new):
        ev = original(self, alpha, beta, H_new)
        counted.append(len(ev.xi))
        live[0] = max(live[0], self.s.nodes.n)
        return ev

    contact_step.Step._evaluate = counting
    try:
        start = time.perf_counter()
        level = contact.run_level(scene, n)
        seconds = time.perf_counter() - start
    finally:
        contact_step.Step._evaluate = original
    return (seconds, len(level.rows) - 1, len(counted), sum(counted), level.nodes.total,
            live[0])


def report_contact():
    """Issue 10's linear-cost target for the moving-edge (contact) stepper: time against
    element-evaluations (the kernel's work) and against steps, per level ``n``."""
    from pulloff.io.scene_file import load_scene
    from pulloff.solvers import contact

    out("\n== moving-edge (contact) stepper: one warm level per n, to separation")
    out(f"  {'config':<18} {'n':>5} {'steps':>6} {'evals':>7} {'elem-evals':>11} "
        f"{'elements':>9} {'live':>6} {'s':>8} {'ns/elem-eval':>13}")
    for config in CONTACT_CONFIGS:
        scene = load_scene(Path(__file__).resolve().parents[1] / "configs" / f"{config}.yaml",
                           overrides=["model.until=separation"])
        contact.run_level(scene, CONTACT_LEVELS[0])  # compile / warm
        rows = [contact_level(scene, n) for n in CONTACT_LEVELS]
        for n, (sec, steps, evals, work, elements, live) in zip(CONTACT_LEVELS, rows):
            out(f"  {config:<18} {n:5d} {steps:6d} {evals:7d} {work:11.3g} {elements:9d} "
                f"{live:6d} {sec:8.3f} {1e9 * sec / work:13.0f}")
        secs = [r[0] for r in rows]
        steps = [r[1] for r in rows]
        p_work = loglog_slope([r[3] for r in rows], secs)
        p_steps = loglog_slope(steps, secs)
        p_top = loglog_slope(steps[-2:], secs[-2:])
        p_elements = loglog_slope(steps, [r[4] for r in rows])
        p_live = loglog_slope(steps, [r[5] for r in rows])
        out(f"  {config}: time ~ element-evaluations^{p_work:.2f}; ~ steps^{p_steps:.2f} over "
            f"all, ^{p_top:.2f} over the top two; elements ~ steps^{p_elements:.2f}, live "
            f"~ steps^{p_live:.2f} (the target: time ~ steps^1, elements bounded)")


def main() -> None:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--contact-only", action="store_true",
                        help="only the moving-edge stepper's section (results/kernels_contact.txt)")
    args = parser.parse_args()
    wall_start = time.perf_counter()
    RESULTS.mkdir(exist_ok=True)
    out(machine_summary())
    if args.contact_only:
        report_contact()
        out(f"\ntotal run time {time.perf_counter() - wall_start:.0f} s")
        (RESULTS / "kernels_contact.txt").write_text("\n".join(_lines) + "\n")
        return
    problem = Problem.from_scene(scene_for_groups(*SCENE))
    out(f"scene alpha = {SCENE[0]:g}, chi = {SCENE[1]:g}: k = {problem.k:.4g}, c = "
        f"{problem.c:.4g} (dimensionless, units of solvers/problem.py)\n")
    report_kernels(problem)
    report_march(problem)
    report_simulate(*SCENE)
    report_run_foundation(problem)
    report_contact()
    out(f"\ntotal run time {time.perf_counter() - wall_start:.0f} s")
    (RESULTS / "kernels.txt").write_text("\n".join(_lines) + "\n")


if __name__ == "__main__":
    main()
