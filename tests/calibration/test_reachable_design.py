"""The reach-checked design: every pose it returns is reachable, and a cramped arm makes it
sample instead of asking without end."""

from __future__ import annotations

import numpy as np
import pytest

from ftcomp.calibration.design import candidate_orientations, nominal_theta, tilt_from_down_rad
from ftcomp.calibration.reachable_design import (
    FEW_MISSES,
    MAX_SAMPLE,
    Reachability,
    design_reachable_poses,
)
from ftcomp.errors import ParameterError


def _within(max_tilt_deg: float) -> Reachability:
    """An arm that turns the tip at most ``max_tilt_deg`` from pointing down."""

    def check(p: np.ndarray, R: np.ndarray) -> bool:
        return bool(np.degrees(tilt_from_down_rad(R[None]))[0] <= max_tilt_deg)

    return Reachability(check, np.array([0.4, 0.0, 0.3]), source="--test", who="a test arm")


def test_a_cramped_arm_gets_reachable_poses_from_the_random_sample() -> None:
    reach = _within(60.0)
    R = design_reachable_poses(
        6, candidate_orientations(180.0), nominal_theta(), keep=None, reach=reach
    )
    assert R.shape == (6, 3, 3)
    assert (np.degrees(tilt_from_down_rad(R)) <= 60.0).all()
    # The D-optimal design wants tilts beyond 60 deg: it missed FEW_MISSES times, then sampled.
    assert reach.checked - reach.reached >= FEW_MISSES
    assert 0 < reach.sampled <= MAX_SAMPLE
    assert "sampled at random" in reach.summary("a test arm")


def test_an_arm_that_reaches_everything_never_samples() -> None:
    reach = _within(180.0)
    design_reachable_poses(
        6, candidate_orientations(180.0), nominal_theta(), keep=None, reach=reach
    )
    assert reach.sampled == 0 and reach.checked == reach.reached


def test_an_arm_that_reaches_almost_nothing_is_one_clear_error() -> None:
    with pytest.raises(ParameterError, match=r"--test: .* out of reach .* count 6"):
        design_reachable_poses(
            6, candidate_orientations(180.0), nominal_theta(), keep=None, reach=_within(1.0)
        )
