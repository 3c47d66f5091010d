"""The one control loop: a cycle that reads and compensates, and stops the robot on every
exit."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.control.loop import ControlCycle, Reading, run_loop
from ftcomp.hardware.protocols import Mount

sys.path.insert(0, str(Path(__file__).parents[1] / "experiments"))
from fake_cell import PAPER_MODEL, R_DOWN, FakeCell


def test_a_cycle_reads_compensates_and_the_loop_ends_when_the_step_says_so() -> None:
    cell = FakeCell(1500.0)
    cell.move_to_clearance(0.05)  # hanging in free air: the contact wrench is the load
    cycle = ControlCycle(cell, cell, compensator=GravityCompensator(PAPER_MODEL))
    seen: list[Reading] = []

    def step(reading: Reading) -> np.ndarray | None:
        seen.append(reading)
        return None if len(seen) == 5 else np.zeros(6)

    stats = run_loop(cycle, step)
    assert stats.cycles == 4 and len(seen) == 5
    force_base = R_DOWN @ seen[-1].wrench_contact_sensor[:3]
    np.testing.assert_allclose(force_base, [0.0, 0.0, -cell.weight], atol=1e-9)
    assert seen[1].now_ns - seen[0].now_ns == 1_000_000


def test_the_loop_stops_the_robot_when_the_step_raises() -> None:
    cell = FakeCell(1500.0)
    cycle = ControlCycle(cell, cell, mount=Mount())
    calls = []

    def step(reading: Reading) -> np.ndarray | None:
        calls.append(reading)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return np.array([0.0, 0.0, -0.01, 0.0, 0.0, 0.0])

    with pytest.raises(KeyboardInterrupt):
        run_loop(cycle, step)
    assert cell.v_cmd == 0.0  # stopped before the exception left the loop
