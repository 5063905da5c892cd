"""Numba kernels, one module per solver (a kernel calls only kernels of its own module: numba's
disk cache does not track changes across modules)."""

from pathlib import Path


def cache_is_warm() -> bool:
    """Whether numba's disk cache already holds this package's compiled kernels (else the
    first call compiles them: measured from an empty cache on a 2-core machine, 7-9 s for
    the seed's onset and 38-45 s for the moving-edge kernels)."""
    from numba.core.config import CACHE_DIR

    where = Path(CACHE_DIR) if CACHE_DIR else Path(__file__).parent / "__pycache__"
    return where.is_dir() and any(where.rglob("contact.evaluate_step-*.nbi"))
