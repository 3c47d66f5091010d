"""``ftcomp calibrate --still-segments`` on a log in motion (as ``stream --robot`` writes one):
the still segments found, listed, each used as one pose."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

from ftcomp.calibration.identify import deviations_in_standard_errors
from ftcomp.cli import main
from ftcomp.io.calibration_json import load_calibration
from ftcomp.paper import paper_poses

from conftest import FORCE_NOISE_N, TORQUE_NOISE_NM, TRUE_MODEL

RATE_HZ = 250.0
HOLD_S, MOVE_S = 1.2, 0.6


def _log_in_motion(path: Path, rng: np.random.Generator) -> Path:
    """The paper's nine orientations held 1.2 s each, 0.6 s slerp moves between, at 250 Hz,
    columns as a ``stream --robot`` log (t, fx..tz, qx..qw), no pose column."""
    poses = paper_poses().rotations
    t_s, rotations = [], []
    clock = 0.0
    for k in range(len(poses)):
        if k:
            move = Slerp([0.0, MOVE_S], poses[[k - 1, k]])
            ts = np.arange(0.0, MOVE_S, 1.0 / RATE_HZ)
            t_s.append(clock + ts)
            rotations.append(move(ts).as_quat())
            clock += MOVE_S
        ts = np.arange(0.0, HOLD_S, 1.0 / RATE_HZ)
        t_s.append(clock + ts)
        rotations.append(np.repeat(poses[k].as_quat()[None], len(ts), axis=0))
        clock += HOLD_S
    t = np.concatenate(t_s)
    q = np.concatenate(rotations)
    clean = TRUE_MODEL.predict(Rotation.from_quat(q).as_matrix())
    w = clean + rng.normal(size=clean.shape) * np.repeat([FORCE_NOISE_N, TORQUE_NOISE_NM], 3)
    with path.open("w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["t", "fx", "fy", "fz", "tx", "ty", "tz", "qx", "qy", "qz", "qw"])
        for row in np.column_stack([t, w, q]):
            out.writerow([f"{v:.10g}" for v in row])
    return path


def test_a_log_in_motion_is_calibrated_from_its_still_segments(
    tmp_path: Path, rng: np.random.Generator, capsys: pytest.CaptureFixture[str]
) -> None:
    log = _log_in_motion(tmp_path / "stream.csv", rng)
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(log), "--still-segments", "-o", str(cal)]) == 0
    printed = capsys.readouterr().out
    assert "Still segments in" in printed and "in 9 still segments (one pose each)" in printed
    assert "orientation within 0.03 deg" in printed  # the thresholds used
    deviations = deviations_in_standard_errors(load_calibration(cal), TRUE_MODEL)
    worst = max(deviations, key=deviations.__getitem__)
    # Estimates from noisy readings: 3 standard errors hold with 99.7 % per number.
    assert deviations[worst] <= 3.0, f"{worst}: {deviations[worst]:.2f} standard errors"


def test_the_segments_go_to_stderr_with_json_and_thresholds_are_options(
    tmp_path: Path, rng: np.random.Generator, capsys: pytest.CaptureFixture[str]
) -> None:
    log = _log_in_motion(tmp_path / "stream.csv", rng)
    assert main(["calibrate", str(log), "--still-segments", "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["format"].startswith("ftcomp.calibration")
    assert "in 9 still segments" in captured.err
    # Holds of 1.2 s are shorter than a 2 s minimum: no segment, one line naming the thresholds.
    assert main(["calibrate", str(log), "--still-segments", "--still-min-s", "2"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1
    assert "no still segment" in err and ">= 2 s" in err


def test_a_recording_in_motion_without_still_segments_points_to_the_option(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rotations = Rotation.from_euler("x", np.linspace(0.0, 60.0, 600)[:, None], degrees=True)
    w = TRUE_MODEL.predict(rotations.as_matrix())
    log = tmp_path / "sweep.csv"
    with log.open("w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["t", "fx", "fy", "fz", "tx", "ty", "tz", "qx", "qy", "qz", "qw"])
        for k, row in enumerate(np.column_stack([w, rotations.as_quat()])):
            out.writerow([f"{k / RATE_HZ:.6f}", *(f"{v:.10g}" for v in row)])
    assert main(["calibrate", str(log)]) == 2
    err = capsys.readouterr().err
    assert "(--still-segments for any recording" in err  # the option, not a Python call
    assert "ftcomp.ros2" not in err


def test_still_segments_need_a_time_column(tmp_path: Path, capsys) -> None:
    log = _log_in_motion(tmp_path / "stream.csv", np.random.default_rng(0))
    rows = list(csv.reader(log.open()))
    no_t = tmp_path / "no_t.csv"
    with no_t.open("w", newline="") as f:
        csv.writer(f).writerows(row[1:] for row in rows)
    assert main(["calibrate", str(no_t), "--still-segments"]) == 2
    assert "no 't' column" in capsys.readouterr().err
