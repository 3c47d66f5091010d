"""The paper's compliant placement (section 2.2.2, Fig. 6 and 7) on any cell.

A robot holds a grasped load a small gap above a surface and sets it down, in one of three modes:

- ``control="position"``: constant-speed descent to a fixed depth below the surface top, no force
  feedback (the paper's Fig. 6): the load is pressed into the surface.
- ``control="admittance"`` with compensation: the combined law ΔV = S (K1 dΔF/dt + K2 ΔF)
  (Eq. 27, S = base z) on the gravity-compensated wrench, desired force 0. While the load hangs,
  the compensated force along gravity is its weight, so the robot lowers it at K2 * weight; as the
  surface takes up the weight the force error and the speed fall to zero. The load counts as
  placed when the filtered compensated force along gravity stays within ``band_N`` of zero (the
  released state: the gripper feels nothing of the load) for ``settle_time_s``; then the gripper
  opens and the arm retracts.
- ``compensation=False``: the same controller on raw readings. Bias and tool weight stay in the
  signal, the force never reaches the band where it should and the robot keeps pushing (the
  paper's Fig. 7 comparison); the safety envelope (travel, force limits) ends the run.

The compensation uses the *identified* calibration it is given (bias, tool weight and centre of
gravity, base tilt); the cell's truth (contact force, load weight) only scores the run. The loop
is the package's one control loop (:func:`ftcomp.control.loop.run_loop`), so the same placement
runs on the simulated cell and on a real one.

Sign conventions of the outputs: displacement and velocity are *along gravity* (positive down,
[mm], [mm/s]); forces ``force_*_N`` are the component along gravity of the wrench the load exerts
on the sensor (positive: the load hangs, 0: the surface carries it, negative: the robot presses
it, as the paper's plots); ``force_true_contact_N`` is the force the surface pushes up on the load
(simulator truth, >= 0); ``peak_press_N`` is the largest true contact force beyond the load's
weight.

Everything is SI inside; only the output columns and the ``*_mm*`` metric keys use mm.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.control.controller import AdmittanceController
from ftcomp.control.filters import LowPassFilter
from ftcomp.control.laws import CombinedLaw, selection_matrix
from ftcomp.control.loop import ControlCycle, Reading, run_loop
from ftcomp.errors import ParameterError
from ftcomp.experiments.placement_config import (
    COLUMNS,
    DEFAULT_GAINS,
    PlacementConfig,
    PlacementControl,
    PlacementResult,
    placement_metrics,
    safety_limits,
)
from ftcomp.hardware.protocols import Mount, Robot, WrenchSensor
from ftcomp.model import GravityModel

__all__ = [
    "COLUMNS",
    "DEFAULT_GAINS",
    "PlacementCell",
    "PlacementConfig",
    "PlacementControl",
    "PlacementResult",
    "run_placement",
    "sweep_gains",
    "write_placement_outputs",
]


class PlacementCell(Protocol):
    """What the experiment needs of a cell (the MuJoCo cell, or a real one with a scale).

    The load is grasped and hangs from the gripper when the experiment starts.
    """

    @property
    def robot(self) -> Robot:
        """The arm."""
        ...

    @property
    def sensor(self) -> WrenchSensor:
        """The wrist F/T sensor."""
        ...

    def move_to_clearance(self, clearance_m: float) -> None:
        """Blocking move holding the load's bottom ``clearance_m`` [m] above the surface."""
        ...

    def true_contact_force_N(self) -> float:
        """True force the surface pushes up on the load [N] (0 without contact)."""
        ...

    def load_weight_N(self) -> float:
        """True weight of the grasped load [N]."""
        ...

    def release(self) -> None:
        """Open the gripper: the load is left on the surface."""
        ...


class _PlacementStep:
    """One placement cycle after the I/O: controller, decision, log (a :func:`run_loop` step).

    Holds the controller's and the decision filter's state and the log rows; returns the twist
    to command, or None when the run is over (``outcome`` says why).
    """

    def __init__(
        self, cell: PlacementCell, config: PlacementConfig, first: Reading, up_base: NDArray
    ) -> None:
        dt = cell.robot.control_period_s
        self.cell, self.config, self.dt, self.up = cell, config, dt, up_base
        self.admittance = config.control == "admittance"
        k1, k2 = (config.k1_m_per_N, config.k2_m_per_s_N) if self.admittance else (0.0, 0.0)
        self.controller = AdmittanceController(
            law=CombinedLaw(np.array(k1), np.array(k2), selection_matrix("z")),
            wrench_filter=LowPassFilter(config.filter_cutoff_hz, dt),
            limits=safety_limits(config),
            frame="base",
        )
        self.depth_target = config.approach_gap_m + config.position_depth_m
        self.nominal_down = -config.position_speed_m_per_s * np.concatenate([up_base, np.zeros(3)])
        self.zero = np.zeros(6)
        w0 = first.wrench_contact_sensor
        if not np.all(np.isfinite(w0)):
            w0 = np.zeros(6)  # the watchdog stops at the first step
        R = first.R_base_sensor
        self.state = self.controller.initial_state(w0, R)
        self.decision_filter = LowPassFilter(config.decision_cutoff_hz, dt, order=1, channels=1)
        self.up_f = tuple(up_base.tolist())  # the per-cycle arithmetic is on floats
        self.p_ref = first.p_base_sensor.tolist()
        f0 = float(-(self.up @ R) @ w0[:3])
        self.decision_state = self.decision_filter.initial_state_scalar(f0)
        self.f_dec = f0
        self.descent_prev = 0.0
        self.t0_ns = first.now_ns
        self.rows: list[tuple[float, ...]] = []
        self.outcome = "timeout"
        self.in_band_since: float | None = None
        self.placed_at: float | None = None
        self.decision_index: int | None = None

    def descent(self, p: NDArray[np.float64]) -> float:
        """How far the sensor has gone down since the start [m]."""
        (x, y, z), (u0, u1, u2) = self.p_ref, self.up_f
        p0, p1, p2 = p.tolist()
        return (x - p0) * u0 + (y - p1) * u1 + (z - p2) * u2

    def forces(self, r: Reading) -> tuple[float, float]:
        """The raw and the compensated force along gravity [N] (the sign of COLUMNS)."""
        u0, u1, u2 = self.up_f
        (a0, a1, a2), (b0, b1, b2), (c0, c1, c2) = r.R_base_sensor.tolist()
        # Gravity's direction in the sensor frame: -(up @ R_base_sensor).
        d0, d1, d2 = (
            -(u0 * a0 + u1 * b0 + u2 * c0),
            -(u0 * a1 + u1 * b1 + u2 * c1),
            -(u0 * a2 + u1 * b2 + u2 * c2),
        )
        w0, w1, w2 = r.wrench_raw_sensor[:3].tolist()
        f0, f1, f2 = r.wrench_contact_sensor[:3].tolist()
        return d0 * w0 + d1 * w1 + d2 * w2, d0 * f0 + d1 * f1 + d2 * f2

    def log(
        self,
        r: Reading,
        velocity: float,
        f_filt: float,
        descent: float | None = None,
        forces: tuple[float, float] | None = None,
    ) -> None:
        """Append one row of :data:`COLUMNS` (``descent`` and ``forces`` when already known)."""
        f_raw, f_comp = self.forces(r) if forces is None else forces
        self.rows.append(
            (
                (r.now_ns - self.t0_ns) * 1e-9,
                (self.descent(r.p_base_sensor) if descent is None else descent) * 1e3,
                velocity * 1e3,
                f_raw,
                f_comp,
                f_filt,
                self.cell.true_contact_force_N(),
            )
        )

    def __call__(self, r: Reading) -> NDArray[np.float64] | None:
        config = self.config
        now = r.now_ns * 1e-9
        if now - self.t0_ns * 1e-9 >= config.max_duration_s:
            return None
        R, w_c = r.R_base_sensor, r.wrench_contact_sensor
        descent = self.descent(r.p_base_sensor)
        nominal = None
        if not self.admittance:
            nominal = self.nominal_down if descent < self.depth_target else self.zero
        self.state, twist = self.controller.step(
            self.state,
            r.t_sample_ns * 1e-9,
            w_c,
            R,
            now,
            self.dt,
            nominal,
            wrench_raw_sensor=r.wrench_raw_sensor,
        )
        forces = self.forces(r)
        f_comp = forces[1]
        if math.isfinite(f_comp):
            self.decision_state, self.f_dec = self.decision_filter.step_scalar(
                self.decision_state, f_comp
            )
        f_filt = self.f_dec if math.isfinite(f_comp) else math.nan
        velocity = (descent - self.descent_prev) / self.dt if self.rows else 0.0
        self.descent_prev = descent
        self.log(r, velocity, f_filt, descent, forces)
        if self.state.stop_reason is not None:
            self.outcome = self.state.stop_reason.value
            return None
        if self.admittance:
            if self.placed_at is not None:
                if now - self.placed_at >= config.hold_s:  # kept under control while held
                    return None
            elif abs(f_filt) <= config.band_N:
                self.in_band_since = now if self.in_band_since is None else self.in_band_since
                if now - self.in_band_since >= config.settle_time_s:
                    self.outcome, self.placed_at = "placed", now
                    self.decision_index = len(self.rows) - 1
            else:
                self.in_band_since = None
        elif descent >= self.depth_target and not np.any(twist[:3]):
            self.outcome = "depth_reached"
            return None
        return twist


def run_placement(
    cell: PlacementCell,
    model: GravityModel,
    config: PlacementConfig,
    *,
    sensor: WrenchSensor | None = None,
    mount: Mount | None = None,
    sinks: Sequence[Callable[[Reading, NDArray[np.float64]], None]] = (),
) -> PlacementResult:
    """Set the grasped load down on the surface; never raises on bad sensor data.

    Args:
        cell: the cell, load grasped.
        model: the *identified* gravity model (bias, tool weight and centre of gravity, tilt):
            the compensator's parameters, and the gravity direction in the base frame.
        config: the run's settings.
        sensor: read this instead of ``cell.sensor`` (e.g. a fault-injecting
            :class:`~ftcomp.hardware.faults.FaultySensor`).
        mount: the sensor frame on the robot's TCP (identity by default).
        sinks: run after each controlled cycle, ``sink(reading, twist)`` (e.g. an MCAP log).

    Returns:
        The timeseries and metrics (see :func:`write_placement_outputs`).
    """
    robot = cell.robot
    dt = robot.control_period_s
    if not model.weight_N > 0.0:
        raise ParameterError(
            "the calibration's tool weight is 0: no gravity direction to place along"
        )
    up_base = -model.gravity_base_N / np.linalg.norm(model.gravity_base_N)
    cell.move_to_clearance(config.approach_gap_m)
    for _ in range(round(0.1 / dt)):
        robot.wait_cycle()

    cycle = ControlCycle(
        robot,
        cell.sensor if sensor is None else sensor,
        mount=mount,
        compensator=GravityCompensator(model) if config.compensation else None,
    )
    step = _PlacementStep(cell, config, cycle.read(), up_base)
    run_loop(cycle, step, sinks=sinks)
    decision_index = step.decision_index if step.decision_index is not None else len(step.rows) - 1
    placed = step.outcome in ("placed", "depth_reached")
    if step.outcome == "depth_reached":  # hold still, then let go and lift
        for _ in range(round(config.hold_s / dt)):
            cycle.advance()
            step.log(cycle.read(), 0.0, step.rows[-1][5])
    hold_end = len(step.rows)
    if placed:
        cell.release()
        reading = cycle.read()
        target = reading.p_base_sensor + config.retract_m * up_base
        robot.move_pose(*cycle.mount.tcp_pose(target, reading.R_base_sensor), 0.3)

    data = np.array(step.rows, dtype=float).reshape(-1, len(COLUMNS))
    series = {name: data[:, i].copy() for i, name in enumerate(COLUMNS)}
    weight = cell.load_weight_N()
    metrics = placement_metrics(
        series, decision_index, hold_end, step.outcome, placed, weight, config, dt
    )
    return PlacementResult(config, series, metrics)


def sweep_gains(
    make_cell: Callable[[], PlacementCell],
    model: GravityModel,
    base: PlacementConfig,
    *,
    k1_values_m_per_N: Sequence[float] = (),
    k2_values_m_per_s_N: Sequence[float] = (),
    on_run: Callable[[str, float, PlacementResult], None] | None = None,
) -> dict[str, list[PlacementResult]]:
    """The paper's Fig. 7 sweeps: K1 with ``base``'s K2 fixed, then K2 with its K1 fixed.

    Args:
        make_cell: a fresh cell per run.
        model: the identified gravity model every run compensates with.
        base: the settings every run starts from (run as admittance).
        k1_values_m_per_N: K1 values [m/N].
        k2_values_m_per_s_N: K2 values [m/(s*N)].
        on_run: called as ``on_run("k1" or "k2", value, result)`` after each run.

    Returns:
        ``{"k1": [...], "k2": [...]}``, one admittance run per value, each on a fresh cell.
    """
    base = replace(base, control="admittance")
    out: dict[str, list[PlacementResult]] = {"k1": [], "k2": []}
    for gain, values in (("k1", k1_values_m_per_N), ("k2", k2_values_m_per_s_N)):
        for value in values:
            config = (
                replace(base, k1_m_per_N=value)
                if gain == "k1"
                else replace(base, k2_m_per_s_N=value)
            )
            result = run_placement(make_cell(), model, config)
            out[gain].append(result)
            if on_run is not None:
                on_run(gain, value, result)
    return out


def _json_safe(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def write_placement_outputs(
    result: PlacementResult, out_dir: str | os.PathLike[str], *, title: str = ""
) -> dict[str, Path]:
    """Write ``timeseries.csv``, ``metrics.json`` and ``placement.png`` into ``out_dir``.

    Returns:
        The paths written, by kind (``"csv"``, ``"metrics"``, ``"plot"``).
    """
    from ftcomp.io.atomic import atomic_write_text
    from ftcomp.io.timeseries import write_timeseries_csv
    from ftcomp.views.figures import plot_placement

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {
        "csv": out / "timeseries.csv",
        "metrics": out / "metrics.json",
        "plot": out / "placement.png",
    }
    write_timeseries_csv(paths["csv"], result.timeseries, COLUMNS)
    metrics = {k: _json_safe(v) for k, v in result.metrics.items()}
    atomic_write_text(paths["metrics"], json.dumps(metrics, indent=2) + "\n")
    plot_placement([result], paths["plot"], title=title)
    return paths
