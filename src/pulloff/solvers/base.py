"""What a solver is: the scenes it supports (and why not others), and how it runs one."""

from __future__ import annotations

from ..model.fields import fmt


class Solver:
    """A way to run scenes. ``unsupported(scene)`` lists, one line each, every setting of the
    scene this solver would not honour (``key = value: reason``); a solver runs a scene only
    when that list is empty, so no setting is ever silently ignored."""

    name = ""
    summary = ""
    #: How it solves (``numerics.method``: "quadrature" or "stepper"; None: a closed form).
    method: str | None = None
    #: The numba kernel (``"module.function"`` under :mod:`pulloff.kernels`) whose cached
    #: copy says this solver's kernels are compiled; None: it compiles none.
    kernel: str | None = None

    def unsupported(self, scene) -> list[str]:
        raise NotImplementedError

    def solve(self, scene, observers):
        """Run ``scene`` with :class:`pulloff.solvers.observers.Observers`; returns a
        :class:`pulloff.solvers.result.Result`."""
        raise NotImplementedError


#: The time steppers' smallest rtol: below it a run costs minutes (their work grows like a
#: power of 1/rtol), while the quadrature onset reaches the schema's 1e-12 at once.
STEPPER_RTOL_FLOOR = 1e-10


def stepper_settings(scene, solver: str) -> list[str]:
    """Problems of a scene for a time-stepping solver: ``numerics.method = quadrature`` and
    an rtol below :data:`STEPPER_RTOL_FLOOR`."""
    out = []
    if scene.numerics.method == "quadrature":
        out.append(problem(
            "numerics.method", "quadrature", f"the {solver} solver steps; the quadrature "
            "covers a Kelvin-Voigt flat punch to its onset (no steps, snapshots or "
            "output.every)"))
    if scene.numerics.rtol < STEPPER_RTOL_FLOOR:
        out.append(problem(
            "numerics.rtol", scene.numerics.rtol, f"below {STEPPER_RTOL_FLOOR:g} a time "
            "stepper costs minutes; only the quadrature onset goes to 1e-12 (a Kelvin-Voigt "
            "flat punch to its onset, no numerics.steps, output.every or output.snapshots, "
            "numerics.method not stepper)"))
    return out


def problem(key: str, value, reason: str) -> str:
    """One problem line: the dotted key, the value as a user writes it, the reason."""
    return f"{key} = {fmt(value)}: {reason}"


def flat_punch_pull(scene, solver: str, zones=("external",), machine=False) -> list[str]:
    """Problems of a scene for a solver that pulls a flat punch at constant speed."""
    out = []
    if scene.geometry.kind != "flat_punch":
        out.append(problem("geometry.kind", scene.geometry.kind,
                           f"the {solver} solver pulls a flat punch only"))
    elif scene.geometry.cohesive_zone not in zones:
        out.append(problem("geometry.cohesive_zone", scene.geometry.cohesive_zone,
                           f"the {solver} solver puts the cohesive zone "
                           f"{' or '.join(zones)} only"))
    if scene.loading.kind != "constant_velocity":
        out.append(problem("loading.kind", scene.loading.kind,
                           f"the {solver} solver pulls at constant speed only"))
    elif scene.loading.machine_stiffness is not None and not machine:
        out.append(problem("loading.machine_stiffness", scene.loading.machine_stiffness,
                           f"the {solver} solver assumes a rigid machine"))
    return out
