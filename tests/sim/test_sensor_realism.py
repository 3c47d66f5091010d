"""The sensor model's optional realism: per-axis gain error and bias drift (rate, random walk)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from ftcomp.errors import ParameterError
from ftcomp.hardware.registry import parse_uri
from ftcomp.sim.backend import sensor_spec_from_uri
from ftcomp.sim.sensor import SensorSpec, SimWrenchSensor


def _sensor(spec: SensorSpec, wrench: np.ndarray, clock: list[float], seed: int = 0):
    return SimWrenchSensor(spec, lambda: wrench.copy(), lambda: clock[0], seed=seed)


def test_gain_error_scales_each_axis_of_the_ideal_reading() -> None:
    gain = np.array([0.015, -0.015, 0.01, 0.0, 0.005, -0.01])
    spec = replace(SensorSpec().ideal(), gain_error_fraction=gain)
    wrench = np.array([10.0, -20.0, 30.0, 0.1, -0.2, 0.3])
    clock = [0.01]
    got = _sensor(spec, wrench, clock).read().wrench_sensor
    # Exact algebra: (1 + g) * ideal + bias.
    np.testing.assert_allclose(got, (1 + gain) * wrench + spec.bias_6, atol=1e-12)


def test_defaults_leave_readings_unchanged() -> None:
    wrench = np.array([1.0, -2.0, 3.0, 0.01, -0.02, 0.03])
    a, b = _sensor(SensorSpec(), wrench, [0.5]), _sensor(SensorSpec(), wrench, [0.5])
    np.testing.assert_array_equal(a.read().wrench_sensor, b.read().wrench_sensor)
    assert not SensorSpec().drifts


def test_drift_rate_adds_rate_times_tick_time_in_read_and_read_new() -> None:
    rate = np.array([0.01, -0.02, 0.0, 1e-4, 0.0, -2e-4])
    spec = replace(SensorSpec().ideal(), bias_drift_rate_per_s=rate)
    clock = [10.0]
    sensor = _sensor(spec, np.zeros(6), clock)
    first = sensor.read()
    np.testing.assert_allclose(first.wrench_sensor, spec.bias_6 + rate * 10.0, atol=1e-12)
    clock[0] = 20.0
    batch = sensor.read_new()
    t = np.array([s.t_ns for s in batch]) * 1e-9
    got = np.array([s.wrench_sensor for s in batch])
    np.testing.assert_allclose(got, spec.bias_6 + np.outer(t, rate), atol=1e-9)


def test_random_walk_spreads_with_the_square_root_of_time() -> None:
    walk = np.array([0.1, 0.1, 0.1, 0.002, 0.002, 0.002])
    spec = replace(SensorSpec().ideal().unbiased(), bias_walk_per_sqrt_s=walk)
    ends = []
    for seed in range(300):
        sensor = SimWrenchSensor(spec, lambda: np.zeros(6), lambda: 0.0, seed=seed)
        ends.append(sensor.drift(0, 1)[0] + sensor.drift(1200 * 4, 1)[0])
    spread = np.std(ends, axis=0)
    # 4 s of walk: std = walk * 2; 300 draws give the std within ~4 % (1 sigma), 15 % is ~4 sigma.
    np.testing.assert_allclose(spread, walk * 2.0, rtol=0.15)


def test_sim_uri_reads_gain_and_drift_options() -> None:
    spec = sensor_spec_from_uri(
        parse_uri("sim://?gain_error_percent=1.5&drift_N_per_min=0.6,0,0&drift_walk_N=0.06")
    )
    np.testing.assert_allclose(spec.gain_error_fraction, 0.015)
    assert spec.bias_drift_rate_per_s[0] == pytest.approx(0.01)
    assert spec.bias_walk_per_sqrt_s[0] == pytest.approx(0.06 / math.sqrt(60))
    six = sensor_spec_from_uri(parse_uri("sim://?gain_error_percent=1,2,3,4,5,6"))
    np.testing.assert_allclose(six.gain_error_fraction, np.arange(1, 7) / 100)


def test_sim_uri_rejects_a_bad_gain_with_the_option_named() -> None:
    with pytest.raises(ParameterError, match="gain_error_percent"):
        sensor_spec_from_uri(parse_uri("sim://?gain_error_percent=80"))
    with pytest.raises(ParameterError, match="drift_N_per_min"):
        sensor_spec_from_uri(parse_uri("sim://?drift_N_per_min=1,2"))


def test_sim_uri_gives_the_realistic_drift_at_a_scale() -> None:
    spec = sensor_spec_from_uri(parse_uri("sim://?realistic_drift=2"))
    reference = SensorSpec().realistic_drift(2.0)
    np.testing.assert_array_equal(spec.bias_wander_std, reference.bias_wander_std)
    np.testing.assert_array_equal(spec.bias_trend, reference.bias_trend)
    assert spec.bias_wander_time_constant_s == reference.bias_wander_time_constant_s
    with pytest.raises(ParameterError, match="realistic_drift"):
        sensor_spec_from_uri(parse_uri("sim://?realistic_drift=-1"))
