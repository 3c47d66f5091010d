"""The twin's FR3 face on what franky-sim does not simulate, through franka:// and
franky-control's libfranka: a collision reflex from the contact itself (not a declared fault),
the error state it leaves until recovery, and a torque-controlled motion refused.

The declared faults and the whole first session are the conformance suite's
(tests/devices/test_conformance.py); franky-sim's own arm is tests/hardware/test_franka_sim.py's.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

pytest.importorskip("mujoco")
franky = pytest.importorskip("franky", reason="franky-control is not installed (extra franka)")
pytest.importorskip("franky_sim", reason="franky-sim is not installed (extra franka-twin)")

from ftcomp.errors import HardwareError  # noqa: E402
from ftcomp.hardware.registry import open_robot  # noqa: E402
from standins.launch import loopback_address  # noqa: E402
from standins.twin_process import running_twin  # noqa: E402

#: The load hangs this far above the book [mm]; the arm descends this fast [m/s].
CLEARANCE_MM = 2.0
DESCENT_M_S = 0.01
#: The Cartesian force collision threshold the test sets [N]: the load's weight (4.9 N) plus
#: a few newtons of press, far below franky's default (30 N).
THRESHOLD_N = 8.0


pytestmark = pytest.mark.live


def _descend_until_stopped(robot: object, seconds: float) -> str | None:
    """Command the descent each period until the arm stops on an error or ``seconds`` pass;
    the error's line. (Its text only: the exception's traceback holds the frames that hold
    franky's Robot, whose connection closes only when it is collected.)"""
    deadline = time.monotonic() + seconds
    twist = np.array([0.0, 0.0, -DESCENT_M_S, 0.0, 0.0, 0.0])
    while time.monotonic() < deadline:
        try:
            robot.command_twist(twist)  # type: ignore[attr-defined]
            robot.wait_cycle()  # type: ignore[attr-defined]
        except HardwareError as exc:
            return str(exc)
    return None


def test_pressing_into_the_book_past_the_threshold_is_a_cartesian_reflex_until_recovered() -> None:
    options = ("--robot", "fr3", "--load-kg", "0.5", "--surface", "book")
    with running_twin(
        "test_franka_face_reflex", *options, "--clearance-mm", f"{CLEARANCE_MM:g}"
    ) as twin:
        uri = f"{twin.robot_uri}&collision_force_n={THRESHOLD_N:g}"
        with open_robot(uri) as robot:
            stopped = _descend_until_stopped(robot, 5.0)
        assert stopped is not None, "the arm pressed on for 5 s without a reflex"
        assert "cartesian_reflex" in stopped and "the arm stopped" in stopped, stopped
        # The error stays on the arm: a new connection is refused, naming it ...
        with pytest.raises(HardwareError, match=r"error state .*cartesian_reflex"), open_robot(uri):
            pass
        # ... until automatic error recovery, asked for; then the arm moves again (up, with a
        # threshold above the press it stopped in: that press is still there, as on an arm).
        with open_robot(f"{twin.robot_uri}&collision_force_n=30&recover=1") as robot:
            start = robot.pose().p_base_tcp
            robot.move_pose(start + np.array([0.0, 0.0, 0.01]), robot.pose().R_base_tcp, 1.0)
            assert robot.pose().p_base_tcp[2] == pytest.approx(start[2] + 0.01, abs=1e-3)


def test_a_torque_controlled_motion_is_refused_not_ignored() -> None:
    with running_twin("test_franka_face_torque", "--robot", "fr3") as twin:
        arm = franky.Robot(twin.robot_host, realtime_config=franky.RealtimeConfig.Ignore)
        with pytest.raises(Exception, match=r"rejected|not possible") as refused:
            arm.move(franky.TorqueStopMotion())
        assert type(refused.value).__name__ in ("CommandException", "ControlException")
    assert "torque-controlled motion" in twin.output()


def test_franky_sims_model_of_the_fr3_puts_the_flange_where_the_cells_arm_does() -> None:
    """The face serves the cell's arm through franky-sim's server, whose Cartesian commands and
    ``O_T_EE`` come from its own Pinocchio model of the FR3: the two kinematics must agree (both
    from Franka's published parameters), to rounding."""
    import dataclasses

    import mujoco

    from ftcomp.sim.arm import fr3_arm
    from ftcomp.sim.cell_config import CellConfig
    from ftcomp.twin.franka_face import FrankaFace

    cell = dataclasses.replace(CellConfig(), arm=fr3_arm()).open_cell()
    face = FrankaFace(loopback_address("test_franka_face_model"), cell, realtime=False, seed=0)
    try:
        lower, upper = cell.joint_range_rad
        rng = np.random.default_rng(5)
        for _ in range(20):
            q = lower + (upper - lower) * rng.random(7)
            T = face.arm.kinematics(q)
            cell.data.qpos[:7] = q
            mujoco.mj_forward(cell.model, cell.data)
            p, R = cell.sensor_pose()
            assert np.abs(T.translation - p).max() < 1e-12
            assert np.abs(T.rotation - R).max() < 1e-12
    finally:
        face.close()
