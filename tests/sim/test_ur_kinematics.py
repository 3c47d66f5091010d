"""The closed-form inverse kinematics of a UR-shaped arm against its forward kinematics."""

from __future__ import annotations

import math

import numpy as np

from ftcomp.sim.arm import dh_flange_pose, fr3_arm, ur5e_arm
from ftcomp.sim.ur_kinematics import is_ur_shaped, ur_inverse_kinematics


def _same_angles(a: np.ndarray, b: np.ndarray) -> float:
    """The largest joint difference [rad], whole turns aside."""
    return float(np.max(np.abs(np.remainder(a - b + math.pi, 2 * math.pi) - math.pi)))


def test_every_branch_reaches_the_pose_and_one_is_the_configuration_it_came_from() -> None:
    arm = ur5e_arm()
    rng = np.random.default_rng(7)
    counts = []
    for _ in range(500):
        q = rng.uniform(-math.pi, math.pi, 6)
        p, R = dh_flange_pose(arm, q)
        branches = ur_inverse_kinematics(arm, p, R)
        counts.append(len(branches))
        for branch in branches:
            p_b, R_b = dh_flange_pose(arm, branch)
            # exact algebra: rounding only
            assert np.allclose(p_b, p, rtol=0, atol=1e-9) and np.allclose(R_b, R, rtol=0, atol=1e-9)
            assert np.all(branch > -math.pi - 1e-12) and np.all(branch <= math.pi + 1e-12)
        assert min(_same_angles(b, q) for b in branches) < 1e-9
        # the branches are distinct configurations
        assert all(
            _same_angles(a, b) > 1e-6 for i, a in enumerate(branches) for b in branches[i + 1 :]
        )
    # shoulder, elbow and wrist: eight where the whole set is in reach (most random poses)
    assert max(counts) == 8 and np.mean(np.array(counts) == 8) > 0.5


def test_at_the_wrist_singularity_joint_6_is_the_callers() -> None:
    arm = ur5e_arm()
    q = np.array([0.3, -1.2, 1.0, -0.4, 0.0, 0.7])  # q5 = 0: joints 4 and 6 on one axis
    p, R = dh_flange_pose(arm, q)
    branches = ur_inverse_kinematics(arm, p, R, q6_if_singular=0.7)
    assert min(_same_angles(b, q) for b in branches) < 1e-9
    for branch in branches:
        p_b, R_b = dh_flange_pose(arm, branch)
        assert np.allclose(p_b, p, atol=1e-9) and np.allclose(R_b, R, atol=1e-9)


def test_beyond_reach_there_is_no_branch() -> None:
    arm = ur5e_arm()
    assert ur_inverse_kinematics(arm, np.array([3.0, 0.0, 0.3]), np.eye(3)) == []
    # inside the cylinder of radius d4 about the base's z axis the wrist cannot go
    assert ur_inverse_kinematics(arm, np.array([0.0, 0.05, 0.4]), np.eye(3)) == []


def test_only_a_ur_shaped_arm_is_taken() -> None:
    assert is_ur_shaped(ur5e_arm())
    assert not is_ur_shaped(fr3_arm())  # seven joints, modified DH


def test_the_arm_stretched_straight_up_is_found() -> None:
    """Wrist and elbow singular at once, the wrist on joint 1's cylinder: every test of a
    branch's existence sits on its edge. The straight elbow's angle is known only to the square
    root of the rounding (a distance short by e bends it by sqrt(e)); the pose, to rounding."""
    arm = ur5e_arm()
    q = np.array([0.0, -math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0])
    p, R = dh_flange_pose(arm, q)
    branches = ur_inverse_kinematics(arm, p, R)
    assert min(_same_angles(b, q) for b in branches) < 1e-7
    for branch in branches:
        p_b, R_b = dh_flange_pose(arm, branch)
        assert np.allclose(p_b, p, atol=1e-9) and np.allclose(R_b, R, atol=1e-9)
