"""The netft:// backend through pynetft against the fake Net F/T: units, bias, reading."""

from __future__ import annotations

import itertools
import time

import numpy as np
import pytest

from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.protocols import ReportsRate, WrenchSensor
from ftcomp.hardware.registry import open_robot, open_sensor
from ftcomp.session.run import sensor_rate_hz

pytest.importorskip("pynetft")

from standins.launch import loopback_address, running
from standins.scenario import TOOL_MODEL, Scenario, rotvecs

pytestmark = pytest.mark.live


def _scenario(**options: object) -> Scenario:
    return Scenario(
        t0=time.monotonic(),
        rotvecs_base_tcp=rotvecs([(10.0, -20.0, 160.0)]),
        model=Scenario.model_fields(TOOL_MODEL),
        max_s=8.0,
        **options,  # type: ignore[arg-type]
    )


def _expected(s: Scenario) -> np.ndarray:
    """The noise-free reading the stand-in serves, after quantisation [N, N*m]."""
    p, R_tcp, _ = s.tcp_pose(0.0)
    w = s.gravity_model().predict(s.mount().sensor_pose(p, R_tcp.as_matrix())[1])
    return s.wrench_from_counts(s.counts(w))


@pytest.mark.parametrize(
    ("force_unit", "torque_unit", "cpf", "cpt"),
    [("N", "Nmm", 1e6, 1e3), ("lbf", "lbf-in", 2e5, 4e4), ("kgf", "N-m", 1e5, 1e6)],
)
def test_readings_arrive_in_newtons_whatever_units_the_sensor_is_configured_in(
    force_unit: str, torque_unit: str, cpf: float, cpt: float, request: pytest.FixtureRequest
) -> None:
    s = _scenario(
        force_unit=force_unit, torque_unit=torque_unit, counts_per_force=cpf, counts_per_torque=cpt
    )
    host = loopback_address(request.node.name)
    with running("fake_netft", host, "49152", "8080", s.to_json()):
        sensor = open_sensor(f"netft://{host}?http_port=8080")
        assert isinstance(sensor, WrenchSensor)
        with sensor:
            time.sleep(0.05)
            readings = sensor.read_new()
            latest = sensor.read()
            again = sensor.read_new()
    assert len(readings) >= 30 and latest.t_ns >= readings[-1].t_ns
    assert all(r.t_ns > q.t_ns for q, r in itertools.pairwise(readings))
    assert all(a.t_ns > readings[-1].t_ns for a in again)  # only what arrived since
    resolution = s.wrench_from_counts(np.full(6, 0.5))
    assert np.all(np.abs(latest.wrench_sensor - _expected(s)) <= resolution)
    assert latest.t_ns <= time.monotonic_ns()  # stamped on the host's monotonic clock


def test_bias_zeroes_the_readings(request: pytest.FixtureRequest) -> None:
    s = _scenario()
    host = loopback_address(request.node.name)
    with (
        running("fake_netft", host, "49152", "8080", s.to_json()),
        open_sensor(f"netft://{host}?http_port=8080&bias=1") as sensor,
    ):
        time.sleep(0.1)
        sensor.read_new()
        time.sleep(0.05)
        after = np.array([r.wrench_sensor for r in sensor.read_new()])
    assert len(after) > 10 and np.all(after == 0.0)  # noise-free stand-in: exactly zero


def test_a_closed_stream_is_an_error_not_a_stale_value(request: pytest.FixtureRequest) -> None:
    s = _scenario(silent_after_s=0.2)
    host = loopback_address(request.node.name)
    with (
        running("fake_netft", host, "49152", "8080", s.to_json()),
        open_sensor(f"netft://{host}?http_port=8080&timeout_s=0.1") as sensor,
    ):
        time.sleep(0.6)
        with pytest.raises(HardwareError, match="sensor fault timeout"):
            sensor.read()
        with pytest.raises(HardwareError, match="the stream is closed"):
            sensor.read_new()


@pytest.mark.parametrize(
    ("uri", "message"),
    [
        ("netft://h?timeout_s=0", "timeout_s must be > 0"),
        ("netft://h?http_port=0", "http_port must be in 1..65535"),
        ("netft://h/x", "takes no path"),
    ],
)
def test_bad_options_are_errors_before_connecting(uri: str, message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        open_sensor(uri)


def test_a_net_ft_cannot_share_the_simulated_robots_clock() -> None:
    with open_robot("sim://") as robot, pytest.raises(ParameterError, match="monotonic clock"):
        open_sensor("netft://127.0.0.9", robot)


def test_the_sample_rate_is_the_stand_ins_to_a_few_percent(request: pytest.FixtureRequest) -> None:
    """What ``run`` sets its wrench filter from (pynetft's own rate estimate starts low:
    67 Hz of a 1 kHz stream a second in, measured on the twin)."""
    s = _scenario(rate_hz=250.0)
    host = loopback_address(request.node.name)
    with (
        running("fake_netft", host, "49152", "8080", s.to_json()),
        open_sensor(f"netft://{host}?http_port=8080") as sensor,
    ):
        assert isinstance(sensor, ReportsRate)
        rate = sensor_rate_hz(sensor)
    # the stand-in paces 250 Hz on an absolute schedule: a late packet is followed by the next
    # on time, so the mean over at least RATE_MIN_SPAN_S (50 readings) is its rate within its
    # own lateness (a first reading 4 ms late: 2 %)
    assert rate == pytest.approx(250.0, rel=0.1)
