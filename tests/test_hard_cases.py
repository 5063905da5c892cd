"""The hard cases of MODEL.md section 7, as shipped scenes under configs/hard/.

Each runs at a modest rtol and is checked against the independent quadrature reference: no
NaN, a bounded number of steps, the true error within rtol and the estimate not hiding it.
"""

import math
from pathlib import Path

import numpy as np
import pytest

from pulloff.io.scene_file import load_scene
from pulloff.solvers import simulate
from onset_helpers import METHODS, reference

HARD = Path(__file__).resolve().parents[1] / "configs" / "hard"
DETACHING = sorted(p.stem for p in HARD.glob("*.yaml")
                   if p.stem not in ("detach_at_t0", "no_detachment"))
RTOL = 1e-5
#: Below this the reference's own error (~1e-12) and rounding decide; no estimate can be
#: checked against it there.
FLOOR = 1e-10


def run(name, rtol=RTOL, method=None):
    overrides = [f"numerics.rtol={rtol}"] + ([f"numerics.method={method}"] if method else [])
    return simulate(load_scene(HARD / f"{name}.yaml", overrides=overrides))


def largest_error(res, reference_rtol=1e-12):
    """The largest relative error of the onset time and forces against the reference."""
    ref = reference(res.problem, reference_rtol)
    return max(abs(res.t_detach / ref["t_detach"] - 1),
               abs(res.F_contact_detach / ref["F_contact"] - 1),
               abs(res.F_total_detach / ref["F_total"] - 1))


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", DETACHING)
def test_hard_case_meets_rtol_against_the_reference(name, method):
    res = run(name, method=method)
    assert res.summary["solver"] == {"quadrature": "onset_quadrature", "stepper": "onset"}[method]
    assert res.detached
    for values in res.history.values():
        assert np.all(np.isfinite(values))
    # Bounded work: the step count follows the accuracy, not the time scales of the scene.
    assert res.n_steps <= 5000 and res.n_elements <= 12000
    error = largest_error(res, reference_rtol=1e-11)
    assert error <= RTOL
    assert res.error_estimate >= error / 10.0 or error < FLOOR


def test_thin_zone_is_resolved():
    res = run("thin_zone_1e-8")
    assert 1e-9 < res.zone_ratio_detach < 1e-7
    # The zone end is resolved in sigma = sqrt(x^2 - a^2)/a: the b history is not one value.
    assert np.unique(res.history["b"] - res.problem.a).size > 10


def test_wide_zone_is_wide():
    assert run("wide_zone_1e2").zone_ratio_detach > 50


def test_detachment_at_t0():
    res = run("detach_at_t0")
    assert res.detached and res.t_detach == 0.0 and res.n_steps == 0


def test_no_detachment_before_t_max():
    res = run("no_detachment")
    assert not res.detached and math.isnan(res.F_contact_detach)
    assert res.t_end == pytest.approx(5e-3, rel=1e-12)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("rtol", [1e-3, 1e-6, 1e-8])
@pytest.mark.parametrize("name", DETACHING)
def test_each_rtol_on_hard_cases(name, rtol, method):
    """Every output the onset reports (its time and both forces), not the contact force
    alone: on a thin zone the force follows the lift and the time's error is up to 3000x the
    force's (metre_punch at rtol 1e-6: 9.6e-9 against 3.1e-12)."""
    res = run(name, rtol, method)
    error = largest_error(res)
    assert error <= rtol
    assert res.error_estimate >= error / 10.0 or error < FLOOR


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("rtol", [1e-6, 1e-8])
@pytest.mark.parametrize("G", [1e-2, 1e-1, 1.0, 10.0])
def test_nearly_viscous_solids_whose_zone_barely_grows(G, rtol, method):
    """near_viscous with G raised to 1e-2 .. 10 Pa (relaxation times 1e7 .. 1e4 s against a
    1.6 ms pull): the zone grows by k t = 3e-11 .. 3e-8 inside the last interval of the
    preloaded mesh, and the ladder's extrapolations creep (README, Known issues). Measured:
    every rtol from 1e-6 to 1e-9 met, the estimate down to 1/8.7 of the error at rtol 1e-8
    (G = 0.1) and to 1/15 at rtol 1e-9 (G = 1e-2, not asserted here: the known issue)."""
    res = simulate(load_scene(HARD / "near_viscous.yaml",
                              overrides=[f"material.G={G}", f"numerics.rtol={rtol}",
                                         f"numerics.method={method}"]))
    error = largest_error(res)
    assert error <= rtol
    assert res.error_estimate >= error / 10.0 or error < FLOOR
