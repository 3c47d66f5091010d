"""identify(): one entry point, the model as a spec, the best the data support by default."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from calibration.drift_data import readings, tilted_poses, truth
from calibration.sim_drift_data import session
from ftcomp.calibration.identify import calibrate
from ftcomp.calibration.identify_extended import DRIFT_SUPPORT, ModelSpec, identify
from ftcomp.calibration_record import StochasticBiasDrift
from ftcomp.errors import ParameterError


def _steady(seed: int, poses: int = 9, per_pose: int = 200):
    """A constant bias, readings with times (a pose every 2 s)."""
    rng = np.random.default_rng(seed)
    return readings(rng, truth(), tilted_poses(rng, poses), per_pose, pose_period_s=2.0)


def test_a_steady_bias_is_kept_constant_and_the_fit_is_the_joint_methods() -> None:
    samples = _steady(0)
    result, choice = identify(samples)
    assert choice.bias_drift == "none"
    assert "do not support a drift" in choice.reasons[0]
    # Without a supported map, the default is exactly the joint method's constant-bias fit.
    joint = calibrate(samples, method="joint")
    assert result.sensor_map is not None and not result.sensor_map.applied
    np.testing.assert_array_equal(result.model.center_of_gravity_m, joint.model.center_of_gravity_m)
    np.testing.assert_array_equal(result.loo_error, joint.loo_error)


def test_a_drifting_bias_is_found_and_identified_as_stochastic() -> None:
    # The simulated sensor's realistic drift from switch-on (the Axia80's warm-up and wander).
    _, samples, _ = session(seed=2, poses=9)
    result, choice = identify(samples, leave_one_out=False)
    assert choice.bias_drift == "stochastic"
    assert f"> {DRIFT_SUPPORT:g}" in choice.reasons[0]
    assert isinstance(result.bias_drift, StochasticBiasDrift)
    assert result.sensor_map is not None  # fitted with the stochastic bias, applied or not


def test_without_times_the_bias_is_constant_and_the_reason_names_t() -> None:
    samples = replace(_steady(3), t=None)
    _, choice = identify(samples, leave_one_out=False)
    assert choice.bias_drift == "none"
    assert "'t'" in choice.reasons[0]


def test_too_few_poses_for_a_drift_keep_the_bias_constant() -> None:
    _, choice = identify(_steady(4, poses=5), leave_one_out=False)
    assert choice.bias_drift == "none"
    assert "5 poses" in choice.reasons[0]


def test_a_forced_model_is_fitted_without_a_choice() -> None:
    samples = _steady(5)
    result, choice = identify(
        samples, ModelSpec(bias_drift="linear", sensor_map="physical"), leave_one_out=False
    )
    assert choice.bias_drift == "linear" and not choice.sensor_map_fitted
    assert choice.reasons == ()
    assert result.bias_drift is not None and result.bias_drift.name == "linear"


def test_the_paper_method_is_the_papers_fit() -> None:
    samples = _steady(6)
    result, choice = identify(samples, ModelSpec(method="paper"))
    paper = calibrate(samples, method="paper")
    np.testing.assert_array_equal(result.model.force_bias_N, paper.model.force_bias_N)
    assert choice.bias_drift == "none" and result.sensor_map is None


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"method": "paper", "bias_drift": "stochastic"}, "need method joint"),
        ({"bias_drift": "stochastic", "identify_mount": "yaw"}, "combine with neither"),
        ({"bias_drift": "quadratic", "sensor_map": "linear"}, "combine with neither"),
        ({"bias_drift": "cubic"}, "bias_drift must be one of"),
    ],
)
def test_model_specs_that_do_not_combine_are_refused_naming_the_fields(kwargs, match) -> None:
    with pytest.raises(ParameterError, match=match) as info:
        ModelSpec(**kwargs)
    assert "bias_drift" in info.value.fields
