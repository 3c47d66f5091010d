"""The UR5e of the twin's cell: its MuJoCo body chain is UR's DH table, its links weigh what
UR publishes, the cell reaches the poses the twin starts in, and the twin reports through
``ur_rtde`` the TCP pose UR's DH forward kinematics gives at its joint positions (a check a
user can repeat on a real UR5e's pendant: Move tab, TCP offset zero)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ftcomp.errors import ParameterError
from ftcomp.frames import matrix_from_rotvec

mujoco = pytest.importorskip("mujoco")

from ftcomp.sim.arm import c4_like_arm, dh_flange_pose, ur5e_arm  # noqa: E402
from ftcomp.sim.cell import SimCell  # noqa: E402
from ftcomp.sim.scene import NAMES, SceneConfig, build_mjcf  # noqa: E402
from ftcomp.sim.tool import LoadSpec  # noqa: E402

#: UR's article "DH Parameters for calculations of kinematics and dynamics", UR5e rows:
#: a [m], d [m], alpha [rad], link mass [kg], centre of mass in the link's DH frame [m].
UR5E_A_M = (0.0, -0.425, -0.3922, 0.0, 0.0, 0.0)
UR5E_D_M = (0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996)
UR5E_ALPHA_RAD = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)
UR5E_MASSES_KG = (3.761, 8.058, 2.846, 1.37, 1.3, 0.365)
UR5E_COM_M = (
    (0.0, -0.02561, 0.00193),
    (0.2125, 0.0, 0.11336),
    (0.15, 0.0, 0.0265),
    (0.0, -0.0018, 0.01634),
    (0.0, 0.0018, 0.01634),
    (0.0, 0.0, -0.001159),
)


pytestmark = pytest.mark.live


def ur_dh_product(q: np.ndarray) -> np.ndarray:
    """``T_base_flange`` (4, 4): the product of UR's published rows, written out here."""
    T = np.eye(4)
    for qi, a, d, alpha in zip(q, UR5E_A_M, UR5E_D_M, UR5E_ALPHA_RAD, strict=True):
        cq, sq, ca, sa = math.cos(qi), math.sin(qi), math.cos(alpha), math.sin(alpha)
        T = T @ np.array(
            [
                [cq, -sq * ca, sq * sa, a * cq],
                [sq, cq * ca, -cq * sa, a * sq],
                [0.0, sa, ca, d],
                [0.0, 0.0, 0.0, 1.0],
            ]
        )
    return T


def _model(config: SceneConfig) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(build_mjcf(config))


def test_the_built_model_s_forward_kinematics_is_ur_s_dh_product() -> None:
    m = _model(SceneConfig(arm=ur5e_arm()))  # level base: world = base
    d = mujoco.MjData(m)
    flange = m.body(NAMES["flange"]).id
    rng = np.random.default_rng(20)
    for _ in range(50):
        q = rng.uniform(-2.0 * math.pi, 2.0 * math.pi, 6)
        d.qpos[:6] = q
        mujoco.mj_kinematics(m, d)
        T = ur_dh_product(q)
        # Exact algebra: only rounding separates the two.
        np.testing.assert_allclose(d.xpos[flange], T[:3, 3], atol=1e-9)
        np.testing.assert_allclose(d.xmat[flange].reshape(3, 3), T[:3, :3], atol=1e-9)
        p, R = dh_flange_pose(ur5e_arm(), q)
        np.testing.assert_allclose(p, T[:3, 3], atol=1e-12)
        np.testing.assert_allclose(R, T[:3, :3], atol=1e-12)


def test_the_links_weigh_what_ur_publishes_with_their_centres_of_mass() -> None:
    m = _model(SceneConfig(arm=ur5e_arm()))
    d = mujoco.MjData(m)
    d.qpos[:6] = np.random.default_rng(21).uniform(-math.pi, math.pi, 6)
    mujoco.mj_kinematics(m, d)
    for i in range(6):
        body = m.body(f"link{i + 1}").id
        assert m.body_mass[body] == pytest.approx(UR5E_MASSES_KG[i], abs=1e-12)
        # The link's body is its DH frame: its centre of mass where UR puts it.
        com_world = d.xipos[body]
        com_link = d.xmat[body].reshape(3, 3).T @ (com_world - d.xpos[body])
        np.testing.assert_allclose(com_link, UR5E_COM_M[i], atol=1e-9)


def test_joint_ranges_are_ur_s_plus_minus_360_degrees() -> None:
    arm = ur5e_arm()
    np.testing.assert_allclose(np.degrees(arm.joint_lower_rad), -360.0)
    np.testing.assert_allclose(np.degrees(arm.joint_upper_rad), 360.0)


def test_a_sensor_offset_on_the_flange_needs_a_dh_arm() -> None:
    with pytest.raises(ParameterError, match="p_flange_sensor_m needs an arm given by a DH"):
        SceneConfig(arm=c4_like_arm(), p_flange_sensor_m=(0.0, 0.0, 0.05))


def test_the_sensor_sits_on_the_flange_at_its_offset() -> None:
    offset_m, rotvec = (0.01, -0.02, 0.15), (0.0, 0.3, 0.5)
    scene = SceneConfig(arm=ur5e_arm(), p_flange_sensor_m=offset_m, rotvec_flange_sensor_rad=rotvec)
    cell = SimCell(scene)
    T = ur_dh_product(cell.q_rad)
    p, R = cell.sensor_pose()
    np.testing.assert_allclose(p, T[:3, 3] + T[:3, :3] @ offset_m, atol=1e-9)
    np.testing.assert_allclose(R, T[:3, :3] @ matrix_from_rotvec(rotvec), atol=1e-9)


def test_the_ur5e_cell_holds_a_load_just_above_the_sponge_and_reaches_the_collection_spot() -> None:
    cell = SimCell(SceneConfig(arm=ur5e_arm(), load=LoadSpec(0.5), surface="sponge"))
    p0, R0 = cell.sensor_pose()
    np.testing.assert_allclose(p0, (0.45, 0.0, 0.42), atol=1e-9)  # the home: tool down
    np.testing.assert_allclose(R0, np.diag([1.0, -1.0, -1.0]), atol=1e-9)
    cell.hold_above_surface(0.02, 0.5)
    cell.grasp()
    cell.hold_above_surface(0.002, 0.3)
    p, _ = cell.placement_pose(0.002)
    assert np.linalg.norm(cell.sensor_pose()[0] - p) < 1e-4  # the servo's sag under 0.5 kg


def test_the_twin_reports_ur_s_forward_kinematics_and_ik_within_the_ur5e_s_reach() -> None:
    rtde_receive = pytest.importorskip("rtde_receive")
    rtde_control = pytest.importorskip("rtde_control")
    from standins.twin_process import running_twin

    with running_twin("twin_ur5e_arm", seconds=30.0) as twin:
        receive = rtde_receive.RTDEReceiveInterface(twin.robot_host)
        control = rtde_control.RTDEControlInterface(twin.robot_host)
        try:
            q = np.array(receive.getActualQ())
            pose = receive.getActualTCPPose()
            down = [0.0, math.pi, 0.0]  # rotation vector of diag(1, -1, -1): the tool down
            within = control.getInverseKinematicsHasSolution([0.8, 0.0, 0.3, *down])
            beyond = control.getInverseKinematicsHasSolution([1.0, 0.0, 0.3, *down])
            control.stopScript()
        finally:
            control.disconnect()
            receive.disconnect()
    # The twin starts tool down, 0.45 m in front of the base and 0.42 m above it.
    np.testing.assert_allclose(pose[:3], (0.45, 0.0, 0.42), atol=1e-6)
    T = ur_dh_product(q)
    # The arm stands still: the two reads see the same state to far below a micrometre.
    np.testing.assert_allclose(pose[:3], T[:3, 3], atol=1e-7)
    np.testing.assert_allclose(matrix_from_rotvec(pose[3:]), T[:3, :3], atol=1e-7)
    assert within and not beyond


def test_the_ur5e_cell_sets_a_half_kilogram_load_down_gently_on_the_sponge() -> None:
    from ftcomp.session.placement import PlacementConfig, run_placement
    from ftcomp.sim.placement_cell import SimPlacementCell

    cell = SimPlacementCell("sponge", 0.5, seed=3, arm=ur5e_arm())
    config = PlacementConfig("admittance", k1_m_per_N=1e-4, k2_m_per_s_N=1e-3)  # the paper's
    metrics = run_placement(cell, cell.true_tool_model, config).metrics
    assert metrics["verdict"] == "placed gently", metrics["verdict_reason"]
