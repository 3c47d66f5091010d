"""The CLI says what it did and what it could not (issue 13): JSON without a file, too few poses
for leave-one-out, a tilt below its standard error, an optional truth file, gains that position
control would ignore, a placement that a safety limit stopped."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from ftcomp.cli import main
from ftcomp.errors import CalibrationFileError
from ftcomp.io.calibration_json import load_calibration, model_from_dict

from conftest import PAPER_CSV


def test_calibrate_prints_json_without_an_output_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["calibrate", str(PAPER_CSV), "--method", "paper", "--json"]) == 0
    captured = capsys.readouterr()
    assert round(json.loads(captured.out)["tool_weight_N"], 3) == 3.153
    assert list(tmp_path.iterdir()) == []
    assert "warning: tilt not identified" in captured.err


def test_calibrate_says_the_paper_tilt_is_below_its_standard_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["calibrate", str(PAPER_CSV), "--method", "paper"]) == 0
    out = capsys.readouterr().out
    assert "tilt not identified: |U| = 0.204 deg < 0.359 deg" in out
    assert "calibration not written" in out


def test_calibrate_with_three_poses_says_leave_one_out_needs_four(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    three = tmp_path / "three.csv"
    three.write_text("\n".join(PAPER_CSV.read_text().splitlines()[:4]) + "\n")
    assert main(["calibrate", str(three), "--method", "paper", "-o", str(tmp_path / "c.json")]) == 0
    out = capsys.readouterr().out
    assert "nan" not in out
    assert "leave-one-pose-out RMS: needs at least 4 poses (3 given)" in out


def test_collect_without_truth_writes_only_the_samples_and_a_truth_file_says_what_it_is(
    tmp_path: Path,
) -> None:
    samples = tmp_path / "s.csv"
    assert main(["sim", "collect", "--samples-per-pose", "20", "-o", str(samples)]) == 0
    assert [p.name for p in tmp_path.iterdir()] == ["s.csv"]
    truth = tmp_path / "t.json"
    argv = ["sim", "collect", "--samples-per-pose", "20", "-o", str(tmp_path / "s2.csv")]
    assert main([*argv, "--truth", str(truth)]) == 0
    data = json.loads(truth.read_text())
    assert data["format"] == "ftcomp.truth/1" and "not a calibration file" in data["description"]
    assert model_from_dict(data, str(truth)).weight_N == pytest.approx(3.153, abs=1e-9)
    with pytest.raises(CalibrationFileError, match=r"its format is 'ftcomp\.truth/1'"):
        load_calibration(truth)


def test_position_control_refuses_admittance_gains(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["sim", "place", "--surface", "sponge", "--control", "position", "--k1", "0.2"]
    assert main([*argv, "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --k1/--k2 are admittance gains") and err.count("\n") == 1
    assert not (tmp_path / "run").exists()


def test_a_placement_stopped_by_a_safety_limit_exits_1_and_says_why(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Position-only on the stiff book: the force limit ends it before its depth."""
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(PAPER_CSV), "--method", "paper", "-o", str(cal)]) == 0
    out = tmp_path / "run"
    argv = ["sim", "place", "--surface", "book", "--control", "position", "-c", str(cal)]
    capsys.readouterr()
    assert main([*argv, "--out", str(out)]) == 1
    captured = capsys.readouterr()
    assert "verdict (true contact): stopped" in captured.out
    assert captured.err.startswith("error: placement failed: stopped by force limit")
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["verdict"] == "stopped" and metrics["true_press_N"] > 30.0
