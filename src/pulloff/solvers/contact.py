"""The contact solver: any indenter, rheology and loading the model knows, with the contact edge
and the zone end free to move (MODEL.md sections 3, 6 and 9).

The stepping is :class:`pulloff.solvers.contact_stepper.Stepper`; this module runs it on the
ladder of :mod:`.levels` (each level halves every step), reports the extrapolated summary
with its estimate, and converts to SI.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..model import analytic
from ..model.loading import ConstantVelocity
from . import levels as ladder
from .base import Solver, problem as problem_line, stepper_settings
from .contact_setup import FLAT_EXTERNAL, setup as make_setup
from .contact_stepper import MAX_STEPS, Stepper
from .frozen import frozen_detach_time
from .problem import Problem
from .result import Result

#: Second order in the step (the paths of the edges are quadratic over a step, every element's
#: load integral is exact for them); a higher measured order is not relied on.
ORDER = ladder.Order(1.0, 2.0)
#: A pull's end when the scene gives no t_max, in frozen onset times.
DEFAULT_SPAN = 100.0
#: The ladder's first level: a flat punch's pull and a smooth indenter's path. From 8 (not
#: 16) the first three levels are trusted only where the order they measure (of the levels
#: themselves, 2 once asymptotic) is at most 4: a higher one says the first level is too
#: coarse for the asymptotic range, and its extrapolation's estimate far too cautious (from
#: 8 without the check finite_punch_internal's estimate at rtol 1e-3 was 32x its error; its
#: levels at n = 8, 16, 32 measure order 4.4, at 16, 32, 64 1.9). The bound is empirical.
#: It was 3; measured on the 50 speeds of benchmarks/sls_rate_sweep.py at rtol 1e-4 against
#: runs at 1e-6, the 11 whose first three levels measure 3 to 4 had estimates 1.2-9.5x their
#: error (the extrapolation at order 2 of levels converging faster can be further off than
#: the finest level, up to 4x at order 4, but the estimate includes its correction), and
#: their fourth level cost as much as the first three. On the 14 scenes of
#: benchmarks/contact_estimate.py at rtol 1e-3 and 1e-4 every estimate stays 0.98-6.5x its
#: error with the bound at 4 (0.98: separation_kv at 1e-2 m/s and rtol 1e-4, the same with
#: the bound at 3). On the shipped smooth paths the levels from 8 never stopped before
#: n = 64, and the n = 8 level only added 8-20 % to their time.
_FIRST_N = {True: 8, False: 16}
_FIRST_ORDER_MAX = ORDER.high + 2.0

#: What a level is judged by (summary names; nan where a run has none). The times of the peak
#: forces are not among them: the time of a smooth maximum is ill-conditioned (an error
#: ``e`` in the force moves it by ``sqrt(e)``), so they are reported uncontrolled.
CONTROLLED = ("t_detach", "h_detach", "F_total_detach", "F_contact_detach", "t_separation",
              "F_peak_total", "F_peak_contact", "F_pulloff", "F_max_compressive", "F_jump_in",
              "h_jump_in", "F_jump_out", "h_jump_out", "energy_dissipated")


def _pull_problems(scene) -> list[str]:
    """The refusals of a flat punch's pull: lifted past its onset at ``t = 0``, a
    near-elastic Kelvin-Voigt face, bonded beyond the face's strength at ``t = 0``."""
    out = []
    lifted = _lifted_past_the_onset(scene)
    if lifted is not None:
        out.append(problem_line(
            "loading.h0", scene.loading.h0, f"lifted past the onset at t = 0 (the gap at "
            f"the zone end is {lifted:.6g} delta with the bond pinned): the contact "
            "stepper meets the onset as the gap reaching delta from below and would run "
            "on without it " + ("(the edge quadrature takes such pulls)"
                                if scene.loading.kind == "constant_velocity" else
                                "(start below the onset and lift with a speed segment)")))
    near = _near_elastic_face(scene)
    if near is not None:
        out.append(problem_line(
            "material.eta", scene.material.eta, f"a Kelvin-Voigt face whose creep time "
            f"eta / G is {near:.2g} of the pull's time unit delta / v (below "
            f"{NEAR_ELASTIC_FACE:g}): the contact stepper's zone alone, released from the "
            "face, jumps out within a few creep times instead of following its branch "
            "(the edge quadrature, the default, runs such faces pulled at constant speed)"))
    beyond = _bonded_beyond_strength(scene)
    if beyond is not None:
        out.append(problem_line(
            "loading.v", scene.loading.v, f"the bond needs {beyond:.6g} times the face's "
            "strength at t = 0: the contact stepper finds no onset there"))
    return out


#: A Kelvin-Voigt face's creep time ``eta / G`` over the pull's time unit ``delta / v`` below
#: which the contact stepper is refused: its zone alone, released from the face, jumps out
#: within a few creep times where the edge quadrature marches it to a collapse ~60 creep
#: times later, and its levels agree on that. Measured against the edge quadrature (rtol
#: 1e-7) on finite_punch_internal (two reviews; errors of t_separation):
#: - 2e-4 m/s, sigma_c 3.5e5 Pa, rtol 1e-6: 1.2e-4 and 2.8e-4 early at 6.7e-6 and 2e-5
#:   (estimates 3e-8, 1.3e-7); at rtol 1e-3 from n = 8: 1.5e-3 and 2.9e-3 at 2e-4 and 4e-4;
#: - 2e-5 m/s, 2e5 Pa, rtol 1e-6: 6.3e-4 early at 6e-5 (estimate 1.4e-7);
#: - 2e-3 m/s, 6e5 Pa, rtol 1e-3: 1.25e-3 at 2e-4, 4.2e-3 and 4.5e-3 at 1.01e-3 and 1.1e-3
#:   (estimates 2.7e-4 .. 3.9e-4);
#: - 2e-2 m/s, 1e6 Pa: 7e-4 at 1.2e-4 (rtol 1e-4, estimate 3.9e-5), 1.9e-3 at 3e-4 and
#:   5.4e-3 at 1.5e-3 (rtol 1e-3; estimates 2e-4, 6.4e-5), even with the ladder from n = 32.
#: At 3e-3 all four were within rtol 1e-3 and 1e-4 (2e-5 .. 3.1e-4 at rtol 1e-3).
NEAR_ELASTIC_FACE = 3e-3


def _near_elastic_face(scene) -> float | None:
    """``eta v / (G delta)`` of a rigid pull of a Kelvin-Voigt face (on a path, with its
    slowest pulling speed) where below :data:`NEAR_ELASTIC_FACE`, else None."""
    material, loading = scene.material, scene.loading
    if (scene.geometry.kind != "flat_punch" or scene.geometry.cohesive_zone != "internal"
            or material.kind != "kelvin_voigt" or material.G == 0.0
            or getattr(loading, "machine_stiffness", None) is not None):
        return None
    if loading.kind == "constant_velocity":
        speeds = [loading.v] if scene.model.until == "separation" else []
    else:
        speeds = [segment.speed for segment in loading.segments
                  if segment.speed is not None and segment.speed > 0.0]
    if not speeds:
        return None
    ratio = material.eta * min(speeds) / (material.G * scene.adhesion.delta)
    return ratio if 0.0 < ratio < NEAR_ELASTIC_FACE else None


def _lifted_past_the_onset(scene) -> float | None:
    """``gap(0) / delta`` with the bond pinned where a flat punch pulled to separation by a
    rigid machine at constant speed starts lifted past its onset (None otherwise). The
    stepper's pinned bond ran on at ``a = R`` with the gap above delta (``separation_kv``
    lifted by 2 delta: no separation in 0.3 s, 1.18 N; a review in the twentieth session)."""
    loading = scene.loading
    if (scene.geometry.kind != "flat_punch" or not loading.h0 > 0.0
            or loading.machine_stiffness is not None):
        return None
    if loading.kind == "path":
        # a rigid path that starts by lifting: the same pinned bond at t = 0 as a pull at
        # its first speed (the gap there is the lift's and the dampers' impulse's)
        first = loading.segments[0]
        if loading.control != "displacement" or not (first.speed or 0.0) > 0.0:
            return None
        scene = scene.model_copy(update={"loading": ConstantVelocity(
            kind="constant_velocity", v=first.speed, h0=loading.h0)})
    elif loading.kind != "constant_velocity" or scene.model.until != "separation":
        return None
    from .edge_quadrature import EdgeModel, March  # (the gap by quadrature; one call)
    gap = March(EdgeModel.from_scene(scene), 1e-6).onset_gap(0.0)
    return gap if gap > 1.0 + 1e-12 else None


def _bonded_beyond_strength(scene) -> float | None:
    """The bonded load over the face's strength ``2 sigma_c R`` at ``t = 0`` where a rigid
    constant-speed pull of a zone on the face needs more than that from the start (a
    Kelvin-Voigt solid's viscous force ``v eta`` of the start, or a lift ``h0``; None
    otherwise). The stepper found no onset there and ran to its span (``separation_kv`` on the
    face at 2e-2 m/s: "separation not reached", where the reference comes off at 0.193 ms)."""
    loading = scene.loading
    if (scene.geometry.kind != "flat_punch" or scene.geometry.cohesive_zone != "internal"
            or loading.kind != "constant_velocity" or loading.machine_stiffness is not None):
        return None
    from .edge_quadrature import EdgeModel
    model = EdgeModel.from_scene(scene)
    return model.ell(0.0) if model.t_strength == 0.0 else None


class ContactSolver(Solver):
    """Flat punches (the zone outside or on the face) pulled to separation, and any
    rheology, behind a rigid machine or a spring."""

    name = "contact"
    method = "stepper"
    kernel = "contact.evaluate_step"
    summary = "moving contact edge and zone end: separation, finite punch, any rheology, machine"

    def unsupported(self, scene) -> list[str]:
        out = []
        if scene.geometry.kind != "flat_punch" and scene.loading.kind == "constant_velocity":
            out.append(problem_line("loading.kind", scene.loading.kind, "a smooth indenter "
                                    "starts apart: give a loading path (kind: path)"))
        if scene.geometry.kind != "flat_punch" and scene.material.kind == "kelvin_voigt":
            # Measured: a Kelvin-Voigt sphere finds no contact state at touch-down (a solid
            # without an instantaneous modulus cannot take the jump into contact).
            out.append(problem_line(
                "material.kind", scene.material.kind, f"a {scene.geometry.kind} on a "
                "Kelvin-Voigt solid is not solved (its jump into contact has no instantaneous "
                "response); use a standard linear solid with a stiff, fast arm"))
        delta = scene.adhesion.delta
        smooth_path = scene.geometry.kind != "flat_punch" and scene.loading.kind == "path"
        if smooth_path and not scene.loading.h0 > delta:
            # The stepper starts a smooth indenter apart with no zone: from within the zone's
            # range (or pressed in) it ran without a zone or a contact, and reported a
            # pull-off of 0 (measured at h0 = 0.5 delta, 0 and -delta on sphere_elastic).
            out.append(problem_line(
                "loading.h0", scene.loading.h0, f"a smooth indenter starts apart, beyond the "
                f"adhesive range: h0 must exceed delta = {delta:.6g} m (press it in with a "
                "speed segment)"))
        if (smooth_path and scene.loading.control == "force"
                and scene.loading.segments[0].speed is None):
            # A smooth indenter starts free, and a free indenter carries no force (these ended
            # at t = 0 in a RuntimeError, then with a note).
            first = scene.loading.segments[0]
            out.append(problem_line(
                f"loading.segments[0].{first.drive}", getattr(first, first.drive), "under "
                "control: force a smooth indenter starts apart and carries no force: bring it "
                "into contact first with a speed segment (speed: m/s)"))
        machine = getattr(scene.loading, "machine_stiffness", None)
        if (machine is not None and scene.model.until == "separation"
                and scene.material.spectrum().arms
                and getattr(scene.geometry, "cohesive_zone", "") == "external"):
            # Measured (standard linear solid, tau 0.1 ms, behind 1e4 N/m): after the contact
            # is lost the zone alone ends at first order, t_separation 2.4 % and 1.1 % apart
            # at n = 16, 32, 64, and the moving-edge reference loses its force balance there.
            # On the face (internal zone) it ends at the reference's fold: behind 100 N/m to
            # 5e-6 at n = 32 and order 3; behind 1 kN/m at a low order (-4.4e-3, -2.5e-3,
            # -8.0e-4 at n = 16..64) but with an honest estimate (error 1.1e-4, estimate
            # 3.2e-4 at rtol 1e-3), so that one is solved, slowly.
            out.append(problem_line(
                "loading.machine_stiffness", machine, "past the onset, a solid with Maxwell "
                "arms behind a machine spring with the zone outside the punch is not solved "
                "reliably yet (first-order convergence, no second method); run it to the "
                "onset (model.until: detach), with a rigid machine, or with the zone on the "
                "face"))
        if scene.model.history != "exact":
            out.append(problem_line(
                "model.history", scene.model.history, "the seed's frozen load history (eq. 31) "
                "is a Kelvin-Voigt onset closed form; the contact solver steps the exact "
                "history" + (f" of a {scene.material.kind}" if scene.material.kind not in
                             ("kelvin_voigt", "elastic") else "")))
        if scene.numerics.steps is not None:
            out.append(problem_line(
                "numerics.steps", scene.numerics.steps, "fixed-step runs cover the seed's onset "
                "only; a moving contact edge is refined from numerics.rtol"))
        if scene.output.snapshots:
            out.append(problem_line(
                "output.snapshots", list(scene.output.snapshots), "the contact solver stores "
                "no displacement profiles yet"))
        return out + _pull_problems(scene) + stepper_settings(scene, "contact")

    def solve(self, scene, observers) -> Result:
        wall = time.perf_counter()
        setup = make_setup(scene)

        def level(n):
            with observers.progress(f"n = {n}", None) as update:
                return run_level(scene, n, setup, update)

        result = ladder.refine(
            level, _controlled, scene.numerics.rtol, _FIRST_N[setup.flat], ORDER,
            can_refine=lambda run, n: 2 * len(run.rows) <= MAX_STEPS,
            interrupted=lambda run: getattr(run, "interrupted", False), extrapolated="measured",
            floor=_floor, first_order_max=_FIRST_ORDER_MAX)
        return _result(scene, setup, result, observers, time.perf_counter() - wall)


def run_level(scene, n: int, setup=None, progress=None) -> Stepper:
    """One level of the ladder at resolution ``n`` (about ``n`` steps per time scale, every
    step halved from ``n`` to ``2 n``), run to the loading's end; its SI summary is
    ``.summary``. What :meth:`ContactSolver.solve` extrapolates, and what the separation
    work-precision benchmark times at fixed ``n``."""
    setup = setup or make_setup(scene)
    t_scale = _time_scale(scene, setup)
    t_end = setup.t_max if math.isfinite(setup.t_max) else DEFAULT_SPAN * t_scale
    stepper = Stepper(setup, n, t_scale)
    try:
        stepper.run(t_end, progress)
    except KeyboardInterrupt:
        stepper.interrupted = True
    stepper.summary = summarise(stepper)
    return stepper


#: Outputs smaller than this share of their run's scale are judged against that share.
FLOOR_SHARE = 1e-2
#: A path's force within this share of its largest magnitude of zero is zero (rounding).
_FORCE_ROUNDING = 1e-12


def _floor(stepper) -> np.ndarray:
    """Per controlled output, the size below which its error counts absolutely: a share of the
    largest |force| (forces), of the lift's range (lifts), of their product (energies); times
    are always relative."""
    rows, s = np.array(stepper.rows), stepper.setup
    force = np.max(np.abs(rows[:, 6])) * s.F0
    lift = (np.ptp(rows[:, 1]) or np.max(np.abs(rows[:, 1]))) * s.delta
    scale = {"F": force, "h": lift, "e": force * lift, "t": 0.0}
    return np.array([FLOOR_SHARE * scale[name[0]] for name in CONTROLLED])


def _time_scale(scene, setup) -> float:
    """The run's time scale (steps are about ``1/n`` of it where nothing moves fast): the
    frozen-history onset bound of a flat punch's pull, else the path's known durations."""
    if scene.loading.kind == "constant_velocity":
        problem = Problem.from_scene(scene)
        t = frozen_detach_time(problem, math.inf)
        t = t if math.isfinite(t) and t > 0.0 else 1.0
        k_m = scene.loading.machine_stiffness
        if k_m is not None:
            # Behind a spring the onset comes about F/(k_m v) later (the spring stretches
            # first): behind 1 N/m that was 135 frozen onset times, past the default span,
            # and every level took ~135 times the steps it needed. The larger of the two
            # (their sum moved a stiff spring's levels: a finite punch behind 1 kN/m then
            # converged less regularly).
            force = (math.pi * problem.a ** 2 * problem.sigma_c
                     if scene.geometry.cohesive_zone == "internal"
                     else float(problem.total_force(t)))
            t = max(t, force / (k_m * problem.delta))
        return t
    # A path's own progress (lift, force, edges) sizes its steps; time only bounds them.
    known = [d.end[1] for d in setup.drives if d.end[0] == "time"]
    return max(known + [1e3])


def _controlled(run) -> np.ndarray:
    return np.array([run.summary.get(name, math.nan) for name in CONTROLLED], dtype=float)


def peak(t: np.ndarray, F: np.ndarray, kinks=()):
    """``(t_peak, F_peak)`` of a sampled history: the largest sample, refined by the parabola
    through it and its neighbours where the maximum is smooth (not at an event, where the
    history has a corner: an unstable crack's onset, a tabulated tip's knot)."""
    i = int(np.argmax(F))
    # Not on a plateau either (a finite punch's face held at its strength limit, its next
    # row 1 ulp lower and 1e-15 later): the parabola's vertex then lies beyond the plateau,
    # above it (the peak was reported 5.5e-6 above pi R^2 sigma_c on sls_finite_punch at
    # 0.72 m/s). A smooth maximum this flat gains nothing from the parabola.
    if (0 < i < F.size - 1 and i not in kinks and min(F[i - 1], F[i + 1]) > 0.9 * F[i]
            and F[i] - max(F[i - 1], F[i + 1]) > 1e-12 * abs(F[i])
            and t[i - 1] < t[i] < t[i + 1]):
        t0, t1, t2 = t[i - 1], t[i], t[i + 1]
        f0, f1, f2 = F[i - 1], F[i], F[i + 1]
        d1 = (f1 - f0) / (t1 - t0)
        d2 = (f2 - f1) / (t2 - t1)
        curv = (d2 - d1) / (t2 - t0)
        if curv < 0.0:
            t_v = 0.5 * (t1 + t0) - d1 / (2.0 * curv)
            if t0 <= t_v <= t2:
                return t_v, f1 + d1 * (t_v - t1) + curv * (t_v - t1) * (t_v - t0)
    return float(t[i]), float(F[i])


def summarise(stepper) -> dict:
    """The summary quantities of one run, SI."""
    s = stepper.setup
    rows = np.array(stepper.rows)
    t, H, a, b = rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3]
    Fc, Ft = rows[:, 5], rows[:, 6]
    out = {}
    events = dict((name, when) for when, name in reversed(stepper.events))
    if "onset" in events:
        i = int(np.nonzero(t == events["onset"])[0][0])
        out.update(t_detach=t[i] * s.T, h_detach=H[i] * s.delta, b_detach=b[i] * s.L,
                   zone_ratio_detach=(b[i] - a[i]) / a[i] if a[i] > 0 else math.nan,
                   F_contact_detach=Fc[i] * s.F0, F_total_detach=Ft[i] * s.F0, detached=True)
    else:
        out["detached"] = False
    if "separated" in events:
        out["t_separation"] = events["separated"] * s.T
    if s.until == "path":  # the path's pull-off replaces the pull's peaks
        out.update(_path_summary(stepper, rows, events))
        return out
    if any(what == "arrest" for what, _ in stepper.notes):
        return out  # the largest force before the run stopped is not the pull's peak
    tp, Fp = peak(t, Ft, stepper.kinks)
    tc, Fcp = peak(t, Fc, stepper.kinks)
    out.update(F_peak_total=Fp * s.F0, t_peak_total=tp * s.T, F_peak_contact=Fcp * s.F0,
               t_peak_contact=tc * s.T)
    return out


def _path_summary(stepper, rows, events) -> dict:
    """Pull-off, jumps, extreme compression and the work along a loading path (SI)."""
    s = stepper.setup
    t, H, Ft = rows[:, 0], rows[:, 1], rows[:, 6]
    i_max = int(np.argmax(Ft))
    i_min = int(np.argmin(Ft))
    tp, Fp = peak(t, Ft, stepper.kinks)
    # A force that only touches zero from below by rounding (a force-controlled path back to
    # F = 0) is no compression: its -0.0 on some levels and nan on others read as an event
    # found on some levels only, and the ladder's estimate was infinite.
    compressed = Ft[i_min] < -_FORCE_ROUNDING * np.max(np.abs(Ft))
    out = {"F_pulloff": Fp * s.F0, "t_pulloff": tp * s.T,
           "h_pulloff": float(np.interp(tp, t, H)) * s.delta if i_max in range(len(t)) else
           math.nan,
           "F_max_compressive": Ft[i_min] * s.F0 if compressed else math.nan}
    for kind in ("in", "out"):
        when = [w for w, name in stepper.events if name == f"jump_{kind}"]
        if when:
            i = int(np.nonzero(t == when[0])[0][0])
            out[f"F_jump_{kind}"] = Ft[i] * s.F0
            out[f"h_jump_{kind}"] = H[i] * s.delta
    energy = float(np.sum(0.5 * (Ft[1:] + Ft[:-1]) * np.diff(H)))
    out["energy_dissipated"] = energy * s.F0 * s.delta
    retract = _last_retraction(stepper, rows)
    Fr, Hr = np.maximum(Ft[retract:], 0.0), H[retract:]
    out["work_separation"] = float(np.sum(0.5 * (Fr[1:] + Fr[:-1]) * np.diff(Hr))) * s.F0 * s.delta
    return out


def _last_retraction(stepper, rows) -> int:
    """First row of the last stretch along which the lift only grows."""
    H = rows[:, 1]
    i = len(H) - 1
    while i > 0 and H[i - 1] <= H[i]:
        i -= 1
    return i


def _path_groups(scene) -> dict:
    """Maugis' lambda (a sphere) and the retraction speed in relaxation times."""
    from ..model.elastic_contact import maugis_lambda

    spectrum = scene.material.spectrum()
    out = {}
    if scene.geometry.kind == "sphere":
        out["maugis_lambda"] = maugis_lambda(scene.geometry.radius, spectrum.G_inf,
                                             scene.adhesion.sigma_c, scene.adhesion.gamma)
    speeds = [seg.speed for seg in scene.loading.segments if seg.speed and seg.speed > 0]
    if speeds and spectrum.relaxation_times:
        out["speed_relaxation"] = speeds[-1] * max(spectrum.relaxation_times) / \
            scene.adhesion.delta
    return out


def _history(stepper, observers) -> dict:
    s = stepper.setup
    rows = np.array(stepper.rows)
    keep = observers.kept_rows(rows.shape[0], np.arange(rows.shape[0]))
    rows = rows[keep]
    return {"t": rows[:, 0] * s.T, "h": rows[:, 1] * s.delta, "a": rows[:, 2] * s.L,
            "b": rows[:, 3] * s.L, "gap": rows[:, 4] * s.delta,
            "F_contact": rows[:, 5] * s.F0, "F_total": rows[:, 6] * s.F0,
            "segment": rows[:, 7]}


def _notes(stepper, scene, estimate, rtol) -> list:
    s = stepper.setup
    notes = []
    for what, t in stepper.notes:
        if what == "t_max":
            end = ("separation" if s.until == "separation" else
                   "the onset" if s.until == "detach" else "the end of the loading path")
            if scene.loading.kind == "path":
                k = stepper.segment
                until = scene.loading.segments[k].until
                if hasattr(until, "model_dump"):
                    # (an event's target dumps to its name alone: "separation")
                    dumped = until.model_dump()
                    until = dumped if isinstance(dumped, str) else ", ".join(
                        f"{key} = {value:g}" if isinstance(value, float) else
                        f"{key} = {value}" for key, value in dumped.items()
                        if value is not None)
                end = (f"the end of loading.segments[{k}] (until {until}, which this path may "
                       f"never reach)")
            notes.append(f"{end} not reached before t_max = {t * s.T:.6g} s"
                         + ("" if scene.numerics.t_max is not None else
                            " (the default span; set numerics.t_max to go further)"))
        elif what == "arrest":
            a_now = stepper.rows[-1][2] * s.L
            notes.append(f"stopped at t = {t * s.T:.6g} s with the bond at a = "
                         f"{a_now:.4g} m: no lift balances the machine spring, and a "
                         "Kelvin-Voigt bond cannot let go at once (its dashpots), so this is "
                         "no snap; either the steps are too coarse for the bond's last "
                         "stretch (a finer rtol may carry it through) or the crack arrests "
                         "(its edge would advance again, which this model does not follow); "
                         "no separation or peak is reported")
        elif what == "free":
            notes.append(f"apart at t = {t * s.T:.6g} s under force control: a free "
                         "indenter carries no force, so the loading path ends there (what "
                         "remains of it was not run)")
        elif what == "steps":
            notes.append(f"stopped at t = {t * s.T:.6g} s: {MAX_STEPS} steps in one run")
    if not estimate <= rtol and not getattr(stepper, "interrupted", False):
        why = ("the levels disagree on which events occur (each found by some only is "
               "reported as the finest level has it)" if math.isinf(estimate) else
               f"error estimate {estimate:.2g} above rtol {rtol:g}")
        notes.append(f"not converged: {why}, at the step cap ({MAX_STEPS} steps per level)")
    return notes


def _result(scene, setup, ladder_result, observers, wall) -> Result:
    finest = ladder_result.finest
    summary = dict(finest.summary)
    estimate = ladder_result.estimate
    if ladder_result.extrapolated is not None:
        for name, value in zip(CONTROLLED, ladder_result.extrapolated):
            if math.isfinite(value):
                summary[name] = float(value)
    spectrum = scene.material.spectrum()
    if scene.loading.kind == "constant_velocity":
        summary.update(analytic.dimensionless_groups(
            spectrum.G_inf, spectrum.eta, scene.adhesion.sigma_c, scene.adhesion.delta,
            getattr(scene.geometry, "radius", math.nan), scene.loading.v))
    else:
        summary.update(_path_groups(scene))
    summary.update(error_estimate=float(estimate), observed_order=float(ladder_result.order),
                   n_elements=int(finest.nodes.total), n_steps=len(finest.rows) - 1,
                   wall_time=wall, t_end=float(finest.now.t * setup.T), solver="contact",
                   history=scene.model.history, until=setup.until,
                   cohesive_zone=getattr(scene.geometry, "cohesive_zone", ""))
    notes = _notes(finest, scene, estimate, scene.numerics.rtol)
    analytic_values = (analytic.predictions(scene) if scene.loading.kind == "constant_velocity"
                       else analytic.path_predictions(scene))
    if setup.indenter.kind != FLAT_EXTERNAL:
        analytic_values.update({k: math.nan for k in ("seed_linearised_t_detach",)})
    # A flat punch's pull keeps the reduced description every flat-punch solver gives.
    problem = (Problem.from_scene(scene) if scene.loading.kind == "constant_velocity"
               else setup)
    return Result.build(summary, analytic_values, _history(finest, observers), notes=notes,
                        complete=not getattr(finest, "interrupted", False), problem=problem)
