"""pulloff: adhesive pull-off of a rigid flat punch from a visco-elastic half-space (MDR + Dugdale).

The Python entry points mirror the command line and need no files::

    import pulloff
    res = pulloff.run("configs/seed_flat_punch.yaml", overrides=["loading.v=1e-2"])
    table = pulloff.sweep("configs/seed_flat_punch.yaml", ["loading.v=log:1e-5:1e-1:9"]).table
    record = pulloff.load("runs/seed_flat_punch.h5")
"""

__version__ = "0.1.0"


def _scene(scene, overrides=()):
    from .scene import Scene, load_scene, parse_scene

    if isinstance(scene, Scene):
        return scene.with_overrides(overrides) if overrides else scene
    if isinstance(scene, dict):
        return parse_scene(scene, overrides)
    return load_scene(scene, overrides)


def run(scene, overrides=(), progress: bool = False):
    """Simulate a scene (a Scene, a dict in file form, or a YAML path); SI
    :class:`pulloff.solver.Result`."""
    from .solver import simulate

    return simulate(_scene(scene, overrides), progress=progress)


def sweep(scene, axes, overrides=(), **options):
    """Run a scene over the product of ``axes`` (``"section.key=log:a:b:n"`` strings or
    :class:`pulloff.sweeps.Axis`); options as :func:`pulloff.sweeps.sweep`."""
    from .sweeps import sweep as _sweep

    return _sweep(_scene(scene, overrides), axes, **options)


def load(path):
    """Read a run file (plain dict of numpy arrays and numbers) or a sweep file
    (:class:`pulloff.sweeps.SweepResult`)."""
    from . import h5io
    from .sweeps import load_sweep

    with h5io.open_for_reading(path) as f:
        kind = f.attrs.get("kind")
    return load_sweep(path) if kind == "sweep" else h5io.load(path)
