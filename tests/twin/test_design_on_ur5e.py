"""A designed pose sequence on the UR5e twin's controller: with spins in a half-turn band the
arm's moveLs run through it; with spins over a full turn wrist 3 winds to its limit.

The controller runs in process here (no sockets): the same :class:`UrController` that
``ftcomp twin`` serves, given ``rtde_control``'s moveL through its registers as ur_rtde writes
them, and the UR5e cell it moves.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")

from ftcomp.calibration.design import (
    candidate_orientations,
    design_poses,
    nominal_theta,
    order_for_travel,
    tilt_from_down_rad,
)
from ftcomp.frames import rotvec_from_matrix
from ftcomp.twin.controller import UrController
from ftcomp.twin.serve import TwinConfig

#: Where ``docs/calibration.md``'s twin recordings hold the sensor [m], base frame.
POSITION_M = np.array([0.45, 0.0, 0.42])
_MOVEL, _DONE = 3, 2


pytestmark = pytest.mark.live


def _visit(poses: np.ndarray) -> tuple[int, np.ndarray]:
    """Drive the twin's controller through moveLs to each orientation at ``POSITION_M`` (0.25
    m/s, 1.5 m/s^2, as record's URI in the docs); return how many completed and the
    commanded joints where it ended [rad]."""
    cell = TwinConfig("127.0.0.1", "127.0.0.2", 1.0).open_cell()  # nothing is bound
    ctl = UrController(cell, 0.002)
    ctl.start_program("def rtde_control():\n  reg_offset_int = 0\n  reg_offset_float = 0\nend")

    def cycle() -> None:
        cell.command_twist(ctl.cycle(0.0))
        cell.wait_cycle()
        cell.wait_cycle()

    for k, R in enumerate(poses):
        values = [*POSITION_M, *rotvec_from_matrix(R), 0.25, 1.5]
        package: dict[str, float | int | tuple[float, ...]] = {
            f"input_double_register_{i}": float(value) for i, value in enumerate(values)
        }
        package["input_int_register_1"] = 0  # blocking
        package["input_int_register_0"] = _MOVEL
        ctl.write_inputs(package)
        for _ in range(10_000):  # 20 s of controller time: a move takes at most 3.5 s
            cycle()
            if ctl.registers.get("output_int_register_0") == _DONE or not ctl.script_running:
                break
        if not ctl.script_running:
            return k, cell.q_command_rad
        ctl.write_inputs({"input_int_register_0": 0})
        cycle()
    return len(poses), cell.q_command_rad


def _design(max_tilt_deg: float, max_spin_deg: float) -> np.ndarray:
    candidates = candidate_orientations(max_tilt_deg, max_spin_deg=max_spin_deg)
    R = design_poses(30, candidates, nominal_theta())
    return R[order_for_travel(R)]


@pytest.mark.parametrize("max_tilt_deg", [35.0, 50.0, 70.0])
def test_a_half_turn_band_of_spins_runs_a_tilted_design_through_the_ur5e(
    max_tilt_deg: float,
) -> None:
    poses = _design(max_tilt_deg, 90.0)
    assert np.degrees(tilt_from_down_rad(poses)).max() > max_tilt_deg - 2.0
    done, q = _visit(poses)
    assert done == 30
    assert np.all(np.abs(q) < np.radians(355.0))


def test_spins_over_a_full_turn_wind_wrist_3_to_its_limit(capfd: pytest.CaptureFixture) -> None:
    done, q = _visit(_design(50.0, 180.0))
    assert done < 30
    assert abs(abs(np.degrees(q[5])) - 360.0) < 1e-3
    assert "joint j6 at its limit" in capfd.readouterr().err
