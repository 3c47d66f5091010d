"""``ftcomp sim place`` called as a function: exit code, files, one-line errors."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from ftcomp.cli import main
from ftcomp.session.placement import COLUMNS


def test_place_writes_timeseries_metrics_and_plot(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        ["sim", "place", "--surface", "sponge", "--control", "position", "--out", str(tmp_path)]
    )
    assert code == 0
    assert "depth_reached" in capsys.readouterr().out
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    for key in (
        "placed",
        "final_force_N",
        "peak_press_N",
        "settle_time_s",
        "descent_mm",
        "max_velocity_mm_s",
        "stop_reason",
    ):
        assert key in metrics
    with (tmp_path / "timeseries.csv").open() as handle:
        rows = list(csv.reader(handle))
    assert tuple(rows[0]) == COLUMNS and len(rows) > 100
    assert (tmp_path / "placement.png").stat().st_size > 1000


def test_place_rejects_a_negative_gain_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        [
            "sim",
            "place",
            "--surface",
            "book",
            "--control",
            "admittance",
            "--k2",
            "-1",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --k2 must be >= 0") and err.count("\n") == 1


def test_place_compensates_with_the_calibration_it_is_given(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The chain through files: sim collect -> calibrate -> sim place -c."""
    samples, truth, cal = tmp_path / "s.csv", tmp_path / "t.json", tmp_path / "cal.json"
    collect = ["sim", "collect", "--samples-per-pose", "200", "-o", str(samples)]
    assert main([*collect, "--truth", str(truth)]) == 0
    assert main(["calibrate", str(samples), "-o", str(cal)]) == 0
    out = tmp_path / "run"
    place = ["sim", "place", "--surface", "sponge", "--control", "admittance"]
    assert main([*place, "-c", str(cal), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert f"calibration ({cal})" in printed
    given, used = (json.loads(p.read_text()) for p in (cal, out / "calibration_used.json"))
    for key in ("tool_weight_N", "center_of_gravity_m", "force_bias_N", "base_tilt_deg"):
        assert used[key] == given[key]
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["placed"] and abs(metrics["final_force_N"]) <= 0.05


def test_place_with_an_unreadable_calibration_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "cal.json"
    bad.write_text("{}", encoding="utf-8")
    place = ["sim", "place", "--surface", "book", "--control", "admittance", "-c", str(bad)]
    assert main([*place, "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and str(bad) in err and err.count("\n") == 1


def test_place_keeps_an_earlier_run_unless_forced(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    out.mkdir()
    (out / "metrics.json").write_text('{"mine": true}')
    argv = ["sim", "place", "--surface", "book", "--control", "position", "--out", str(out)]
    assert main(argv) == 2
    assert "not empty; pass --force" in capsys.readouterr().err
    assert json.loads((out / "metrics.json").read_text()) == {"mine": True}
