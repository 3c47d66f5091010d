"""The exported ros2_control parameters, applied exactly as ros-controls' code computes them."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
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


def test_a_frame_name_with_yaml_syntax_is_written_quoted_and_read_back() -> None:
    # tf2 takes 'base link: x' as a frame id; quoted, YAML reads it back as that string.
    text = ros2_control_parameters(TILTED, world_frame="base link: x", sensor_frame="s")
    assert 'world_frame: "base link: x"' in text


NAME_OPTIONS = ("world_frame", "sensor_frame", "sensor_name", "broadcaster", "admittance")


def _names_read_back(params: dict, names: dict[str, str]) -> dict[str, object]:
    """Every name as a YAML 1.2 parser reads it back from the exported file."""
    broadcaster = params[names["broadcaster"]]["ros__parameters"]
    admittance = params[names["admittance"]]["ros__parameters"]
    gc = broadcaster["sensor_filter_chain"]["filter1"]["params"]
    return {
        "broadcaster frame_id": broadcaster["frame_id"],
        "broadcaster sensor_name": broadcaster["sensor_name"],
        "filter world_frame": gc["world_frame"],
        "filter sensor_frame": gc["sensor_frame"],
        "admittance sensor name": admittance["ft_sensor"]["name"],
        "admittance world frame": admittance["fixed_world_frame"]["frame"]["id"],
    }


@pytest.mark.parametrize("name", ["yes", "no", "on", "null", "true", "Null", "nan", "inf", "y"])
def test_names_that_yaml_reads_as_other_types_are_written_as_strings(name: str) -> None:
    names = {**dict.fromkeys(NAME_OPTIONS, name), "admittance": name + "_admittance"}
    text = ros2_control_parameters(TILTED, **names)
    # YAML 1.2 (ruamel's default) and YAML 1.1 (the rules of ROS's parameter parser, where
    # yes, on and y are booleans too): the same strings either way.
    for document in (text, "%YAML 1.1\n---\n" + text):
        read = _names_read_back(_load(document), names)
        for value in read.values():
            assert value == name and isinstance(value, str)


def test_the_two_controllers_may_not_share_a_name() -> None:
    with pytest.raises(ParameterError, match="admittance controller name 'c'"):
        ros2_control_parameters(
            TILTED, world_frame="b", sensor_frame="s", broadcaster="c", admittance="c"
        )


@pytest.mark.parametrize("name", ["", "/a", "/base_link"])
def test_a_frame_tf2_refuses_is_refused(name: str) -> None:
    with pytest.raises(ParameterError, match=r"world frame .*: not a valid tf2 frame id"):
        ros2_control_parameters(TILTED, world_frame=name, sensor_frame="s")


@pytest.mark.parametrize("name", ["0x1F", "sensor-1", "a:b", "ur/tool0", "yes", "a/"])
def test_a_tf2_frame_id_that_is_no_ros_name_is_accepted_and_quoted(name: str) -> None:
    text = ros2_control_parameters(TILTED, world_frame="base", sensor_frame=name)
    assert f"frame_id: {json.dumps(name)}" in text


@pytest.mark.parametrize("name", ["~", "1", "0x1F", "a b", "a/b", ""])
def test_a_controller_name_that_is_not_a_ros_name_is_refused(name: str) -> None:
    with pytest.raises(ParameterError, match=r"broadcaster name .*: not a valid ROS name"):
        ros2_control_parameters(TILTED, world_frame="b", sensor_frame="s", broadcaster=name)


#: Any printable text (ASCII and Unicode), ROS-valid names, and the words YAML 1.1 reads as
#: booleans or null.
NAMES = st.one_of(
    st.text(st.characters(min_codepoint=32, max_codepoint=126), max_size=12),
    st.text(st.characters(categories=("L", "N", "P", "S", "Zs")), max_size=8),  # any printable
    st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,6}(/[A-Za-z_][A-Za-z0-9_]{0,4}){0,2}", fullmatch=True),
    st.sampled_from(["yes", "No", "ON", "off", "y", "n", "null", "Null", "true", "False"]),
)


@settings(max_examples=200, deadline=None)
@given(names=st.fixed_dictionaries(dict.fromkeys(NAME_OPTIONS, NAMES)))
def test_any_printable_name_is_refused_or_read_back_by_yaml_1_2_as_that_string(
    names: dict[str, str],
) -> None:
    try:
        text = ros2_control_parameters(TILTED, **names)
    except ParameterError:
        return
    assert _load(text) == _load("%YAML 1.1\n---\n" + text)  # and YAML 1.1 reads the same
    params = _load(text)
    assert names["broadcaster"] in params and names["admittance"] in params
    read = _names_read_back(params, names)
    assert read["filter world_frame"] == read["admittance world frame"] == names["world_frame"]
    for key in ("broadcaster frame_id", "filter sensor_frame"):
        assert read[key] == names["sensor_frame"]
    for key in ("broadcaster sensor_name", "admittance sensor name"):
        assert read[key] == names["sensor_name"]
    assert all(isinstance(v, str) for v in read.values())


def _round_trip(text: str) -> dict:
    """Load with ruamel's round-trip loader, dump, load again (comments and quotes kept)."""
    import io

    rt = YAML(typ="rt")
    first = rt.load(text)
    out = io.StringIO()
    rt.dump(first, out)
    again = rt.load(out.getvalue())
    assert again == first
    return _load(out.getvalue())


@pytest.mark.parametrize("distro", ["humble", "jazzy", "kilted", "rolling"])
def test_each_distribution_gets_a_file_that_round_trips_and_says_what_to_add(distro: str) -> None:
    text = ros2_control_parameters(
        TILTED, world_frame="base_link", sensor_frame="ft_sensor", distro=distro
    )
    params = _round_trip(text)
    assert f"for ROS 2 {distro}" in text
    broadcaster = params["force_torque_sensor_broadcaster"]["ros__parameters"]
    has_chain = "sensor_filter_chain" in broadcaster
    assert has_chain == (
        distro != "humble"
    )  # Humble: no filter chain, no GravityCompensationWrench
    admittance = params["admittance_controller"]["ros__parameters"]
    # The admittance section is a fragment: every required parameter the export does not write
    # is named in the comment above it (admittance_controller_parameters.yaml, no default).
    required = [
        "joints", "command_interfaces", "state_interfaces", "chainable_command_interfaces",
        "kinematics.plugin_name", "kinematics.plugin_package", "kinematics.base",
        "kinematics.tip", "ft_sensor.name", "ft_sensor.frame.id", "control.frame.id",
        "fixed_world_frame.frame.id", "gravity_compensation.frame.id",
        "gravity_compensation.CoG.pos", "admittance.selected_axes", "admittance.mass",
        "admittance.damping_ratio", "admittance.stiffness",
    ]  # fmt: skip
    fragment = text[text.index("A FRAGMENT") :]
    for name in required:
        node: object = admittance
        for key in name.split("."):
            node = node.get(key) if isinstance(node, dict) else None
        assert node is not None or name in fragment, name


def test_the_chained_admittance_reads_the_broadcasters_interfaces_where_they_exist() -> None:
    kwargs = {"world_frame": "base_link", "sensor_frame": "ft_sensor", "sensor_name": "tcp_fts"}
    text = ros2_control_parameters(TILTED, distro="jazzy", chained=True, **kwargs)
    adm = _round_trip(text)["admittance_controller"]["ros__parameters"]
    assert adm["ft_sensor"]["name"] == "force_torque_sensor_broadcaster/tcp_fts"
    assert "the bias removed by its offset" in text
    with pytest.raises(ParameterError, match="humble's force_torque_sensor_broadcaster"):
        ros2_control_parameters(TILTED, distro="humble", chained=True, **kwargs)
    with pytest.raises(ParameterError, match="distro 'iron'"):
        ros2_control_parameters(TILTED, distro="iron", **kwargs)
