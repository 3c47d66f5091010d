"""The URDF chain: pytransform3d's parse, composed in batch, against pytransform3d and MuJoCo."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from pytransform3d.urdf import UrdfTransformManager

from ftcomp.errors import InputFileError
from ftcomp.ros2.bag import JointStates
from ftcomp.ros2.urdf import UrdfChain

sys.path.insert(0, str(Path(__file__).parent))
from simbag import EPOCH_NS, recording


@pytest.fixture(scope="module")
def urdf(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("urdf") / "robot.urdf"
    path.write_text(recording().urdf)
    return path


def test_batch_kinematics_equal_pytransform3d_one_configuration_at_a_time(urdf, rng) -> None:
    chain = UrdfChain(urdf, "base", "ft_sensor")
    assert chain.joint_names == ("j1", "j2", "j3", "j4", "j5", "j6")
    q = rng.uniform(-0.8, 0.8, (20, 6))  # within the limits: pytransform3d clips to them
    T = chain.forward({name: q[:, k] for k, name in enumerate(chain.joint_names)}, len(q))
    manager = UrdfTransformManager(strict_check=False, check=False)
    manager.load_urdf(urdf.read_text())
    for row, T_k in zip(q, T, strict=True):
        for name, value in zip(chain.joint_names, row, strict=True):
            manager.set_joint(name, value)
        np.testing.assert_allclose(T_k, manager.get_transform("ft_sensor", "base"), atol=1e-12)
    # Between two links in different branches: flange seen from the sensor, and back.
    back = UrdfChain(urdf, "ft_sensor", "flange").forward({"j6": np.zeros(1)}, 1)[0]
    np.testing.assert_allclose(back, manager.get_transform("flange", "ft_sensor"), atol=1e-12)


def test_joint_states_give_the_pose_mujoco_computes(urdf) -> None:
    """MuJoCo's forward kinematics of the same joint positions (the recording's link6 pose is
    one physics step behind its joint positions, so it is recomputed here)."""
    import mujoco

    from ftcomp.sim import SceneConfig, SimCell

    rec = recording()
    cell = SimCell(SceneConfig())
    data = mujoco.MjData(cell.model)
    link6 = cell.model.body("link6").id
    q = rec.q_rad[::50]
    t = rec.pose_t_ns[::50]
    p_expected, R_expected = [], []
    for row in q:
        data.qpos[:6] = row
        mujoco.mj_kinematics(cell.model, data)
        p_expected.append(cell.R_world_base.T @ data.xpos[link6])
        R_expected.append(cell.R_world_base.T @ data.xmat[link6].reshape(3, 3))
    names = ("j1", "j2", "j3", "j4", "j5", "j6")
    states = JointStates("/joint_states", t, names, q)
    p, R, valid = UrdfChain(urdf, "base", "flange").sensor_poses(states, t, "test")
    assert valid.all()
    np.testing.assert_allclose(p, p_expected, atol=1e-9)
    np.testing.assert_allclose(R.as_matrix(), R_expected, atol=1e-9)


def test_a_joint_missing_from_the_joint_states_is_named(urdf) -> None:
    chain = UrdfChain(urdf, "base", "ft_sensor")
    states = JointStates("/js", np.array([EPOCH_NS]), ("j1", "j2"), np.zeros((1, 2)))
    with pytest.raises(InputFileError, match=r"joint 'j3' of the chain .* is not in /js; joints"):
        chain.sensor_poses(states, np.array([EPOCH_NS]), "bag")


def test_a_link_not_in_the_urdf_is_named(urdf, tmp_path) -> None:
    with pytest.raises(InputFileError, match="link 'tool0' is not in the URDF; links: base"):
        UrdfChain(urdf, "base", "tool0")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot><link name='a'/>")
    with pytest.raises(InputFileError, match=r"bad\.urdf: not a valid URDF"):
        UrdfChain(bad, "a", "a")
