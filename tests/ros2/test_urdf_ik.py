"""Inverse kinematics of a URDF chain: the Jacobian, recovered poses, joint limits, defaults."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.chain_ik import ChainIk, mid_configuration
from ftcomp.errors import InputFileError
from ftcomp.ros2.urdf import UrdfChain
from ftcomp.ros2.urdf_ik import front_position

sys.path.insert(0, str(Path(__file__).parent))
from simbag import urdf_of_cell

#: A tree with a movable joint on each side of the common ancestor ``link1``: a camera on a
#: prismatic slide and a pan joint (continuous), an arm with a prismatic joint in its middle.
BRANCHED = """<?xml version="1.0"?>
<robot name="branched">
  <link name="base"/><link name="link1"/><link name="link2"/><link name="link3"/>
  <link name="tip"/><link name="slide"/><link name="camera"/>
  <joint name="a1" type="revolute"><parent link="base"/><child link="link1"/>
    <origin xyz="0 0 0.3" rpy="0 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3"/></joint>
  <joint name="a2" type="prismatic"><parent link="link1"/><child link="link2"/>
    <origin xyz="0.1 0 0" rpy="0.3 0 0"/><axis xyz="1 0 0"/><limit lower="0" upper="0.4"/></joint>
  <joint name="a3" type="revolute"><parent link="link2"/><child link="link3"/>
    <origin xyz="0 0.2 0" rpy="0 0.5 0"/><axis xyz="0 1 1"/><limit lower="-2" upper="2"/></joint>
  <joint name="fixed_tip" type="fixed"><parent link="link3"/><child link="tip"/>
    <origin xyz="0.05 0 0.1" rpy="0.1 0.2 0.3"/></joint>
  <joint name="c1" type="prismatic"><parent link="link1"/><child link="slide"/>
    <origin xyz="0 0 0.2" rpy="0 0 0"/><axis xyz="0 0 1"/><limit lower="-0.1" upper="0.1"/></joint>
  <joint name="c2" type="continuous"><parent link="slide"/><child link="camera"/>
    <origin xyz="0 0.1 0" rpy="0 0 1.0"/><axis xyz="1 0 0"/></joint>
</robot>
"""


@pytest.fixture(scope="module")
def arm_text() -> str:
    """The simulated six-joint arm as URDF (base -> ... -> flange -> ft_sensor)."""
    from ftcomp.sim import SceneConfig, SimCell

    return urdf_of_cell(SimCell(SceneConfig()))


@pytest.fixture(scope="module")
def arm(arm_text: str, tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("urdf") / "arm.urdf"
    path.write_text(arm_text)
    return path


def _limit_j1(text: str, lower: float, upper: float) -> str:
    """The arm's URDF with joint j1's range replaced."""
    head, rest = text.split('<joint name="j1"', 1)
    joint, tail = rest.split("</joint>", 1)
    start = joint.index("<limit")
    end = joint.index("/>", start) + 2
    limit = f'<limit lower="{lower!r}" upper="{upper!r}" effort="9" velocity="3"/>'
    return f'{head}<joint name="j1"{joint[:start]}{limit}{joint[end:]}</joint>{tail}'


def _batch(chain: UrdfChain, q: np.ndarray) -> np.ndarray:
    """The same configuration through the batch kinematics."""
    return chain.forward({n: np.array([v]) for n, v in zip(chain.joint_names, q, strict=True)}, 1)[
        0
    ]


def _finite_difference_jacobian(chain: UrdfChain, q: np.ndarray) -> np.ndarray:
    """Central differences of the tip's position and of its rotation (``dR R^T`` = ``[w]x``)."""
    T0, _ = chain.pose_and_jacobian(q)
    h = 1e-6
    J = np.zeros((6, len(q)))
    for i in range(len(q)):
        dq = np.zeros(len(q))
        dq[i] = h
        Tp, _ = chain.pose_and_jacobian(q + dq)
        Tm, _ = chain.pose_and_jacobian(q - dq)
        J[:3, i] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        W = (Tp[:3, :3] - Tm[:3, :3]) / (2 * h) @ T0[:3, :3].T
        J[3:, i] = (W[2, 1], W[0, 2], W[1, 0])
    return J


@pytest.mark.parametrize(
    ("base", "tip"), [("base", "ft_sensor"), ("flange", "base"), ("link3", "ft_sensor")]
)
def test_the_jacobian_of_the_arm_matches_finite_differences(arm, rng, base, tip) -> None:
    """Error of central differences with h = 1e-6: truncation h^2 ~ 1e-12, rounding
    1e-16 / h ~ 1e-10; 1e-8 is far above both and far below any wrong column (~0.1)."""
    chain = UrdfChain(arm, base, tip)
    for q in rng.uniform(-1.0, 1.0, (5, len(chain.joint_names))):
        T, J = chain.pose_and_jacobian(q)
        batch = _batch(chain, q)
        np.testing.assert_allclose(T, batch, atol=1e-12)
        np.testing.assert_allclose(J, _finite_difference_jacobian(chain, q), atol=1e-8)


def test_a_branched_chain_with_prismatic_and_continuous_joints_has_the_right_jacobian(
    tmp_path, rng
) -> None:
    path = tmp_path / "branched.urdf"
    path.write_text(BRANCHED)
    chain = UrdfChain(path, "camera", "tip")  # up through c2, c1, down through a2, a3
    assert chain.joint_names == ("c1", "c2", "a2", "a3")
    assert chain.joint_revolute == (False, True, False, True)
    np.testing.assert_array_equal(
        chain.joint_limits, [[-0.1, 0.1], [-np.inf, np.inf], [0.0, 0.4], [-2.0, 2.0]]
    )
    for q in rng.uniform(-1.0, 1.0, (5, 4)):
        T, J = chain.pose_and_jacobian(q)
        batch = _batch(chain, q)
        np.testing.assert_allclose(T, batch, atol=1e-12)
        np.testing.assert_allclose(J, _finite_difference_jacobian(chain, q), atol=1e-8)


def test_ik_recovers_the_pose_of_known_configurations(arm, rng) -> None:
    """A pose reached exactly: the solver stops when a step moves q by less than 1e-12
    relative, after quadratic convergence, so the pose error is near 1e-12; 1e-6 m and 1e-6 rad
    are far below the acceptance tolerances (1 mm, 0.1 deg) and would catch a solver that only
    met those."""
    chain = UrdfChain(arm)
    ik = ChainIk(chain)
    lower, upper = chain.joint_limits.T
    margin = 0.1 * (upper - lower)  # away from the limits, where a pose has few solutions
    for q_true in rng.uniform(lower + margin, upper - margin, (12, 6)):
        p, R = ik.pose(q_true)
        q = ik.solve(p, R)
        assert q is not None, q_true
        assert np.all(q >= lower) and np.all(q <= upper)
        dp, angle = ik.errors(q, p, R)
        assert dp < 1e-6 and angle < 1e-6, (q_true, dp, angle)


def test_ik_rejects_a_pose_reachable_only_outside_the_joint_limits(arm, arm_text, tmp_path):
    """The tip turned 1 rad about the base axis: with j1 limited to +-0.5 rad no configuration
    reaches it (the arm can reach that side only by turning j1 to 1 rad or 1 - pi)."""
    full = ChainIk(UrdfChain(arm))
    q_true = np.array([1.0, 0.3, 1.2, 0.2, 0.8, -0.4])
    p, R = full.pose(q_true)
    q = full.solve(p, R)
    assert q is not None
    narrow_path = tmp_path / "narrow.urdf"
    narrow_path.write_text(_limit_j1(arm_text, -0.5, 0.5))
    narrow = ChainIk(UrdfChain(narrow_path))
    np.testing.assert_array_equal(narrow.chain.joint_limits[0], [-0.5, 0.5])
    assert narrow.solve(p, R) is None
    assert narrow.solve(p) is None  # not even the position
    q_in = q_true.copy()
    q_in[0] = 0.4  # the same arm pose turned back within the limits: reachable
    assert narrow.solve(*narrow.pose(q_in)) is not None


def test_ik_agrees_with_the_simulated_cell_on_reachable_orientations(arm) -> None:
    """The simulated cell's own IK (MuJoCo Jacobians, 32 seeds) is an independent check: at a
    position where some orientations are out of reach, both give the same verdict (on 400
    orientations at three positions they agreed on every one; 16 here, for time)."""
    from ftcomp.calibration.design import candidate_orientations
    from ftcomp.errors import UnreachablePoseError
    from ftcomp.sim import SceneConfig, SimCell

    cell = SimCell(SceneConfig())
    ik = ChainIk(UrdfChain(arm))
    p = np.array([0.595, 0.0, 0.74])  # the tip at the zero configuration: 2 of 16 out of reach
    candidates = candidate_orientations(directions=8, spins=2)
    ours = [ik.solve(p, R) is not None for R in candidates]
    theirs = []
    for R in candidates:
        try:
            cell.solve_ik(p, R)
            theirs.append(True)
        except UnreachablePoseError:
            theirs.append(False)
    assert ours == theirs
    assert 0 < sum(ours) < len(ours)


def test_default_links_are_the_root_and_the_single_leaf(arm, tmp_path) -> None:
    chain = UrdfChain(arm)
    assert (chain.base_link, chain.tip_link) == ("base", "ft_sensor")
    branched = tmp_path / "branched.urdf"
    branched.write_text(BRANCHED)
    with pytest.raises(InputFileError, match=r"no single tip link below 'base'.*camera, tip"):
        UrdfChain(branched)
    assert UrdfChain(branched, sensor="tip").base_link == "base"


def test_bad_limits_and_disconnected_links_are_named(arm_text, tmp_path) -> None:
    bad = tmp_path / "bad.urdf"
    bad.write_text(_limit_j1(arm_text, 1.0, -1.0))
    with pytest.raises(InputFileError, match="joint 'j1' has lower limit 1 above upper -1"):
        UrdfChain(bad)
    two = tmp_path / "two.urdf"
    two.write_text('<robot name="r"><link name="a"/><link name="b"/></robot>')
    with pytest.raises(InputFileError, match=r"2 root links \(a, b\)"):
        UrdfChain(two)
    with pytest.raises(InputFileError, match="links 'a' and 'b' are not connected"):
        UrdfChain(two, "a", "b")


def test_the_front_position_is_half_the_chain_ahead_at_shoulder_height(arm) -> None:
    """The arm at zero: joint origins (0,0,0), (0.1,0,0.32), (0.1,0,0.72), (0.1,0,0.74),
    (0.5,0,0.74), (0.565,0,0.74) and the tip 0.03 further along x (exact algebra)."""
    chain = UrdfChain(arm)
    length = math.hypot(0.1, 0.32) + 0.4 + 0.02 + 0.4 + 0.065 + 0.03
    np.testing.assert_allclose(front_position(chain), [length / 2, 0.0, 0.32], atol=1e-12)
    ik = ChainIk(chain)
    down = Rotation.from_euler("x", 180, degrees=True).as_matrix()
    assert ik.solve(front_position(chain), down) is not None
    np.testing.assert_allclose(mid_configuration(chain)[[0, 3, 4, 5]], 0.0, atol=1e-12)


def test_a_joint_loop_or_a_zero_axis_is_an_error_not_a_hang(arm_text, tmp_path) -> None:
    loop = tmp_path / "loop.urdf"
    loop.write_text(
        '<robot name="r"><link name="a"/><link name="b"/>'
        '<joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>'
        '<joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint></robot>'
    )
    with pytest.raises(InputFileError, match="the joints form a loop through 'a'"):
        UrdfChain(loop, "a", "b")
    flat = tmp_path / "flat.urdf"
    flat.write_text(arm_text.replace('<axis xyz="0.0 0.0 1.0"/>', '<axis xyz="0 0 0"/>', 1))
    with pytest.raises(InputFileError, match="joint 'j1' has no axis direction"):
        UrdfChain(flat)
