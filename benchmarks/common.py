"""Shared pieces of the benchmark scripts: scenes from dimensionless groups, timing, fits.

The scripts pin numba and BLAS to one thread before importing anything (this module included),
so that the numbers are single-threaded and do not compete for cores.
"""

from __future__ import annotations

import math
import platform
import statistics
import time
from dataclasses import dataclass

import numpy as np

from pulloff.io.scene_file import scene_from_groups


# --------------------------------------------------------------------------------------------
# Scenes

def scene_for_groups(alpha, chi, **kw):
    """A seed scene with the given alpha and chi (MODEL.md section 4), as the tests build it."""
    return scene_from_groups(alpha, chi, **kw)


# --------------------------------------------------------------------------------------------
# Timing.

@dataclass
class Timing:
    """Wall time of one call [s]: median, minimum and quartiles over ``repeats`` samples."""

    median: float
    minimum: float
    q1: float
    q3: float
    repeats: int
    calls_per_sample: int

    @property
    def iqr(self) -> float:
        return self.q3 - self.q1


def time_call(fn, min_repeats: int = 5, min_total: float = 0.2, max_repeats: int = 200,
              sample_floor: float = 1e-3):
    """Time ``fn()`` warm: at least ``min_repeats`` samples and at least ``min_total`` seconds.

    The caller warms ``fn`` up first (one call per method compiles or loads numba's kernels;
    after that every call of the method is warm). Calls shorter than ``sample_floor`` seconds
    are timed in batches of 10^j calls per sample so that the clock's resolution and the loop
    overhead stay negligible. Returns ``(Timing, last result of fn)``, times per call.
    """
    clock = time.perf_counter
    number = 1
    while True:
        start = clock()
        for _ in range(number):
            result = fn()
        first = clock() - start
        if first >= sample_floor or number >= 10**6:
            break
        number *= 10
    samples = [first / number]
    total = first
    while len(samples) < min_repeats or (total < min_total and len(samples) < max_repeats):
        start = clock()
        for _ in range(number):
            result = fn()
        elapsed = clock() - start
        samples.append(elapsed / number)
        total += elapsed
    q1, _, q3 = statistics.quantiles(samples, n=4, method="inclusive")
    return Timing(statistics.median(samples), min(samples), q1, q3, len(samples), number), result


# --------------------------------------------------------------------------------------------
# Fits.

def loglog_slope(x, y) -> float:
    """Least-squares slope of ``log y`` against ``log x`` (nan with fewer than two points)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    keep = (x > 0) & (y > 0) & np.isfinite(x) & np.isfinite(y)
    if keep.sum() < 2:
        return math.nan
    return float(np.polyfit(np.log(x[keep]), np.log(y[keep]), 1)[0])


def machine_summary() -> str:
    """One line naming the interpreter, the library versions and the CPU."""
    import numba
    import scipy

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return (f"Python {platform.python_version()}, numpy {np.__version__}, scipy "
            f"{scipy.__version__}, numba {numba.__version__}; {cpu}; single thread")
