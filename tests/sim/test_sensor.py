"""The sensor model: bias, noise, quantisation, saturation, overload, 1.2 kHz ticks."""

from __future__ import annotations

import numpy as np
import pytest

from ftcomp.errors import ParameterError
from ftcomp.sim.sensor import SensorSpec, SimWrenchSensor


def _sensor(spec: SensorSpec, wrench: np.ndarray, clock: list[float], seed: int = 0):
    return SimWrenchSensor(spec, lambda: wrench.copy(), lambda: clock[0], seed=seed)


def test_paper_sensor_quantises_to_one_2000th_of_its_range() -> None:
    spec = SensorSpec()
    np.testing.assert_allclose(spec.step_6, [0.125] * 3 + [0.003] * 3, rtol=1e-12)
    readings, _ = spec.apply(np.full((50, 6), 0.3), np.random.default_rng(1).normal(size=(50, 6)))
    counts = readings / spec.step_6
    # Exact algebra: every reading is a whole number of steps.
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-9)


def test_readings_saturate_at_the_range_and_flag_overload_beyond_its_limit() -> None:
    spec = SensorSpec().ideal().unbiased()
    ideal = np.array([[300.0, 0, 0, 0, 0, 0], [1100.0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, -13.0]])
    readings, overloaded = spec.apply(ideal, np.zeros((3, 6)))
    assert readings[0, 0] == 250.0 and readings[2, 5] == -6.0
    assert overloaded.tolist() == [False, True, True]


def test_ideal_sensor_reads_the_wrench_plus_bias_exactly() -> None:
    spec = SensorSpec().ideal()
    wrench = np.array([1.0, -2.0, 3.0, 0.01, -0.02, 0.03])
    clock = [0.01]
    sample = _sensor(spec, wrench, clock).read()
    np.testing.assert_allclose(sample.wrench_sensor, wrench + spec.bias_6, atol=1e-15)


def test_noise_has_the_specified_standard_deviation() -> None:
    spec = SensorSpec(resolution_fraction_of_range=0.0).unbiased()
    clock = [0.0]
    sensor = _sensor(spec, np.zeros(6), clock)
    readings = sensor.convert(np.zeros((20000, 6)))
    # 20000 draws: the sample std is within ~1 % (3 sigma) of the true one.
    np.testing.assert_allclose(readings.std(axis=0), spec.noise_std_6, rtol=0.03)


def test_dithered_quantisation_leaves_means_unbiased() -> None:
    spec = SensorSpec().unbiased()
    true = np.array([0.3, -1.04, 2.71, 0.0011, -0.0047, 0.0123])
    sensor = _sensor(spec, true, [0.0], seed=3)
    readings = sensor.convert(np.tile(true, (40000, 1)))
    standard_error = spec.noise_std_6 / np.sqrt(len(readings))
    assert np.all(np.abs(readings.mean(axis=0) - true) < 4 * standard_error)


def test_reads_come_at_1200_hz_ticks_and_repeat_within_a_tick() -> None:
    clock = [0.0]
    sensor = _sensor(SensorSpec(), np.zeros(6), clock)
    times = []
    for k in range(1, 30):
        clock[0] = k * 1e-3
        times.append(sensor.read().t_s)
    ticks = np.array(times) * 1200.0
    # Stamps are integer nanoseconds: a tick's time rounded to 0.5 ns is 6e-7 of a tick.
    np.testing.assert_allclose(ticks, np.round(ticks), atol=1200 * 0.5e-9)
    assert np.all(np.diff(times) > 0.0), "a 1 kHz reader never sees the same tick twice"
    first = sensor.read()
    assert sensor.read() is first


def test_same_seed_gives_the_same_readings() -> None:
    a = _sensor(SensorSpec(), np.ones(6), [0.0], seed=7).convert(np.ones((100, 6)))
    b = _sensor(SensorSpec(), np.ones(6), [0.0], seed=7).convert(np.ones((100, 6)))
    c = _sensor(SensorSpec(), np.ones(6), [0.0], seed=8).convert(np.ones((100, 6)))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.parametrize(
    ("field", "value"),
    [("force_range_N", 0.0), ("force_noise_std_N", -1.0), ("overload_force_percent", 50.0)],
)
def test_sensor_spec_rejects_impossible_values(field: str, value: float) -> None:
    with pytest.raises(ParameterError, match=field):
        SensorSpec(**{field: value})


def test_a_stream_gets_every_tick_once_also_when_reads_come_between() -> None:
    # A streaming loop calls read() (the controller's newest sample) and then read_new() (the
    # log) every 1 ms cycle: the log must still get every 1.2 kHz tick, once, in order, and the
    # very sample read() returned.
    clock = [0.0]
    sensor = _sensor(SensorSpec(), np.array([1.0, 2.0, 3.0, 0.1, 0.2, 0.3]), clock)
    streamed = sensor.read_new()  # starts the stream with the newest reading
    seen_by_read = []
    for k in range(1, 101):
        clock[0] = k * 1e-3
        seen_by_read.append(sensor.read())
        if k % 7 == 0:
            clock[0] += 0.0004  # a stalled cycle: the log catches up later
        streamed += sensor.read_new()
    ticks = np.round(np.array([s.t_ns for s in streamed]) * 1200e-9).astype(int)
    np.testing.assert_array_equal(ticks, np.arange(ticks[0], ticks[-1] + 1))
    by_stamp = {s.t_ns: s for s in streamed}
    assert all(by_stamp[s.t_ns] is s for s in seen_by_read)
    assert sensor.read_new() == []  # nothing new at the same time
