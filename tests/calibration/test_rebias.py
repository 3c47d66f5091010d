"""Re-bias: the bias alone from still readings, the tool model kept."""

from __future__ import annotations

import numpy as np

from calibration.drift_data import NOISE_6, readings, tilted_poses, truth
from ftcomp.calibration.identify import calibrate
from ftcomp.calibration.rebias import bias_from_still, rebias
from ftcomp.compensation.compensator import GravityCompensator

PER_POSE = 200


def test_rebias_restores_a_fresh_calibrations_error_from_one_pose() -> None:
    rng = np.random.default_rng(5)
    model = truth()
    R = tilted_poses(rng, 12)
    calibration = calibrate(readings(rng, model, R, PER_POSE))
    step = np.array([0.4, -0.3, 0.2, 0.005, 0.004, -0.003])  # the bias moved since
    drifted = lambda t: np.broadcast_to(step, (len(t), 6))  # noqa: E731
    still = readings(rng, model, R[:1], 1200, drift=drifted)  # one second at one pose
    new = rebias(calibration, still)
    test = readings(rng, model, R, PER_POSE, drift=drifted)
    err_old = GravityCompensator(calibration).compensate(test.wrench_sensor, test.R_base_sensor)
    err_new = GravityCompensator(new).compensate(test.wrench_sensor, test.R_base_sensor)
    fresh = calibrate(test)
    err_fresh = GravityCompensator(fresh).compensate(test.wrench_sensor, test.R_base_sensor)

    def mean_error(e: np.ndarray) -> float:  # the per-pose mean error: bias left over
        pose = np.repeat(np.arange(12), PER_POSE)
        means = np.array([e[pose == k, :3].mean(axis=0) for k in range(12)])
        return float(np.sqrt(np.mean(means**2)))

    assert mean_error(err_old) > 0.2
    # The fresh calibration's own error is its residual (~floor); re-bias adds the bias SE
    # of 1200 readings (0.125/sqrt(1200) = 0.0036 N) and the tool model's error: 2x is ample.
    assert mean_error(err_new) < 2.0 * mean_error(err_fresh) + 0.005


def test_bias_from_still_standard_error_matches_the_scatter() -> None:
    rng = np.random.default_rng(6)
    model = truth()
    R = np.broadcast_to(tilted_poses(rng, 1)[0], (400, 3, 3))
    w = model.predict(R) + rng.standard_normal((400, 6)) * NOISE_6
    bias, se = bias_from_still(model, w, R)
    np.testing.assert_allclose(se, NOISE_6 / 20.0, rtol=0.15)  # 400 draws: SE of SE ~3.5 %
    expected = np.concatenate([model.force_bias_N, model.torque_bias_Nm])
    assert np.all(np.abs(bias - expected) < 4 * se)
