"""The sensor's mount rotation identified jointly with the tool model."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from calibration.drift_data import readings, tilted_poses, truth
from ftcomp.calibration.identify import calibrate
from ftcomp.calibration.identify_extended import calibrate_extended
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.errors import IdentificationError

#: The sensor frame in the flange frame: a mounting yaw of 10 deg the user does not know.
R_FLANGE_SENSOR = Rotation.from_euler("z", 10, degrees=True).as_matrix()


def _flange_samples(seed: int, R_sensor: np.ndarray, per_pose: int = 200):
    rng = np.random.default_rng(seed)
    return readings(rng, truth(), R_sensor, per_pose, R_recorded=R_sensor @ R_FLANGE_SENSOR.T)


def _held_out_force_error(calibration, *, flange: bool) -> float:
    """RMS per-pose mean contact force over fresh readings at 20 new poses (no contact: all of
    it is error), recorded with the flange's orientations or the sensor's."""
    rng = np.random.default_rng(99)
    R = tilted_poses(rng, 20)
    test = readings(rng, truth(), R, 200, R_recorded=R @ R_FLANGE_SENSOR.T if flange else None)
    contact = GravityCompensator(calibration).compensate(test.wrench_sensor, test.R_base_sensor)
    means = contact[:, :3].reshape(20, 200, 3).mean(axis=1)
    return float(np.sqrt(np.mean(means**2)))


def test_yaw_is_recovered_within_3_standard_errors_and_the_error_returns() -> None:
    rng = np.random.default_rng(11)
    R = tilted_poses(rng, 12)
    samples = _flange_samples(11, R)
    result = calibrate_extended(samples, identify_mount="yaw", leave_one_out=False)
    assert result.mount is not None
    yaw, se = result.mount.angles_rad[0], result.mount.std_errors_rad[0]
    assert abs(yaw - np.radians(10.0)) < 3 * se
    assert not result.warnings
    ignored = calibrate(samples, leave_one_out=False)
    # The no-offset level: the same poses recorded with the sensor's own orientations.
    clean = calibrate(readings(np.random.default_rng(11), truth(), R, 200), leave_one_out=False)
    no_offset = _held_out_force_error(clean, flange=False)
    identified = _held_out_force_error(result, flange=True)
    assert _held_out_force_error(ignored, flange=True) > 10 * no_offset
    # Both are a pose mean's noise (0.125/sqrt(200) = 0.009 N) plus the fit's own error; one
    # more parameter from the same data: within 1.3x.
    assert identified < 1.3 * no_offset


def test_full_mount_is_recovered_with_rich_poses() -> None:
    rng = np.random.default_rng(12)
    samples = _flange_samples(12, tilted_poses(rng, 15))
    result = calibrate_extended(samples, identify_mount="full", leave_one_out=False)
    assert result.mount is not None
    expected = Rotation.from_matrix(R_FLANGE_SENSOR).as_rotvec()
    z = (result.mount.angles_rad - expected) / result.mount.std_errors_rad
    assert np.all(np.abs(z) < 4.0)


def test_poses_hanging_straight_down_or_up_give_a_clear_warning() -> None:
    spin = Rotation.from_euler("z", np.linspace(0, 300, 6)[:, None], degrees=True)
    down = Rotation.from_euler("x", 180, degrees=True)
    R = np.concatenate([(down * spin).as_matrix(), spin.as_matrix()])
    result = calibrate_extended(_flange_samples(13, R), identify_mount="yaw", leave_one_out=False)
    assert any("mount yaw not identified" in w for w in result.warnings)


def test_too_few_poses_for_the_mount_is_an_error() -> None:
    rng = np.random.default_rng(14)
    with pytest.raises(IdentificationError, match="needs at least 6"):
        calibrate_extended(_flange_samples(14, tilted_poses(rng, 5)), identify_mount="full")
