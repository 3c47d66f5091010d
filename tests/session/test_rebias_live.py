"""Re-bias at the start of a live session (``--rebias-s``), on the simulated cell."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import ftcomp
from ftcomp.calibration.identify import calibrate
from ftcomp.cli import main
from ftcomp.errors import HardwareError, ParameterError
from ftcomp.io.calibration_json import save_calibration
from ftcomp.model import GravityModel
from ftcomp.session.rebias_live import rebias_still

from conftest import synthetic_samples

#: The bias moved since the calibration (a sensor warming up moves it by about a newton in
#: minutes): beyond the bias tracker's 1 N contact threshold.
MOVED = np.array([0.3, -0.2, 1.1, 0.004, -0.003, 0.002])


def _calibration_off_by(model: GravityModel, moved: np.ndarray, rng: np.random.Generator):
    """A calibration of ``model`` whose bias is ``moved`` short of the sensor's now."""
    then = replace(
        model,
        force_bias_N=model.force_bias_N - moved[:3],
        torque_bias_Nm=model.torque_bias_Nm - moved[3:],
    )
    return calibrate(synthetic_samples(rng, then, poses=12, readings=400))


def test_a_rebias_at_the_start_finds_how_far_the_bias_moved(rng: np.random.Generator) -> None:
    with ftcomp.open_robot("sim://?seed=3") as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        truth = robot.true_gravity_model()  # type: ignore[attr-defined]
        calibration = _calibration_off_by(truth, MOVED, rng)
        result = rebias_still(robot, sensor, calibration, 0.5)
    # 0.5 s of the simulated sensor at 1.2 kHz; the shift within a few standard errors of the
    # re-bias and of the calibration's own bias.
    assert result.readings >= 0.45 * 1200
    se = np.hypot(result.std_errors, _bias_se(calibration))
    assert np.all(np.abs(result.shift - MOVED) < 4 * se), (result.shift, MOVED, se)
    assert result.calibration.bias_drift is None
    assert result.calibration.model.weight_N == calibration.model.weight_N
    assert "re-biased from" in result.line() and "+1.1" in result.line()


def _bias_se(calibration) -> np.ndarray:
    se = calibration.std_errors
    return np.concatenate([se.force_bias_N, se.torque_bias_Nm])


def test_a_rebias_refuses_an_arm_that_moves(rng: np.random.Generator) -> None:
    with ftcomp.open_robot("sim://?seed=3") as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        calibration = _calibration_off_by(robot.true_gravity_model(), MOVED, rng)  # type: ignore[attr-defined]
        robot.command_twist(np.array([0.02, 0.0, 0.0, 0.0, 0.0, 0.0]))
        with pytest.raises(HardwareError, match="the arm moved while the bias was read"):
            rebias_still(robot, sensor, calibration, 0.5)
        with pytest.raises(ParameterError, match=r"duration_s must be in \(0, 60\] s"):
            rebias_still(robot, sensor, calibration, 0.0)


def test_stream_rebias_s_compensates_the_bias_now(tmp_path: Path, rng, capsys) -> None:
    with ftcomp.open_robot("sim://") as robot:
        truth = robot.true_gravity_model()  # type: ignore[attr-defined]
    cal = tmp_path / "cal.json"
    save_calibration(cal, _calibration_off_by(truth, MOVED, rng))
    argv = ["stream", "--robot", "sim://", "--sensor", "sim://", "-c", str(cal), "--seconds", "0.3"]
    assert main([*argv, "--rebias-s", "0.3", "-o", str(tmp_path / "re.csv")]) == 0
    assert "re-biased from" in capsys.readouterr().out
    assert main([*argv, "-o", str(tmp_path / "plain.csv")]) == 0
    header = (tmp_path / "re.csv").read_text().splitlines()[0].split(",")
    k = header.index("cfx")
    for name, off in (("re.csv", np.zeros(3)), ("plain.csv", MOVED[:3])):
        rows = np.loadtxt(tmp_path / name, delimiter=",", skiprows=1, ndmin=2)
        # 360 readings of 0.125 N noise: 0.007 N; the calibration's bias to ~0.005 N.
        np.testing.assert_allclose(rows[:, k : k + 3].mean(axis=0), off, atol=0.03, err_msg=name)


def test_run_rebias_s_starts_the_loop_from_the_bias_now(tmp_path: Path, rng, capsys) -> None:
    with ftcomp.open_robot("sim://") as robot:
        truth = robot.true_gravity_model()  # type: ignore[attr-defined]
    cal = tmp_path / "cal.json"
    save_calibration(cal, _calibration_off_by(truth, MOVED, rng))
    argv = ["run", "--robot", "sim://", "--sensor", "sim://", "-c", str(cal)]
    argv += ["--control", "admittance", "--dry-run", "--seconds", "0.2", "--rebias-s", "0.2"]
    assert main([*argv, "-o", str(tmp_path / "run.csv")]) == 0
    assert "re-biased from" in capsys.readouterr().out
    header = (tmp_path / "run.csv").read_text().splitlines()[0].split(",")
    rows = np.loadtxt(tmp_path / "run.csv", delimiter=",", skiprows=1, ndmin=2)
    # Nothing touches the tool: the force error (base z, the default axis) is noise about zero,
    # not the 1.1 N the bias moved (one reading a cycle, 0.125 N noise over ~200 cycles).
    assert abs(rows[:, header.index("ez")].mean()) < 0.05


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--rebias-s", "0"], "--rebias-s must be in (0, 60] s"),
        (["--rebias-s", "nan"], "--rebias-s must be in (0, 60] s"),
    ],
)
def test_bad_rebias_arguments_are_one_line_and_exit_2(
    tmp_path: Path, rng, capsys, extra: list[str], message: str
) -> None:
    cal = tmp_path / "cal.json"
    save_calibration(cal, calibrate(synthetic_samples(rng)))
    argv = ["stream", "--robot", "sim://", "--sensor", "sim://", "--seconds", "0.1"]
    assert main([*argv, "-c", str(cal), *extra, "-o", str(tmp_path / "a.csv")]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert main([*argv, "--rebias-s", "0.2", "-o", str(tmp_path / "b.csv")]) == 2
    assert "--rebias-s needs the tool's calibration (-c)" in capsys.readouterr().err
    assert not (tmp_path / "a.csv").exists() and not (tmp_path / "b.csv").exists()
