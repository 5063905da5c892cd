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

from pulloff.scene import parse_scene


# --------------------------------------------------------------------------------------------
# Scenes (copied from tests/test_solver.py so the benchmarks do not import the tests).

def make_scene(G=3e5, eta=3e3, sigma_c=5e6, delta=1e-8, a=1e-3, v=1e-3, h0=0.0,
               history="exact", rtol=1e-6, t_max=None, **output):
    """A validated scene from SI values: G [Pa], eta [Pa s], sigma_c [Pa], delta, a, h0 [m],
    v [m/s], t_max [s]."""
    data = {
        "schema": 1,
        "geometry": {"kind": "flat_punch", "radius": a},
        "material": {"kind": "kelvin_voigt", "G": G, "eta": eta},
        "adhesion": {"kind": "dugdale", "sigma_c": sigma_c, "delta": delta},
        "loading": {"kind": "constant_velocity", "v": v, "h0": h0},
        "model": {"history": history},
        "numerics": {"rtol": rtol, **({"t_max": t_max} if t_max is not None else {})},
        "output": output,
    }
    return parse_scene(data)


def scene_for_groups(alpha, chi, a=1e-3, G=1e6, sigma_c=1e6, **kw):
    """SI values with the given alpha and chi (MODEL.md section 4)."""
    delta = chi * sigma_c * a / (math.pi * G)
    # alpha = chi / (4 V^2) with V = eta v / (sigma_c a); choose v = 1e-3 m/s.
    V = math.sqrt(chi / (4.0 * alpha))
    v = 1e-3
    eta = V * sigma_c * a / v
    return make_scene(G=G, eta=eta, sigma_c=sigma_c, delta=delta, a=a, v=v, **kw)


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
