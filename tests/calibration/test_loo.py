"""Leave-one-pose-out without refitting every pose: closed form (paper), one step (joint)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.calibration.identify import calibrate, pose_means
from ftcomp.calibration.loo import (
    LOO_EXACT_MAX_POSES,
    leave_one_out,
    loo_joint_one_step,
    loo_paper,
    loo_refit,
)
from ftcomp.calibration.methods import fit_method
from ftcomp.samples import Samples

from conftest import TRUE_MODEL, synthetic_samples


def _per_pose(samples: Samples):
    _, R, wrench, count, var = pose_means(samples)
    return wrench, R, var, count


@pytest.mark.parametrize("readings", [1, 20])
def test_the_paper_methods_closed_form_equals_refitting_every_pose(rng, readings) -> None:
    """Exact algebra: the block hat-matrix formula and the refits agree to rounding."""
    wrench, R, var, count = _per_pose(synthetic_samples(rng, poses=40, readings=readings))
    closed = loo_paper(wrench, R)
    refit = loo_refit("paper", wrench, R, var, count)
    scale = np.abs(refit).max()
    np.testing.assert_allclose(closed, refit, rtol=0, atol=1e-9 * scale)


@pytest.mark.parametrize("readings", [1, 20])
def test_the_joint_one_step_agrees_with_refits_within_5_percent_on_100_poses(rng, readings):
    """The approximation: within 5 % of the exact refits, per channel's RMS and per pose."""
    samples = synthetic_samples(rng, poses=100, readings=readings)
    wrench, R, var, count = _per_pose(samples)
    fit, sigma = fit_method("joint", wrench, R, var, count)
    assert sigma is not None
    approx = loo_joint_one_step(wrench, R, sigma, fit)
    exact = loo_refit("joint", wrench, R, var, count)
    rms_exact = np.sqrt(np.mean(exact**2, axis=0))
    rms_approx = np.sqrt(np.mean(approx**2, axis=0))
    np.testing.assert_allclose(rms_approx, rms_exact, rtol=0.05)
    assert np.all(np.abs(approx - exact) < 0.05 * rms_exact)
    # ... and calibrate uses it beyond LOO_EXACT_MAX_POSES.
    result = calibrate(samples, method="joint")
    np.testing.assert_allclose(result.loo_error, approx, rtol=1e-9, atol=1e-15)


def test_calibrate_refits_the_joint_method_exactly_up_to_the_pose_limit(rng) -> None:
    samples = synthetic_samples(rng, poses=LOO_EXACT_MAX_POSES, readings=5)
    wrench, R, var, count = _per_pose(samples)
    result = calibrate(samples, method="joint")
    np.testing.assert_array_equal(result.loo_error, loo_refit("joint", wrench, R, var, count))


@pytest.mark.parametrize("method", ["paper", "joint"])
def test_a_pose_the_others_cannot_do_without_gets_nan(rng, method) -> None:
    """Poses A, B, C, A: without B (or C) only two orientations remain: nothing to predict
    with; without either A the others still identify the model."""
    R3 = Rotation.random(3, rng=rng).as_matrix()
    R = np.concatenate([R3, R3[:1]])
    samples = Samples(
        wrench_sensor=TRUE_MODEL.predict(R) + rng.normal(scale=1e-3, size=(4, 6)),
        R_base_sensor=R,
        encoding="rotvec",
        pose=np.array(["a", "b", "c", "d"]),
    )
    loo = calibrate(samples, method=method).loo_error  # type: ignore[arg-type]
    assert np.isnan(loo[1]).all() and np.isnan(loo[2]).all()
    assert np.isfinite(loo[0]).all() and np.isfinite(loo[3]).all()
    wrench, R_mean, var, count = _per_pose(samples)
    fit, sigma = fit_method(method, wrench, R_mean, var, count)  # type: ignore[arg-type]
    for exact in (True, False):
        other = leave_one_out(method, wrench, R_mean, var, count, fit, sigma, exact=exact)  # type: ignore[arg-type]
        np.testing.assert_array_equal(np.isnan(other), np.isnan(loo))


def test_three_poses_have_no_leave_one_out(rng) -> None:
    samples = synthetic_samples(rng, poses=3, readings=4)
    assert np.isnan(calibrate(samples, method="paper").loo_error).all()


def test_thousands_of_poses_calibrate_with_leave_one_out_in_both_methods(rng) -> None:
    """O(P) leave-one-pose-out: 3,000 poses take well under a second here (bench_io times
    10,000); before, the refits made 1,000 poses take twenty minutes."""
    samples = synthetic_samples(rng, poses=3000, readings=2)
    for method in ("paper", "joint"):
        result = calibrate(samples, method=method)  # type: ignore[arg-type]
        assert np.isfinite(result.loo_error).all()
        # Unseen poses are predicted about as well as seen ones when there are this many.
        assert result.loo_rms[0] == pytest.approx(result.residual_rms[0], rel=0.02)
