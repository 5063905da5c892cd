"""Observed order of the moving-edge (contact) stepper, against the independent moving-edge
reference (``pulloff.references.edge``, values in ``tests/data/edge_reference.json``, each
converged to ~1e-9 or better): onset, separation and peak, external and internal zones,
Kelvin-Voigt and a standard linear solid (issue 10).

A level ``n`` is one run of the ladder at fixed resolution (``contact.run_level``). The order is
the slope of the errors' logarithm over the levels n = 8, 16, 32, 64, 128 (a least-squares fit,
which averages out the scatter of a single doubling: the Kelvin-Voigt peak passes 1e-9 at
n = 32 by cancellation). Measured (relative errors; fitted order):

================================  =============================================  =====
scene, output                     errors at n = 8, 16, 32, 64, 128               order
================================  =============================================  =====
separation_kv, onset time         9.1e-7, 1.5e-7, 6.1e-9, 3.7e-11, 4.6e-10      3.39
separation_kv, separation time    1.5e-4, 2.4e-5, 2.3e-6, 8.5e-7, 3.3e-8        2.91
separation_kv, peak force         1.2e-5, 5.6e-7, 1.1e-9, 5.3e-8, 5.0e-9        2.59
finite_punch_internal, onset      2.7e-6, 4.6e-7, 6.4e-8, 4.3e-9, 2.6e-10       3.34
finite_punch_internal, separation 8.4e-4, 4.7e-5, 1.1e-5, 1.2e-6, 2.8e-7        2.83
finite_punch_internal, peak       1.3e-4, 2.7e-5, 8.3e-6, 1.0e-6, 2.9e-7        2.23
sls_finite_punch, onset           1.5e-7, 1.1e-8, 9.2e-10, 8.0e-11, 7.5e-12     3.56
sls_finite_punch, separation      2.2e-4, 1.4e-5, 9.8e-7, 3.8e-7, 1.0e-7        2.73
sls_finite_punch, peak            1.7e-5, 2.0e-6, 4.1e-7, 6.5e-8, 3.4e-8        2.28
sls external at 1e-2 m/s, onset   1.5e-6, 1.9e-7, 2.4e-8, 3.0e-9, 3.7e-10       2.99
sls external, separation          1.7e-5, 2.9e-6, 3.7e-7, 5.7e-8, 9.9e-9        2.71
sls external, peak                (the onset: it comes off there)                2.99
seed_flat_punch, onset            (n = 64, 128, 256) 1.7e-7, 2.5e-8, 3.7e-9     2.78
seed_flat_punch, separation       9.4e-6, 1.5e-6, 2.1e-7                        2.76
seed_flat_punch, peak             1.9e-6, 4.9e-7, 1.1e-7                        2.04
================================  =============================================  =====

The seed scene (its rows above; its default solver is now the edge quadrature) needs the
levels n = 64, 128, 256, 5 s of the suite: its check runs by hand with the stepper's other
long checks (``python benchmarks/long_checks.py``). Its peak converged at order 1.07 over
n = 64..256 (1.9e-6, 9.6e-7, 4.2e-7) until the elements its receding edge releases came at
a spacing falling like ``1/n`` from n = 64 on (``contact_stepper.Stepper.per_release``; like
``1/sqrt(n)`` before).

The method is second order (quadratic paths of the edges and the lift over a step, Richardson
with order 2 in ``solvers.contact.ORDER``). The band's floor, 1.75, is below the measured
minimum (2.04, the seed's peak over three levels; 2.23 over five on the others) by the
scatter of the fit; its ceiling catches an error that vanishes by
cancellation rather than converges.

Until the steps started from a force range of 1 (``contact_stepper.FORCE_RANGE``, was 1e-3),
two peak forces fell short of order 2 over n = 8..64 (the Kelvin-Voigt peak 1.37, the standard
linear solid's 1.18, stalling near 2e-7 from n = 16 to 64) and were asserted as measured; the
coarse bonded phase makes n = 8 less accurate now (the standard linear solid's peak 2.8e-6
then, 1.7e-5 now), so the fit reaches n = 128.
"""

import functools
import json
from pathlib import Path

import numpy as np
import pytest

from pulloff.io.scene_file import load_scene
from pulloff.solvers import contact

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
REFERENCE = json.loads((Path(__file__).parent / "data" / "edge_reference.json").read_text())
LEVELS = (8, 16, 32, 64, 128)
ORDER_BAND = (1.75, 4.5)
#: Reference entry -> (config, overrides, levels).
SCENES = {
    "separation_kv": ("separation_kv", [], LEVELS),
    "finite_punch_internal": ("finite_punch_internal", [], LEVELS),
    "sls_finite_punch": ("sls_finite_punch", [], LEVELS),
    # (to n = 64: its errors fall regularly from n = 8, orders 3.0 and 2.7 over n = 8..64;
    # its n = 128 level costs half the scene's 2.3 s)
    "sls_external_v1e-2": ("sls_finite_punch", ["loading.v=1e-2",
                                                "geometry.cohesive_zone=external"],
                           LEVELS[:-1]),
}
#: Our summary name -> the reference's.
OUTPUTS = {"t_detach": "t_onset", "t_separation": "t_separation",
           "F_peak_total": "F_peak_total"}


@functools.lru_cache(maxsize=None)
def level_errors(name):
    """Relative errors of every judged output at each of the scene's levels."""
    config, extra, levels = SCENES[name]
    scene = load_scene(CONFIGS / f"{config}.yaml", overrides=["model.until=separation"] + extra)
    ref = REFERENCE[name]
    errors = {}
    for n in levels:
        summary = contact.run_level(scene, n).summary
        errors[n] = {ours: abs(summary[ours] / ref[theirs] - 1.0)
                     for ours, theirs in OUTPUTS.items()}
    return errors


@pytest.mark.parametrize("output", sorted(OUTPUTS))
@pytest.mark.parametrize("name", sorted(SCENES))
def test_observed_order_against_the_reference_is_at_least_second(name, output):
    errors = level_errors(name)
    levels = sorted(errors)
    series = [errors[n][output] for n in levels]
    assert min(series) > 0.0, errors  # an exact answer would hide the order
    slope = np.polyfit(np.log2(levels), np.log2(series), 1)[0]
    assert ORDER_BAND[0] <= -slope <= ORDER_BAND[1], (-slope, errors)
    assert max(series) < 1e-3, errors
    # The finest level is already close: no level converges to something else.
    assert series[-1] < 1e-5, errors
