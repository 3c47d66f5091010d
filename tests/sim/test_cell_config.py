"""CellConfig: one typed record of a simulated cell, its ranges checked once, the sim:// URI's
parse, and the cell it opens."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from ftcomp.errors import ParameterError
from ftcomp.hardware.registry import open_robot, open_sensor, parse_uri
from ftcomp.sim.arm import DHArmSpec, ur5e_arm
from ftcomp.sim.backend import cell_config_from_uri
from ftcomp.sim.cell import COLLECTION_POSITION_BASE_M, SimCell
from ftcomp.sim.cell_config import MAX_LOAD_KG, CellConfig


def test_the_uri_parses_into_the_config_with_every_option() -> None:
    uri = (
        "sim://?arm=ur5e&tilt_deg=1.5,-2&load_kg=0.5&grasp=1&surface=sponge&clearance_mm=3"
        "&seed=7&gain_error_percent=1,2,3,4,5,6&drift_N_per_min=0.6,0,-0.3"
        "&drift_Nm_per_min=0,0.01,0&drift_walk_N=0.05&realistic_drift=2"
    )
    config = cell_config_from_uri(parse_uri(uri))
    assert isinstance(config.arm, DHArmSpec) and config.arm.name == "ur5e"
    arm = ur5e_arm()  # (arrays inside: the same object on both sides compares equal)
    assert replace(config, arm=arm) == CellConfig(
        arm=arm,
        tilt_deg=(1.5, -2.0),
        load_kg=0.5,
        grasp=True,
        surface="sponge",
        clearance_mm=3.0,
        seed=7,
        gain_error_percent=(1.0, 2.0, 3.0, 4.0, 5.0, 6.0),
        drift_N_per_min=(0.6, 0.0, -0.3),
        drift_Nm_per_min=(0.0, 0.01, 0.0),
        drift_walk_N=0.05,
        realistic_drift=2.0,
    )


def test_one_gain_error_is_every_axis_gain_error() -> None:
    assert CellConfig(gain_error_percent=1.5).gain_error_percent == (1.5,) * 6
    np.testing.assert_allclose(
        CellConfig(gain_error_percent=1.5).sensor_spec().gain_error_fraction, 0.015
    )


def test_the_uri_without_a_tilt_has_the_papers_tilt_and_the_config_is_level() -> None:
    from ftcomp import paper

    assert cell_config_from_uri(parse_uri("sim://")).tilt_deg == paper.TILT_DEG
    assert CellConfig().tilt_deg == (0.0, 0.0)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"tilt_deg": (30.0, 0.0)}, "tilt_deg must be within +-30 deg"),
        ({"tilt_deg": (1.0,)}, "tilt_deg needs 2 values within +-30 deg"),
        ({"load_kg": MAX_LOAD_KG + 0.1}, "load_kg must be in (0, 4] kg"),
        ({"load_kg": 0.0}, "load_kg must be in"),
        ({"load_kg": 0.5, "gripper": False}, "load_kg needs the gripper"),
        ({"grasp": True}, "grasp needs a load"),
        ({"surface": "sand"}, "surface must be one of none, sponge, book"),
        ({"load_kg": 0.5, "grasp": True, "clearance_mm": 2.0}, "clearance_mm needs grasp and a"),
        (
            {"load_kg": 0.5, "grasp": True, "surface": "book", "clearance_mm": 101.0},
            "clearance_mm must be in [0, 100]",
        ),
        ({"seed": -1}, "seed must be >= 0"),
        ({"gain_error_percent": 50.0}, "gain_error_percent must be within +-50 %"),
        ({"gain_error_percent": (1.0, 2.0)}, "gain_error_percent needs 6 values"),
        ({"drift_N_per_min": (1.0, math.nan, 0.0)}, "drift_N_per_min must be finite on every axis"),
        ({"drift_walk_N": -0.1}, "drift_walk_N must be >= 0"),
        ({"realistic_drift": 101.0}, "realistic_drift must be in [0, 100]"),
        ({"p_flange_sensor_m": (0.0, 0.0, 0.1)}, "needs an arm given by a DH table"),
    ],
)
def test_a_bad_field_is_one_error_naming_it(kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(ParameterError) as info:
        CellConfig(**kwargs)  # type: ignore[arg-type]
    assert message in str(info.value) and "\n" not in str(info.value)
    if "SceneConfig" not in str(info.value):  # the field is named for the CLI to map to a flag
        assert str(info.value).startswith(info.value.fields[0])


def test_a_bad_uri_option_names_the_uri_and_the_field() -> None:
    with pytest.raises(ParameterError, match=r"^'sim://\?load_kg=9': load_kg must be in") as info:
        open_robot("sim://?load_kg=9")
    assert info.value.fields == ("load_kg",)
    with pytest.raises(ParameterError, match="arm='franka': expected one of c4, fr3, ur5e"):
        open_robot("sim://?arm=franka")


def test_open_cell_holds_the_grasped_load_at_the_clearance() -> None:
    config = CellConfig(load_kg=0.5, grasp=True, surface="sponge", clearance_mm=4.0, seed=2)
    with config.open_cell() as cell:
        assert cell.holding
        p_target, _ = cell.placement_pose(0.004)
        np.testing.assert_allclose(cell.pose().p_base_tcp, p_target, atol=2e-4)


def test_open_cell_is_what_the_uri_opens_reading_for_reading() -> None:
    uri = "sim://?seed=4&surface=book&load_kg=0.5&grasp=1&clearance_mm=2&gain_error_percent=1"
    config = cell_config_from_uri(parse_uri(uri))
    a, b = config.open_cell(), open_robot(uri)
    assert isinstance(b, SimCell)
    sensor_b = open_sensor("sim://", b)
    for _ in range(20):
        a.wait_cycle()
        b.wait_cycle()
    np.testing.assert_array_equal(a.sensor.read().wrench_sensor, sensor_b.read().wrench_sensor)
    np.testing.assert_array_equal(a.pose().p_base_tcp, b.pose().p_base_tcp)


def test_an_offset_sensor_starts_at_the_start_pose_tool_down() -> None:
    config = CellConfig(arm=ur5e_arm(), p_flange_sensor_m=(0.0, 0.02, 0.05))
    with config.open_cell() as cell:
        pose = cell.pose()
        np.testing.assert_allclose(pose.p_base_tcp, COLLECTION_POSITION_BASE_M, atol=1e-4)
        np.testing.assert_allclose(pose.R_base_tcp, np.diag([1.0, -1.0, -1.0]), atol=1e-3)
