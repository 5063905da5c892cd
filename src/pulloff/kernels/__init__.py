"""Numba kernels, one module per solver (a kernel calls only kernels of its own module: numba's
disk cache does not track changes across modules)."""
