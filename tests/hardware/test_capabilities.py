"""Capabilities as protocols: every backend has exactly the capabilities it declares, each
checked with ``isinstance`` (issue 19)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ftcomp.errors import ParameterError
from ftcomp.hardware.faults import FaultySensor
from ftcomp.hardware.pacing import RateLimiter, on_host_clock
from ftcomp.hardware.protocols import (
    ChecksReachability,
    CountsLostPackets,
    ReportsLateness,
    ReportsStreamHealth,
    Robot,
    StreamHealth,
    TakesControl,
    WrenchSensor,
)
from ftcomp.hardware.registry import open_robot, open_sensor

ROBOT_CAPABILITIES = (TakesControl, ReportsLateness, ChecksReachability)
SENSOR_CAPABILITIES = (CountsLostPackets, ReportsStreamHealth)


pytestmark = pytest.mark.live


def _replay_file(path: Path) -> str:
    rows = ["t,fx,fy,fz,tx,ty,tz,qx,qy,qz,qw"]
    rows += [f"{0.002 * k},0,0,1,0,0,0,0,0,0,1" for k in range(5)]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return f"replay://{path}"


def _robot(kind: str, tmp_path: Path) -> Robot:
    if kind == "ur":
        pytest.importorskip("rtde_receive")
        return open_robot("ur://127.0.0.9")  # not entered: nothing connects
    if kind in ("ros2", "ros2-servo"):
        pytest.importorskip("rclpy")  # not entered: no participant starts
        servo = "&twist_topic=/servo_node/delta_twist_cmds" if kind == "ros2-servo" else ""
        return open_robot("ros2:///?base_frame=base&tcp_frame=tool0" + servo)
    if kind == "replay":
        return open_robot(_replay_file(tmp_path / "log.csv"))
    return open_robot(
        {"sim": "sim://", "fixed": "fixed://", "posed": "fixed://?rpy_deg=0,180,0"}[kind]
    )


@pytest.mark.parametrize(
    ("kind", "capabilities", "clock", "pose_known"),
    [
        ("sim", {ChecksReachability}, "simulation", True),
        ("fixed", {ReportsLateness}, "monotonic", False),
        ("posed", {ReportsLateness}, "monotonic", True),
        ("replay", set(), "replay", True),
        ("ur", {TakesControl, ReportsLateness, ChecksReachability}, "monotonic", True),
        ("ros2", set(), "monotonic", True),
        ("ros2-servo", set(), "monotonic", True),
    ],
)
def test_each_robot_has_exactly_the_capabilities_it_declares(
    tmp_path: Path, kind: str, capabilities: set[type], clock: str, pose_known: bool
) -> None:
    robot = _robot(kind, tmp_path)
    assert isinstance(robot, Robot)
    for capability in ROBOT_CAPABILITIES + SENSOR_CAPABILITIES:
        assert isinstance(robot, capability) == (capability in capabilities), capability.__name__
    assert robot.clock_name == clock and on_host_clock(robot) == (clock == "monotonic")
    assert robot.pose_known is pose_known


def _sensor(kind: str, tmp_path: Path) -> WrenchSensor:
    if kind == "netft":
        pytest.importorskip("pynetft")
        return open_sensor("netft://127.0.0.9")  # not entered: nothing connects
    if kind == "ur":
        pytest.importorskip("rtde_receive")
        return open_sensor("ur://127.0.0.9", open_robot("ur://127.0.0.9"))
    if kind == "ros2":
        pytest.importorskip("rclpy")  # not entered: no participant starts
        return open_sensor("ros2:///ft/wrench")
    if kind == "replay":
        return open_sensor(_replay_file(tmp_path / "log.csv"))
    if kind == "faulty":
        return FaultySensor(open_sensor("sim://", open_robot("sim://")), "nan", np.inf)
    return open_sensor("sim://", open_robot("sim://"))


@pytest.mark.parametrize(
    ("kind", "capabilities"),
    [
        ("sim", set()),
        ("replay", set()),
        ("faulty", set()),
        ("netft", {CountsLostPackets, ReportsStreamHealth}),
        ("ur", set()),
        ("ros2", set()),
    ],
)
def test_each_sensor_has_exactly_the_capabilities_it_declares(
    tmp_path: Path, kind: str, capabilities: set[type]
) -> None:
    sensor = _sensor(kind, tmp_path)
    assert isinstance(sensor, WrenchSensor)
    for capability in ROBOT_CAPABILITIES + SENSOR_CAPABILITIES:
        assert isinstance(sensor, capability) == (capability in capabilities), capability.__name__


def test_a_paced_robot_reports_its_pacers_lateness() -> None:
    robot = open_robot("fixed://?rate_hz=1000")
    assert isinstance(robot, ReportsLateness)
    now = [0.0]
    robot.pacer = RateLimiter(  # type: ignore[attr-defined]
        0.001, clock=lambda: now[0], sleep=lambda s: None, log_overruns=False
    )
    assert (robot.periods_behind, robot.late_cycles, robot.worst_lateness_s) == (0, 0, 0.0)
    # Periods end at 1, 2, 3 ms: the first two cycles end 0.5 and 0.2 ms late, the third early.
    for now[0] in (0.0015, 0.0022):
        robot.wait_cycle()
    assert robot.periods_behind == 0 and robot.late_cycles == 2
    assert robot.worst_lateness_s == pytest.approx(0.0005, abs=1e-12)
    now[0] = 0.0025
    robot.wait_cycle()
    assert robot.periods_behind == 0 and robot.late_cycles == 2
    now[0] = 0.0075  # a stall: 3.5 ms past the period that ended at 4 ms
    robot.wait_cycle()
    assert robot.periods_behind == 3 and robot.late_cycles == 3


def test_the_simulated_cell_checks_reachability_without_changing_later_moves() -> None:
    from ftcomp.sim import COLLECTION_POSITION_BASE_M, SimCell

    down = np.diag([1.0, -1.0, -1.0])
    p = np.array(COLLECTION_POSITION_BASE_M)
    cell, twin = SimCell(), SimCell()
    assert cell.is_reachable(p, down)
    assert not cell.is_reachable(np.array([2.0, 0.0, 0.42]), down)  # 2 m out: beyond the arm
    # The check changes nothing: the cell's next solve is the same as that of a twin that
    # never checked.
    far = np.array([0.3, 0.35, 0.25])
    np.testing.assert_array_equal(cell.solve_ik(far, down), twin.solve_ik(far, down))
    np.testing.assert_array_equal(cell.q_command_rad, twin.q_command_rad)


def test_stream_health_refuses_negative_counts() -> None:
    with pytest.raises(ParameterError, match="lost_packets=-1"):
        StreamHealth(10, -1, None, 1000.0, "N", "N-m")
