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
gravity, base tilt); the cell's truth (contact force, load weight) only scores the run
(:mod:`ftcomp.session.verdicts`). The step is the package's one compliant step
(:class:`~ftcomp.session.compliant.CompliantStep`, the same as ``ftcomp run``'s) in its one
control loop (:func:`ftcomp.control.loop.run_loop`), so the same placement runs on the simulated
cell and on a real one. The decision is the step's settle rule: the force error the controller
acted on (base z), low-passed at ``decision_cutoff_hz``, within ``band_N`` for
``settle_time_s``; the run then stays under control for ``hold_s`` before the gripper opens.

Sign conventions of the outputs: displacement and velocity are *along gravity* (positive down,
[mm], [mm/s]); ``force_raw_N`` and ``force_compensated_N`` are the component along gravity of
the wrench the load exerts on the sensor (positive: the load hangs, 0: the surface carries it,
negative: the robot presses it, as the paper's plots), ``force_filtered_N`` the same component
of the error the decision judged (the controller's filtered error, low-passed again by the
settle rule); ``force_true_contact_N`` is the force the surface pushes up on the load
(simulator truth, >= 0); ``peak_press_N`` is the largest true contact force beyond the load's
weight.

Everything is SI inside; only the output columns and the ``*_mm*`` metric keys use mm.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray
from scipy import signal

from ftcomp import paper
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.config_fields import check_fields, param
from ftcomp.control.controller import AdmittanceController
from ftcomp.control.filters import LowPassFilter
from ftcomp.control.laws import CombinedLaw, selection_matrix
from ftcomp.control.loop import ControlCycle, Reading, run_loop
from ftcomp.control.safety import (
    MAX_ROTATION_ACCEL_RAD_S2,
    MAX_ROTATION_SPEED_RAD_S,
    SafetyLimits,
)
from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import Mount, Robot, WrenchSensor
from ftcomp.model import GravityModel
from ftcomp.session.compliant import CompliantStep, CycleRecord, SettleRule
from ftcomp.session.log import LogObserver, ObserverThread
from ftcomp.session.run import RUN_COLUMNS, cycle_row
from ftcomp.session.verdicts import judge_placement

__all__ = [
    "COLUMNS",
    "DEFAULT_GAINS",
    "PLACEMENT_CONTROLS",
    "ContactWrench",
    "PlacementCell",
    "PlacementConfig",
    "PlacementControl",
    "PlacementResult",
    "placement_metrics",
    "run_placement",
    "safety_limits",
    "sweep_gains",
    "write_placement_outputs",
]

PlacementControl = Literal["position", "admittance"]
#: The controllers of a placement run.
PLACEMENT_CONTROLS: tuple[PlacementControl, ...] = ("position", "admittance")

#: Admittance gains (K1 [m/N], K2 [m/(s*N)]) that place 500 g gently on each surface of the
#: simulated cell. The book's contact (with the arm's servo) is ~1.5e5 N/m stiff: the K1 term
#: needs K1 * stiffness < 1 (0.1 mm/N gives 15 and rings), and K2 * stiffness must stay below the
#: filter's bandwidth, so the book gets K1 = 0 and the paper's K2 = 0.1 mm/(s*N). The sponge
#: (1500 N/m) takes the paper's K1 and a K2 ten times the paper's to settle in seconds.
DEFAULT_GAINS: dict[str, tuple[float, float]] = {"sponge": (1e-4, 1e-3), "book": (0.0, 1e-4)}

#: Columns of ``timeseries.csv`` (see the module docstring for signs).
COLUMNS = (
    "t_s",
    "displacement_mm",
    "velocity_mm_s",
    "force_raw_N",
    "force_compensated_N",
    "force_filtered_N",
    "force_true_contact_N",
)


@dataclass(frozen=True)
class PlacementConfig:
    """Settings of one placement run (SI units).

    Attributes:
        control: ``"position"`` or ``"admittance"`` (no default: it is the experiment).
        compensation: use the gravity-compensated wrench (False: raw readings).
        k1_m_per_N: K1 on the gravity axis [m/N] (paper k13 = 0.1 mm/N = 1e-4 m/N).
        k2_m_per_s_N: K2 on the gravity axis [m/(s*N)] (paper k23 = 0.1 mm/(s*N)).
        filter_cutoff_hz: low-pass cut-off of the wrench fed to the law [Hz]; its lag must stay
            well below the contact loop's crossover (stiffness * K2) or a stiff surface rings.
        decision_cutoff_hz: slower low-pass for the placement decision [Hz] (sensor noise of
            0.125 N per sample must fall well inside the band).
        band_N: placed when |filtered force along gravity| <= band_N ... [N]
        settle_time_s: ... for this long [s].
        gentle_press_N: the verdict's tolerance on the *true* contact [N]: placed gently when
            the surface carries the load's weight within this, pressed beyond it (see
            :mod:`ftcomp.session.verdicts`). Five times the paper's band: the band is on the
            sensed force, and the true force also carries the calibration's error (a few
            hundredths of a newton with the paper's nine poses).
        approach_gap_m: clearance between load and surface at the start [m].
        position_speed_m_per_s: descent speed of the position-only mode [m/s].
        position_depth_m: position-only end point below the surface top [m] (the planned
            height is wrong by this much, as a camera-located surface would be). The paper
            gives neither its target nor its surfaces' stiffness; 4.5 mm makes our sponge's
            press the size of the paper's (Fig. 6: -1.467 N at the end).
        travel_margin_m: the maximum travel is ``approach_gap_m + travel_margin_m`` (plus the
            depth in position mode) [m].
        max_force_N: protective stop above this contact-force norm [N].
        max_speed_m_per_s: velocity limit [m/s].
        max_accel_m_per_s2: acceleration limit [m/s^2].
        stale_after_s: watchdog age limit of a sample [s].
        max_identical_samples: consecutive fresh samples with identical raw values that count as
            a frozen sensor (the paper's sensor has about one count of noise per axis).
        sensor_range_N: the sensor's force range per axis [N]: a raw reading there is saturated.
        sensor_range_Nm: the sensor's torque range per axis [N*m].
        max_duration_s: give up (``"timeout"``) after this long [s].
        hold_s: time recorded after the decision, before releasing [s].
        retract_m: lift after releasing [m].
    """

    control: PlacementControl = param(choices=PLACEMENT_CONTROLS, help="the controller")
    compensation: bool = True
    k1_m_per_N: float = param(1e-4, ge=0.0, unit="m/N", help="K1 on the gravity axis")
    k2_m_per_s_N: float = param(1e-3, ge=0.0, unit="m/(s*N)", help="K2 on the gravity axis")
    filter_cutoff_hz: float = param(
        20.0, gt=0.0, unit="Hz", help="low-pass of the wrench fed to the law"
    )
    decision_cutoff_hz: float = param(
        2.0, gt=0.0, unit="Hz", help="low-pass of the placement decision"
    )
    band_N: float = param(0.05, gt=0.0, unit="N", help="placed within this force along gravity")
    settle_time_s: float = param(0.3, gt=0.0, unit="s", help="... for this long")
    gentle_press_N: float = param(
        0.25, gt=0.0, unit="N", help="the verdict's tolerance on the true contact"
    )
    approach_gap_m: float = param(0.002, gt=0.0, unit="m", help="clearance at the start")
    position_speed_m_per_s: float = param(
        0.004, gt=0.0, unit="m/s", help="descent speed of the position-only mode"
    )
    position_depth_m: float = param(
        0.0045, ge=0.0, unit="m", help="position-only end point below the surface top"
    )
    travel_margin_m: float = param(0.008, gt=0.0, unit="m", help="travel beyond the gap")
    max_force_N: float = param(40.0, gt=0.0, unit="N", help="protective stop above")
    max_speed_m_per_s: float = param(0.02, gt=0.0, unit="m/s", help="speed limit")
    max_accel_m_per_s2: float = param(0.5, gt=0.0, unit="m/s^2", help="acceleration limit")
    stale_after_s: float = param(0.005, gt=0.0, unit="s", help="a reading older than this stops")
    max_identical_samples: int = param(
        50, ge=1, integer=True, help="identical fresh readings that count as a frozen sensor"
    )
    sensor_range_N: float = param(
        paper.SENSOR["force_range_N"], gt=0.0, unit="N", help="the sensor's force range"
    )
    sensor_range_Nm: float = param(
        paper.SENSOR["torque_range_Nm"], gt=0.0, unit="N*m", help="the sensor's torque range"
    )
    max_duration_s: float = param(30.0, gt=0.0, unit="s", help="give up after this long")
    hold_s: float = param(0.2, ge=0.0, unit="s", help="recorded after the decision")
    retract_m: float = param(0.01, ge=0.0, unit="m", help="lift after releasing")

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass(frozen=True)
class PlacementResult:
    """One run: its configuration, timeseries (columns of :data:`COLUMNS`) and metrics."""

    config: PlacementConfig
    timeseries: dict[str, NDArray[np.float64]] = field(repr=False)
    metrics: dict[str, Any]


def _ripple(values: NDArray[np.float64], dt: float) -> float:
    """RMS of ``values`` about their 1 Hz zero-phase trend (0 when too short to tell)."""
    sos = signal.butter(2, 1.0, fs=1.0 / dt, output="sos")
    if len(values) < 200:
        return 0.0
    trend = signal.sosfiltfilt(sos, values)
    return float(np.sqrt(np.mean((values - trend) ** 2)))


def _contact_stiffness(
    descent_mm: NDArray[np.float64], true_force_N: NDArray[np.float64]
) -> float | None:
    """Slope of the true contact force over the sensor's descent while in contact [N/mm]: the
    surface and everything between it and the sensor, in series (None: too little contact)."""
    finite = np.isfinite(descent_mm) & np.isfinite(true_force_N)
    x, y = descent_mm[finite], true_force_N[finite]
    if len(x) < 20 or np.ptp(x) < 0.01:
        return None
    slope = np.polyfit(x, y, 1)[0]
    return float(slope) if math.isfinite(slope) else None


def safety_limits(config: PlacementConfig) -> SafetyLimits:
    """The safety envelope of a placement run (base-frame axes)."""
    max_travel_z = config.approach_gap_m + config.travel_margin_m
    if config.control != "admittance":
        max_travel_z += config.position_depth_m
    return SafetyLimits(
        max_twist=np.array([config.max_speed_m_per_s] * 3 + [MAX_ROTATION_SPEED_RAD_S] * 3),
        max_twist_rate=np.array([config.max_accel_m_per_s2] * 3 + [MAX_ROTATION_ACCEL_RAD_S2] * 3),
        max_travel=np.array([0.005, 0.005, max_travel_z, 0.1, 0.1, 0.1]),
        max_force_N=config.max_force_N,
        max_torque_Nm=config.max_force_N * 0.2,
        stale_after_s=config.stale_after_s,
        max_identical_samples=config.max_identical_samples,
        sensor_range=(config.sensor_range_N, config.sensor_range_Nm),
    )


def placement_metrics(
    s: dict[str, NDArray[np.float64]],
    decision: int,
    hold_end: int,
    outcome: str,
    placed: bool,
    weight_N: float,
    config: PlacementConfig,
    dt: float,
    true_wrench: NDArray[np.float64] | None = None,
    down_base: NDArray[np.float64] | None = None,
) -> dict[str, Any]:
    """The run's metrics from its timeseries (see the module docstring of
    :mod:`ftcomp.session.placement` for signs); ``decision`` is the row where the run was
    decided, ``hold_end`` the end of the hold after it. With the six-axis true contact wrench
    of every row (``true_wrench``, shape (n, 6), base frame) and gravity's direction in the
    base frame (``down_base``), the verdict also judges the lateral contact force."""
    run = slice(0, decision + 1)
    true_force = s["force_true_contact_N"][run]
    in_contact = np.flatnonzero(true_force > 0.05 * weight_N)
    contact = slice(int(in_contact[0]), decision + 1) if len(in_contact) else slice(0, 0)
    hold = s["force_compensated_N"][decision + 1 : hold_end]
    if len(hold) > 10:  # decided: the mean over the hold
        final_force = float(np.mean(hold))
    elif placed:
        final_force = float(s["force_filtered_N"][decision])
    else:  # stopped: the reading that stopped it (the slow decision filter lags a sudden rise)
        final_force = float(s["force_compensated_N"][decision])
    final_true = float(true_force[-1]) if len(true_force) else 0.0
    peak_press = max(0.0, float(np.max(s["force_true_contact_N"], initial=0.0)) - weight_N)
    final_wrench: list[float] | None = None
    lateral: float | None = None
    if true_wrench is not None and down_base is not None and len(true_wrench) > decision:
        w = true_wrench[decision]
        force = w[:3]
        lateral = float(np.linalg.norm(force - (force @ down_base) * down_base))
        final_wrench = w.tolist()
    verdict = judge_placement(
        outcome, final_true, peak_press, weight_N, config.gentle_press_N, lateral
    )
    return {
        "final_true_contact_wrench": final_wrench,
        "final_true_lateral_N": lateral,
        "placed": placed,
        "verdict": verdict.verdict,
        "true_press_N": verdict.true_press_N,
        "verdict_reason": verdict.reason,
        "stop_reason": outcome,
        "control": config.control,
        "compensation": config.compensation,
        "k1_mm_per_N": config.k1_m_per_N * 1e3,
        "k2_mm_per_s_per_N": config.k2_m_per_s_N * 1e3,
        "load_weight_N": weight_N,
        "final_force_N": final_force,
        "final_true_contact_N": final_true,
        "peak_press_N": peak_press,
        "contact_stiffness_N_per_mm": _contact_stiffness(
            s["displacement_mm"][contact], s["force_true_contact_N"][contact]
        ),
        "settle_time_s": float(s["t_s"][decision]) if placed else None,
        "descent_mm": float(s["displacement_mm"][decision]),
        "max_velocity_mm_s": float(np.max(np.abs(s["velocity_mm_s"][run]), initial=0.0)),
        "force_ripple_N": _ripple(s["force_filtered_N"][contact], dt),
        "velocity_ripple_mm_s": _ripple(s["velocity_mm_s"][contact], dt),
    }


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


@runtime_checkable
class ContactWrench(Protocol):
    """A placement cell that reports the whole true contact wrench (six axes), not only the
    force along gravity: the simulated cell and the twin."""

    def true_contact_wrench_N(self) -> NDArray[np.float64]:
        """The wrench the surface exerts on the load, base frame: force [N], torque about the
        TCP [N*m], shape (6,)."""
        ...


class _PlacementLog:
    """The placement's rows (:data:`COLUMNS`) from the compliant step's cycle records, and the
    position-only descent's planned twist (see the module docstring)."""

    def __init__(self, cell: PlacementCell, config: PlacementConfig, up_base: NDArray) -> None:
        self.cell, self.config = cell, config
        self.dt = cell.robot.control_period_s
        self.down = -up_base  # gravity's direction, base frame
        self.nominal_down = -config.position_speed_m_per_s * np.concatenate([up_base, np.zeros(3)])
        self.depth_target = config.approach_gap_m + config.position_depth_m
        self.zero = np.zeros(6)
        self.p_ref: NDArray[np.float64] | None = None
        self.t0_ns = 0
        self.rows: list[tuple[float, ...]] = []
        self.wrench_cell = cell if isinstance(cell, ContactWrench) else None
        self.true_wrenches: list[NDArray[np.float64]] = []
        self.descent_prev = 0.0
        self.decision_index: int | None = None
        self.f_filt = math.nan
        # Without a settle rule (position only) the plotted force is low-passed here as the
        # rule would (a view of the error, not a decision).
        self.view_filter = (
            None
            if config.control == "admittance"
            else LowPassFilter(config.decision_cutoff_hz, self.dt, order=1, channels=6)
        )
        self.view_state: NDArray[np.float64] | None = None

    def start(self, r: Reading) -> None:
        """The first reading: the origin of the descent and of the log's time."""
        if self.p_ref is None:
            self.p_ref, self.t0_ns = r.p_base_sensor, r.now_ns

    def descent(self, p_base_sensor: NDArray[np.float64]) -> float:
        """How far the sensor has gone down since the start [m]."""
        if self.p_ref is None:
            return 0.0
        return float(self.down @ (p_base_sensor - self.p_ref))

    def nominal(self, r: Reading) -> NDArray[np.float64]:
        """The position-only descent: down at constant speed until the planned depth."""
        self.start(r)
        return self.nominal_down if self.descent(r.p_base_sensor) < self.depth_target else self.zero

    def along_gravity(self, R_base_sensor: NDArray[np.float64], wrench: NDArray) -> float:
        """A sensor-frame force's component along gravity [N]."""
        return float((self.down @ R_base_sensor) @ wrench[:3])

    def log(self, r: Reading, velocity: float, f_filt: float) -> None:
        """Append one row of :data:`COLUMNS` (``f_filt`` is logged as NaN where the compensated
        force is not finite)."""
        self.start(r)
        R = r.R_base_sensor
        f_comp = self.along_gravity(R, r.wrench_contact_sensor)
        self.rows.append(
            (
                (r.now_ns - self.t0_ns) * 1e-9,
                self.descent(r.p_base_sensor) * 1e3,
                velocity * 1e3,
                self.along_gravity(R, r.wrench_raw_sensor),
                f_comp,
                f_filt if math.isfinite(f_comp) else math.nan,
                self.cell.true_contact_force_N(),
            )
        )
        if self.wrench_cell is not None:
            self.true_wrenches.append(self.wrench_cell.true_contact_wrench_N())

    def __call__(self, record: CycleRecord) -> None:
        """One controlled cycle."""
        r = record.reading
        self.start(r)
        descent = self.descent(r.p_base_sensor)
        velocity = (descent - self.descent_prev) / self.dt if self.rows else 0.0
        self.descent_prev = descent
        e = record.settle_error
        if e is None and self.view_filter is not None and np.all(np.isfinite(record.error)):
            if self.view_state is None:
                self.view_state = self.view_filter.initial_state(record.error)
            self.view_state, e = self.view_filter.step(self.view_state, record.error)
        if e is not None and np.all(np.isfinite(e[:3])):
            self.f_filt = float(self.down @ e[:3])  # the error is in the base frame
        self.log(r, velocity, self.f_filt)
        if record.settled and self.decision_index is None:
            self.decision_index = len(self.rows) - 1


def run_placement(
    cell: PlacementCell,
    model: GravityModel,
    config: PlacementConfig,
    *,
    sensor: WrenchSensor | None = None,
    mount: Mount | None = None,
    observers: Sequence[LogObserver] = (),
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
        observers: see each controlled cycle as a row of
            :data:`~ftcomp.session.run.RUN_COLUMNS` (stamped with its ``now_ns``) and the end,
            on a worker thread (e.g. an MCAP log,
            :class:`~ftcomp.ros2.mcap_log.SessionMcapLog`), as ``ftcomp run``'s do.

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

    admittance = config.control == "admittance"
    k1, k2 = (config.k1_m_per_N, config.k2_m_per_s_N) if admittance else (0.0, 0.0)
    controller = AdmittanceController(
        law=CombinedLaw(np.array(k1), np.array(k2), selection_matrix("z")),
        wrench_filter=LowPassFilter(config.filter_cutoff_hz, dt),
        limits=safety_limits(config),
        frame="base",
    )
    settle = (
        SettleRule(
            config.band_N,
            hold_s=config.settle_time_s,
            cutoff_hz=config.decision_cutoff_hz,
            then_hold_s=config.hold_s,
        )
        if admittance
        else None
    )
    cycle = ControlCycle(
        robot,
        cell.sensor if sensor is None else sensor,
        mount=mount,
        compensator=GravityCompensator(model) if config.compensation else None,
    )
    log = _PlacementLog(cell, config, up_base)
    thread = ObserverThread(observers) if observers else None
    if thread is not None:
        thread.open(RUN_COLUMNS)

    def on_cycle(record: CycleRecord) -> None:
        log(record)
        if thread is not None:  # the row built here: a simulated loop keeps no period
            thread.row(record.reading.now_ns, cycle_row(record, log.t0_ns))

    compliant = CompliantStep(
        controller,
        robot,
        config.max_duration_s,
        on_cycle,
        settle=settle,
        nominal=None if admittance else log.nominal,
    )
    outcome = ""

    def step(r: Reading) -> NDArray[np.float64] | None:
        nonlocal outcome
        twist = compliant(r)
        if twist is None:
            return None
        reached = not admittance and log.descent(r.p_base_sensor) >= log.depth_target
        if reached and not np.any(twist[:3]):
            outcome = "depth_reached"
            return None
        return twist

    try:
        run_loop(cycle, step)
    except BaseException:
        if thread is not None:
            thread.close()
        raise
    outcome = outcome or {"settled": "placed", "duration": "timeout"}.get(
        compliant.outcome, compliant.outcome
    )
    if thread is not None:
        end_ns = log.t0_ns + round(log.rows[-1][0] * 1e9) if log.rows else 0
        thread.event(end_ns, "fault" if compliant.faulted else "end", outcome)
        thread.close()
    decision_index = log.decision_index if log.decision_index is not None else len(log.rows) - 1
    placed = outcome in ("placed", "depth_reached")
    if outcome == "depth_reached":  # hold still, then let go and lift
        for _ in range(round(config.hold_s / dt)):
            cycle.advance()
            log.log(cycle.read(), 0.0, log.rows[-1][5])
    hold_end = len(log.rows)
    if placed:
        cell.release()
        reading = cycle.read()
        target = reading.p_base_sensor + config.retract_m * up_base
        robot.move_pose(*cycle.mount.tcp_pose(target, reading.R_base_sensor), 0.3)

    data = np.array(log.rows, dtype=float).reshape(-1, len(COLUMNS))
    series = {name: data[:, i].copy() for i, name in enumerate(COLUMNS)}
    weight = cell.load_weight_N()
    wrenches = np.array(log.true_wrenches) if log.true_wrenches else None
    metrics = placement_metrics(
        series, decision_index, hold_end, outcome, placed, weight, config, dt, wrenches, log.down
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
    result: PlacementResult, out_dir: str | os.PathLike[str]
) -> dict[str, Path]:
    """Write ``timeseries.csv`` (:data:`COLUMNS`) and ``metrics.json`` into ``out_dir`` (the
    plot is a view: :func:`ftcomp.views.figures.plot_placement`).

    Returns:
        The paths written, by kind (``"csv"``, ``"metrics"``).
    """
    from ftcomp.io.atomic import atomic_write_text
    from ftcomp.io.tables import write_timeseries_csv

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"csv": out / "timeseries.csv", "metrics": out / "metrics.json"}
    write_timeseries_csv(paths["csv"], result.timeseries, COLUMNS)
    metrics = {k: _json_safe(v) for k, v in result.metrics.items()}
    atomic_write_text(paths["metrics"], json.dumps(metrics, indent=2) + "\n")
    return paths
