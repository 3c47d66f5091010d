"""The bias as a stochastic process (calibrate_extended with bias_drift="stochastic"), tested on
the simulated sensor's realistic drift where the truth is known."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from calibration.drift_data import NOISE_6
from calibration.sim_drift_data import PER_POSE, session, spanning_split, subset
from ftcomp.calibration.identify import calibrate, pose_means
from ftcomp.calibration.identify_extended import calibrate_extended
from ftcomp.calibration_record import StochasticBiasDrift
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.errors import IdentificationError
from ftcomp.io.calibration_json import load_calibration, save_calibration

POSES = 30


def _held_out_force_rms(seed: int, train_poses: int, model: str) -> float:
    """RMS force error [N] predicting the held-out poses' mean readings at their times."""
    _, samples, _ = session(seed, POSES)
    rng = np.random.default_rng(seed + 100)
    train = np.zeros(POSES, bool)
    train[rng.choice(POSES, train_poses, replace=False)] = True
    fit_on, held = subset(samples, train), subset(samples, ~train)
    if model == "none":
        result = calibrate(fit_on, leave_one_out=False)
    else:
        result = calibrate_extended(fit_on, bias_drift=model, leave_one_out=False)  # type: ignore[arg-type]
    ids, R, wrench, _, _ = pose_means(held)
    t = np.array([held.t[held.pose == i].mean() for i in ids])
    error = GravityCompensator(result).compensate(wrench, R, t_s=t)
    return float(np.sqrt(np.mean(error[:, :3] ** 2)))


def test_stochastic_drift_beats_constant_and_quadratic_at_nine_poses() -> None:
    floor = NOISE_6[0] / np.sqrt(PER_POSE)  # one pose mean's force noise [N]
    errors = {
        m: [_held_out_force_rms(s, 9, m) for s in range(3)]
        for m in ("none", "quadratic", "stochastic")
    }
    stochastic = np.median(errors["stochastic"])
    assert stochastic < 0.5 * np.median(errors["none"])
    assert stochastic < np.median(errors["quadratic"])
    # Held-out poses before the first training pose get its bias held: a few floors at most.
    assert stochastic < 5 * floor


@pytest.mark.parametrize("t0_s", [0.0, 1800.0], ids=["switch-on", "warmed"])
def test_nine_poses_spanning_the_session_predict_within_1_2_times_the_floor(t0_s: float) -> None:
    # Issue 24's goal: 9 poses at the record's pace (2 s a pose), the session's first and last
    # among them, the other 21 held out, each predicted at its time. The median over 20 seeds
    # (deterministic) measures 1.08x from switch-on and 1.07x 30 min later (means 1.13x);
    # bench/bench_accuracy.py --sim prints the other models beside it.
    floor = NOISE_6[0] / np.sqrt(PER_POSE)
    errors = []
    for seed in range(20):
        _, samples, _ = session(seed, POSES, t0_s=t0_s)
        train, test = spanning_split(np.random.default_rng(seed + 200), POSES, 9)
        fit_on = subset(samples, np.isin(np.arange(POSES), train))
        held = subset(samples, np.isin(np.arange(POSES), test))
        result = calibrate_extended(fit_on, bias_drift="stochastic", leave_one_out=False)
        ids, R, wrench, _, _ = pose_means(held)
        t = np.array([held.t[held.pose == i].mean() for i in ids])
        error = GravityCompensator(result).compensate(wrench, R, t_s=t)
        errors.append(float(np.sqrt(np.mean(error[:, :3] ** 2))))
    assert np.median(errors) < 1.2 * floor


def test_stochastic_drift_at_twenty_poses_is_near_the_floor() -> None:
    floor = NOISE_6[0] / np.sqrt(PER_POSE)
    errors = [_held_out_force_rms(s, 20, "stochastic") for s in range(3)]
    assert np.median(errors) < 2.0 * floor


def test_after_the_session_the_bias_is_held_and_its_uncertainty_grows() -> None:
    # Poses 10 s apart: a two-minute session, over which the drift is well above the noise.
    _, samples, _ = session(5, 12, pose_period_s=10.0)
    result = calibrate_extended(samples, bias_drift="stochastic")
    drift = result.bias_drift
    assert isinstance(drift, StochasticBiasDrift)
    end = drift.t_max_s
    np.testing.assert_allclose(drift.offset(np.array([end, end + 60, end + 6000])), 0.0, atol=1e-12)
    std = drift.offset_std(np.array([end, end + 60.0, end + 600.0]))
    assert np.all(np.diff(std, axis=0) > 0.0)
    np.testing.assert_allclose(std[0], drift.end_std, rtol=1e-9)
    # Standard errors include the drift: the bias's is well above what noise alone leaves on a
    # constant bias averaged over 12 poses.
    noise_only = NOISE_6[0] / np.sqrt(PER_POSE * 12)
    assert np.all(result.std_errors.force_bias_N > 2 * noise_only)
    assert drift.outside(end - 10.0, end + 600.0) is not None
    assert "held at its last estimate" in (drift.outside(end - 10.0, end + 600.0) or "")
    assert drift.outside(drift.t_min_s, end) is None
    assert np.all(np.isfinite(result.loo_error))


def test_without_leave_one_out_the_fit_is_the_same_and_no_refit_is_made() -> None:
    _, samples, _ = session(5, 12, pose_period_s=10.0)
    full = calibrate_extended(samples, bias_drift="stochastic")
    lean = calibrate_extended(samples, bias_drift="stochastic", leave_one_out=False)
    assert np.all(np.isnan(lean.loo_error)) and np.all(np.isfinite(full.loo_error))
    np.testing.assert_allclose(lean.model.force_bias_N, full.model.force_bias_N, rtol=1e-12)
    np.testing.assert_allclose(
        lean.std_errors.center_of_gravity_m, full.std_errors.center_of_gravity_m, rtol=1e-12
    )


def test_polynomial_drift_holds_its_end_value_past_the_session() -> None:
    _, samples, _ = session(6, 12)
    drift = calibrate_extended(samples, bias_drift="quadratic", leave_one_out=False).bias_drift
    assert drift is not None
    end = drift.t_max_s
    np.testing.assert_allclose(drift.offset(np.array([end + 1.0, end + 3600.0])), 0.0, atol=1e-12)
    start = drift.offset(np.array([drift.t_min_s]))
    np.testing.assert_allclose(drift.offset(np.array([drift.t_min_s - 100.0])), start, atol=1e-12)


def test_stochastic_drift_round_trips_through_the_calibration_file(tmp_path) -> None:
    _, samples, _ = session(7, 8)
    result = calibrate_extended(samples, bias_drift="stochastic", leave_one_out=False)
    path = tmp_path / "cal.json"
    save_calibration(path, result)
    data = json.loads(path.read_text())
    assert data["bias_drift"]["model"] == "stochastic"
    assert data["bias_drift"]["t_range_s"] == [result.bias_drift.t_min_s, result.bias_drift.t_max_s]
    loaded = load_calibration(path)
    t = np.linspace(-10.0, 200.0, 50)
    np.testing.assert_allclose(loaded.bias_drift.offset(t), result.bias_drift.offset(t), atol=1e-12)


def test_bad_input_for_the_stochastic_drift_is_a_clear_error() -> None:
    _, samples, _ = session(8, 8)
    with pytest.raises(IdentificationError, match="no 't'"):
        calibrate_extended(replace(samples, t=None), bias_drift="stochastic")
    few = subset(samples, np.arange(8) < 5)
    with pytest.raises(IdentificationError, match="needs at least 6"):
        calibrate_extended(few, bias_drift="stochastic")
    t = samples.t.copy()
    t[1000] = t[999] - 1.0
    with pytest.raises(IdentificationError, match="must not decrease"):
        calibrate_extended(replace(samples, t=t), bias_drift="stochastic")
