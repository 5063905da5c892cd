"""pulloff validate (small grids): figures, report and the invariants that must hold."""

from pathlib import Path

import pytest

from pulloff.studies import validate as val
from pulloff.cli import main


@pytest.fixture(scope="module")
def validation(tmp_path_factory):
    out = tmp_path_factory.mktemp("validation")
    report = val.validate(out, rtol=1e-4, small=True, workers=1)
    return out, report


def test_report_and_figures_exist(validation):
    out, report = validation
    text = report.read_text()
    for name in ("alpha_tstar.png", "taylor.png", "force_speed.png", "error_map.png"):
        assert (out / name).stat().st_size > 20_000
        assert f"({name})" in text
    assert "7.34 %" in text and "2.545194" in text


def test_invariants(validation):
    out, _ = validation
    sweeps = val.run_sweeps(Path(out), rtol=1e-4, small=True)  # resumed: nothing recomputed
    curves = val._labelled(*sweeps["curves"])
    emap = val._labelled(*sweeps["map"])
    n = val.summarise(curves, emap, sweeps["speeds"])
    # Frozen history on eq. 53 in the thin-zone limit (chi = 1e-6; measured 4e-5).
    assert n["frozen_vs_eq53"] < 1e-3
    # The elastic and viscous ends of the speed sweep on their closed forms.
    assert abs(n["speed_slowest"][1]) < 1e-4
    assert abs(n["speed_fastest"][1]) < 1e-4
    # The error map is finite everywhere and no scene failed.
    assert n["map_finite"] and n["map_failed"] == 0 and n["speed_failed"] == 0
    # The seed's own number is reproduced.
    assert n["t_star_switch"] == pytest.approx(2.54519, abs=5e-6)
    # The exact model departs from eq. 53 by an O(1) factor where G t / eta ~ 1.
    assert n["exact_vs_eq53_thin"][0] < 0.7


def test_validate_is_idempotent(validation):
    out, report = validation
    before = report.read_text().splitlines()[3:]  # line 3 holds the run time
    val.validate(out, rtol=1e-4, small=True, workers=1)
    assert report.read_text().splitlines()[3:] == before


def test_cli_validate(tmp_path, capsys):
    assert main(["validate", "-o", str(tmp_path), "--small", "-q", "--workers", "1"]) == 0
    assert (tmp_path / "report.md").exists()
    assert "report.md" in capsys.readouterr().out
