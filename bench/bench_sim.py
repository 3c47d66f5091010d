"""Benchmark the simulated cell: real-time factor of a 1 kHz Python control loop.

Run by hand (not a test): ``.venv/bin/python bench/bench_sim.py``.
Goal: the placement loop (read the sensor, compensate, admittance law, command a twist, one
control cycle, read the true contact force) runs >= 20x faster than real time.

Every loop runs on the same placement scene (500 g load held just above the sponge, then
pressed into it) and is printed beside a bare ``mujoco.mj_step`` loop timed in the same run, as
a ratio, so the numbers mean something on a shared, noisy machine.
"""

from __future__ import annotations

import statistics
import sys
import time
from collections.abc import Callable

import mujoco
import numpy as np

from ftcomp.sim import LoadSpec, SceneConfig, SimCell

CYCLES = 3000  # 3 s of simulated time per run
REPEATS = 5


def _placement_cell(surface: str) -> SimCell:
    cell = SimCell(SceneConfig(surface=surface, load=LoadSpec(0.5)), seed=0)  # type: ignore[arg-type]
    cell.hold_above_surface(0.002, 0.5)
    cell.grasp()
    cell.settle()
    return cell


def _time_per_cycle(run: Callable[[SimCell], None], surface: str) -> tuple[float, float]:
    """Median wall and CPU time of one control cycle [s] over REPEATS fresh runs.

    CPU time (this process only) is the steadier number on a machine shared with others.
    """
    wall, cpu = [], []
    for _ in range(REPEATS):
        cell = _placement_cell(surface)
        t0, c0 = time.perf_counter(), time.process_time()
        run(cell)
        wall.append((time.perf_counter() - t0) / CYCLES)
        cpu.append((time.process_time() - c0) / CYCLES)
    return statistics.median(wall), statistics.median(cpu)


def bare_mj_step(cell: SimCell) -> None:
    """Baseline: MuJoCo alone, no Python work between steps (ctrl held)."""
    m, d = cell.model, cell.data
    step = mujoco.mj_step
    for _ in range(CYCLES):
        step(m, d)


def hold(cell: SimCell) -> None:
    """The cell's cycle with no twist: servo feedforward + physics."""
    for _ in range(CYCLES):
        cell.wait_cycle()


def descend(cell: SimCell) -> None:
    """Constant twist: differential IK every cycle + physics."""
    cell.command_twist(np.array([0.0, 0.0, -0.002, 0.0, 0.0, 0.0]))
    for _ in range(CYCLES):
        cell.wait_cycle()


def admittance_loop(cell: SimCell) -> None:
    """A minimal placement loop: what the admittance experiment does per 1 ms cycle."""
    sensor = cell.sensor
    # Compensation at a fixed orientation: bias + tool and load gravity, from the truth.
    expected = cell.true_gravity_model().predict(cell.sensor_pose()[1])
    k2 = 1e-3  # m/(s*N)
    twist = np.zeros(6)
    contact = 0.0
    for _ in range(CYCLES):
        sample = sensor.read()
        delta_fz = sample.wrench_sensor[2] - expected[2]  # sensor z is down: + is unloading
        twist[2] = -0.002 - k2 * delta_fz
        cell.command_twist(twist)
        cell.wait_cycle()
        contact = cell.true_contact_force_N()
    assert contact >= 0.0


def main() -> int:
    rows = []
    for surface in ("sponge", "book"):
        base = _time_per_cycle(bare_mj_step, surface)
        for name, fn in (
            ("bare mj_step (baseline)", bare_mj_step),
            ("cell.wait_cycle, holding", hold),
            ("cell.wait_cycle, twist (DLS IK)", descend),
            ("full placement loop", admittance_loop),
        ):
            wall, cpu = base if fn is bare_mj_step else _time_per_cycle(fn, surface)
            rows.append((surface, name, wall, cpu, cpu / base[1]))
    print(
        f"{'scene':8} {'loop':34} {'wall us':>8} {'RTF wall':>9} {'CPU us':>7} {'RTF CPU':>8} "
        f"{'CPU x baseline':>15}"
    )
    for surface, name, wall, cpu, ratio in rows:
        print(
            f"{surface:8} {name:34} {wall * 1e6:8.1f} {1e-3 / wall:9.1f} {cpu * 1e6:7.1f} "
            f"{1e-3 / cpu:8.1f} {ratio:15.2f}"
        )
    full = [r for r in rows if r[1] == "full placement loop"]
    worst_wall = min(1e-3 / r[2] for r in full)
    worst_cpu = min(1e-3 / r[3] for r in full)
    verdict = "meets" if worst_wall >= 20.0 else "misses"
    print(
        f"\nplacement loop real-time factor: >= {worst_wall:.1f}x wall, >= {worst_cpu:.1f}x CPU; "
        f"{verdict} the 20x goal (wall)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
