"""``ftcomp calibrate`` on a recording with the sensor's temperature, and ``ftcomp
compensate`` with the model it chose, called as a user would: the choice and its evidence,
the slopes per degC, the file, held-out readings at the noise floor, and one-line errors."""

from __future__ import annotations

import contextlib
import csv
import io
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from calibration.temperature_data import SLOPES, floor_N, recording
from ftcomp.cli import main
from ftcomp.cli.common import live_end_lines
from ftcomp.io.samples_csv import write_samples
from ftcomp.samples import Samples
from ftcomp.session.outcome import Outcome
from ftcomp.session.stream import StreamResult


def _write(path: Path, samples: Samples, *, temperature: bool = True) -> Path:
    write_samples(
        path,
        samples.wrench_sensor,
        Rotation.from_matrix(samples.R_base_sensor),
        encoding="quaternion",
        pose=samples.pose,
        t=samples.t,
        extras=dict(samples.extras) if temperature else None,
    )
    return path


def _error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: "), err[:500]
    return err


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """``ftcomp calibrate`` (no model flag) on a recording whose bias follows its temperature:
    the calibration file and what the command printed."""
    folder = tmp_path_factory.mktemp("temperature")
    samples = _write(folder / "samples.csv", recording(1))
    cal = folder / "cal.json"
    out = io.StringIO()
    with contextlib.redirect_stdout(out):  # capsys is per test; the fit is made once
        assert main(["calibrate", str(samples), "-o", str(cal)]) == 0
    return cal, out.getvalue()


def test_calibrate_chooses_the_temperature_model_and_prints_its_slopes(calibrated) -> None:
    cal, printed = calibrated
    assert "model: a bias linear in the sensor's temperature" in printed
    assert "a temperature bias +" in printed and "(needs > 6)" in printed
    assert "Bias temperature slopes" in printed and "per degC" in printed
    entry = json.loads(cal.read_text())["bias_drift"]
    assert entry["model"] == "temperature"
    assert set(entry) >= {"T_ref_C", "T_range_C", "slopes_per_C", "std_errors"}
    slopes, se = np.array(entry["slopes_per_C"]), np.array(entry["std_errors"])
    # estimates from noisy data: within 4 standard errors of the truth
    assert np.all(np.abs(slopes - SLOPES) < 4.0 * se)


def test_compensate_applies_it_to_held_out_readings_down_to_the_noise_floor(
    calibrated, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cal, _ = calibrated
    held_out = _write(tmp_path / "held_out.csv", recording(2, poses=24, low_C=22.5, high_C=27.5))
    out = tmp_path / "out.csv"
    assert main(["compensate", str(held_out), "-c", str(cal), "-o", str(out)]) == 0
    with out.open() as f:
        rows = list(csv.DictReader(f))
    force = np.array([[float(r[c]) for c in ("fx_ext", "fy_ext", "fz_ext")] for r in rows])
    pose = np.array([r["pose"] for r in rows])
    means = np.array([force[pose == p].mean(axis=0) for p in np.unique(pose)])
    # a pose mean's noise is the floor; 1.5x leaves the model's error from 16 poses and a few
    # standard errors of an RMS over 72 numbers (a constant bias: 10x and more)
    assert np.sqrt(np.mean(means**2)) < 1.5 * floor_N()


def test_compensate_warns_where_temperatures_leave_the_calibrated_range(
    calibrated, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cal, _ = calibrated
    hot = _write(tmp_path / "hot.csv", recording(3, poses=4, low_C=29.0, high_C=33.0))
    assert main(["compensate", str(hot), "-c", str(cal), "-o", str(tmp_path / "o.csv")]) == 0
    err = capsys.readouterr().err
    assert "beyond the temperature bias model's range" in err and "held" in err


def test_compensate_without_a_temperature_column_is_one_line_exit_2(
    calibrated, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cal, _ = calibrated
    plain = _write(tmp_path / "plain.csv", recording(2), temperature=False)
    out = tmp_path / "out.csv"
    assert main(["compensate", str(plain), "-c", str(cal), "-o", str(out)]) == 2
    assert "the file has no 'temperature_C' column" in _error_line(capsys)
    assert not out.exists()


def test_a_non_finite_temperature_is_one_line_exit_2_naming_its_row(
    calibrated, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cal, _ = calibrated
    samples = recording(2)
    temperature = samples.extras["temperature_C"].copy()
    temperature[4] = np.nan
    bad = Samples(
        samples.wrench_sensor,
        samples.R_base_sensor,
        "quaternion",
        pose=samples.pose,
        t=samples.t,
        extras={"temperature_C": temperature},
    )
    path = _write(tmp_path / "bad.csv", bad)
    out = tmp_path / "out.csv"
    assert main(["compensate", str(path), "-c", str(cal), "-o", str(out)]) == 2
    assert "row 5, column 'temperature_C'" in _error_line(capsys)
    assert not out.exists()
    assert main(["calibrate", str(path)]) == 2
    assert "row 5, column 'temperature_C'" in _error_line(capsys)


def test_calibrate_temperature_without_temperatures_is_one_line_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plain = _write(tmp_path / "plain.csv", recording(2), temperature=False)
    assert main(["calibrate", str(plain), "--bias-drift", "temperature"]) == 2
    err = _error_line(capsys)
    assert "--bias-drift temperature" in err and "no 'temperature_C' column" in err


def test_calibrate_without_temperatures_never_offers_the_model(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plain = _write(tmp_path / "plain.csv", recording(1), temperature=False)
    assert main(["calibrate", str(plain), "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out).get("bias_drift", {}).get("model") != "temperature"
    assert "temperature" not in captured.err


def test_a_live_session_with_a_sensor_without_temperature_is_one_line_exit_2(
    calibrated, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cal, _ = calibrated
    replay = _write(tmp_path / "replay.csv", recording(2, poses=3), temperature=False)
    out = tmp_path / "log.csv"
    args = ["stream", "--robot", "fixed://?rpy_deg=0,0,0", "--sensor", f"replay://{replay}"]
    assert main([*args, "-c", str(cal), "--seconds", "1", "-o", str(out)]) == 2
    assert "the sensor reports no temperature_C" in _error_line(capsys)
    assert not out.exists()


def test_a_live_sessions_end_says_when_temperatures_left_the_calibrated_range(
    tmp_path: Path,
) -> None:
    said = "temperatures 21 .. 31.5 degC reach beyond ...; above 30 degC the bias is held there"
    result = StreamResult(Outcome.DURATION, "", 10, 1.0, tmp_path / "log.csv")
    assert not any("temperature" in line for line in live_end_lines(result))
    lines = live_end_lines(replace(result, temperature_outside=said))
    assert f"temperature bias model: {said}" in lines
