"""A flat punch pulled to separation through a machine spring by the edge quadrature
(:mod:`pulloff.solvers.edge_machine`): the lift's exponential rule, the force balance along
the history, agreement and convergence against the independent moving-edge reference
(``tests/data/edge_reference.json``: ``compliant_machine``, 100 N/m, and the same scene
behind 10 and 1 N/m; each snaps off where the bond radius reaches 0), and the elastic limit.

Measured at rtol 1e-6 (nineteenth session): worst errors of onset, separation and peak
forces 1.9e-9, 6.1e-10, 1.7e-9 behind 100, 10, 1 N/m (the reference's own estimates 9e-11,
4e-11, 7.8e-9), estimates 4.3e-9, 8.6e-10, 4.3e-10.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from pulloff import solvers
from pulloff.io.scene_file import load_scene
from pulloff.kernels import quadrature as kernels
from pulloff.model import analytic
from pulloff.solvers import edge_quadrature as edge

from edge_helpers import assert_agrees_with_the_reference

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
REFERENCE = json.loads((Path(__file__).parent / "data" / "edge_reference.json").read_text())
#: Reference entry -> the machine's stiffness [N/m] on compliant_machine.yaml.
SPRINGS = {"compliant_machine": 100.0, "compliant_machine_k10": 10.0,
           "compliant_machine_k1": 1.0}
OUTPUTS = {"t_detach": "t_onset", "F_total_detach": "F_onset_total",
           "t_separation": "t_separation", "F_peak_total": "F_peak_total",
           "F_peak_contact": "F_peak_contact"}


def scene_of(name, *extra):
    return load_scene(CONFIGS / "compliant_machine.yaml", overrides=[
        "model.until=separation", f"loading.machine_stiffness={SPRINGS[name]!r}", *extra])


def errors(summary, name):
    ref = REFERENCE[name]
    return {ours: abs(summary[ours] / ref[theirs] - 1.0) for ours, theirs in OUTPUTS.items()}


def test_the_lifts_rule_integrates_the_exponential_memory_of_a_quintic():
    """Over the last interval, ``int e^(-rate (t_i - s)) ell(s) ds`` with ``ell`` of degree 5
    in sigma and ``t(sigma)`` quadratic is the weights against the nodes' ``ell``: exact but
    for the Gauss rule's error on the exponential (against scipy's adaptive quadrature)."""
    from scipy.integrate import quad

    from pulloff.solvers.edge_machine import _GW, _GX

    def t_of(x):
        return 3.0 + 0.7 * x + 0.05 * x * x

    def ell_of(x):
        return 1.0 + 0.3 * x - 0.2 * x ** 3 + 0.01 * x ** 5

    sig = np.array([0.0, 0.4, 0.9, 1.3, 2.0, 2.2])
    hist = np.vstack([t_of(sig), np.zeros(6), sig, ell_of(sig)])
    rate = 1.7
    weights = np.empty(6)
    assert kernels.lift_step_weights(hist, 0, 5, rate, _GX, _GW, weights) == 6
    exact = quad(lambda x: (0.7 + 0.1 * x) * math.exp(-rate * (t_of(2.2) - t_of(x)))
                 * ell_of(x), 2.0, 2.2, epsabs=0.0, epsrel=1e-13)[0]
    assert weights @ ell_of(sig) == pytest.approx(exact, rel=1e-13)
    # a piece's first steps use the nodes it has
    assert kernels.lift_step_weights(hist, 3, 5, rate, _GX, _GW, weights) == 3


@pytest.fixture(scope="module")
def results():
    return {name: solvers.simulate(scene_of(name, "numerics.rtol=1e-6")) for name in SPRINGS}


@pytest.mark.parametrize("name", sorted(SPRINGS))
def test_the_reference_agrees_within_rtol_with_an_honest_estimate(results, name):
    res = results[name]
    # measured at most 1.9e-9, estimates 0.25x the error at worst
    assert_agrees_with_the_reference(res, errors(res.summary, name), 1e-6 / 100)
    # it snaps off where a reaches 0, as the reference finds
    assert REFERENCE[name]["separation_kind"] == "snap_at_a_zero"
    assert res.t_separation == pytest.approx(REFERENCE[name]["t_a_zero"], rel=1e-8)
    assert any("snaps off" in note for note in res.notes)


@pytest.mark.parametrize("name", sorted(SPRINGS))
def test_the_spring_holds_the_whole_line_load_along_the_history(results, name):
    """``F_total = k_m (v t - h)`` on every row: the lift solved with the edges is the one
    the spring and the zone's force agree on (and the rows before the onset are the lift
    path's)."""
    res = results[name]
    k_m, v = SPRINGS[name], 1e-3
    rows = res.history
    spring = k_m * (v * rows["t"] - rows["h"])
    scale = np.max(np.abs(rows["F_total"]))
    assert np.max(np.abs(spring - rows["F_total"])) <= 1e-9 * scale
    assert np.all(np.diff(rows["t"]) >= 0.0) and rows["a"][-1] == 0.0


def test_order_of_convergence_in_the_nodes():
    """Behind 100 N/m (the reference's estimate 9e-11): measured errors 6.9e-6, 1.5e-7,
    9.0e-9, 1.6e-10 at tolerances 1e-3 .. 1e-6 (36, 48, 71, 102 nodes): order 10."""
    model = edge.EdgeModel.from_scene(scene_of("compliant_machine"))
    rows = []
    for tol in (1e-3, 1e-4, 1e-5, 1e-6):
        run = edge.run_at(model, tol, math.inf)
        assert run.end == "snap"
        rows.append((run.n, max(errors(edge.summarise(run), "compliant_machine").values())))
    nodes, errs = np.array(rows).T
    assert errs[-1] < 1e-9, rows
    order = -np.polyfit(np.log(nodes), np.log(errs), 1)[0]
    assert 4.0 <= order <= 16.0, (order, rows)


def test_an_elastic_punch_behind_a_spring_comes_off_at_its_onset_with_the_closed_form():
    """Its crack is unstable (the punch moves with the spring as the bond recedes): off at
    the onset, at the elastic closed form's force whatever the spring."""
    res = solvers.simulate(load_scene(CONFIGS / "separation_elastic.yaml", overrides=[
        "model.until=separation", "loading.machine_stiffness=10", "numerics.rtol=1e-6"]))
    assert res.summary["solver"] == "edge_quadrature"
    p = res.problem
    exact = analytic.elastic_mdr_dugdale(p.G, p.sigma_c, p.delta, p.a)
    assert res.t_separation == res.t_detach
    assert res.F_peak_total == res.F_total_detach
    assert res.F_total_detach == pytest.approx(exact["F_total"], rel=1e-9)


def test_a_fast_pull_behind_a_stiff_spring_has_the_onset_quadratures_onset():
    """300 N/m at 0.1 m/s (the spring 3.75 times the solid at the start): the lift path
    starts like ``sqrt(t)`` over a layer a fair part of the onset time, which the gap's
    history integral must grade toward ``t = 0`` (found by a review: the onset was 2.0e-6
    off at rtol 1e-6 and 3.2e-5 at 1e-5, estimates 1.5e-8 and 2.8e-8; now 1e-13 and 1.2e-10).
    The onset's own quadrature lays its panels out differently (its ``Span`` and graded
    memory), so it is an independent check of the onset."""
    common = ["loading.machine_stiffness=300", "loading.v=1e-1", "numerics.rtol=1e-6"]
    onset = solvers.simulate(load_scene(CONFIGS / "compliant_machine.yaml",
                                        overrides=common))
    assert onset.summary["solver"] == "onset_quadrature"
    run = solvers.simulate(scene_of("compliant_machine", *common))
    assert run.summary["solver"] == "edge_quadrature"
    assert run.t_detach == pytest.approx(onset.t_detach, rel=1e-10)
    assert run.F_total_detach == pytest.approx(onset.F_total_detach, rel=1e-10)


def test_a_run_ending_in_a_fold_keeps_the_spring_balanced_on_its_last_row():
    """300 N/m at 1e-3 m/s: the zone alone turns back in time (a fold). The history's last
    row is the fold's time with the last node's force and radii; its lift is the one that
    balances that force (a review found it 3e-5 off, the lift of the radii past the fold)."""
    res = solvers.simulate(scene_of("compliant_machine", "loading.machine_stiffness=300",
                                    "numerics.rtol=1e-6"))
    assert res.summary["solver"] == "edge_quadrature" and not res.notes
    rows = res.history
    spring = 300.0 * (1e-3 * rows["t"] - rows["h"])
    assert np.max(np.abs(spring - rows["F_total"])) <= 1e-12 * np.max(rows["F_total"])
    assert rows["t"][-1] == res.t_separation > rows["t"][-2]


#: The contact stepper behind 0.1 N/m at rtol 1e-4 (11 s; its estimate 2.6e-6): no moving-edge
#: reference value exists here, since that solver reports an arrest at its first level even
#: given the run's scales as behind 1 N/m (twentieth session).
STEPPER_K01 = {"t_separation": 14.343973518452195, "F_peak_total": 0.0014333986710225969,
               "estimate": 2.634552222224394e-06}


@pytest.mark.parametrize("tol", [8e-4, 8e-5])
def test_behind_a_tenth_of_a_newton_per_metre_the_bond_runs_through_and_snaps(tol):
    """Behind 0.1 N/m the onset comes 14.3 s (4e4 creep times) into the pull, the crack then
    runs for 9.3 ms and the punch snaps where a reaches 0. With the onset time as its time
    unit the march turned back near the onset at every tolerance (the slow standard linear
    solid's false fold: edge._CREEP_TIMES) and the stepper answered, in 7-11 s. Measured
    since: 1.7e-7, 2.0e-7 off the stepper's separation time and peak force at these
    tolerances (2.3e-7 at 8e-6), within the stepper's own estimate."""
    scene = load_scene(CONFIGS / "compliant_machine.yaml", overrides=[
        "model.until=separation", "loading.machine_stiffness=0.1"])
    run = edge.run_at(edge.EdgeModel.from_scene(scene), tol, math.inf)
    assert run.end == "snap"
    summary = edge.summarise(run)
    for name in ("t_separation", "F_peak_total"):
        assert summary[name] == pytest.approx(STEPPER_K01[name], rel=STEPPER_K01["estimate"])
