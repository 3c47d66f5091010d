"""The exported ros2_control parameters, applied exactly as ros-controls' code computes them."""

from __future__ import annotations

import numpy as np
import pytest
from ruamel.yaml import YAML
from scipy.spatial.transform import Rotation

from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.errors import ParameterError
from ftcomp.model import GravityModel
from ftcomp.ros2.export import ros2_control_parameters, yaml_double

from conftest import TRUE_MODEL

#: A clearly tilted base and an off-axis tool, so every term of the chain matters.
TILTED = GravityModel(
    12.5,
    np.array([0.012, -0.008, 0.094]),
    np.array([-0.8613, 1.1015, 0.1976]),
    np.array([-0.0202, -0.0605, 0.0255]),
    tilt_U_rad=np.radians(4.0),
    tilt_V_rad=np.radians(-7.5),
)


def _load(text: str) -> dict:
    return YAML(typ="safe", pure=True).load(text)


def broadcaster_and_filter(params: dict, raw: np.ndarray, R_base_sensor: np.ndarray) -> np.ndarray:
    """force_torque_sensor_broadcaster 6.9.0 then GravityCompensationWrench (control_toolbox
    6.3.0), transcribed: ``(raw + offset) * multiplier``; ``F_g = mass * gravity_field`` in
    world_frame; ``g_s = R_sensor_world F_g``; ``force -= g_s``; ``torque -= CoG x g_s``."""
    offset = params["offset"]
    w = raw.astype(float).copy()
    for i, (kind, axis) in enumerate((f, a) for f in ("force", "torque") for a in "xyz"):
        w[i] += offset[kind][axis]
        w[i] *= params.get("multiplier", {}).get(kind, {}).get(axis, 1.0)
    gc = params["sensor_filter_chain"]["filter1"]
    assert gc["type"] == "control_filters/GravityCompensationWrench"
    tool = gc["params"]["tool"]
    cst_ext_force = np.array(tool["gravity_field"]) * tool["mass"]
    g_s = R_base_sensor.T @ cst_ext_force  # transform_sensor_world_ = lookup(sensor, world)
    w[:3] -= g_s
    w[3:] -= np.cross(np.array(tool["CoG"]), g_s)
    return w


@pytest.mark.parametrize("model", [TILTED, TRUE_MODEL], ids=["tilt-7deg", "paper"])
def test_the_broadcaster_and_filter_compute_what_the_compensator_does(
    model: GravityModel, rng: np.random.Generator
) -> None:
    text = ros2_control_parameters(model, world_frame="base_link", sensor_frame="ft_sensor")
    params = _load(text)["force_torque_sensor_broadcaster"]["ros__parameters"]
    gc = params["sensor_filter_chain"]["filter1"]["params"]
    assert (gc["world_frame"], gc["sensor_frame"]) == ("base_link", "ft_sensor")
    assert params["frame_id"] == "ft_sensor"
    compensator = GravityCompensator(model)
    for R in Rotation.random(50, rng=rng).as_matrix():
        raw = rng.normal(size=6) * np.repeat([20.0, 1.0], 3)
        expected = compensator.compensate(raw, R)
        np.testing.assert_allclose(broadcaster_and_filter(params, raw, R), expected, atol=1e-9)


def test_the_gravity_field_carries_the_tilt_at_standard_gravity() -> None:
    params = _load(ros2_control_parameters(TILTED, world_frame="b", sensor_frame="s"))
    tool = params["force_torque_sensor_broadcaster"]["ros__parameters"]["sensor_filter_chain"][
        "filter1"
    ]["params"]["tool"]
    field = np.array(tool["gravity_field"])
    assert np.linalg.norm(field) == pytest.approx(9.80665, abs=1e-12)
    np.testing.assert_allclose(field * tool["mass"], TILTED.gravity_base_N, atol=1e-12)
    assert abs(field[0]) > 1.0 and abs(field[1]) > 0.5  # 7.5 and 4 degrees of tilt


def test_the_admittance_section_states_what_it_cannot_express() -> None:
    text = ros2_control_parameters(TILTED, world_frame="base_link", sensor_frame="ft_sensor")
    adm = _load(text)["admittance_controller"]["ros__parameters"]
    assert adm["gravity_compensation"]["CoG"]["force"] == TILTED.weight_N
    assert adm["gravity_compensation"]["CoG"]["pos"] == TILTED.center_of_gravity_m.tolist()
    assert adm["gravity_compensation"]["frame"]["id"] == "ft_sensor"
    assert "neither the sensor bias" in text and "nor the base tilt" in text


@pytest.mark.parametrize(
    ("value", "text"), [(1e-05, "1.0e-05"), (-2.0, "-2.0"), (0.1, "0.1"), (3e20, "3.0e+20")]
)
def test_yaml_doubles_always_read_back_as_doubles(value: float, text: str) -> None:
    assert yaml_double(value) == text
    assert _load(f"x: {text}")["x"] == value


def test_a_frame_name_with_yaml_syntax_is_refused() -> None:
    with pytest.raises(ParameterError, match="world frame 'base link'"):
        ros2_control_parameters(TILTED, world_frame="base link", sensor_frame="s")
