"""solve_pose on the UR5e cell: a pose in reach is solved to its tolerance; out of reach, each
seed is given up once it stops making progress, not after all its iterations."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")

import ftcomp.sim.ik as ik
from ftcomp.sim.scene import NAMES
from ftcomp.twin.serve import TwinConfig


@pytest.fixture(scope="module")
def cell():  # type: ignore[no-untyped-def]
    return TwinConfig("127.0.0.1", "127.0.0.2", 1.0).open_cell()  # nothing is bound


def _solve(cell, p_world, R_world, seeds):  # type: ignore[no-untyped-def]
    import mujoco

    n = cell.n_joints
    lower, upper = cell.joint_range_rad
    return ik.solve_pose(
        cell.model, mujoco.MjData(cell.model), cell.model.site(NAMES["ft_site"]).id,
        np.arange(n, dtype=np.intp), np.arange(n, dtype=np.intp), p_world, R_world, seeds,
        lower, upper,
    )  # fmt: skip


def _site_pose(cell, q):  # type: ignore[no-untyped-def]
    import mujoco

    data = mujoco.MjData(cell.model)
    data.qpos[: cell.n_joints] = q
    mujoco.mj_kinematics(cell.model, data)
    site = cell.model.site(NAMES["ft_site"]).id
    return data.site_xpos[site].copy(), data.site_xmat[site].reshape(3, 3).copy()


def test_a_pose_in_reach_is_solved_to_the_tolerance(cell) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(1)
    lower, upper = cell.joint_range_rad
    home = np.array(cell.config.arm.home_q_rad)
    target_q = home + rng.uniform(-0.3, 0.3, cell.n_joints)
    p, R = _site_pose(cell, target_q)
    q = _solve(cell, p, R, [home])
    assert q is not None and np.all((q >= lower) & (q <= upper))
    p_q, R_q = _site_pose(cell, q)
    assert np.max(np.abs(ik.pose_error_world(p, R, p_q, R_q))) < 1e-9


def test_a_pose_out_of_reach_gives_up_on_each_seed_once_it_stalls(
    cell, monkeypatch: pytest.MonkeyPatch
) -> None:  # type: ignore[no-untyped-def]
    import mujoco

    calls = 0
    kinematics = mujoco.mj_kinematics

    def counted(model, data) -> None:  # type: ignore[no-untyped-def]
        nonlocal calls
        calls += 1
        kinematics(model, data)

    monkeypatch.setattr(ik.mujoco, "mj_kinematics", counted)
    home = np.array(cell.config.arm.home_q_rad)
    seeds = [home + 0.1 * k for k in range(5)]
    p_base = np.array([3.0, 0.0, 0.4])  # 3 m out: a UR5e reaches 0.85 m
    assert _solve(cell, cell.R_world_base @ p_base, np.eye(3), seeds) is None
    # all 200 iterations of each seed would be 1000 calls; a stalled seed ends within about
    # the stall limit after its error stops shrinking
    assert calls < 0.5 * 200 * len(seeds), calls
