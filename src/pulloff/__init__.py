"""pulloff: adhesive contact and pull-off of rigid indenters from visco-elastic half-spaces,
simulated with the method of dimensionality reduction (MDR) and a Dugdale cohesive zone.

The package reads bottom-up: ``model`` (the scene as data: geometry, rheology, adhesion,
loading, the output table), ``kernels`` (numba), ``solvers`` (which solver runs a scene, the
accuracy ladder, observers), ``io`` (scene files, HDF5, console, figures), ``studies`` (sweeps,
validation) and ``references`` (independent solvers for the tests). The Python entry points
mirror the command line and need no files::

    import pulloff
    res = pulloff.run("configs/seed_flat_punch.yaml", overrides=["loading.v=1e-2"])
    table = pulloff.sweep("configs/seed_flat_punch.yaml", ["loading.v=log:1e-5:1e-1:9"]).table
    record = pulloff.load("runs/seed_flat_punch.h5")
"""

__version__ = "0.2.0"


def scene(source, overrides=()):
    """A validated scene from a :class:`pulloff.model.scene.Scene`, a dict in file form or a YAML
    path, with ``section.key=value`` overrides applied."""
    from .io.scene_file import load_scene, override, parse_scene
    from .model.scene import Scene

    if isinstance(source, Scene):
        return override(source, overrides) if overrides else source
    if isinstance(source, dict):
        return parse_scene(source, overrides)
    return load_scene(source, overrides)


def run(source, overrides=(), progress: bool = False):
    """Simulate a scene (a Scene, a dict in file form, or a YAML path); SI
    :class:`pulloff.solvers.result.Result`."""
    from . import solvers

    hook = None
    if progress:
        from .io.console import progress_bar

        hook = lambda desc, total=None: progress_bar(True, desc, total)  # noqa: E731
    return solvers.simulate(scene(source, overrides), progress=hook)


def sweep(source, axes, overrides=(), **options):
    """Run a scene over the product of ``axes`` (``"section.key=log:a:b:n"`` strings or
    :class:`pulloff.studies.sweeps.Axis`); options as :func:`pulloff.studies.sweeps.sweep`."""
    from .studies.sweeps import sweep as _sweep

    if isinstance(axes, str):  # one axis given as one string, not a list of characters
        axes = [axes]
    return _sweep(scene(source, overrides), axes, **options)


def load(path):
    """Read a run file (plain dict of numpy arrays and numbers) or a sweep file
    (:class:`pulloff.studies.sweeps.SweepResult`)."""
    from .io import h5
    from .studies.sweeps import load_sweep

    with h5.open_for_reading(path) as f:
        kind = f.attrs.get("kind")
    return load_sweep(path) if kind == "sweep" else h5.load(path)
