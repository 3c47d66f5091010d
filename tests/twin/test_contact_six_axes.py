"""Contact judged in six axes: the simulated cell's true contact wrench, the verdict's lateral
force, and the cause of the lateral force a grasped load shows on the sponge."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

pytest.importorskip("mujoco")

from ftcomp.hardware.registry import parse_uri
from ftcomp.session.verdicts import judge_placement
from ftcomp.sim.backend import open_robot
from ftcomp.sim.cell import SimCell

WEIGHT_N = 4.905
PLACE = "sim://?seed=4&tilt_deg=0,0&surface=sponge&load_kg=0.5&grasp=1&clearance_mm=2"


pytestmark = pytest.mark.live


def test_the_verdict_reports_the_lateral_force_and_keeps_its_judgement() -> None:
    v = judge_placement("placed", WEIGHT_N - 0.03, 0.0, WEIGHT_N, 0.25, lateral_N=1.7)
    assert v.verdict == "placed gently"
    assert v.true_lateral_N == pytest.approx(1.7)
    assert "lateral contact 1.700 N" in v.reason and "static friction" in v.reason
    quiet = judge_placement("placed", WEIGHT_N, 0.0, WEIGHT_N, 0.25, lateral_N=0.01)
    assert "negligible" in quiet.reason
    assert judge_placement("placed", WEIGHT_N, 0.0, WEIGHT_N, 0.25).true_lateral_N is None


def _set_down(friction: float, shear: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Lower the held load straight down (world z) until the sponge carries it; the contact
    wrench (base frame) and the TCP's measured-minus-commanded position [m]. Without shear the
    sponge is a plate on a vertical slide only, rigid across (the cell before the fix)."""
    cell = open_robot(parse_uri(PLACE))
    assert isinstance(cell, SimCell)
    if not shear:
        sponge = dataclasses.replace(cell.config.sponge, shear_stiffness_N_per_m=math.inf)
        cell = SimCell(dataclasses.replace(cell.config, sponge=sponge), seed=4)
        cell.hold_above_surface(0.02, 0.5)  # as sim://...&clearance_mm=2 sets it up
        cell.grasp()
        cell.hold_above_surface(0.002, 0.3)
    m = cell.model
    for name in ("load_geom", "sponge_top"):
        m.geom_friction[m.geom(name).id, 0] = friction
    cell.command_twist(np.array([0.0, 0.0, -0.002, 0.0, 0.0, 0.0]))
    for _ in range(4000):
        cell.wait_cycle()
        if cell.true_contact_wrench_base(cell.sensor_pose()[0])[2] > WEIGHT_N:
            break
    cell.stop()
    cell.step(300)
    p = cell.sensor_pose()[0]
    commanded = SimCell(cell.config, q_start_rad=cell.q_command_rad).sensor_pose()[0]
    return cell.true_contact_wrench_base(p), p - commanded


def test_on_a_sponge_rigid_across_the_servo_springback_is_held_by_friction() -> None:
    sticking, sag = _set_down(friction=1.0, shear=False)
    sliding, relaxed = _set_down(friction=0.0, shear=False)
    assert sticking[2] == pytest.approx(WEIGHT_N, abs=0.1)
    assert abs(sticking[0]) > 1.0  # about -1.7 N across the surface
    # Without friction nothing holds the arm: it springs back to its command, no lateral force.
    assert np.linalg.norm(sliding[:2]) < 0.01
    assert np.linalg.norm(relaxed[:2]) < 2e-6
    # With friction the arm stays where the load's weight had sagged it, across the surface.
    assert sag[0] < -1e-5
    assert np.sign(sticking[0]) == np.sign(sag[0])


def test_a_sponge_that_shears_takes_the_springback_with_almost_no_lateral_force() -> None:
    sticking, _ = _set_down(friction=1.0)
    assert sticking[2] == pytest.approx(WEIGHT_N, abs=0.1)
    # The pad shears with the arm's ~25 um springback: 600 N/m * 25 um = 0.015 N.
    assert np.linalg.norm(sticking[:2]) < 0.05


def test_the_contact_wrench_is_the_sum_over_mujocos_contacts_one_by_one() -> None:
    """The vectorised sum against MuJoCo's contacts taken one at a time (each contact's force
    in its frame, rotated to the world, its moment about a point off the contacts)."""
    import mujoco

    cell = open_robot(parse_uri(PLACE))
    assert isinstance(cell, SimCell)
    cell.command_twist(np.array([0.0, 0.0, -0.002, 0.0, 0.0, 0.0]))
    for _ in range(4000):
        cell.wait_cycle()
        if cell.true_contact_wrench_base(cell.sensor_pose()[0])[2] > WEIGHT_N:
            break
    m, d = cell.model, cell.data
    load = m.geom("load_geom").id
    surfaces = {m.geom(name).id for name in ("floor", "table", "sponge_top")}
    point = np.array([0.3, -0.1, 0.5])
    expected = np.zeros(6)
    c6 = np.zeros(6)
    for i in range(d.ncon):
        c = d.contact[i]
        pair = (int(c.geom1), int(c.geom2))
        if load not in pair or ({*pair} - {load}).isdisjoint(surfaces):
            continue
        mujoco.mj_contactForce(m, d, i, c6)
        on_load = 1.0 if pair[1] == load else -1.0  # the force acts on geom2
        f = on_load * c.frame.reshape(3, 3).T @ c6[:3]
        expected[:3] += f
        expected[3:] += np.cross(c.pos - point, f) + on_load * c.frame.reshape(3, 3).T @ c6[3:]
    assert d.ncon > 0 and expected[2] > WEIGHT_N
    np.testing.assert_allclose(cell._contact_wrench_world(point), expected, rtol=1e-12, atol=1e-12)
