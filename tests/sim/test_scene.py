"""The MJCF cell: it compiles, and what hangs below the sensor weighs what the paper says."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import ParameterError
from ftcomp.paper import TABLE4_LOAD_WEIGHTS_N
from ftcomp.sim.scene import NAMES, SceneConfig, build_mjcf
from ftcomp.sim.tool import LoadSpec, table4_loads


def _model(config: SceneConfig) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(build_mjcf(config))


@pytest.mark.parametrize("surface", ["none", "sponge", "book"])
def test_every_scene_compiles_with_the_arm_as_the_first_six_dofs(surface: str) -> None:
    m = _model(SceneConfig(surface=surface, load=LoadSpec(0.5)))  # type: ignore[arg-type]
    assert m.nu == 6
    assert [m.jnt_dofadr[m.joint(f"j{i}").id] for i in range(1, 7)] == list(range(6))


@pytest.mark.parametrize(("gripper", "weight_N"), [(True, 3.153), (False, 0.835)])
def test_subtree_below_the_sensor_weighs_the_papers_tool(gripper: bool, weight_N: float) -> None:
    m = _model(SceneConfig(gripper=gripper))
    body = m.body(NAMES["sensing_end"]).id
    # Exact up to float rounding of mass = weight / g.
    assert m.body_subtreemass[body] * STANDARD_GRAVITY_MPS2 == pytest.approx(weight_N, abs=1e-12)


def test_no_joint_or_actuator_acts_inside_the_sensed_subtree() -> None:
    m = _model(SceneConfig(load=LoadSpec(0.5)))
    sensed = {m.body(NAMES["sensing_end"]).id, m.body(NAMES["gripper"]).id}
    assert not any(int(m.jnt_bodyid[j]) in sensed for j in range(m.njnt))


def test_base_is_mounted_with_the_tilt() -> None:
    U, V = math.radians(-0.204), math.radians(-0.129)
    config = SceneConfig(tilt_U_rad=U, tilt_V_rad=V)
    m = _model(config)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    np.testing.assert_allclose(
        d.xmat[m.body(NAMES["base"]).id].reshape(3, 3), config.R_world_base, atol=1e-12
    )


def test_table4_loads_have_the_papers_true_weights() -> None:
    weights = [load.weight_N for load in table4_loads()]
    np.testing.assert_allclose(weights, TABLE4_LOAD_WEIGHTS_N, rtol=1e-12)


def test_scene_config_rejects_a_load_without_the_gripper() -> None:
    with pytest.raises(ParameterError, match="gripper"):
        SceneConfig(gripper=False, load=LoadSpec(0.5))
