"""Faults: outputs that are not files, two writers, signals, killed processes, sweep limits.

Nothing lost, nothing overwritten, nothing silent (issue 13): every bad input ends in exit 2
with one line naming the key and the path, before any work and without a file left behind;
SIGTERM and SIGHUP stop like Ctrl-C (a valid file marked incomplete); a killed writer's
temporary file is removed by the next run; sweep workers die with their parent.
"""

from __future__ import annotations

import functools
import os
import signal
import stat
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

import pulloff
from pulloff.cli import build_parser, main
from pulloff.io import h5 as h5io
from pulloff.io.scene_file import load_scene
from pulloff.studies import sweeps as sw

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
SEED = CONFIGS / "seed_flat_punch.yaml"
QUICK = ["--set", "numerics.rtol=1e-3"]
POSIX = pytest.mark.skipif(os.name != "posix", reason="SIGTERM, SIGHUP, FIFOs and device "
                           "nodes exist only on POSIX systems")


def _listing(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def _one_error_line(err: str, command: str, *words) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"pulloff {command}: error: "), err
    assert "Traceback" not in err
    for word in words:
        assert str(word) in lines[0], (word, err)
    return lines[0]


# --- output targets -------------------------------------------------------------------------

def _make_target(kind: str, path: Path, tmp_path: Path) -> Path:
    """The output target of the given kind at ``path`` (a character device: a private copy of
    /dev/full where device nodes can be made, else the system's /dev/null, which a user
    without that right cannot harm either); returns it."""
    if kind == "directory":
        path.mkdir()
    elif kind == "symlink":
        (tmp_path / "real.h5").write_bytes(b"keep me")
        path.symlink_to(tmp_path / "real.h5")
    elif kind == "dangling symlink":
        path.symlink_to(tmp_path / "nowhere.h5")
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "character device":
        try:  # a private copy of /dev/full (1, 7): never the system's own node
            os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 7))
        except (PermissionError, OSError):
            return Path("/dev/null")
    return path


KINDS = ["directory", "symlink", "dangling symlink", "fifo", "character device"]


@POSIX
@pytest.mark.parametrize("kind", KINDS)
def test_run_refuses_an_output_that_is_not_a_regular_file(tmp_path, capsys, kind):
    target = _make_target(kind, tmp_path / "out.h5", tmp_path)
    before = _listing(tmp_path)
    beside = _listing(target.parent)
    mode = os.lstat(target).st_mode
    assert main(["run", str(SEED), "-o", str(target), "-q", *QUICK]) == 2
    _one_error_line(capsys.readouterr().err, "run", "-o", str(target), "not a regular file")
    assert _listing(tmp_path) == before  # no .png beside it, no lock, no temp file
    assert _listing(target.parent) == beside
    assert os.lstat(target).st_mode == mode
    if kind == "symlink":
        assert (tmp_path / "real.h5").read_bytes() == b"keep me"


@POSIX
@pytest.mark.parametrize("kind", ["fifo", "symlink"])
def test_sweep_and_plot_refuse_such_outputs_too(tmp_path, capsys, kind):
    target = _make_target(kind, tmp_path / "target.h5", tmp_path)
    before = _listing(tmp_path)
    assert main(["sweep", str(SEED), "--vary", "loading.v=1e-3,2e-3", "-o", str(target),
                 "-q", *QUICK]) == 2
    _one_error_line(capsys.readouterr().err, "sweep", "-o", str(target))
    run = tmp_path / "sub" / "run.h5"
    assert main(["run", str(SEED), "-o", str(run), "-q", "--no-plot", *QUICK]) == 0
    capsys.readouterr()
    assert main(["plot", str(run), "-o", str(target)]) == 2
    _one_error_line(capsys.readouterr().err, "plot", "-o", str(target))
    assert sorted(set(_listing(tmp_path)) - {"sub"}) == before


def test_the_figure_beside_the_result_is_checked_too(tmp_path, capsys):
    out = tmp_path / "r.h5"
    (tmp_path / "r.png").mkdir()
    assert main(["run", str(SEED), "-o", str(out), "-q", *QUICK]) == 2
    _one_error_line(capsys.readouterr().err, "run", "figure", "r.png")
    assert main(["run", str(SEED), "-o", str(tmp_path / "same.png"), "-q", *QUICK]) == 2
    _one_error_line(capsys.readouterr().err, "run", "same.png")
    assert _listing(tmp_path) == ["r.png"]


@pytest.mark.parametrize("argv", [
    ["run", str(SEED), "-o", ""],
    ["run", str(SEED), "-o", "   "],
    ["sweep", str(SEED), "--vary", "loading.v=1,2", "-o", ""],
    ["validate", "--small", "-o", ""],
])
def test_an_empty_output_path_is_an_error(tmp_path, capsys, monkeypatch, argv):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    _one_error_line(capsys.readouterr().err, argv[0], "-o", "empty")
    assert _listing(tmp_path) == []


@pytest.mark.parametrize("name", ["../../escaped", "/tmp/absolute", "sub/dir", "..", "a\\b"])
def test_a_scene_name_is_not_a_path(tmp_path, capsys, monkeypatch, name):
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(SEED), "-q", "--set", f"name={name!r}", *QUICK]) == 2
    _one_error_line(capsys.readouterr().err, "run", "name", "not a path")
    assert _listing(tmp_path) == []


def test_a_name_without_output_writes_under_runs(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(SEED), "-q", "--no-plot", "--set", "name=plain name",
                 "--set", "output.path=null", *QUICK]) == 0
    assert (tmp_path / "runs" / "plain name.h5").is_file()


def test_output_path_from_the_scene_is_named_in_the_error(tmp_path, capsys):
    (tmp_path / "d.h5").mkdir()
    assert main(["run", str(SEED), "-q", "--set", f"output.path={tmp_path / 'd.h5'}",
                 *QUICK]) == 2
    _one_error_line(capsys.readouterr().err, "run", "output.path", "d.h5")


# --- two writers ----------------------------------------------------------------------------

_HOLDER = textwrap.dedent("""
    import sys, time
    from pulloff.io import h5
    with h5.output_lock(sys.argv[1]):
        print("ready", flush=True)
        time.sleep(30)
""")


@pytest.fixture
def held(tmp_path):
    """Another process holding the lock of tmp_path/shared.h5."""
    out = tmp_path / "shared.h5"
    proc = subprocess.Popen([sys.executable, "-c", _HOLDER, str(out)], stdout=subprocess.PIPE,
                            text=True)
    try:
        assert proc.stdout.readline().strip() == "ready"
        yield out, proc.pid
    finally:
        proc.kill()
        proc.wait()


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_a_second_writer_is_refused_naming_the_file_and_the_holder(held, capsys, command):
    out, pid = held
    argv = (["run", str(SEED), "-o", str(out), "-q", *QUICK] if command == "run" else
            ["sweep", str(SEED), "--vary", "loading.v=1e-3,2e-3", "-o", str(out), "-q",
             "--workers", "1", *QUICK])
    assert main(argv) == 2
    line = _one_error_line(capsys.readouterr().err, command, str(out), f"pid {pid}",
                           "another pulloff process")
    assert "host" in line
    assert not out.exists()


def test_the_lock_is_released_and_the_next_writer_proceeds(tmp_path, capsys):
    out = tmp_path / "again.h5"
    for _ in range(2):
        assert main(["run", str(SEED), "-o", str(out), "-q", "--no-plot", *QUICK]) == 0
    assert h5io.load(out)["complete"]


# --- signals and killed runs ----------------------------------------------------------------

def _pulloff(*args, **kwargs) -> subprocess.Popen:
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.Popen([sys.executable, "-m", "pulloff.cli", *map(str, args)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            **kwargs)


def _wait_for(condition, timeout=60.0, what="condition"):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


@functools.cache
def _stepper_compiled() -> None:
    """The onset stepper's kernels in numba's disk cache (the seed's default run no longer
    compiles them: it is solved by quadrature), so that a long run's signal arrives while it
    steps, not while it compiles."""
    from pulloff.solvers import simulate

    simulate(load_scene(SEED, overrides=["numerics.steps=64"]))


def _long_run(out: Path) -> subprocess.Popen:
    """A run that takes a minute: a million fixed steps, history streamed into the file."""
    _stepper_compiled()
    return _pulloff("run", SEED, "-o", out, "-q", "--no-plot", "--set", "numerics.steps=1000000")


@POSIX
def test_sigterm_of_a_run_leaves_a_valid_file_marked_incomplete(tmp_path):
    out = tmp_path / "term.h5"
    for delay in (1.0, 4.0):  # a loaded machine may still be setting up after the first
        proc = _long_run(out)
        _wait_for(lambda: h5io.stale_temp_files(out), what="the run's temporary file")
        time.sleep(delay)  # into the stepping
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
        assert proc.returncode == 128 + signal.SIGTERM, err
        assert len(err.splitlines()) == 1 and "SIGTERM" in err and "Traceback" not in err
        assert h5io.stale_temp_files(out) == []
        if out.exists():
            break
        # Stopped before the first step, like Ctrl-C there: nothing computed, no file.
        assert "no partial file written" in err
    assert "complete = False" in err
    record = h5io.load(out)
    assert record["complete"] is False
    t = record["history"]["t"]
    assert t.size >= 1 and t[0] == 0.0 and np.all(np.diff(t) > 0) and np.all(np.isfinite(t))


@POSIX
def test_a_killed_run_leaves_a_temp_file_that_the_next_run_removes(tmp_path, capsys):
    out = tmp_path / "killed.h5"
    proc = _long_run(out)
    _wait_for(lambda: h5io.stale_temp_files(out), what="the run's temporary file")
    proc.kill()
    proc.communicate(timeout=10)
    stale = h5io.stale_temp_files(out)
    assert len(stale) == 1 and not out.exists()
    assert main(["run", str(SEED), "-o", str(out), "-q", "--no-plot", *QUICK]) == 0
    assert h5io.stale_temp_files(out) == []
    assert h5io.load(out)["complete"]


def test_write_errors_name_the_users_path_not_the_temp_file(tmp_path, monkeypatch):
    out = tmp_path / "x.h5"

    def broken(*args, **kwargs):
        raise OSError(28, f"No space left on device: '{args[0]}'")

    monkeypatch.setattr(h5py, "File", broken)
    with pytest.raises(h5io.OutputError) as info:
        with h5io.atomic_file(out):
            pass
    assert str(out) in str(info.value) and ".tmp" not in str(info.value)
    assert _listing(tmp_path) == []


def _children(pid: int) -> list[int]:
    """Every descendant process (workers may hang under a fork server)."""
    found = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            found += [int(c) for c in (task / "children").read_text().split()]
        except OSError:
            pass
    return found + [g for c in found for g in _children(c)]


def _alive(pid: int) -> bool:
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    return "\nState:\tZ" not in status  # a zombie has exited


LONG_SWEEP_POINTS = 50_000  # (below sweeps.MAX_POINTS, the default cap)


def _long_sweep(out: Path):
    """A sweep on two workers that cannot end before the test signals it (50 000 seed scenes,
    ~25 s on two cores of a fast machine; 3000 had ended before the signal there), once both
    workers run: ``(process, worker pids)``."""
    proc = _pulloff("sweep", SEED, "--vary", f"loading.v=log:1e-4:1e-2:{LONG_SWEEP_POINTS}",
                    "-o", out,
                    "--workers", "2", "-q")
    _wait_for(lambda: len(_children(proc.pid)) >= 2, what="two workers")
    return proc, _children(proc.pid)


linux_proc = pytest.mark.skipif(not Path("/proc/self/task").exists() or
                                not sys.platform.startswith("linux"),
                                reason="finds the sweep's worker processes through Linux's "
                                       "/proc")


@linux_proc
def test_sighup_of_a_sweep_keeps_its_rows_and_ends_its_workers(tmp_path):
    out = tmp_path / "hup.h5"
    proc, workers = _long_sweep(out)
    _wait_for(out.exists, what="the first rows in the file")
    proc.send_signal(signal.SIGHUP)
    _, err = proc.communicate(timeout=20)
    assert proc.returncode == 128 + signal.SIGHUP, err
    assert "SIGHUP" in err and "resume" in err and "Traceback" not in err
    _wait_for(lambda: not any(_alive(w) for w in workers), timeout=5, what="workers to end")
    result = pulloff.load(out)
    assert result.complete is False and result.n_points == LONG_SWEEP_POINTS
    kept = result.table["index"]
    assert 0 < kept.size < LONG_SWEEP_POINTS and np.all(result.table["status"] == "ok")
    assert h5io.stale_temp_files(out) == []


@linux_proc
def test_sweep_workers_die_with_their_parent(tmp_path):
    out = tmp_path / "orphans.h5"
    proc, workers = _long_sweep(out)
    proc.kill()
    # A caller reading the pipe is not left hanging by orphans holding it open.
    proc.communicate(timeout=10)
    _wait_for(lambda: not any(_alive(w) for w in workers), timeout=5, what="workers to end")


def test_die_with_parent_polls_where_prctl_is_missing(monkeypatch):
    started = []
    monkeypatch.setattr(sw.sys, "platform", "darwin")
    import threading

    monkeypatch.setattr(threading.Thread, "start", lambda self: started.append(self.name))
    sw.die_with_parent()
    assert started == ["pulloff-parent-watch"]


# --- sweeps: limits and checks before work --------------------------------------------------

@pytest.mark.parametrize("args,words", [
    (["--vary", "loading.v=log:1e-3:1e-1:100000000"], ["100000000", "--max-points"]),
    (["--vary", "loading.v=lin:1:2:1000", "--vary", "material.eta=lin:1:2:1000"],
     ["1000000 points", "--max-points"]),
    (["--vary", "loading.v=1,2,3", "--max-points", "2"], ["--max-points"]),
    (["--vary", "loading.v=1e-3", "--workers", "-2"], ["--workers"]),
    (["--vary", "loading.v=1e-3", "--workers", "0"], ["--workers"]),
    (["--vary", "loading.v=1e-3", "--workers", "two"], ["--workers"]),
    (["--vary", "loading.v=foo:1:2:3"], ["unknown spacing", "foo"]),
    (["--vary", "foo:1:2:3"], ["foo:1:2:3"]),
    (["--vary", "loading.v=1e-3,,2e-3"], ["empty"]),
    (["--vary", "loading.v=1e-3,"], ["empty"]),
    (["--vary", "loading..v=1,2"], ["dotted"]),
    (["--vary", "loading.speed=1,2"], ["loading.speed", "no such scene key"]),
    (["--vary", "loading.v=1,2", "--vary", "loading.v=3,4"], ["given twice"]),
])
def test_sweep_mistakes_are_refused_before_any_work(tmp_path, capsys, monkeypatch, args,
                                                    words):
    ran = []
    monkeypatch.setattr(sw, "run_point", lambda *a: ran.append(a))
    out = tmp_path / "s.h5"
    start = time.perf_counter()
    assert main(["sweep", str(SEED), "-o", str(out), "-q", *args]) == 2
    assert time.perf_counter() - start < 5.0
    _one_error_line(capsys.readouterr().err, "sweep", *words)
    assert ran == [] and _listing(tmp_path) == []


def test_a_large_grid_runs_when_asked_for(tmp_path, monkeypatch):
    monkeypatch.setattr(sw, "run_point", lambda *a: {"status": "ok", "message": ""})
    seed = load_scene(SEED)
    result = sw.sweep(seed, "loading.v=lin:1e-3:2e-3:7", workers=1, max_points=7)
    assert result.n_points == 7 and result.complete
    with pytest.raises(sw.SweepError, match="more than --max-points 6"):
        sw.sweep(seed, "loading.v=lin:1e-3:2e-3:7", workers=1, max_points=6)
    for bad in (0, -2, 1.5, True):
        with pytest.raises(sw.SweepError, match="--workers"):
            sw.sweep(seed, "loading.v=1e-3", workers=bad)


def test_the_grid_is_not_built_as_a_list(monkeypatch):
    """A point is computed from its index; only a few scenes are in flight per worker."""
    axes = [sw.parse_axis("loading.v=lin:1:4:4"), sw.parse_axis("model.history=exact,frozen")]
    layout = sw._Layout.product("x", axes)
    assert [layout.point(i) for i in range(layout.n)] == sw.grid(axes)
    np.testing.assert_array_equal(layout.column(0, np.array([7, 0, 3])), [4.0, 1.0, 2.0])


def test_pulloff_sweep_accepts_one_string(tmp_path, monkeypatch):
    monkeypatch.setattr(sw, "run_point", lambda *a: {"status": "ok", "message": ""})
    result = pulloff.sweep(str(SEED), "loading.v=1e-3,2e-3", workers=1)
    assert result.table["loading.v"].tolist() == [1e-3, 2e-3]


def test_prony_terms_can_be_varied(monkeypatch):
    calls = []
    monkeypatch.setattr(sw, "run_point",
                        lambda base, ov, *a: calls.append(ov) or {"status": "ok", "message": ""})
    scene = load_scene(CONFIGS / "prony_external.yaml")
    sw.sweep(scene, ["material.terms.0.G=1e5,2e5"], workers=1)
    assert calls == [["material.terms.0.G=100000.0"], ["material.terms.0.G=200000.0"]]
    with pytest.raises(sw.SweepError, match="not an index"):
        sw.sweep(scene, ["material.terms.9.G=1e5"], workers=1)


# --- interrupted sweeps: show, load, resume ---------------------------------------------------

@pytest.fixture
def cut_sweep(tmp_path, monkeypatch):
    """A sweep file interrupted after 2 of its 4 rows (rows are quick fakes)."""
    out = tmp_path / "cut.h5"
    calls = []

    def fake(base, overrides, *args):
        if len(calls) == 2:
            raise KeyboardInterrupt
        calls.append(overrides)
        return {"status": "ok", "message": "", "F_contact_detach": 1.0 + len(calls),
                "seed_closed_form_F": 2.0, "alpha": 0.5, "chi": 1e-3, "detached": True}

    monkeypatch.setattr(sw, "run_point", fake)
    with pytest.raises(KeyboardInterrupt):
        sw.sweep(load_scene(SEED), "loading.v=1e-3,2e-3,3e-3,4e-3", out=out, workers=1)
    return out


def test_an_interrupted_sweep_is_marked_incomplete(cut_sweep, capsys):
    result = pulloff.load(cut_sweep)
    assert result.complete is False and result.n_points == 4
    assert result.table["index"].tolist() == [0, 1]
    assert main(["show", str(cut_sweep)]) == 0
    shown = capsys.readouterr().out
    assert shown.splitlines()[0] == "seed_flat_punch"  # the scene's name, not the path
    assert "INCOMPLETE: 2 of 4 planned rows" in shown


def test_show_csv_of_a_sweep_and_of_a_run(cut_sweep, tmp_path, capsys):
    import csv
    import io

    assert main(["show", str(cut_sweep), "--csv"]) == 0
    rows = list(csv.reader(io.StringIO(capsys.readouterr().out)))
    assert rows[0][:2] == ["index", "loading.v [m/s]"] and "F_contact_detach [N]" in rows[0]
    assert len(rows) == 3 and rows[1][1] == "0.001"
    run = tmp_path / "r.h5"
    assert main(["run", str(SEED), "-o", str(run), "-q", "--no-plot", *QUICK]) == 0
    capsys.readouterr()
    assert main(["show", str(run), "--csv"]) == 0
    rows = list(csv.reader(io.StringIO(capsys.readouterr().out)))
    assert rows[0] == ["t [s]", "h [m]", "a [m]", "b [m]", "gap [m]", "F_contact [N]",
                       "F_total [N]", "segment [1]"]
    assert len(rows) - 1 == h5io.load(run)["history_rows_in_file"]


def test_to_dataframe_and_a_clear_error_without_pandas(cut_sweep, monkeypatch):
    result = pulloff.load(cut_sweep)
    pd = pytest.importorskip("pandas")
    frame = result.to_dataframe()
    assert isinstance(frame, pd.DataFrame) and list(frame.index) == [0, 1]
    assert frame["F_contact_detach"].tolist() == [2.0, 3.0]
    assert frame.attrs["complete"] is False and frame.attrs["units"]["loading.v"] == "m/s"
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ImportError, match=r"pandas.*optional extra"):
        result.to_dataframe()


def test_a_changed_grid_keeps_the_shared_rows_when_asked(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(sw, "run_point", lambda base, ov, *a: calls.append(ov) or
                        {"status": "ok", "message": "", "F_contact_detach": 1.0})
    seed = load_scene(SEED)
    out = tmp_path / "grid.h5"
    sw.sweep(seed, "loading.v=1e-3,2e-3,3e-3", out=out, workers=1)
    calls.clear()
    with pytest.raises(sw.SweepError, match="different sweep"):
        sw.sweep(seed, "loading.v=2e-3,3e-3,4e-3,5e-3", out=out, workers=1)
    result = sw.sweep(seed, "loading.v=2e-3,3e-3,4e-3,5e-3", out=out, workers=1, replace=True)
    assert calls == [["loading.v=0.004"], ["loading.v=0.005"]]
    assert result.complete and pulloff.load(out).table["loading.v"].tolist() == \
        [2e-3, 3e-3, 4e-3, 5e-3]


# --- validate ---------------------------------------------------------------------------------

def test_validate_small_never_writes_the_committed_report(tmp_path, monkeypatch, capsys):
    from pulloff.studies import validate

    seen = []
    monkeypatch.setattr(validate, "validate", lambda out, **kw: seen.append(Path(out)) or
                        Path(out) / "report.md")
    monkeypatch.chdir(tmp_path)
    assert main(["validate", "--small", "-q"]) == 0
    assert main(["validate", "--small", "-q", "-o", "validation"]) == 0
    assert main(["validate", "-q"]) == 0
    assert seen == [Path("runs/validation_small"), Path("validation"), Path("validation")]


def test_validate_on_another_grid_recomputes_only_what_differs(tmp_path, monkeypatch):
    from pulloff.studies import validate

    tiny = {"curve_alpha": np.array([0.1, 10.0]), "curve_chi": (1e-6, 1.0),
            "map_alpha": np.array([0.1, 10.0]), "map_chi": np.array([1e-5, 1.0]),
            "speeds": np.array([1e-9, 1e-3, 10.0])}
    more = dict(tiny, curve_alpha=np.array([0.1, 1.0, 10.0]))
    monkeypatch.setitem(validate.GRIDS, "small", tiny)
    monkeypatch.setitem(validate.GRIDS, "full", more)
    real = sw.run_point
    calls = []
    monkeypatch.setattr(sw, "run_point", lambda *a: calls.append(a[1]) or real(*a))
    validate.run_sweeps(tmp_path, rtol=1e-3, small=True, workers=1)
    first = len(calls)
    calls.clear()
    validate.run_sweeps(tmp_path, rtol=1e-3, small=False, workers=1)
    # Only the new alpha (exact at two chi, frozen at one) is computed.
    assert len(calls) == 3 and first == 6 + 4 + 3


# --- messages -------------------------------------------------------------------------------

def test_the_top_level_help_names_what_the_product_covers():
    text = build_parser().description
    for word in ("Kelvin-Voigt", "standard linear solid", "Prony", "flat punches", "spheres",
                 "cones", "power-law", "loading paths"):
        assert word in text


def test_titles_are_the_scene_name(tmp_path, capsys, monkeypatch):
    from pulloff.io import plots

    run = tmp_path / "some_file.h5"
    assert main(["run", str(SEED), "-o", str(run), "-q", "--no-plot", *QUICK,
                 "--set", "name=my scene"]) == 0
    capsys.readouterr()
    assert main(["show", str(run)]) == 0
    assert capsys.readouterr().out.splitlines()[0] == "my scene"
    titles = []
    monkeypatch.setattr(plots, "plot_history", lambda rec, png, title=None: titles.append(title))
    assert main(["plot", str(run)]) == 0
    assert titles == ["my scene"]


def test_multi_problem_scenes_are_one_line(tmp_path, capsys):
    assert main(["run", str(SEED), "--set", "material.G=-1", "--set", "loading.v=0"]) == 2
    _one_error_line(capsys.readouterr().err, "run", "material.G", "loading.v")


def test_an_order_and_a_percentage_only_where_they_mean_something():
    from pulloff.io.console import format_table

    summary = dict(alpha=1.0, chi=1.0, V=1.0, detached=True, t_detach=1.0, h_detach=1.0,
                   b_detach=1.0, zone_ratio_detach=0.1, F_contact_detach=1.0,
                   F_total_detach=1.0, error_estimate=1e-3, until="separation", t_end=1.0,
                   n_elements=1, n_steps=1, wall_time=0.1, F_peak_total=2.0, t_peak_total=1.0,
                   F_peak_contact=1.0, t_peak_contact=1.0, t_separation=2.0)
    record = {"analytic": {"seed_closed_form_F": 12442139.0, "kendall_F": 1.05},
              "history": {"t": np.zeros(3)}}
    for order, shown in ((-0.677, "none: levels not converging"), (1.93, "1.93")):
        text = format_table(dict(record, summary=dict(summary, observed_order=order)))
        assert shown in text and "-0.677" not in text
    assert "+5.00%" in text and "x1.24e+07" in text and "%" not in text.split("x1.24e+07")[0][-20:]


# --- figures ----------------------------------------------------------------------------------

def _record(machine=None):
    t = np.linspace(0.0, 1e-2, 50)
    history = {"t": t, "h": 1e-3 * t, "a": np.full_like(t, 1e-3),
               "b": 1e-3 * (1 + 3e-6 * (1 + t / 1e-2)), "gap": 1e-8 * (t / 1e-2) ** 2,
               "F_contact": 0.02 + 3.0 * t, "F_total": 0.02 + 3.1 * t}
    scene = ("schema: 1\nname: fig\ngeometry: {kind: flat_punch, radius: 0.001}\n"
             "adhesion: {kind: dugdale, sigma_c: 5.0e6, delta: 1.0e-8}\n"
             f"loading: {{kind: constant_velocity, v: 0.001, h0: 0.0, "
             f"machine_stiffness: {machine if machine else 'null'}}}\n")
    summary = {"detached": True, "t_detach": 1e-2, "F_contact_detach": 0.05,
               "until": "separation", "F_peak_total": 0.051, "t_peak_total": 1e-2}
    analytic = {"seed_closed_form_F": 0.0599, "seed_linearised_F": 0.0598, "kendall_F": 0.0388,
                "elastic_F_contact": 0.0388, "viscous_F": 1e-9}
    return {"history": history, "summary": summary, "analytic": analytic, "scene": scene}


def _drawn(monkeypatch):
    from pulloff.io import plots

    figures = []
    monkeypatch.setattr(plots, "_save", lambda fig, path: figures.append(fig) or Path(path))
    return plots, figures


def test_run_figure_reads_as_a_scientist_needs(monkeypatch):
    plots, figures = _drawn(monkeypatch)
    plots.plot_history(_record(), "x.png", title="fig")
    ax_f, ax_r = figures[0].axes[:2]
    labels = [t.get_text() for t in ax_f.get_legend().get_texts()]
    for wanted in ("seed closed form", "Kendall", "elastic MDR-Dugdale F_contact",
                   "onset of detachment", "peak F_total"):
        assert any(label.startswith(wanted) for label in labels), (wanted, labels)
    styles = [(line.get_color(), str(line.get_linestyle()), line.get_dashes() if hasattr(
        line, "get_dashes") else None) for line in ax_f.get_lines()[2:6]]
    assert len({(c, s) for c, s, _ in styles}) == 4  # every closed form its own look
    # The legend sits beside the panel, not over the lines.
    bbox = ax_f.get_legend().get_bbox_to_anchor().transformed(ax_f.transAxes.inverted())
    assert bbox.x0 >= 1.0
    assert ax_r.get_ylabel() == "(b - a)/a"
    assert ax_r.yaxis.get_major_formatter().get_useOffset() is False
    assert len(figures[0].axes) == 4  # force, zone (+ its twin for a), gap: no machine panel


def test_a_compliant_machine_gets_a_driver_and_spring_panel(monkeypatch):
    plots, figures = _drawn(monkeypatch)
    plots.plot_history(_record(machine=100.0), "x.png")
    last = figures[0].axes[3]  # the fourth panel (the twin axis of a comes after)
    labels = [t.get_text() for t in last.get_legend().get_texts()]
    assert labels[0] == "driver h0 + v t" and "punch lift h" in labels
    assert any("spring" in label for label in labels)


def test_force_speed_spends_its_range_on_the_simulated_forces(monkeypatch):
    from types import SimpleNamespace

    plots, figures = _drawn(monkeypatch)
    v = np.logspace(-9, 1, 6)
    F = np.array([0.05, 0.05, 0.05, 0.06, 4.0, 400.0])
    table = {"loading.v": v, "F_contact_detach": F, "F_total_detach": 1.1 * F,
             "seed_closed_form_F": F}
    material = {"G": 0.5e6, "eta": 5e3, "sigma_c": 1e6, "delta": 5e-8, "a": 1e-3}
    plots.plot_force_speed(SimpleNamespace(table=table), material, "x.png")
    low, high = figures[0].axes[0].get_ylim()
    assert low >= 0.05 / 3 and high <= 440 * 3
