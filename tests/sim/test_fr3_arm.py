"""The Franka Research 3, a seven-joint arm given by its modified DH table as data: its MuJoCo
body chain is Franka's kinematics (checked against the URDF's joint origins, an independent
statement of them), its links weigh what franka_description publishes, the cell reaches designed
poses with it and its settled readings are the analytic gravity model, as the UR5e's are."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.errors import ParameterError
from ftcomp.sim.arm import (
    FR3_HOME_Q_RAD,
    DHArmSpec,
    dh_flange_pose,
    fr3_arm,
    ur5e_arm,
)
from ftcomp.sim.cell import SimCell
from ftcomp.sim.cell_config import CellConfig
from ftcomp.sim.scene import SceneConfig, flange_body_name
from ftcomp.sim.sensor import SensorSpec
from ftcomp.sim.tool import LoadSpec

TOOL_DOWN = np.diag([1.0, -1.0, -1.0])

#: franka_description's robots/fr3 joint origins (xyz [m], rpy [rad]) of joint1..7 and the
#: fixed flange joint8: the URDF's own statement of the kinematics, each joint about its z.
FR3_URDF_JOINTS = (
    ((0.0, 0.0, 0.333), (0.0, 0.0, 0.0)),
    ((0.0, 0.0, 0.0), (-math.pi / 2, 0.0, 0.0)),
    ((0.0, -0.316, 0.0), (math.pi / 2, 0.0, 0.0)),
    ((0.0825, 0.0, 0.0), (math.pi / 2, 0.0, 0.0)),
    ((-0.0825, 0.384, 0.0), (-math.pi / 2, 0.0, 0.0)),
    ((0.0, 0.0, 0.0), (math.pi / 2, 0.0, 0.0)),
    ((0.088, 0.0, 0.0), (math.pi / 2, 0.0, 0.0)),
)
FR3_URDF_FLANGE_M = (0.0, 0.0, 0.107)
#: franka_description's robots/fr3/inertials.yaml: link masses [kg], links 1..7.
FR3_MASSES_KG = (
    2.9274653454,
    2.9355370338,
    2.2449013699,
    2.6155955791,
    2.3271207594,
    1.8170376524,
    0.6271432862,
)


def urdf_flange(q: np.ndarray) -> np.ndarray:
    """``T_base_flange`` (4, 4) from the URDF's joint origins: ``T(xyz) R(rpy) Rz(q)``."""
    T = np.eye(4)
    for qi, (xyz, rpy) in zip(q, FR3_URDF_JOINTS, strict=True):
        step = np.eye(4)
        step[:3, :3] = (Rotation.from_euler("xyz", rpy) * Rotation.from_euler("z", qi)).as_matrix()
        step[:3, 3] = xyz
        T = T @ step
    flange = np.eye(4)
    flange[:3, 3] = FR3_URDF_FLANGE_M
    return T @ flange


def test_the_ready_pose_puts_the_flange_tool_down_in_front_of_the_base() -> None:
    p, R = dh_flange_pose(fr3_arm(), FR3_HOME_Q_RAD)
    # Franka's ready pose: with the Franka Hand (its TCP 0.1034 m along the flange's z) the
    # end effector is at (0.307, 0, 0.487) m, given to the millimetre, tool straight down,
    # the hand's x (the flange's turned by -45 deg about the tool axis) along base x.
    np.testing.assert_allclose(p + R @ (0.0, 0.0, 0.1034), (0.307, 0.0, 0.487), atol=5e-4)
    R_hand = R @ Rotation.from_euler("z", -math.pi / 4).as_matrix()
    np.testing.assert_allclose(R_hand, TOOL_DOWN, atol=1e-12)


def test_the_dh_table_is_the_urdf_s_joint_chain() -> None:
    arm = fr3_arm()
    rng = np.random.default_rng(30)
    for _ in range(50):
        q = rng.uniform(arm.joint_lower_rad, arm.joint_upper_rad)
        T = urdf_flange(q)
        p, R = dh_flange_pose(arm, q)
        # Exact algebra: only rounding separates the two.
        np.testing.assert_allclose(p, T[:3, 3], atol=1e-12)
        np.testing.assert_allclose(R, T[:3, :3], atol=1e-12)


def test_the_built_model_s_forward_kinematics_is_the_dh_product() -> None:
    arm = fr3_arm()
    cell = SimCell(SceneConfig(arm=arm))  # level base: world = base
    m, d = cell.model, cell.data
    flange = m.body(flange_body_name(arm)).id
    rng = np.random.default_rng(31)
    for q in [np.array(FR3_HOME_Q_RAD), *rng.uniform(-math.pi, math.pi, (30, 7))]:
        d.qpos[:7] = q
        mujoco.mj_kinematics(m, d)
        p, R = dh_flange_pose(arm, q)
        np.testing.assert_allclose(d.xpos[flange], p, atol=1e-9)
        np.testing.assert_allclose(d.xmat[flange].reshape(3, 3), R, atol=1e-9)


def test_the_links_weigh_what_franka_publishes_with_their_centres_of_mass() -> None:
    arm = fr3_arm()
    cell = SimCell(SceneConfig(arm=arm))
    m, d = cell.model, cell.data
    for i in range(7):
        body = m.body(f"link{i + 1}").id
        assert m.body_mass[body] == pytest.approx(FR3_MASSES_KG[i], abs=1e-12)
        com_link = d.xmat[body].reshape(3, 3).T @ (d.xipos[body] - d.xpos[body])
        np.testing.assert_allclose(com_link, arm.link_com_m[i], atol=1e-12)
        # The full tensor, back in the link frame from MuJoCo's principal axes.
        R = d.xmat[body].reshape(3, 3).T @ d.ximat[body].reshape(3, 3)
        inertia = R @ np.diag(m.body_inertia[body]) @ R.T
        np.testing.assert_allclose(inertia, arm.link_inertia_kgm2[i], atol=1e-12)


def test_the_cell_has_seven_joints_and_franka_s_ranges() -> None:
    cell = SimCell(SceneConfig(arm=fr3_arm()))
    assert cell.n_joints == 7 and cell.joint_names == ("j1", "j2", "j3", "j4", "j5", "j6", "j7")
    assert cell.q_rad.shape == cell.q_command_rad.shape == cell.qd_rad_per_s.shape == (7,)
    lower, upper = cell.joint_range_rad
    assert lower[3] == -3.0421 and upper[3] == -0.1518 and upper[5] == 4.5169
    with pytest.raises(ParameterError, match=r"joint j4=0\.00 deg is outside"):
        cell.move_joints(np.zeros(7), 0.5)
    with pytest.raises(ParameterError, match="q_rad must be 7 finite joint angles"):
        cell.move_joints(np.zeros(6), 0.5)


def test_the_fr3_cell_reaches_designed_poses_and_reads_the_analytic_model() -> None:
    rng = np.random.default_rng(32)
    cell = SimCell(
        SceneConfig(
            tilt_U_rad=math.radians(-0.204), tilt_V_rad=math.radians(-0.129), arm=fr3_arm()
        ),
        SensorSpec().ideal(),
    )
    truth = cell.true_gravity_model()
    worst = np.zeros(2)
    for _ in range(6):
        p = rng.uniform([0.35, -0.2, 0.35], [0.55, 0.2, 0.5])
        tilt = Rotation.from_rotvec([*rng.normal(size=2) * 0.3, 0.0])
        R = (tilt * Rotation.from_matrix(TOOL_DOWN)).as_matrix()
        cell.move_pose(p, R, 1.5)
        cell.settle(velocity_tol=1e-7)
        p_now, R_now = cell.sensor_pose()
        # Servo sag under the tool's weight: stiff gains and feedforward keep it sub-0.1 mm.
        assert np.linalg.norm(p_now - p) < 1e-4
        assert Rotation.from_matrix(R_now.T @ R).magnitude() < 1e-3
        error = cell.sensor.read().wrench_sensor - truth.predict(R_now)
        worst = np.maximum(worst, [np.abs(error[:3]).max(), np.abs(error[3:]).max()])
    assert worst[0] < 1e-6, f"force error {worst[0]:.3g} N"
    assert worst[1] < 1e-7, f"torque error {worst[1]:.3g} N*m"


def test_the_fr3_cell_follows_a_twist_with_seven_joints() -> None:
    cell = SimCell(SceneConfig(arm=fr3_arm()))
    cell.move_pose((0.45, 0.0, 0.42), TOOL_DOWN, 1.0)
    cell.settle()
    p0 = cell.sensor_pose()[0]
    cell.command_twist(np.array([0.0, 0.02, -0.01, 0.0, 0.0, 0.0]))
    cell.step(500)
    cell.stop()
    cell.settle()
    np.testing.assert_allclose(cell.sensor_pose()[0] - p0, (0.0, 0.01, -0.005), atol=2e-4)


def test_a_cell_config_with_the_fr3_holds_a_load_above_the_sponge() -> None:
    config = CellConfig(
        arm=fr3_arm(), load_kg=0.5, grasp=True, surface="sponge", clearance_mm=5.0, seed=1
    )
    with config.open_cell() as cell:
        assert cell.holding
        p, _ = cell.placement_pose(0.005)
        assert np.linalg.norm(cell.sensor_pose()[0] - p) < 2e-4


def test_the_sim_uri_opens_the_fr3() -> None:
    from ftcomp.hardware.registry import open_robot

    with open_robot("sim://?arm=fr3&seed=2") as robot:
        assert isinstance(robot, SimCell) and robot.n_joints == 7


def test_a_dh_arm_rejects_rows_of_different_lengths_and_an_unknown_convention() -> None:
    arm = ur5e_arm()
    with pytest.raises(ParameterError, match="dh_d_m"):
        DHArmSpec(**{**_fields(arm), "dh_d_m": np.zeros(5)})
    with pytest.raises(ParameterError, match="convention: unknown 'craig'"):
        DHArmSpec(**{**_fields(arm), "convention": "craig"})


def _fields(arm: DHArmSpec) -> dict[str, object]:
    from dataclasses import fields

    return {f.name: getattr(arm, f.name) for f in fields(arm)}


def test_a_held_load_on_the_fr3_adds_its_weight() -> None:
    cell = SimCell(SceneConfig(arm=fr3_arm(), load=LoadSpec(0.5)), SensorSpec().ideal())
    cell.move_pose((0.45, 0.0, 0.42), TOOL_DOWN, 1.0)
    cell.grasp()
    cell.settle(velocity_tol=1e-7)
    truth = cell.true_gravity_model()
    error = cell.sensor.read().wrench_sensor - truth.predict(cell.sensor_pose()[1])
    assert np.abs(error[:3]).max() < 1e-5 and np.abs(error[3:]).max() < 1e-6


def test_a_calibration_on_the_fr3_cell_recovers_its_truth_within_three_standard_errors() -> None:
    from ftcomp.calibration.identify import calibrate, deviations_in_standard_errors
    from ftcomp.paper import paper_poses
    from ftcomp.sim.collect import record_with_truth

    cell = CellConfig(arm=fr3_arm(), tilt_deg=(-0.204, -0.129), seed=12).open_cell()
    data, truth = record_with_truth(cell, paper_poses(), 500)  # the paper's nine poses, reached
    deviations = deviations_in_standard_errors(calibrate(data, method="joint"), truth)
    # At the paper's noise level (one count) each estimate is off by noise alone: 3 SE.
    worst = max(deviations, key=deviations.__getitem__)
    assert deviations[worst] < 3.0, f"{worst} is {deviations[worst]:.2f} SE off: {deviations}"
