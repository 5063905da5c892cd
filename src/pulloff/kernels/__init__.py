"""Numba kernels, one module per solver (a kernel calls only kernels of its own module: numba's
disk cache does not track changes across modules)."""

import importlib
from pathlib import Path


def cache_is_warm(kernel: str) -> bool:
    """Whether numba's disk cache already holds the compiled ``kernel`` (``"module.function"``
    of this package, e.g. ``"onset.march"``: a solver's outermost kernel, compiled last), else
    the first call compiles it (measured from an empty cache on a 2-core machine: 4-6 s for
    the seed's onset, 20-45 s for the moving-edge kernels). Until the fourteenth session
    this looked for a moving-edge kernel whatever the run, so every onset run said it was
    compiling until a moving-edge scene had run once."""
    entries = cached_entries(kernel)
    if entries is not None:
        return entries > 0
    # numba's cache internals changed: any index file of the kernel, in the usual places
    from numba.core.config import CACHE_DIR

    where = Path(CACHE_DIR) if CACHE_DIR else Path(__file__).parent / "__pycache__"
    return where.is_dir() and any(where.rglob(f"{kernel}-*.nbi"))


def cached_entries(kernel: str):
    """Compiled versions numba's own cache index holds for ``kernel`` and would load (an index
    written for other source is read as empty), wherever numba keeps it (``NUMBA_CACHE_DIR``,
    the package's ``__pycache__`` or the user's cache); None where numba's private cache
    attributes are not there to ask."""
    module, name = kernel.split(".")
    dispatcher = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    try:
        return len(dispatcher._cache._cache_file._load_index())
    except (AttributeError, OSError, EOFError, ValueError):
        return None
