"""``calibrate --bias-drift/--identify-mount``, ``compensate`` with a drift, ``rebias`` and
``poses design``: called as a user would, exit codes and output."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from calibration.drift_data import readings, tilted_poses, truth
from ftcomp.cli import main
from ftcomp.io.calibration_json import load_calibration

RATE = np.array([0.3, -0.2, 0.25, 0.004, -0.003, 0.002]) / 120.0


def _write(path, samples, *, with_t: bool = True) -> None:
    quat = Rotation.from_matrix(samples.R_base_sensor).as_quat()
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(
            [
                "pose",
                *(["t"] if with_t else []),
                "fx",
                "fy",
                "fz",
                "tx",
                "ty",
                "tz",
                "qx",
                "qy",
                "qz",
                "qw",
            ]
        )
        for k in range(len(samples)):
            t = [f"{samples.t[k]:.6f}"] if with_t else []
            w.writerow([samples.pose[k], *t, *samples.wrench_sensor[k], *quat[k]])


def _drifting_csv(tmp_path, *, with_t: bool = True, t0: float = 0.0):
    rng = np.random.default_rng(21)
    s = readings(
        rng, truth(), tilted_poses(rng, 10), 50, t0_s=t0, drift=lambda t: np.outer(t, RATE)
    )
    path = tmp_path / ("drift.csv" if with_t else "no_t.csv")
    _write(path, s, with_t=with_t)
    return path


def test_calibrate_with_linear_drift_writes_the_model_and_compensate_applies_it(
    tmp_path, capsys
) -> None:
    samples = _drifting_csv(tmp_path)
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(samples), "--bias-drift", "linear", "-o", str(cal)]) == 0
    printed = capsys.readouterr().out
    assert "Bias drift (linear" in printed and "rate per min" in printed
    data = json.loads(cal.read_text())
    assert data["bias_drift"]["model"] == "linear"
    assert data["bias_drift"]["t_range_s"][0] == 0.0
    loaded = load_calibration(cal)
    assert loaded.bias_drift is not None and loaded.bias_drift.order == 1
    out = tmp_path / "out.csv"
    assert main(["compensate", str(samples), "-c", str(cal), "-o", str(out)]) == 0
    assert "reach beyond" not in capsys.readouterr().err
    later = _drifting_csv(
        tmp_path / "later" if (tmp_path / "later").mkdir() is None else tmp_path, t0=500.0
    )
    assert main(["compensate", str(later), "-c", str(cal), "-o", str(tmp_path / "o2.csv")]) == 0
    assert "held at its last estimate, not extrapolated" in capsys.readouterr().err


def test_old_calibration_files_load_without_drift_or_mount(tmp_path) -> None:
    samples = _drifting_csv(tmp_path)
    cal = tmp_path / "cal.json"
    # a constant bias asked for (by default calibrate chooses the drift these readings support)
    assert main(["calibrate", str(samples), "--bias-drift", "none", "-o", str(cal)]) == 0
    data = json.loads(cal.read_text())
    assert "bias_drift" not in data and "mount" not in data
    loaded = load_calibration(cal)
    assert loaded.bias_drift is None and loaded.mount is None


def test_drift_without_a_t_column_is_one_line_exit_2(tmp_path, capsys) -> None:
    samples = _drifting_csv(tmp_path, with_t=False)
    assert main(["calibrate", str(samples), "--bias-drift", "linear"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error:") and "no 't'" in err


def test_too_few_poses_for_the_mount_is_one_line_exit_2(tmp_path, capsys) -> None:
    rng = np.random.default_rng(3)
    path = tmp_path / "few.csv"
    _write(path, readings(rng, truth(), tilted_poses(rng, 5), 20))
    assert main(["calibrate", str(path), "--identify-mount", "full"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "needs at least 6" in err


def test_calibrate_identify_mount_writes_the_mount(tmp_path, capsys) -> None:
    rng = np.random.default_rng(4)
    R = tilted_poses(rng, 10)
    R_fs = Rotation.from_euler("z", 10, degrees=True).as_matrix()
    path = tmp_path / "flange.csv"
    _write(path, readings(rng, truth(), R, 50, R_recorded=R @ R_fs.T))
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(path), "--identify-mount", "yaw", "-o", str(cal)]) == 0
    assert "sensor mount (yaw" in capsys.readouterr().out
    mount = load_calibration(cal).mount
    assert mount is not None
    assert abs(np.degrees(mount.angles_rad[0]) - 10.0) < 3 * np.degrees(mount.std_errors_rad[0])


def test_rebias_writes_a_new_calibration_with_the_new_bias(tmp_path, capsys) -> None:
    samples = _drifting_csv(tmp_path)
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(samples), "-o", str(cal)]) == 0
    rng = np.random.default_rng(8)
    step = np.array([0.5, 0.0, 0.0, 0.0, 0.0, 0.0])
    still = tmp_path / "still.csv"
    _write(
        still,
        readings(
            rng,
            truth(),
            tilted_poses(rng, 1),
            600,
            drift=lambda t: np.broadcast_to(step, (len(t), 6)),
        ),
    )
    new = tmp_path / "new.json"
    assert main(["rebias", str(cal), str(still), "-o", str(new)]) == 0
    assert "bias re-estimated from 600 readings" in capsys.readouterr().out
    fx = load_calibration(new).model.force_bias_N[0]
    # 600 readings: SE 0.125/sqrt(600) = 0.005 N; the tool model's error adds about as much.
    assert abs(fx - (truth().force_bias_N[0] + 0.5)) < 0.03
    assert main(["rebias", str(cal), str(still), "-o", str(new)]) == 2  # no --force


def test_poses_design_writes_a_pose_file_and_prints_the_errors(tmp_path, capsys) -> None:
    out = tmp_path / "poses.csv"
    assert main(["poses", "design", "--count", "6", "-o", str(out), "--max-tilt-deg", "70"]) == 0
    printed = capsys.readouterr().out
    assert "the paper's 9 poses" in printed and "M0" in printed
    from ftcomp.io.poses_csv import read_pose_file

    poses = read_pose_file(out)
    assert len(poses.ids) == 6
    keep = tmp_path / "more.csv"
    assert main(["poses", "design", "--count", "2", "--keep", str(out), "-o", str(keep)]) == 0
    assert len(read_pose_file(keep).ids) == 8


def test_poses_design_count_below_the_minimum_is_one_line_exit_2(tmp_path, capsys) -> None:
    assert main(["poses", "design", "--count", "2", "-o", str(tmp_path / "p.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "at least 3 poses" in err


@pytest.mark.parametrize("value", ["0", "181", "nan"])
def test_poses_design_spin_band_outside_a_half_circle_is_one_line_exit_2(
    tmp_path, capsys, value: str
) -> None:
    out = tmp_path / "p.csv"
    assert main(["poses", "design", "--count", "6", "-o", str(out), "--max-spin-deg", value]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--max-spin-deg" in err and "(0, 180]" in err
    assert not out.exists()


def test_a_live_stream_says_that_it_does_not_apply_the_drift(tmp_path, capsys) -> None:
    cal = tmp_path / "cal.json"
    assert (
        main(["calibrate", str(_drifting_csv(tmp_path)), "--bias-drift", "linear", "-o", str(cal)])
        == 0
    )
    capsys.readouterr()
    out = tmp_path / "log.csv"
    argv = ["stream", "--robot", "sim://", "--sensor", "sim://", "-c", str(cal)]
    assert main([*argv, "--seconds", "0.05", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "bias drift model is held at the end of its session live" in err
    assert "add --track-bias" in err
    # with --track-bias it says the tracking follows the bias, not to add what is given
    out2 = tmp_path / "log2.csv"
    assert main([*argv, "--seconds", "0.05", "--track-bias", "-o", str(out2)]) == 0
    err = capsys.readouterr().err
    assert "--track-bias follows the bias from there" in err and "add --track-bias" not in err
