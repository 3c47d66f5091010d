"""A bias that follows the sensor's temperature, applied at run time: the compensator from each
reading's ``temperature_C`` (held at the calibrated range's ends, never silently without one),
the cycle's pipeline from the sensor's extra channel, once per reading."""

from __future__ import annotations

import csv
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftcomp
from calibration.temperature_data import SLOPES, T0_C, TOOL, recording
from ftcomp.calibration.identify import calibrate
from ftcomp.calibration_record import BiasDrift, Calibration, TemperatureBiasDrift
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.compensation.pipeline import WrenchPipeline
from ftcomp.control.loop import ControlCycle
from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import NothingToClose, WrenchSample, WrenchSensor
from ftcomp.session.stream import StreamConfig, stream

HEAT = TemperatureBiasDrift(T0_C, 20.0, 30.0, SLOPES, np.full(6, 1e-3))


@pytest.fixture(scope="module")
def thermal() -> Calibration:
    """The true tool with the true temperature slopes (a calibration's record around them)."""
    return replace(calibrate(recording(1), leave_one_out=False), model=TOOL, bias_drift=HEAT)


def _reading(R: np.ndarray, T: np.ndarray | float) -> np.ndarray:
    return TOOL.predict(R) + np.multiply.outer(np.asarray(T, float) - T0_C, SLOPES)


def test_the_compensator_removes_the_bias_at_each_readings_temperature(thermal) -> None:
    rng = np.random.default_rng(7)
    R = Rotation.random(50, random_state=rng).as_matrix()
    T = rng.uniform(20.0, 30.0, 50)
    comp = GravityCompensator(thermal)
    assert comp.needs_temperature
    batch = comp.compensate(_reading(R, T), R, temperature_C=T)
    one = np.array(
        [comp.compensate(_reading(R[k], T[k]), R[k], temperature_C=T[k]) for k in range(50)]
    )
    # exact algebra on floats: rounding only
    np.testing.assert_allclose(batch, 0.0, atol=1e-9)
    np.testing.assert_allclose(one, batch, atol=1e-12)
    # the time drift is not this model's: a time changes nothing
    t_far = comp.compensate(_reading(R[0], T[0]), R[0], temperature_C=T[0], t_s=1e9)
    np.testing.assert_allclose(t_far, 0.0, atol=1e-9)


def test_a_temperature_beyond_the_calibrated_range_holds_the_bias_at_its_end(thermal) -> None:
    comp = GravityCompensator(thermal)
    R = np.eye(3)
    hot = comp.compensate(_reading(R, 35.0), R, temperature_C=35.0)
    cold = comp.compensate(_reading(R, 15.0), R, temperature_C=15.0)
    # held at 30 and 20 degC: what is left is the slope times the 5 degC beyond
    np.testing.assert_allclose(hot, SLOPES * 5.0, atol=1e-9)
    np.testing.assert_allclose(cold, -SLOPES * 5.0, atol=1e-9)
    assert "above 30 degC the bias is held" in (HEAT.outside(22.0, 35.0) or "")
    assert HEAT.outside(21.0, 29.0) is None


def test_a_temperature_model_without_a_temperature_is_an_error_not_a_constant_bias(
    thermal,
) -> None:
    comp = GravityCompensator(thermal)
    with pytest.raises(ParameterError, match="needs each reading's temperature_C"):
        comp.compensate(_reading(np.eye(3), 25.0), np.eye(3))
    nan = comp.compensate(_reading(np.eye(3), 25.0), np.eye(3), temperature_C=np.nan)
    assert np.isnan(nan).all()  # garbage in: the loop's watchdog stops on it


def test_a_calibration_in_time_ignores_a_temperature(thermal) -> None:
    drift = BiasDrift(1, 10.0, 0.0, 10.0, np.full((1, 6), 0.01), np.zeros((1, 6)))
    comp = GravityCompensator(replace(thermal, bias_drift=drift))
    assert not comp.needs_temperature
    w = TOOL.predict(np.eye(3))
    np.testing.assert_allclose(
        comp.compensate(w, np.eye(3), t_s=5.0, temperature_C=99.0),
        comp.compensate(w, np.eye(3), t_s=5.0),
        atol=0.0,
    )


def test_a_pipeline_refuses_a_temperature_model_for_a_sensor_without_a_temperature(
    thermal,
) -> None:
    with pytest.raises(ParameterError, match=r"the sensor reports no temperature_C .*: none"):
        WrenchPipeline(GravityCompensator(thermal))
    with pytest.raises(ParameterError, match="channels: accel_x_m_s2"):
        WrenchPipeline(GravityCompensator(thermal), extra_channels=("accel_x_m_s2",))
    with pytest.raises(ParameterError, match="reports no temperature_C"):
        WrenchPipeline.weighing(thermal, 500.0)
    with pytest.raises(ParameterError, match="reports no temperature_C"):
        WrenchPipeline.weighing(thermal, None)


class _WarmingSensor(NothingToClose):
    """``sensor`` (entered by the caller) whose bias follows a temperature that rises 10 degC
    a second from 22 degC, reported with each reading (after the IMU's first channel)."""

    extra_channels = ("accel_x_m_s2", "temperature_C")

    def __init__(self, sensor: WrenchSensor) -> None:
        self.sensor = sensor

    def _warm(self, sample: WrenchSample) -> WrenchSample:
        T = 22.0 + 10.0 * (sample.t_ns % 800_000_000) * 1e-9
        w = sample.wrench_sensor + (T - T0_C) * SLOPES
        return WrenchSample(sample.t_ns, w, (0.0, T))

    def read(self) -> WrenchSample:
        return self._warm(self.sensor.read())

    def read_new(self) -> list[WrenchSample]:
        return [self._warm(s) for s in self.sensor.read_new()]


def test_a_stream_compensates_each_reading_once_at_its_own_temperature(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    calls: list[Any] = []
    compensate = GravityCompensator.compensate

    def counted(c: GravityCompensator, *args: Any, **kwargs: Any) -> Any:
        calls.append(kwargs.get("temperature_C"))
        return compensate(c, *args, **kwargs)

    with ftcomp.open_robot("sim://?seed=4") as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        tool = robot.true_gravity_model()  # type: ignore[attr-defined]
        calibration = replace(calibrate(recording(1), leave_one_out=False), model=tool)
        monkeypatch.setattr(GravityCompensator, "compensate", counted)
        log = tmp_path / "s.csv"
        result = stream(
            robot,
            _WarmingSensor(sensor),
            StreamConfig(0.3),
            log,
            calibration=replace(calibration, bias_drift=HEAT),
        )
    assert result.outcome == "duration" and result.readings > 300
    with log.open() as f:
        rows = list(csv.DictReader(f))
    temperatures = np.array([float(r["temperature_C"]) for r in rows])
    assert np.ptp(temperatures) > 1.0  # the bias moved by 0.1 N and more while streaming
    contact = np.array([[float(r[c]) for c in ("cfx", "cfy", "cfz")] for r in rows])
    # the simulated sensor's noise and the still arm's settling leave the contact at a few
    # 0.01 N; without the temperature model its bias error would reach 0.12 * 3 = 0.36 N
    assert np.max(np.abs(contact.mean(axis=0))) < 0.03
    # every reading compensated once, each with its own temperature
    assert len(calls) >= result.readings and all(T is not None for T in calls)
    assert result.temperature_outside == ""  # 22-30 degC: within the calibrated 20-30


def test_a_pipeline_says_when_readings_left_the_calibrated_temperatures(thermal) -> None:
    R = np.eye(3)
    pipeline = WrenchPipeline(GravityCompensator(thermal), extra_channels=("temperature_C",))
    for k, T in enumerate((25.0, 29.0, 21.0)):
        pipeline.contact(k, _reading(R, T), R, (T,))
    assert pipeline.temperature_outside() == ""
    hot = pipeline.contact(3, _reading(R, 31.5), R, (31.5,))
    np.testing.assert_allclose(hot, SLOPES * 1.5, atol=1e-9)  # held at 30 degC
    said = pipeline.temperature_outside()
    assert "temperatures 21 .. 31.5 degC" in said and "above 30 degC the bias is held" in said


class _Still(NothingToClose):
    """A sensor on a still arm: the tool's reading at ``R``, stamped by a counter."""

    def __init__(self, R: np.ndarray) -> None:
        self.wrench, self.t_ns = TOOL.predict(R), 0

    def read(self) -> WrenchSample:
        self.t_ns += 2_000_000
        return WrenchSample(self.t_ns, self.wrench)

    def read_new(self) -> list[WrenchSample]:
        return [self.read()]


def test_a_control_cycle_compensates_its_newest_reading_at_its_temperature(thermal) -> None:
    with ftcomp.open_robot("fixed://?rpy_deg=0,180,0") as robot:
        R = robot.pose().R_base_tcp
        cycle = ControlCycle(
            robot, _WarmingSensor(_Still(R)), compensator=GravityCompensator(thermal)
        )
        readings = [cycle.read() for _ in range(20)]
    temperatures = [r.extras[1] for r in readings]
    assert max(temperatures) - min(temperatures) > 0.3  # 40 ms at 10 degC/s
    # exact algebra: the bias at each reading's temperature removed, rounding only
    np.testing.assert_allclose([r.wrench_contact_sensor for r in readings], 0.0, atol=1e-9)
