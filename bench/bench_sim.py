"""Benchmark the simulated cell: real-time factor of a 1 kHz Python control loop.

Run by hand (not a test): ``.venv/bin/python bench/bench_sim.py``.
Goal: the *real* placement loop runs >= 25x faster than real time: the same function
``ftcomp sim place`` runs (:func:`ftcomp.experiments.placement.run_placement`: the one control
loop with compensation on the identified calibration, the admittance controller with its safety
envelope, the decision filter and the per-cycle log), from the approach move to the retract.

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

from ftcomp.model import GravityModel
from ftcomp.session.placement import DEFAULT_GAINS, PlacementConfig, run_placement
from ftcomp.sim import LoadSpec, SceneConfig, SimCell, SimPlacementCell

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


def _identified_model(surface: str) -> GravityModel:
    cell = SimPlacementCell(surface, 0.5, seed=7, identify_samples_per_pose=100)
    assert cell.identified is not None
    return cell.identified.model


def placement_run(surface: str, model: GravityModel) -> tuple[float, float, float]:
    """``run_placement`` as ``sim place`` runs it: (wall s, CPU s, simulated s) per control
    cycle, median over REPEATS fresh cells."""
    k1, k2 = DEFAULT_GAINS[surface]
    config = PlacementConfig("admittance", k1_m_per_N=k1, k2_m_per_s_N=k2)
    wall, cpu = [], []
    for seed in range(REPEATS):
        cell = SimPlacementCell(surface, 0.5, seed=seed)
        t_sim0 = cell.cell.time()
        t0, c0 = time.perf_counter(), time.process_time()
        run_placement(cell, model, config)
        cycles = (cell.cell.time() - t_sim0) / cell.cell.control_period_s
        wall.append((time.perf_counter() - t0) / cycles)
        cpu.append((time.process_time() - c0) / cycles)
    return statistics.median(wall), statistics.median(cpu), 1e-3


def main() -> int:
    rows = []
    for surface in ("sponge", "book"):
        base = _time_per_cycle(bare_mj_step, surface)
        for name, fn in (
            ("bare mj_step (baseline)", bare_mj_step),
            ("cell.wait_cycle, holding", hold),
            ("cell.wait_cycle, twist (DLS IK)", descend),
        ):
            wall, cpu = base if fn is bare_mj_step else _time_per_cycle(fn, surface)
            rows.append((surface, name, wall, cpu, cpu / base[1]))
        wall, cpu, _ = placement_run(surface, _identified_model(surface))
        rows.append((surface, "run_placement (sim place)", wall, cpu, cpu / base[1]))
    print(
        f"{'scene':8} {'loop':34} {'wall us':>8} {'RTF wall':>9} {'CPU us':>7} {'RTF CPU':>8} "
        f"{'CPU x baseline':>15}"
    )
    for surface, name, wall, cpu, ratio in rows:
        print(
            f"{surface:8} {name:34} {wall * 1e6:8.1f} {1e-3 / wall:9.1f} {cpu * 1e6:7.1f} "
            f"{1e-3 / cpu:8.1f} {ratio:15.2f}"
        )
    full = [r for r in rows if r[1] == "run_placement (sim place)"]
    worst_wall = min(1e-3 / r[2] for r in full)
    worst_cpu = min(1e-3 / r[3] for r in full)
    verdict = "meets" if worst_wall >= 25.0 else "misses"
    print(
        f"\nplacement loop real-time factor: >= {worst_wall:.1f}x wall, >= {worst_cpu:.1f}x CPU; "
        f"{verdict} the 25x goal (wall)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
