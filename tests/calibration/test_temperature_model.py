"""The bias linear in the sensor's temperature through the joint method (``calibrate
--bias-drift temperature``) and ``auto``'s choice of it by the restricted likelihood: chosen
where the temperature drives the bias, never offered without temperatures, and compensating
held-out readings to the noise floor; the record's file round trip."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from calibration.temperature_data import SLOPES, T0_C, TOOL, floor_N, recording
from ftcomp.calibration.identify import pose_means
from ftcomp.calibration.identify_extended import ModelSpec, calibrate_extended, identify
from ftcomp.calibration.still import StillConfig, still_samples
from ftcomp.calibration_record import TemperatureBiasDrift
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.errors import CalibrationFileError, IdentificationError, ParameterError
from ftcomp.io.calibration_json import calibration_to_dict, load_calibration, save_calibration
from ftcomp.samples import Samples


def _held_out_force_rms(calibration, samples: Samples) -> float:
    """RMS over poses and axes of the compensated pose means' force [N] (zero contact)."""
    temperature = samples.extras.get("temperature_C")
    contact = GravityCompensator(calibration).compensate(
        samples.wrench_sensor, samples.R_base_sensor, temperature_C=temperature
    )
    means = replace(samples, wrench_sensor=contact)
    _, _, mean, _, _ = pose_means(means)
    return float(np.sqrt(np.mean(mean[:, :3] ** 2)))


def test_auto_picks_temperature_where_the_bias_follows_it_and_compensates_to_the_floor() -> None:
    calibration, choice = identify(recording(1))
    assert choice.bias_drift == "temperature"
    assert "linear in the sensor's temperature" in choice.reasons[0]
    heat = calibration.bias_drift
    assert isinstance(heat, TemperatureBiasDrift)
    # estimates from noisy data: within 4 standard errors of the truth
    assert np.all(np.abs(heat.slopes - SLOPES) < 4.0 * heat.std_errors)
    bias_at_T0 = calibration.model.force_bias_N + (T0_C - heat.T_ref_C) * heat.slopes[:3]
    se = calibration.std_errors.force_bias_N
    assert np.all(np.abs(bias_at_T0 - TOOL.force_bias_N) < 4.0 * se)
    # Held out: new poses at new temperatures within the range. A pose mean's noise is the
    # floor; 16 poses of 20 readings leave the model's own error at about sqrt(1 + 9/48) of it
    # (9 force parameters from 48 numbers), so 1.5x is a margin of a few standard errors of an
    # RMS over 24 x 3 numbers; a constant bias is 10x and more (6 degC at 0.05-0.12 N/degC).
    held_out = recording(2, poses=24, low_C=22.5, high_C=27.5)
    assert _held_out_force_rms(calibration, held_out) < 1.5 * floor_N()
    constant, _ = identify(recording(1), ModelSpec(bias_drift="none"))
    assert _held_out_force_rms(constant, held_out) > 10.0 * floor_N()


def test_auto_never_offers_temperature_without_a_temperature_channel() -> None:
    _, choice = identify(recording(1, with_temperature=False))
    assert choice.bias_drift != "temperature"
    assert not any("temperature" in reason for reason in choice.reasons)


def test_auto_keeps_a_constant_bias_where_the_temperature_explains_nothing() -> None:
    _, choice = identify(recording(3, follows=False))
    assert choice.bias_drift == "none"
    assert "a temperature bias" in choice.reasons[0] and "needs > 6" in choice.reasons[0]


def test_a_temperature_that_does_not_vary_is_no_candidate_and_no_model() -> None:
    flat = recording(4, low_C=30.0, high_C=30.0, follows=False)  # the twin's Bota: 30 degC
    flat = replace(flat, extras={"temperature_C": np.full(len(flat), 30.0)})
    _, choice = identify(flat)
    assert choice.bias_drift == "none" and "span 0 degC" in choice.reasons[0]
    with pytest.raises(IdentificationError, match="span 0 degC"):
        calibrate_extended(flat, bias_drift="temperature")


def test_a_temperature_model_needs_temperatures_that_are_numbers() -> None:
    samples = recording(5, with_temperature=False)
    with pytest.raises(IdentificationError, match="no 'temperature_C' column"):
        calibrate_extended(samples, bias_drift="temperature")
    bad = recording(5).extras["temperature_C"].copy()
    bad[7] = np.nan
    with pytest.raises(IdentificationError, match="row 8, column 'temperature_C'"):
        identify(replace(samples, extras={"temperature_C": bad}))


def test_a_temperature_model_combines_with_neither_a_stochastic_bias_nor_a_sensor_map() -> None:
    with pytest.raises(ParameterError, match="polynomial or temperature drift"):
        ModelSpec(bias_drift="temperature", sensor_map="linear")


def test_the_temperature_model_round_trips_through_the_calibration_file(tmp_path) -> None:
    calibration, _ = identify(recording(1), ModelSpec(bias_drift="temperature"))
    path = tmp_path / "cal.json"
    save_calibration(path, calibration)
    entry = json.loads(path.read_text())["bias_drift"]
    assert entry["model"] == "temperature" and len(entry["slopes_per_C"]) == 6
    loaded = load_calibration(path)
    heat, back = calibration.bias_drift, loaded.bias_drift
    assert isinstance(heat, TemperatureBiasDrift) and isinstance(back, TemperatureBiasDrift)
    # JSON keeps a float's shortest repr: exact
    assert (back.T_ref_C, back.T_min_C, back.T_max_C) == (heat.T_ref_C, heat.T_min_C, heat.T_max_C)
    assert np.array_equal(back.slopes, heat.slopes)
    assert np.array_equal(back.std_errors, heat.std_errors)
    assert calibration_to_dict(loaded)["bias_drift"] == entry


def test_an_old_file_without_a_bias_model_still_loads_with_a_constant_bias(tmp_path) -> None:
    calibration, _ = identify(recording(1), ModelSpec(bias_drift="temperature"))
    data = calibration_to_dict(calibration)
    del data["bias_drift"]
    path = tmp_path / "old.json"
    path.write_text(json.dumps(data))
    assert load_calibration(path).bias_drift is None


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        ({"slopes_per_C": [0.1] * 5}, "slopes_per_C \\[6\\]"),
        ({"T_range_C": [30.0, 20.0]}, "T_min_C <= T_ref_C <= T_max_C"),
        ({"T_ref_C": None}, "'T_ref_C' must be a number"),
    ],
)
def test_a_broken_temperature_entry_is_one_error_naming_it(tmp_path, change, expected) -> None:
    calibration, _ = identify(recording(1), ModelSpec(bias_drift="temperature"))
    data = calibration_to_dict(calibration)
    data["bias_drift"].update(change)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(CalibrationFileError, match=expected):
        load_calibration(path)


def test_still_segments_keep_the_temperatures_for_the_model() -> None:
    samples = recording(6, readings=60)
    segments = still_samples(replace(samples, pose=None), StillConfig())
    assert "temperature_C" in segments.samples.extras
    assert len(segments.samples.extras["temperature_C"]) == len(segments.samples)
