"""The onset (both methods: quadrature and stepper) against the independent reference (pulloff.references.onset).

The reference integrates the same model by nested adaptive quadrature of the explicit element
solutions (a different method, sharing no code with the stepper) to ~1e-12.
"""

import math
from pathlib import Path

import pytest

from pulloff.io.scene_file import load_scene
from pulloff.solvers import simulate
from onset_helpers import METHODS, reference, with_method
from test_solver import make_scene, scene_for_groups

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def _errors(res):
    p = res.problem
    ref = reference(p, rtol=1e-11)
    assert ref["detached"]
    return max(abs(res.t_detach / ref["t_detach"] - 1.0),
               abs(res.F_contact_detach / ref["F_contact"] - 1.0),
               abs(res.F_total_detach / ref["F_total"] - 1.0),
               abs((res.b_detach - p.a) / (ref["b_detach"] - p.a) - 1.0))


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("alpha", [1e-2, 1.0, 1e2])
@pytest.mark.parametrize("chi", [1e-4, 1e-2, 1.0])
def test_meets_rtol_across_alpha_and_chi(alpha, chi, method):
    rtol = 1e-6
    res = simulate(with_method(scene_for_groups(alpha, chi, rtol=rtol), method))
    error = _errors(res)
    assert error <= rtol
    # The estimate is what the user is told: it must not hide the true error.
    assert res.error_estimate >= error / 10.0


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("rtol", [1e-3, 1e-5, 1e-8])
def test_meets_each_requested_rtol_on_the_seed_scene(rtol, method):
    res = simulate(with_method(make_scene(rtol=rtol), method))
    error = _errors(res)
    assert error <= rtol
    assert res.error_estimate >= error / 10.0


@pytest.mark.parametrize("name", ["seed_flat_punch", "elastic_kendall", "viscous_limit",
                                  "wide_zone"])
@pytest.mark.parametrize("method", METHODS)
def test_shipped_configs_meet_their_rtol(name, method):
    scene = with_method(load_scene(CONFIGS / f"{name}.yaml"), method)
    res = simulate(scene)
    assert _errors(res) <= scene.numerics.rtol


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("h0", [1e-6, 5e-6])
def test_initial_lift_and_preloaded_zone(h0, method):
    res = simulate(with_method(make_scene(h0=h0, rtol=1e-6), method))
    assert _errors(res) <= 1e-6


@pytest.mark.parametrize("method", METHODS)
def test_near_elastic_where_the_relaxation_layer_is_thinner_than_a_step(method):
    # c/k ~ 3e-6 of the pull: the layer sits inside the youngest interval at every rtol here.
    res = simulate(with_method(make_scene(G=1e6, eta=1e-2, sigma_c=1e6, delta=3e-6, a=1e-5,
                                          rtol=1e-7), method))
    assert _errors(res) <= 1e-7
    assert math.isfinite(res.error_estimate)
