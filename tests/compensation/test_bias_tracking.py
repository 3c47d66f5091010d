"""Live bias tracking (BiasTracker), offline with the simulated sensor's realistic drift: a
calibration used 10 minutes after its session, with and without tracking."""

from __future__ import annotations

import numpy as np
import pytest

from calibration.drift_data import NOISE_6
from calibration.sim_drift_data import PER_POSE, session, used_later
from ftcomp.calibration.identify_extended import calibrate_extended
from ftcomp.compensation.bias_tracking import BiasTracker, BiasTrackingConfig
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.errors import ParameterError

RATE_HZ = 500.0


def _still_cycles(seed, model, drift, R, t0_s, seconds, contact=None):
    """Raw readings of a still arm at ``R`` from ``t0_s`` for ``seconds`` at 500 Hz."""
    rng = np.random.default_rng(seed)
    t = t0_s + np.arange(int(seconds * RATE_HZ)) / RATE_HZ
    w = model.predict(R) + drift(t) + rng.standard_normal((len(t), 6)) * NOISE_6
    if contact is not None:
        w = w + contact
    return t, w


def _run(tracker, comp, t, w, R):
    contact = comp.compensate(w, np.broadcast_to(R, (len(w), 3, 3)))
    moved = [tracker.update(float(ti), ci, R) for ti, ci in zip(t, contact, strict=True)]
    return np.array(moved)


def test_tracking_keeps_a_calibration_ten_minutes_old_within_twice_the_floor() -> None:
    # The session 30 min after the sensor was switched on: right after it, the realistic
    # warm-up moves the z bias by 1.1 N in 10 min, more than the tracker's contact threshold
    # (docs/calibration.md).
    use = used_later(11, 1800.0)
    floor = NOISE_6[0] / np.sqrt(PER_POSE)
    assert use.updates > 0.9 * use.readings
    assert use.tracked_N < 2 * floor
    assert use.untracked_N > 2 * use.tracked_N  # what 10 minutes of drift does untracked
    print(
        f"10 min after: {use.untracked_N / floor:.1f} floors untracked, "
        f"{use.tracked_N / floor:.2f} tracked"
    )


def test_right_after_switch_on_a_rebias_at_the_start_lets_tracking_follow() -> None:
    # The same 10 minutes right after switching on move the z bias by about 1.1 N: beyond the
    # contact threshold, so tracking alone never starts (the sensor looks touched). A re-bias
    # from the first 0.5 s of the still readings (--rebias-s 0.5) starts it from the bias now.
    use = used_later(11, 0.0)
    floor = NOISE_6[0] / np.sqrt(PER_POSE)
    assert use.updates == 0 and use.tracked_N == use.untracked_N > 100 * floor
    assert use.rebiased_updates > 0.9 * (use.readings - 250)
    assert use.rebiased_tracked_N < 2 * floor


def test_no_update_in_contact_or_while_moving() -> None:
    model, samples, drift = session(12, 8)
    result = calibrate_extended(samples, bias_drift="stochastic", leave_one_out=False)
    comp = GravityCompensator(result)
    R = samples.R_base_sensor[0]
    tracker = BiasTracker(BiasTrackingConfig())
    t, w = _still_cycles(2, model, drift, R, 200.0, 2.0, contact=np.array([0, 0, 5.0, 0, 0, 0]))
    assert not _run(tracker, comp, t, w, R).any()
    assert not tracker.correction.any()
    # Moving: the orientation turns 0.1 rad/s.
    from scipy.spatial.transform import Rotation

    t, w = _still_cycles(3, model, drift, R, 210.0, 2.0)
    turning = [Rotation.from_rotvec([0, 0, 0.1 * (ti - 210.0)]).as_matrix() @ R for ti in t]
    contact = comp.compensate(w, np.broadcast_to(R, (len(w), 3, 3)))
    assert not any(
        tracker.update(float(ti), ci, Ri) for ti, ci, Ri in zip(t, contact, turning, strict=True)
    )


def test_the_correction_moves_no_faster_than_its_limit() -> None:
    config = BiasTrackingConfig(max_rate_force_N_per_s=0.01, contact_force_N=5.0)
    tracker = BiasTracker(config, initial_std=np.repeat([1.0, 0.01], 3))
    R = np.eye(3)
    offset = np.array([0.8, 0, 0, 0, 0, 0])  # a bias step well inside the contact threshold
    for k in range(1000):
        tracker.update(k / RATE_HZ, offset, R)
    # Still from the 2nd cycle, updating from 0.5 s on: at most 0.01 N/s for ~1.5 s.
    assert 0.0 < tracker.correction[0] <= 0.01 * 2.0 + 1e-12


def test_bad_tracking_config_is_a_clear_error() -> None:
    with pytest.raises(ParameterError, match="still_hold_s"):
        BiasTrackingConfig(still_hold_s=0.0)
    with pytest.raises(ParameterError, match="initial_std"):
        BiasTracker(BiasTrackingConfig(), initial_std=[1.0, 2.0])
