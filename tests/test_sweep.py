"""Sweeps: axes, parallel runs, failures as rows, resuming, Dask, the CLI and the Python API."""

import math
from pathlib import Path

import numpy as np
import pytest

from pulloff.io.scene_file import override
import pulloff
from pulloff.studies import sweeps as sw
from pulloff.cli import main
from pulloff.io.scene_file import load_scene
from pulloff.solvers import simulate

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
SEED = CONFIGS / "seed_flat_punch.yaml"


@pytest.fixture(scope="module")
def seed():
    return load_scene(SEED, overrides=["numerics.rtol=1e-4"])


def test_parse_axis_specs():
    assert sw.parse_axis("loading.v=lin:1:3:3").values == (1.0, 2.0, 3.0)
    log = sw.parse_axis("loading.v=log:1e-6:1e-2:5")
    np.testing.assert_allclose(log.values, [1e-6, 1e-5, 1e-4, 1e-3, 1e-2], rtol=1e-12)
    assert sw.parse_axis("material.eta=0,1e3, 3.0e3").values == (0.0, 1000.0, 3000.0)
    assert sw.parse_axis("model.history=exact,frozen").values == ("exact", "frozen")
    assert sw.parse_axis("loading.v=[1e-3,2e-3]").values == (1e-3, 2e-3)


@pytest.mark.parametrize("text,reason", [("loading.v", "expected"), ("=1,2", "expected"),
                                         ("loading.v=log:0:1:3", "START, STOP > 0"),
                                         ("loading.v=lin:1:2", "lin:START:STOP:COUNT"),
                                         ("loading.v=lin:1:2:x", "integer count"),
                                         ("loading.v=lin:1:2:0", "count must be >= 1")])
def test_bad_axes_are_rejected(text, reason):
    with pytest.raises(sw.SweepError, match=reason):
        sw.parse_axis(text)


@pytest.mark.parametrize("axis,reason", [("loading.speed=1,2", "no such scene key"),
                                         ("material=1,2", "is a section"),
                                         ("adhesion.sigma_c=1,2", None)])
def test_axes_are_checked_against_the_scene_before_any_work(seed, axis, reason, monkeypatch):
    calls = []
    monkeypatch.setattr(sw, "run_point", lambda *a: calls.append(a) or {"status": "ok",
                                                                        "message": ""})
    if reason is None:
        sw.sweep(seed, [axis], workers=1)
        assert len(calls) == 2
        return
    with pytest.raises(sw.SweepError, match=reason):
        sw.sweep(seed, [axis], workers=1)
    assert calls == []


def test_sweep_rows_equal_single_runs_and_run_in_parallel(seed):
    result = sw.sweep(seed, ["loading.v=log:1e-4:1e-2:3", "model.history=exact,frozen"],
                      workers=2)
    t = result.table
    assert t["index"].tolist() == list(range(6))
    assert list(t["model.history"]) == ["exact", "frozen"] * 3
    for r in (0, 3, 5):
        single = simulate(override(seed, [f"loading.v={float(t['loading.v'][r])!r}",
                                               f"model.history={t['model.history'][r]}"]))
        assert t["F_contact_detach"][r] == single.F_contact_detach
        assert t["alpha"][r] == single.groups["alpha"]
        assert t["seed_closed_form_F"][r] == single.analytic["seed_closed_form_F"]
    assert np.all(t["status"] == "ok") and np.all(t["detached"])


def test_parallel_batches_give_every_row_once_as_one_process_does(seed, monkeypatch):
    """Worker processes take growing batches of scenes (here up to MAX_BATCH from the second
    round); every row arrives once, equal to the in-process sweep's."""
    monkeypatch.setattr(sw, "BATCH_SECONDS", 1.0)
    axes = ["loading.v=log:1e-4:1e-2:40", "numerics.rtol=1e-3"]
    parallel = sw.sweep(seed, axes, workers=2).table
    alone = sw.sweep(seed, axes, workers=1).table
    assert parallel["index"].tolist() == list(range(40))
    assert parallel["F_contact_detach"].tolist() == alone["F_contact_detach"].tolist()
    assert np.all(parallel["status"] == "ok")


def test_batch_size_follows_the_slowest_scene_of_a_finished_batch_and_grows_gently():
    ok = [(0, {"wall_time": 0.002}), (1, {"wall_time": 0.003})]
    assert sw._batch_size(ok, 1) == 2  # at most twice the last batch
    assert sw._batch_size(ok, 16) == int(sw.BATCH_SECONDS / 0.003)  # by the slowest scene
    assert sw._batch_size([(0, {"wall_time": 1e-9})], 40) == sw.MAX_BATCH
    assert sw._batch_size([(0, {"wall_time": 10.0})], 7) == 1
    assert sw._batch_size([(0, {"status": "failed"})], 7) == 7  # nothing timed: unchanged


def test_a_failing_scene_is_a_row_and_the_sweep_goes_on(seed):
    t = sw.sweep(seed, ["loading.v=1e-3,-1,2e-3"], workers=1).table
    assert list(t["status"]) == ["ok", "failed", "ok"]
    assert "loading.v" in t["message"][1] and "-1" in t["message"][1]
    assert math.isnan(t["F_contact_detach"][1]) and np.isfinite(t["F_contact_detach"][[0, 2]]).all()


def test_varying_one_dugdale_parameter_holds_delta(seed):
    t = sw.sweep(seed, ["adhesion.sigma_c=2e6,5e6"], workers=1).table
    single = simulate(override(seed, ["adhesion.sigma_c=2e6",
                                           f"adhesion.gamma={2e6 * seed.adhesion.delta!r}"]))
    assert t["F_contact_detach"][0] == pytest.approx(single.F_contact_detach, rel=1e-12)


def test_interrupted_sweep_resumes_without_recomputing(seed, tmp_path, monkeypatch):
    out = tmp_path / "s.h5"
    real = sw.run_point
    calls = []

    def flaky(*args):
        if len(calls) == 3:
            raise KeyboardInterrupt
        calls.append(args[1])
        return real(*args)

    monkeypatch.setattr(sw, "run_point", flaky)
    axes = ["loading.v=log:1e-4:1e-2:5"]
    with pytest.raises(KeyboardInterrupt):
        sw.sweep(seed, axes, out=out, workers=1, flush_seconds=0.0)
    kept = pulloff.load(out)
    assert kept.table["index"].tolist() == [0, 1, 2]
    calls.clear()
    monkeypatch.setattr(sw, "run_point", lambda *a: calls.append(a[1]) or real(*a))
    full = sw.sweep(seed, axes, out=out, workers=1)
    assert len(calls) == 2  # only the two missing rows ran
    assert full.table["index"].tolist() == [0, 1, 2, 3, 4]
    np.testing.assert_array_equal(full.table["F_contact_detach"][:3], kept.table["F_contact_detach"])
    with pytest.raises(sw.SweepError, match="different sweep"):
        sw.sweep(seed, ["loading.v=log:1e-4:1e-2:4"], out=out, workers=1)


def test_histories_on_request(seed, tmp_path):
    out = tmp_path / "h.h5"
    sw.sweep(seed, ["loading.v=1e-3,2e-3"], out=out, workers=1, histories=True)
    back = pulloff.load(out)
    assert sorted(back.histories) == [0, 1]
    h = back.histories[1]
    assert h["F_contact"][-1] == pytest.approx(back.table["F_contact_detach"][1], rel=1e-15)


@pytest.mark.parametrize("overrides", [[], ["model.history=frozen"],
                                       ["model.until=separation", "loading.v=1e-2"]],
                         ids=["onset", "frozen", "contact"])
def test_a_row_without_its_history_is_the_row_with_it(overrides):
    # Rows that keep no history run with a two-row one (sweeps.run_point): nothing in the
    # summary or the closed forms may depend on how many rows the history has.
    from pulloff.io.scene_file import scene_to_yaml

    base = scene_to_yaml(load_scene(SEED, overrides=["numerics.rtol=1e-3"]))
    bare = sw.run_point(base, overrides)
    full = sw.run_point(base, overrides, history=True)
    assert bare["status"] == "ok" and full[sw.ARRAYS]["t"].size > 2
    assert set(bare) == set(full) - {sw.ARRAYS}
    for key, value in bare.items():
        if key != "wall_time":
            assert value == full[key] or (value != value and full[key] != full[key]), key


def test_sweep_on_a_local_dask_cluster(seed):
    from distributed import LocalCluster  # the [dask] extra; part of the test extra too

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address="127.0.0.1:0") as cluster:
        remote = sw.sweep(seed, ["loading.v=log:1e-4:1e-2:4"],
                          scheduler=cluster.scheduler_address)
    local = sw.sweep(seed, ["loading.v=log:1e-4:1e-2:4"], workers=1)
    np.testing.assert_array_equal(remote.table["F_contact_detach"], local.table["F_contact_detach"])


def test_cli_sweep_and_show(tmp_path, capsys):
    out = tmp_path / "cli.h5"
    assert main(["sweep", str(SEED), "--vary", "loading.v=log:1e-4:1e-2:3", "-o", str(out),
                 "--set", "numerics.rtol=1e-4", "--workers", "1", "-q"]) == 0
    printed = capsys.readouterr().out
    assert "3 rows, 0 failed" in printed and "loading.v" in printed
    assert main(["show", str(out)]) == 0
    assert "3 rows, 0 failed" in capsys.readouterr().out
    assert main(["plot", str(out), "-o", str(tmp_path / "sweep.png")]) == 0
    assert (tmp_path / "sweep.png").stat().st_size > 20_000
    assert main(["sweep", str(SEED), "--vary", "loading.speed=1,2", "-o",
                 str(tmp_path / "bad.h5")]) == 2
    assert "loading.speed" in capsys.readouterr().err
    assert not (tmp_path / "bad.h5").exists()


def test_python_api_needs_no_files(tmp_path):
    scene = {"schema": 1, "geometry": {"kind": "flat_punch", "radius": 1e-3},
             "material": {"kind": "kelvin_voigt", "G": 3e5, "eta": 3e3},
             "adhesion": {"kind": "dugdale", "sigma_c": 5e6, "delta": 1e-8},
             "loading": {"kind": "constant_velocity", "v": 1e-3}}
    res = pulloff.run(scene, overrides=["numerics.rtol=1e-4"])
    assert res.detached
    table = pulloff.sweep(scene, ["loading.v=1e-3,1e-2"], workers=1).table
    assert table["F_contact_detach"][0] == pytest.approx(res.F_contact_detach, rel=1e-3)


def test_a_sweep_file_without_its_layout_is_a_clear_error(tmp_path):
    import h5py

    from pulloff.io import h5 as h5io
    from pulloff.studies.sweeps import SweepError, load_sweep

    path = tmp_path / "old.h5"
    with h5py.File(path, "w") as f:
        h5io.stamp(f)
        f.attrs["kind"] = "sweep"
    with pytest.raises(SweepError, match=r"old\.h5: a sweep file without axes, points"):
        load_sweep(path)


def test_sweep_over_a_path_segment_speed_shows_and_plots_the_pull_off(tmp_path, capsys):
    """A path's segment is swept by its index; the table and the figure then show F_pulloff
    (the master curve of a retraction speed) instead of the seed's pull columns."""
    out = tmp_path / "path.h5"
    assert main(["sweep", str(CONFIGS / "sphere_elastic.yaml"), "--vary",
                 "loading.segments.1.speed=1e-6,1e-5", "-o", str(out), "--set",
                 "numerics.rtol=1e-3", "--workers", "1", "-q"]) == 0
    printed = capsys.readouterr().out
    assert "F_pulloff [N]" in printed and "lambda" in printed and "2 rows, 0 failed" in printed
    t = sw.load_sweep(out).table
    assert np.all(np.isfinite(t["F_pulloff"])) and np.all(t["F_pulloff"] > 2e-6)
    assert main(["plot", str(out), "-o", str(tmp_path / "curve.png")]) == 0
    assert (tmp_path / "curve.png").stat().st_size > 20_000
