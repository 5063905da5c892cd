"""Numba kernels, one module per solver (a kernel calls only kernels of its own module: numba's
disk cache does not track changes across modules)."""

from pathlib import Path


def cache_is_warm(kernel: str) -> bool:
    """Whether numba's disk cache already holds the compiled ``kernel`` (``"module.function"``
    of this package, e.g. ``"onset.march"``: a solver's outermost kernel, compiled last), else
    the first call compiles it (measured from an empty cache on a 2-core machine: 4-6 s for
    the seed's onset, 20-45 s for the moving-edge kernels). Until the fourteenth session
    this looked for a moving-edge kernel whatever the run, so every onset run said it was
    compiling until a moving-edge scene had run once."""
    from numba.core.config import CACHE_DIR

    where = Path(CACHE_DIR) if CACHE_DIR else Path(__file__).parent / "__pycache__"
    return where.is_dir() and any(where.rglob(f"{kernel}-*.nbi"))
