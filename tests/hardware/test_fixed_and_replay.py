"""fixed:// (a sensor held still) and replay://FILE (a recording played at its own stamps)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.cli import main
from ftcomp.errors import HardwareError, InputFileError, ParameterError
from ftcomp.hardware.registry import open_robot, open_sensor
from ftcomp.hardware.replay import EndOfReplayError

ROWS = 150
PERIOD_S = 0.002


def _recording(path: Path, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A log as ``ftcomp stream`` writes it with a pose: t, fx..tz, qx..qw, px..pz."""
    t = 100.0 + PERIOD_S * np.arange(ROWS)
    wrench = rng.normal(size=(ROWS, 6))
    quat = Rotation.random(ROWS, rng=rng).as_quat()
    p = rng.normal(size=(ROWS, 3))
    data = np.column_stack([t, wrench, quat, p])
    header = "t,fx,fy,fz,tx,ty,tz,qx,qy,qz,qw,px,py,pz"
    np.savetxt(path, data, delimiter=",", header=header, comments="", fmt="%.12g")
    return data, Rotation.from_quat(quat).as_matrix()


def test_replaying_a_log_through_stream_gives_back_every_row(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    source, out = tmp_path / "in.csv", tmp_path / "out.csv"
    data, _ = _recording(source, rng)
    uri = f"replay://{source}"
    code = main(["stream", "--robot", uri, "--sensor", uri, "--seconds", "5", "-o", str(out)])
    assert code == 0  # the end of the recording is a normal end
    logged = np.genfromtxt(out, delimiter=",", skip_header=1, ndmin=2)
    # Every row once, in order, with its own stamp and values (a row or two at either end may
    # fall before the loop's first cycle or after the last).
    n = len(logged)
    start = round((logged[0, 0] - data[0, 0]) / PERIOD_S)
    assert n >= ROWS - 4 and start <= 2
    assert np.allclose(logged[:, :7], data[start : start + n, :7], rtol=0, atol=1e-9)


def test_a_loop_that_stalls_past_the_end_still_gets_every_row(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    source = tmp_path / "in.csv"
    data, _ = _recording(source, rng)
    uri = f"replay://{source}?speed=10"  # the 0.3 s recording lasts 30 ms
    with open_robot(uri) as robot:
        sensor = open_sensor(uri, robot)
        with sensor:
            first = sensor.read_new()
            time.sleep(0.1)  # the loop stalls until well past the end
            robot.pose()  # rows are still to be handed out: not the end yet
            rest = sensor.read_new()
            stamps = [s.t_ns for s in first + rest]
            assert stamps == data[:, 0].round(9).__mul__(1e9).round().astype(int).tolist()
            with pytest.raises(EndOfReplayError):
                sensor.read_new()
            with pytest.raises(EndOfReplayError):
                robot.pose()


def test_a_replayed_sensor_alone_runs_on_the_hosts_clock(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    source = tmp_path / "in.csv"
    data, _ = _recording(source, rng)
    with open_robot("fixed://?rpy_deg=0,180,0") as robot:
        sensor = open_sensor(f"replay://{source}", robot)
        with sensor:
            first = sensor.read()
            assert abs(first.t_ns - robot.now_ns()) < 50_000_000
            assert np.allclose(first.wrench_sensor, data[0, 1:7], rtol=0, atol=1e-9)
            with pytest.raises(EndOfReplayError):
                for _ in range(2000):
                    sensor.read_new()
                    robot.wait_cycle()


def test_the_replayed_robot_reports_the_recorded_poses_and_cannot_move(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    source = tmp_path / "in.csv"
    data, R = _recording(source, rng)
    with open_robot(f"replay://{source}?speed=0.5") as robot:
        pose = robot.pose()
        row = int(np.argmin(np.linalg.norm(R - pose.R_base_tcp, axis=(1, 2))))
        assert np.allclose(pose.R_base_tcp, R[row], atol=1e-9)  # a recorded pose ...
        assert data[row, 0] * 1e9 <= pose.t_ns < data[row, 0] * 1e9 + 2 * PERIOD_S * 1e9  # ... due
        assert np.allclose(pose.p_base_tcp, data[row, 11:14], rtol=0, atol=1e-9)
        assert robot.control_period_s == pytest.approx(PERIOD_S)
        with pytest.raises(HardwareError, match="cannot move"):
            robot.move_pose(np.zeros(3), np.eye(3), 1.0)


def test_fixed_reports_its_pose_and_refuses_motion() -> None:
    with open_robot("fixed://?rpy_deg=0,180,0&xyz_mm=100,0,500&rate_hz=500") as robot:
        pose = robot.pose()
        assert np.allclose(pose.p_base_tcp, [0.1, 0.0, 0.5])
        assert np.allclose(pose.R_base_tcp, np.diag([-1.0, 1.0, -1.0]), atol=1e-12)
        assert robot.control_period_s == pytest.approx(0.002)
        robot.command_twist(np.zeros(6))
        with pytest.raises(HardwareError, match="cannot move"):
            robot.command_twist(np.array([0.0, 0.0, 0.01, 0.0, 0.0, 0.0]))


@pytest.mark.parametrize(
    ("uri", "error", "message"),
    [
        ("replay://", ParameterError, "give the file"),
        ("replay://{missing}", InputFileError, "cannot read"),
        ("replay://{file}?speed=0", ParameterError, "speed must be in"),
        ("fixed://host", ParameterError, "takes options only"),
        ("fixed://?rate_hz=0", ParameterError, "rate_hz must be in"),
    ],
)
def test_bad_replay_and_fixed_uris_are_clear_errors(
    uri: str, error: type[Exception], message: str, tmp_path: Path, rng: np.random.Generator
) -> None:
    source = tmp_path / "in.csv"
    _recording(source, rng)
    with pytest.raises(error, match=message):
        open_robot(uri.format(missing=tmp_path / "none.csv", file=source))


def test_a_replay_without_orientations_cannot_be_a_robot(tmp_path: Path) -> None:
    source = tmp_path / "raw.csv"
    source.write_text("t,fx,fy,fz,tx,ty,tz\n0,1,2,3,4,5,6\n0.001,1,2,3,4,5,6\n")
    with pytest.raises(InputFileError, match="no orientation columns"):
        open_robot(f"replay://{source}")
