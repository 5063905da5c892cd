"""Every combination of rheology x until x zone x machine x history x output option is either
honoured, with its effect visible in the result, or refused before any work with one line
naming the key (issue 9: each of these was once silently ignored somewhere).

The scenes are small and coarse (rtol 1e-2): what is checked is that a setting acts, not how
accurately; accuracy has its own tests.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from pulloff import solvers
from pulloff.io.scene_file import parse_scene
from pulloff.model.scene import SceneError
from pulloff.solvers.frozen import frozen_detach_time
from pulloff.solvers.problem import Problem

RHEOLOGIES = {
    "elastic": {"kind": "elastic", "G": 1e6},
    "kelvin_voigt": {"kind": "kelvin_voigt", "G": 1e6, "eta": 1e3},
    # (tau_1 = 0.1 ms: a real zone-only phase, and cheaper than at 1 ms)
    "standard_linear_solid": {"kind": "standard_linear_solid", "G_inf": 1e6, "G_1": 9e6,
                              "tau_1": 1e-4},
    "prony": {"kind": "prony", "G_inf": 1e6,
              "terms": [{"G": 4e6, "tau": 1e-4}, {"G": 5e6, "tau": 1e-3}]},
}
V = 1e-3  # m/s
MACHINE = 1e4  # N/m: stiff enough to be cheap, soft enough to move the lift visibly
SNAPSHOT = 2e-4  # s, before the onset of every one of these scenes (the earliest: 6.6e-4 s)
OPTIONS = ("steps", "every", "snapshots")



def combinations(rheologies) -> list[tuple]:
    """Every combination for the given rheologies (the file is split in two by rheology so
    that the two test workers share the work)."""
    return list(itertools.product(rheologies, ("detach", "separation"),
                                  ("external", "internal"), (None, MACHINE),
                                  ("exact", "frozen"), OPTIONS))


COMBINATIONS = combinations(("elastic", "kelvin_voigt"))  # the others: test_combinations_arms


def _scene_dict(rheology, until, zone, machine, history, option) -> dict:
    loading = {"kind": "constant_velocity", "v": V}
    if machine is not None:
        loading["machine_stiffness"] = machine
    d = {"schema": 1, "name": "combination",
         "geometry": {"kind": "flat_punch", "radius": 1e-5, "cohesive_zone": zone},
         "material": RHEOLOGIES[rheology],
         "adhesion": {"kind": "dugdale", "sigma_c": 1e6, "delta": 3e-6},
         "loading": loading, "model": {"until": until, "history": history},
         "numerics": {"rtol": 1e-2}, "output": {}}
    if option == "steps":
        d["numerics"] = {"steps": 50}
    elif option == "every":
        d["output"]["every"] = 3
    else:
        d["output"]["snapshots"] = [SNAPSHOT]
    return d


def _key_of(option) -> str:
    return {"steps": "numerics.steps", "every": "output.every",
            "snapshots": "output.snapshots"}[option]


@pytest.mark.parametrize("rheology,until,zone,machine,history,option", COMBINATIONS,
                         ids=["-".join(str(p) for p in c) for c in COMBINATIONS])
def test_every_setting_is_honoured_or_refused(rheology, until, zone, machine, history, option):
    check_combination(rheology, until, zone, machine, history, option)


def check_combination(rheology, until, zone, machine, history, option):
    """Run or refuse one combination and check that each of its settings acted."""
    d = _scene_dict(rheology, until, zone, machine, history, option)
    try:
        scene = parse_scene(d)
    except SceneError as refusal:
        line = str(refusal)
        # The refusal names a key of this combination that is not its default.
        named = {"model.history": history != "exact", "loading.machine_stiffness": machine,
                 "model.until": until != "detach", "material.kind": rheology != "elastic",
                 "geometry.cohesive_zone": zone != "external", _key_of(option): True}
        assert any(key in line and on for key, on in named.items()), line
        return
    result = solvers.simulate(scene)
    s = result.summary
    t_det = s["t_detach"]
    assert s["detached"] and t_det > 0.0, s["notes"]

    # until: separation reports when the surfaces came apart (at or after the onset).
    if until == "separation":
        assert t_det * (1 - 1e-12) <= s["t_separation"] < 1.0
    else:
        assert math.isnan(s["t_separation"])

    # zone: external grows outside the rim, internal stays on the face.
    if zone == "external":
        assert s["b_detach"] > 1e-5
    else:
        assert s["b_detach"] <= 1e-5 * (1 + 1e-9)

    # machine: the lift lags the driver by the spring's stretch, F / k.
    stretch = s["F_total_detach"] / machine if machine is not None else 0.0
    # (to 1e-6: the times and forces are extrapolated from the levels, the lift is not)
    assert s["h_detach"] == pytest.approx(V * t_det - stretch, rel=1e-6)
    if machine is not None:
        assert stretch > 1e-3 * V * t_det

    # history: frozen is the seed's closed form (eq. 31), exact is not.
    problem = Problem.from_scene(scene)
    frozen = frozen_detach_time(problem, math.inf) * problem.time_scale
    if history == "frozen":
        assert t_det == pytest.approx(frozen, rel=1e-2)
    elif rheology == "kelvin_voigt" and machine is None and zone == "external":
        assert abs(t_det / frozen - 1.0) > 1e-2

    n_rows = result.history["t"].size
    if option == "steps":
        assert 50 <= s["n_steps"] <= 52 and math.isnan(s["observed_order"])
    elif option == "every":
        assert n_rows == pytest.approx(s["n_steps"] / 3, abs=2)
    else:
        assert SNAPSHOT < t_det
        assert [t for t, _, _ in result.snapshots] == pytest.approx([SNAPSHOT], rel=1e-9)
        _, x, u = result.snapshots[0]
        assert x.size == u.size >= 2 and np.all(np.isfinite(u))
