"""Solvers: which one runs a scene (one routing rule), and running it.

Every solver declares what it does not support (:meth:`Solver.unsupported`); :func:`route` runs
a scene with the first solver that supports every setting of it. A scene no solver supports is
rejected before any work with the problems of the solver that came closest: the fewest problems
with the model itself (geometry, material, adhesion, loading, model), then the fewest with
settings (numerics, output); on a tie the more general one, later in :data:`SOLVERS`.
"""

from __future__ import annotations

from ..model.scene import SceneError
from .base import Solver
from .contact import ContactSolver
from .edge_quadrature import EdgeQuadratureSolver
from .frozen import FrozenSolver
from .observers import Observers
from .onset import OnsetSolver
from .onset_quadrature import OnsetQuadratureSolver

#: In order of preference: the specialised closed form, the onset by quadrature and the onset
#: stepper, a rigid pull to separation by quadrature, before the general one.
SOLVERS: tuple[Solver, ...] = (FrozenSolver(), OnsetQuadratureSolver(), OnsetSolver(),
                               EdgeQuadratureSolver(), ContactSolver())


def route(scene) -> Solver:
    """The solver that runs ``scene``; :class:`SceneError` naming every unsupported setting
    otherwise. A scene that names a ``numerics.method`` is told the problems of a solver of
    that method (the one it asked for), or of one without a method."""
    best, best_rank = None, None
    asked = scene.numerics.method
    for solver in SOLVERS:
        problems = solver.unsupported(scene)
        if not problems:
            return solver
        if asked is not None and solver.method not in (None, asked):
            continue
        settings = sum(line.startswith(("numerics.", "output.")) for line in problems)
        rank = (len(problems) - settings, settings)
        if best_rank is None or rank <= best_rank:
            best, best_rank = problems, rank
    raise SceneError(best)


def check(scene) -> None:
    """Raise :class:`SceneError` unless a solver honours every setting of ``scene``."""
    route(scene)


def simulate(scene, progress=None, stream=None, observers: Observers | None = None):
    """Run a validated scene; SI :class:`pulloff.solvers.result.Result`.

    ``progress`` is a progress hook (see :class:`Observers`) and ``stream`` a callable taking
    SI history columns as a fixed-step run computes them.
    """
    observers = observers or Observers.for_scene(scene, progress=progress, stream=stream)
    return route(_observed(scene, observers)).solve(scene, observers)


def _observed(scene, observers: Observers):
    """``scene`` with the history and snapshots that ``observers`` ask for (given through
    the Python API rather than the scene's output section): routing must see them, since
    not every solver keeps steps or element fields."""
    every, snapshots = observers.every, list(observers.snapshot_times)
    if every == scene.output.every and snapshots == list(scene.output.snapshots):
        return scene
    return scene.model_copy(update={"output": scene.output.model_copy(
        update={"every": every, "snapshots": snapshots})})
