"""``ur_rtde``'s own clients drive the twin (no ftcomp code on the client side): moveL arrives
and reports done, speedL moves at its speed, servoL tracks a streamed line, stops hold."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator

import numpy as np
import pytest

rtde_control = pytest.importorskip("rtde_control")
rtde_receive = pytest.importorskip("rtde_receive")
pytest.importorskip("mujoco")

from ftcomp.frames import matrix_from_rotvec  # noqa: E402
from standins.twin_process import Twin, running_twin  # noqa: E402

pytestmark = pytest.mark.live


@pytest.fixture(scope="module")
def twin() -> Iterator[Twin]:
    # It serves the whole module (about 20 s on a quiet host); the block's end stops it. A twin
    # that ended by itself under the clients would leave ur_rtde reconnecting into nothing.
    with running_twin("test_rtde_control", seconds=300.0) as t:
        yield t


@pytest.fixture(scope="module")
def clients(twin: Twin) -> Iterator[tuple[object, object]]:
    control = rtde_control.RTDEControlInterface(twin.robot_host)
    receive = rtde_receive.RTDEReceiveInterface(twin.robot_host)
    yield control, receive
    control.stopScript()
    control.disconnect()
    receive.disconnect()


def _angle_deg(a: list[float], b: list[float]) -> float:
    R = matrix_from_rotvec(a[3:]) @ matrix_from_rotvec(b[3:]).T
    return math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(R) - 1.0) / 2.0))))


def test_moveL_arrives_within_a_millimetre_and_a_tenth_of_a_degree(clients) -> None:
    control, receive = clients
    start = receive.getActualTCPPose()
    R = matrix_from_rotvec(start[3:]) @ matrix_from_rotvec([0.0, 0.0, math.radians(10.0)])
    from ftcomp.frames import rotvec_from_matrix

    target = [start[0] - 0.03, start[1] + 0.02, start[2] + 0.01, *rotvec_from_matrix(R)]
    assert control.moveL(target, 0.2, 1.0)
    reached = receive.getActualTCPPose()
    assert np.linalg.norm(np.subtract(reached[:3], target[:3])) < 1e-3
    assert _angle_deg(reached, target) < 0.1


def _controller_wait(receive: object, seconds: float) -> None:
    """Wait until ``seconds`` of the controller's own clock (RTDE ``timestamp``) pass: the
    twin's time, which runs behind the wall clock when a loaded host holds its loop off."""
    t0 = receive.getTimestamp()  # type: ignore[attr-defined]
    while receive.getTimestamp() - t0 < seconds:  # type: ignore[attr-defined]
        time.sleep(0.005)


def _assert_holds(receive: object) -> None:
    """Once the TCP is at rest (its measured pose moving less than 0.1 mm/s: the servo catches
    up with the stopped reference after it), it stays within 0.1 mm for 0.3 s of the
    controller's time."""
    deadline = time.monotonic() + 10.0
    while True:
        before = receive.getActualTCPPose()  # type: ignore[attr-defined]
        _controller_wait(receive, 0.02)
        moved = np.subtract(receive.getActualTCPPose()[:3], before[:3])  # type: ignore[attr-defined]
        if np.linalg.norm(moved) < 2e-6:
            break
        assert time.monotonic() < deadline, "the TCP did not come to rest"
    held = receive.getActualTCPPose()  # type: ignore[attr-defined]
    _controller_wait(receive, 0.3)
    drift = np.subtract(receive.getActualTCPPose()[:3], held[:3])  # type: ignore[attr-defined]
    assert np.linalg.norm(drift) < 1e-4


def test_speedL_at_10_mm_s_for_one_second_moves_10_mm_and_the_stop_holds(clients) -> None:
    control, receive = clients
    start = receive.getActualTCPPose()
    t0 = receive.getTimestamp()
    while receive.getTimestamp() - t0 < 1.0:  # a second of the controller's clock
        control.speedL([0.0, 0.0, 0.01, 0.0, 0.0, 0.0], 2.0, 0.0)
        time.sleep(0.01)
    control.speedStop(2.0)
    moved = receive.getActualTCPPose()[2] - start[2]
    assert moved == pytest.approx(0.010, abs=0.001)
    _assert_holds(receive)


def test_servoL_tracks_a_streamed_line_and_servoStop_holds(clients) -> None:
    control, receive = clients
    start = receive.getActualTCPPose()
    worst = 0.0
    for k in range(1, 251):  # 0.5 s of a 20 mm/s line in y, one target every 2 ms
        period = control.initPeriod()
        target = [start[0], start[1] + 0.02 * k * 0.002, *start[2:]]
        control.servoL(target, 0.0, 0.0, 0.002, 0.1, 300.0)
        if k > 10:
            actual = receive.getActualTCPPose()
            worst = max(worst, abs(actual[1] - (target[1] - 0.02 * 0.01)))
        control.waitPeriod(period)
    control.servoStop(2.0)
    assert worst < 1e-3
    _assert_holds(receive)


def test_the_twin_answers_reachability_and_safety_limits(clients) -> None:
    control, receive = clients
    pose = receive.getActualTCPPose()
    assert control.getInverseKinematicsHasSolution(pose)
    assert control.isPoseWithinSafetyLimits(pose)
    assert not control.getInverseKinematicsHasSolution([3.0, 0.0, 0.3, *pose[3:]])
    assert receive.getSafetyMode() == 1


#: Untimed: judged by where the moves end and what ur:// says (9 s of moves, beside the other
#: tests under -n 2).
@pytest.mark.untimed
def test_a_moveL_that_a_joint_limit_holds_ends_the_program_as_a_ur_controller_does() -> None:
    """Turning the tool 170 deg about its axis three times winds wrist 3 past its 360 deg: the
    third moveL stops there, the program ends (ur_rtde's moveL returns False), and ur://
    names where the arm stopped (the twin's moveL once reported done there)."""
    from ftcomp.errors import HardwareError
    from ftcomp.hardware.registry import open_robot

    turn = matrix_from_rotvec([0.0, 0.0, math.radians(170.0)])
    fast = "?max_speed_mm_s=250&max_accel_mm_s2=1500"  # 1 rad/s: three 170 deg turns in 9 s
    with (
        running_twin("test_moveL_held", seconds=60.0) as twin,
        open_robot(twin.robot_uri + fast) as robot,
    ):
        here = robot.pose()
        R = here.R_base_tcp @ turn
        robot.move_pose(here.p_base_tcp, R, 1.0)
        robot.move_pose(here.p_base_tcp, R @ turn, 1.0)
        # From -107.2 deg, 510 deg in all: the third stops at 360 deg, 42.8 deg short.
        with pytest.raises(
            HardwareError, match=r"moveL did not complete: the arm stopped 0\.0 mm and 42\.\d deg"
        ):
            robot.move_pose(here.p_base_tcp, R @ turn @ turn, 1.0)
        held = robot.pose()
        time.sleep(0.2)
        assert np.linalg.norm(robot.pose().p_base_tcp - held.p_base_tcp) < 1e-4


def test_moveJ_moves_every_joint_to_its_target_and_reports_done(clients) -> None:
    """The twin once answered moveJ True and left the arm where it was."""
    control, receive = clients
    q0 = np.array(receive.getActualQ())
    q1 = q0 + np.radians([10.0, -8.0, 6.0, 12.0, -9.0, 45.0])
    assert control.moveJ(q1.tolist(), 1.05, 1.4)
    # the servos hold within 0.01 deg (stiff PD loops under the arm's own weight)
    assert np.all(np.abs(np.array(receive.getActualQ()) - q1) < np.radians(0.01))
    assert control.moveJ(q0.tolist(), 1.05, 1.4)


def test_getInverseKinematics_answers_the_solution_nearest_qnear(clients) -> None:
    """The pose where a moveJ put the arm, back through the inverse kinematics near the joints
    there: the same joints (to 1e-6 rad: the solver's 1e-9 m tolerance over the arm's 0.1-0.4 m
    links); near the same joints with wrist 3 a turn on, that turn on (within its +-360 deg)."""
    control, receive = clients
    q0 = np.array(receive.getActualQ())
    assert control.moveJ((q0 + np.radians([5.0, -5.0, 5.0, 5.0, 5.0, 5.0])).tolist(), 1.05, 1.4)
    q, pose = np.array(receive.getActualQ()), receive.getActualTCPPose()
    assert np.allclose(control.getInverseKinematics(pose, q.tolist()), q, atol=1e-6)
    turned = q + np.array([0.0, 0.0, 0.0, 0.0, 0.0, 2.0 * math.pi])
    if turned[5] > 2.0 * math.pi:
        turned[5] -= 4.0 * math.pi
    assert np.allclose(control.getInverseKinematics(pose, turned.tolist()), turned, atol=1e-6)
    assert control.moveJ(q0.tolist(), 1.05, 1.4)


def test_moveJ_IK_moves_the_tcp_to_the_pose(clients) -> None:
    control, receive = clients
    start = receive.getActualTCPPose()
    target = [start[0] + 0.02, start[1] - 0.01, start[2], *start[3:]]
    assert control.moveJ_IK(target, 1.05, 1.4)
    reached = receive.getActualTCPPose()
    assert np.linalg.norm(np.subtract(reached[:3], target[:3])) < 1e-3
    assert _angle_deg(reached, target) < 0.1


def test_a_command_the_twin_does_not_model_fails_as_a_stopped_program() -> None:
    """teachMode (not modelled): ur_rtde sees the program end and returns False, never True
    for a command that did nothing."""
    with running_twin("test_unmodelled_command", seconds=30.0) as twin:
        control = rtde_control.RTDEControlInterface(twin.robot_host)
        try:
            assert not control.teachMode()
            assert not control.isProgramRunning()
        finally:
            control.disconnect()
        assert "command 18 (teachMode) of the control script is not modelled" in twin.output()
