"""The cycle's one wrench pipeline: each reading compensated once, by the cycle, whatever the
session (``run`` one per cycle, ``stream`` one per reading); an online load weighed at a rate
measured from the readings, the readings held back meanwhile and none lost."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

import ftcomp
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.compensation.online import OnlineLoadCompensator, OnlineSettings
from ftcomp.compensation.pipeline import MIN_RATE_READINGS, WrenchPipeline
from ftcomp.control.loop import ControlCycle
from ftcomp.control.safety import SafetyLimits
from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import IMU_CHANNELS
from ftcomp.model import GravityModel
from ftcomp.session.run import AdmittanceConfig, RunConfig, run_compliant
from ftcomp.session.stream import StreamConfig, stream

BIAS = np.array([0.3, -0.2, 0.1, 0.01, -0.02, 0.03])
MODEL = GravityModel(
    10.0, np.array([0.001, -0.002, 0.05]), BIAS[:3], BIAS[3:], tilt_U_rad=0.0, tilt_V_rad=0.0
)


class _Counted:
    """Counts the calls of ``GravityCompensator.compensate`` and of ``ControlCycle.read``."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.compensations = 0
        self.reads = 0
        compensate, read = GravityCompensator.compensate, ControlCycle.read

        def counted_compensate(c: GravityCompensator, *args: Any, **kwargs: Any) -> Any:
            self.compensations += 1
            return compensate(c, *args, **kwargs)

        def counted_read(cycle: ControlCycle) -> Any:
            self.reads += 1
            return read(cycle)

        monkeypatch.setattr(GravityCompensator, "compensate", counted_compensate)
        monkeypatch.setattr(ControlCycle, "read", counted_read)


def test_a_run_compensates_once_per_cycle(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    limits = SafetyLimits(
        max_twist=np.array([0.02] * 3 + [0.5] * 3),
        max_twist_rate=np.array([0.5] * 3 + [5.0] * 3),
        max_travel=np.array([0.02] * 3 + [0.1] * 3),
        max_force_N=40.0,
        max_torque_Nm=8.0,
        stale_after_s=0.02,
    )
    with ftcomp.open_robot("sim://?seed=4") as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        tool = robot.true_gravity_model()  # type: ignore[attr-defined]
        counted = _Counted(monkeypatch)
        result = run_compliant(
            robot,
            sensor,
            tool,
            RunConfig(AdmittanceConfig(limits), duration_s=0.3),
            tmp_path / "r.csv",
        )
    assert result.outcome == "duration" and result.cycles > 250
    # Every cycle read once (the last read ends the run), and compensated what it read once.
    assert counted.reads == result.cycles + 1
    assert counted.compensations == counted.reads


def test_a_stream_compensates_each_reading_once(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    with ftcomp.open_robot("sim://?seed=4") as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        tool = robot.true_gravity_model()  # type: ignore[attr-defined]
        delivered: list[int] = []
        read_new = sensor.read_new

        def counted_read_new() -> Any:
            batch = read_new()
            delivered.append(len(batch))
            return batch

        sensor.read_new = counted_read_new  # type: ignore[method-assign]
        counted = _Counted(monkeypatch)
        result = stream(robot, sensor, StreamConfig(0.3), tmp_path / "s.csv", calibration=tool)
    assert result.outcome == "duration" and result.readings > 300
    # The sensor's rate (1.2 kHz) above the loop's (1 kHz): some cycles take two readings.
    readings = sum(delivered[1:])  # the first call drops what came before the loop
    assert counted.reads < readings
    assert counted.compensations == readings  # each reading once, by the cycle alone
    assert result.readings <= readings  # those stamped before the end


def test_a_rate_measured_from_the_readings_holds_them_back_and_loses_none(
    rng: np.random.Generator,
) -> None:
    rate_Hz = 1000.0
    measured = WrenchPipeline.weighing(MODEL, None, measure_s=0.05)
    given = WrenchPipeline.weighing(MODEL, rate_Hz)
    R, p = np.eye(3), np.zeros(3)
    g_sensor = np.array([0.0, 0.0, -10.0])
    for k in range(200):
        w = BIAS + np.r_[g_sensor, np.zeros(3)] + rng.normal(size=6) * 0.01
        for pipeline in (measured, given):
            pipeline.push(k * 1_000_000, w, R, p)
        if k < MIN_RATE_READINGS - 1 or k < 50:
            assert measured.measuring and not measured.ready
    measured.finish()
    assert not measured.measuring
    assert measured.rate_Hz == pytest.approx(rate_Hz)
    assert measured.rate_source.startswith("measured from 51 readings")
    assert [c.t_ns for c in measured.ready] == [c.t_ns for c in given.ready]
    for a, b in zip(measured.ready, given.ready, strict=True):
        np.testing.assert_allclose(a.wrench_contact_sensor, b.wrench_contact_sensor, atol=1e-9)
        assert a.load == b.load and len(a.load) == 7


def test_a_pipeline_passes_the_raw_reading_on_without_a_compensator() -> None:
    pipeline = WrenchPipeline()
    w = np.arange(6.0)
    assert pipeline.contact(0, w, np.eye(3)) is w
    assert pipeline.load is None and np.isnan(pipeline.rate_Hz)
    assert isinstance(WrenchPipeline.weighing(MODEL, 500.0).compensator, OnlineLoadCompensator)
    with pytest.raises(ParameterError, match="rate must be > 0"):
        WrenchPipeline.weighing(MODEL, 0.0)
    with pytest.raises(ParameterError, match="needs a calibration with a tool weight"):
        weightless = GravityModel(
            0.0, np.zeros(3), np.zeros(3), np.zeros(3), tilt_U_rad=0.0, tilt_V_rad=0.0
        )
        WrenchPipeline.weighing(weightless)
    still = WrenchPipeline.weighing(MODEL, None, settings=OnlineSettings())
    with pytest.raises(ParameterError, match="still being measured"):
        still.contact(0, w, np.eye(3))


def test_a_pipeline_with_the_accelerometer_takes_each_readings_own_acceleration() -> None:
    channels = ("temperature_C", *IMU_CHANNELS)
    pipeline = WrenchPipeline(
        GravityCompensator(MODEL), extra_channels=channels, accelerometer=True
    )
    reading, R = np.arange(6.0), np.eye(3)
    extras = (25.0, 0.4, -1.2, -9.3, 0.1, 0.2, 0.3)
    np.testing.assert_array_equal(
        pipeline.contact(0, reading, R, extras),
        GravityCompensator(MODEL).compensate(reading, R, specific_force_mps2=extras[1:4]),
    )
    weighing = WrenchPipeline.weighing(MODEL, 500.0, extra_channels=channels, accelerometer=True)
    online = OnlineLoadCompensator(MODEL, OnlineSettings(rate_Hz=500.0))
    np.testing.assert_array_equal(
        weighing.contact(0, reading, R, extras),
        online.compensate(reading, R, specific_force_mps2=extras[1:4]),
    )
    # Without it the same reading is held at its pose's gravity.
    plain = WrenchPipeline(GravityCompensator(MODEL), extra_channels=channels)
    np.testing.assert_array_equal(
        plain.contact(0, reading, R, extras), GravityCompensator(MODEL).compensate(reading, R)
    )
    with pytest.raises(ParameterError, match=r"accelerometer: the sensor reports no acc.*accel_y"):
        WrenchPipeline(
            GravityCompensator(MODEL), extra_channels=("accel_x_m_s2",), accelerometer=True
        )
