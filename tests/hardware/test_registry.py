"""Backends by URI: sim:// opens the MuJoCo cell; bad URIs are one clear error."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import Robot, WrenchSensor
from ftcomp.hardware.registry import open_robot, open_sensor, parse_uri
from ftcomp.sim.cell import SimCell


def test_parse_uri_splits_scheme_host_port_path_and_options() -> None:
    uri = parse_uri("netft://127.0.0.3:49152/x?rate=1000&units=si")
    assert (uri.scheme, uri.host, uri.port, uri.path) == ("netft", "127.0.0.3", 49152, "/x")
    assert dict(uri.options) == {"rate": "1000", "units": "si"}


def test_sim_uri_builds_the_cell_it_describes_and_the_sensor_attaches_to_it() -> None:
    with open_robot("sim://?tilt_deg=1.5,-2&load_kg=0.3&grasp=1&seed=4") as robot:
        sensor = open_sensor("sim://", robot)
        assert isinstance(robot, Robot) and isinstance(sensor, WrenchSensor)
        assert isinstance(robot, SimCell) and robot.holding
        assert robot.config.tilt_U_rad == pytest.approx(math.radians(1.5), abs=1e-15)
        assert robot.config.tilt_V_rad == pytest.approx(math.radians(-2.0), abs=1e-15)
        sample = sensor.read()
        assert sample.t_ns <= robot.now_ns() and np.all(np.isfinite(sample.wrench_sensor))


@pytest.mark.parametrize(
    ("robot", "sensor", "message"),
    [
        ("sim://?tilt=1", "sim://", "unknown option 'tilt' for sim://; valid: tilt_deg"),
        ("sim://?tilt_deg=1", "sim://", "option tilt_deg='1': expected 2 comma-separated"),
        ("sim://?load_kg=9", "sim://", "load_kg must be in (0, 4] kg"),
        ("sim://?surface=sand", "sim://", "expected one of none, sponge, book"),
        ("sim://?grasp=1", "sim://", "grasp needs a load"),
        ("sim://?seed=-1", "sim://", "seed must be >= 0"),
        ("warp://x", "sim://", "no robot backend warp://; valid: sim://"),
        ("sim:", "sim://", "not a backend URI"),
        ("sim://", "sim://?seed=1", "the simulated sensor takes no options"),
    ],
)
def test_bad_uris_are_one_clear_error(robot: str, sensor: str, message: str) -> None:
    with pytest.raises(ParameterError) as info, open_robot(robot) as opened:
        open_sensor(sensor, opened)
    assert message in str(info.value) and "\n" not in str(info.value)


def test_the_simulated_sensor_needs_the_simulated_robot() -> None:
    with pytest.raises(ParameterError, match="needs a sim:// robot"):
        open_sensor("sim://", None)
