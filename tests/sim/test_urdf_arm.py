"""An arm read from a URDF: the FR3 written as franka_description states it (joint origins,
inertials) builds the same arm as its modified DH table; fixed links merge into their moving
link; links off the base-flange path are left out; a bad path is one clear error."""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.errors import InputFileError
from ftcomp.sim.arm import FR3_HOME_Q_RAD, chain_flange_pose, dh_flange_pose, fr3_arm
from ftcomp.sim.cell import SimCell
from ftcomp.sim.scene import SceneConfig, flange_body_name
from ftcomp.sim.sensor import SensorSpec

pytest.importorskip("pytransform3d")

from ftcomp.sim.urdf_arm import urdf_arm

TOOL_DOWN = np.diag([1.0, -1.0, -1.0])
#: franka_description's robots/fr3 joint origins (xyz [m], rpy [rad]) of joint1..7.
FR3_URDF_JOINTS = (
    ((0.0, 0.0, 0.333), (0.0, 0.0, 0.0)),
    ((0.0, 0.0, 0.0), (-math.pi / 2, 0.0, 0.0)),
    ((0.0, -0.316, 0.0), (math.pi / 2, 0.0, 0.0)),
    ((0.0825, 0.0, 0.0), (math.pi / 2, 0.0, 0.0)),
    ((-0.0825, 0.384, 0.0), (-math.pi / 2, 0.0, 0.0)),
    ((0.0, 0.0, 0.0), (math.pi / 2, 0.0, 0.0)),
    ((0.088, 0.0, 0.0), (math.pi / 2, 0.0, 0.0)),
)
WEIGHT_KG, WEIGHT_AT_M = 0.2, (0.01, -0.02, 0.03)


def _inertial(mass: float, com: np.ndarray, inertia: np.ndarray) -> str:
    mass, com, inertia = float(mass), np.asarray(com).tolist(), np.asarray(inertia).tolist()
    (xx, xy, xz), (_, yy, yz), (_, _, zz) = inertia
    return (
        f'<inertial><origin xyz="{com[0]!r} {com[1]!r} {com[2]!r}" rpy="0 0 0"/>'
        f'<mass value="{mass!r}"/><inertia ixx="{xx!r}" ixy="{xy!r}" ixz="{xz!r}" '
        f'iyy="{yy!r}" iyz="{yz!r}" izz="{zz!r}"/></inertial>'
    )


def fr3_urdf(tmp_path: Path, *, weight_on_link7: bool = False) -> Path:
    """The FR3 as a URDF from the published joint origins and fr3_arm()'s inertials, with a
    massless flange link8 and a hand branch (its own mass, off the arm's path)."""
    arm = fr3_arm()
    parts = ['<robot name="fr3">', '<link name="fr3_link0"/>']
    for i, (xyz, rpy) in enumerate(FR3_URDF_JOINTS):
        lo, hi = float(arm.joint_lower_rad[i]), float(arm.joint_upper_rad[i])
        parts += [
            f'<link name="fr3_link{i + 1}">'
            + _inertial(arm.link_masses_kg[i], arm.link_com_m[i], arm.link_inertia_kgm2[i])
            + "</link>",
            f'<joint name="fr3_joint{i + 1}" type="revolute"><parent link="fr3_link{i}"/>'
            f'<child link="fr3_link{i + 1}"/><origin xyz="{xyz[0]!r} {xyz[1]!r} {xyz[2]!r}" '
            f'rpy="{rpy[0]!r} {rpy[1]!r} {rpy[2]!r}"/><axis xyz="0 0 1"/>'
            f'<limit lower="{lo!r}" upper="{hi!r}" effort="87" velocity="2.6"/></joint>',
        ]
    parts += [
        '<link name="fr3_link8"/>',
        '<joint name="fr3_joint8" type="fixed"><parent link="fr3_link7"/>'
        '<child link="fr3_link8"/><origin xyz="0 0 0.107" rpy="0 0 0"/></joint>',
        '<link name="fr3_hand">' + _inertial(0.73, np.zeros(3), np.eye(3) * 1e-3) + "</link>",
        '<joint name="fr3_hand_joint" type="fixed"><parent link="fr3_link8"/>'
        '<child link="fr3_hand"/><origin xyz="0 0 0" rpy="0 0 -0.785398"/></joint>',
    ]
    if weight_on_link7:
        parts += [
            '<link name="weight">'
            + _inertial(WEIGHT_KG, np.array(WEIGHT_AT_M), np.eye(3) * 1e-4)
            + "</link>",
            '<joint name="weight_joint" type="fixed"><parent link="fr3_link7"/>'
            '<child link="weight"/><origin xyz="0 0 0" rpy="0 0 0.3"/></joint>',
            '<joint name="weight_to_link8" type="fixed"><parent link="weight"/>'
            '<child link="fr3_link8b"/><origin xyz="0 0 0" rpy="0 0 0"/></joint>',
            '<link name="fr3_link8b"/>',
        ]
    parts.append("</robot>")
    path = tmp_path / "fr3.urdf"
    path.write_text("\n".join(parts), encoding="utf-8")
    return path


def _from_urdf(path: Path, flange_link: str = "fr3_link8"):
    arm = fr3_arm()
    return urdf_arm(
        path,
        base_link="fr3_link0",
        flange_link=flange_link,
        kp=arm.kp,
        kv=arm.kv,
        armature_kgm2=arm.armature_kgm2,
        home_q_rad=FR3_HOME_Q_RAD,
    )


def test_the_urdf_arm_is_the_dh_arm_link_for_link(tmp_path: Path) -> None:
    arm, dh = _from_urdf(fr3_urdf(tmp_path)), fr3_arm()
    assert arm.name == "fr3" and arm.n_joints == 7
    np.testing.assert_array_equal(arm.link_masses_kg, dh.link_masses_kg)
    np.testing.assert_allclose(arm.link_com_m, dh.link_com_m, atol=1e-15)
    np.testing.assert_allclose(arm.link_inertia_kgm2, dh.link_inertia_kgm2, atol=1e-15)
    np.testing.assert_array_equal(arm.joint_lower_rad, dh.joint_lower_rad)
    rng = np.random.default_rng(40)
    for q in [
        np.array(FR3_HOME_Q_RAD),
        *rng.uniform(dh.joint_lower_rad, dh.joint_upper_rad, (30, 7)),
    ]:
        p, R = chain_flange_pose(arm, q)
        p_dh, R_dh = dh_flange_pose(dh, q)
        np.testing.assert_allclose(p, p_dh, atol=1e-12)
        np.testing.assert_allclose(R, R_dh, atol=1e-12)


def test_the_built_model_s_forward_kinematics_is_the_chain_s(tmp_path: Path) -> None:
    arm = _from_urdf(fr3_urdf(tmp_path))
    cell = SimCell(SceneConfig(arm=arm))  # level base: world = base
    m, d = cell.model, cell.data
    flange = m.body(flange_body_name(arm)).id
    rng = np.random.default_rng(41)
    for q in rng.uniform(-math.pi, math.pi, (30, 7)):
        d.qpos[:7] = q
        mujoco.mj_kinematics(m, d)
        p, R = chain_flange_pose(arm, q)
        np.testing.assert_allclose(d.xpos[flange], p, atol=1e-9)
        np.testing.assert_allclose(d.xmat[flange].reshape(3, 3), R, atol=1e-9)


def test_the_urdf_arm_s_cell_reaches_a_pose_and_reads_the_analytic_model(tmp_path: Path) -> None:
    cell = SimCell(SceneConfig(arm=_from_urdf(fr3_urdf(tmp_path))), SensorSpec().ideal())
    R = (Rotation.from_rotvec([0.2, -0.1, 0.0]) * Rotation.from_matrix(TOOL_DOWN)).as_matrix()
    cell.move_pose((0.45, 0.05, 0.40), R, 1.5)
    cell.settle(velocity_tol=1e-7)
    p_now, R_now = cell.sensor_pose()
    assert np.linalg.norm(p_now - (0.45, 0.05, 0.40)) < 1e-4
    error = cell.sensor.read().wrench_sensor - cell.true_gravity_model().predict(R_now)
    assert np.abs(error[:3]).max() < 1e-6 and np.abs(error[3:]).max() < 1e-7


def test_a_link_fixed_to_a_moving_link_joins_its_mass(tmp_path: Path) -> None:
    path = fr3_urdf(tmp_path, weight_on_link7=True)
    arm, dh = _from_urdf(path, flange_link="fr3_link8b"), fr3_arm()
    m7, c7 = dh.link_masses_kg[6], dh.link_com_m[6]
    assert arm.link_masses_kg[6] == pytest.approx(m7 + WEIGHT_KG, abs=1e-15)
    w = Rotation.from_euler("z", 0.3).apply(WEIGHT_AT_M)  # the weight's frame turned 0.3 rad
    com = (m7 * c7 + WEIGHT_KG * w) / (m7 + WEIGHT_KG)
    np.testing.assert_allclose(arm.link_com_m[6], com, atol=1e-15)
    # Both parts' inertias about the common centre of mass (parallel axes).
    expected = dh.link_inertia_kgm2[6] + np.eye(3) * 1e-4
    for m, c in ((m7, c7), (WEIGHT_KG, w)):
        r = c - com
        expected = expected + m * (r @ r * np.eye(3) - np.outer(r, r))
    np.testing.assert_allclose(arm.link_inertia_kgm2[6], expected, atol=1e-15)
    np.testing.assert_array_equal(arm.link_masses_kg[:6], dh.link_masses_kg[:6])
    # The flange fixed to link 7 through the weight's turned frame: at link 7's origin.
    np.testing.assert_allclose(arm.p_link_flange_m, 0.0, atol=1e-15)


def test_a_flange_not_below_the_base_or_a_missing_link_is_one_clear_error(tmp_path: Path) -> None:
    path = fr3_urdf(tmp_path)
    with pytest.raises(InputFileError, match="link 'fr3_link9' is not in the URDF; links: fr3_"):
        _from_urdf(path, flange_link="fr3_link9")
    with pytest.raises(InputFileError, match="no revolute joint between"):
        urdf_arm(
            path,
            base_link="fr3_link7",
            flange_link="fr3_link8",
            kp=[],
            kv=[],
            armature_kgm2=[],
            home_q_rad=[],
        )
    with pytest.raises(InputFileError, match="'fr3_link2' is not below link 'fr3_link5'"):
        urdf_arm(
            path,
            base_link="fr3_link5",
            flange_link="fr3_link2",
            kp=[1.0],
            kv=[1.0],
            armature_kgm2=[1.0],
            home_q_rad=[0.0],
        )
