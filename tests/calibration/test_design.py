"""Pose design on the joint model's Fisher information."""

from __future__ import annotations

import numpy as np
import pytest

from ftcomp import paper
from ftcomp.calibration.design import (
    candidate_orientations,
    design_poses,
    fisher_blocks,
    nominal_theta,
    order_for_travel,
    predicted_std_errors,
    tilt_from_down_rad,
)
from ftcomp.calibration.identify import calibrate
from ftcomp.calibration.methods import joint_residuals
from ftcomp.errors import ParameterError
from ftcomp.model import GravityModel
from ftcomp.samples import Samples

THETA = nominal_theta()


def test_fisher_blocks_match_finite_differences_of_the_residuals() -> None:
    R = candidate_orientations(90.0, directions=20, spins=2)[:5]
    sigma = np.broadcast_to(np.repeat([0.125, 0.003], 3) / np.sqrt(500), (5, 6))
    J = np.zeros((30, 12))
    for k in range(12):
        h = 1e-6 * max(1.0, abs(THETA[k]))
        d = np.zeros(12)
        d[k] = h
        J[:, k] = (
            joint_residuals(THETA + d, R, np.zeros((5, 6)), sigma)
            - joint_residuals(THETA - d, R, np.zeros((5, 6)), sigma)
        ) / (2 * h)
    # Central differences of a quadratic-at-most model: agreement to ~1e-6 relative.
    np.testing.assert_allclose(fisher_blocks(R, THETA).sum(axis=0), J.T @ J, rtol=1e-5, atol=1e-3)


def test_candidates_respect_the_max_tilt() -> None:
    R = candidate_orientations(30.0)
    assert len(R) > 0
    assert np.degrees(tilt_from_down_rad(R)).max() <= 30.0 + 1e-9
    np.testing.assert_allclose(
        R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape), atol=1e-12
    )


def test_spins_stay_within_their_band_about_the_tilted_axis() -> None:
    # Each candidate is tilt * flip * spin: undoing the tilt and the flip leaves the spin.
    directions, spins = 30, 7
    banded = candidate_orientations(60.0, directions=directions, spins=spins, max_spin_deg=90.0)
    full = candidate_orientations(60.0, directions=directions, spins=spins)
    straight = full[::spins]  # spin 0 of each axis: the shortest tilt from down, flipped
    spin = np.repeat(straight, spins, axis=0).transpose(0, 2, 1) @ banded
    angle = np.degrees(np.arctan2(spin[:, 1, 0], spin[:, 0, 0]))
    np.testing.assert_allclose(spin[:, 2, 2], 1.0, atol=1e-12)  # a turn about z alone
    np.testing.assert_allclose(
        angle, np.tile(np.linspace(-90, 90, spins), len(straight)), atol=1e-9
    )
    with pytest.raises(ParameterError, match="max_spin_deg must be in"):
        candidate_orientations(60.0, max_spin_deg=0.0)


def test_designed_poses_beat_the_papers_poses_in_every_predicted_error() -> None:
    designed = design_poses(9, candidate_orientations(90.0, directions=150, spins=8), THETA)
    ours = predicted_std_errors(designed, THETA)
    theirs = predicted_std_errors(paper.paper_poses().rotations.as_matrix(), THETA)
    for name in ("G", "F0", "M0", "P"):
        assert np.linalg.norm(ours[name]) < np.linalg.norm(theirs[name])
    # G: the bench (200 trials) measures ~3x; the predicted gain must reach 2.5x here.
    assert theirs["G"][0] / ours["G"][0] > 2.5


def test_design_honours_reachability_and_keeps_given_poses() -> None:
    candidates = candidate_orientations(120.0, directions=100, spins=6)
    keep = paper.paper_poses().rotations.as_matrix()[:3]

    def reachable(R: np.ndarray) -> bool:  # pretend the robot cannot tilt beyond 60 deg
        return bool(tilt_from_down_rad(R[None])[0] <= np.radians(60.0))

    designed = design_poses(4, candidates, THETA, keep=keep, reachable=reachable)
    assert len(designed) == 4
    assert np.degrees(tilt_from_down_rad(designed)).max() <= 60.0 + 1e-9


def test_a_count_below_the_minimum_is_an_error() -> None:
    with pytest.raises(ParameterError, match="at least 3 poses"):
        design_poses(2, candidate_orientations(90.0, directions=20, spins=2), THETA)


def test_travel_order_is_a_permutation_no_longer_than_the_given_order() -> None:
    R = candidate_orientations(90.0, directions=30, spins=3)[::7]

    def travel(order: np.ndarray) -> float:
        Rs = R[order]
        c = (np.einsum("nij,nij->n", Rs[:-1], Rs[1:]) - 1) / 2
        return float(np.arccos(np.clip(c, -1, 1)).sum())

    order = order_for_travel(R)
    assert sorted(order.tolist()) == list(range(len(R)))
    assert travel(order) <= travel(np.arange(len(R))) + 1e-12


def test_monte_carlo_small_joint_at_designed_poses_beats_paper_at_papers_poses() -> None:
    """A fast version of bench/bench_design.py: 12 trials, 100 readings per pose."""
    truth = GravityModel(
        paper.TOOL_WEIGHT_N,
        np.array(paper.CENTER_OF_GRAVITY_M),
        np.array(paper.FORCE_BIAS_N),
        np.array(paper.TORQUE_BIAS_Nm),
        tilt_U_rad=0.0,
        tilt_V_rad=0.0,
    )
    designed = design_poses(9, candidate_orientations(90.0, directions=150, spins=8), THETA)
    R_paper = paper.paper_poses().rotations.as_matrix()
    noise = np.repeat([0.125, 0.003], 3)

    def g_error(R: np.ndarray, method: str, seed: int) -> float:
        rng = np.random.default_rng(seed)
        pose = np.repeat(np.arange(9), 100)
        w = truth.predict(R[pose]) + rng.standard_normal((900, 6)) * noise
        s = Samples(w, R[pose], "quaternion", pose=pose.astype(str))
        return calibrate(s, method=method, leave_one_out=False).model.weight_N - truth.weight_N

    ours = np.sqrt(np.mean([g_error(designed, "joint", k) ** 2 for k in range(12)]))
    base = np.sqrt(np.mean([g_error(R_paper, "paper", k) ** 2 for k in range(12)]))
    # Expected ratio ~3 (200 trials in the bench); the RMS of 12 draws is within ~20 % (1 SE),
    # so each side within ~40 % at 2 SE: a ratio above 1.5 is certain for a real gain.
    assert base / ours > 1.5
