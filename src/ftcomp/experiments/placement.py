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

Sign conventions of the outputs: displacement and velocity are *along gravity* (positive down,
[mm], [mm/s]); forces ``force_*_N`` are the component along gravity of the wrench the load exerts
on the sensor (positive: the load hangs, 0: the surface carries it, negative: the robot presses
it, as the paper's plots); ``force_true_contact_N`` is the force the surface pushes up on the load
(simulator truth, >= 0); ``peak_press_N`` is the largest true contact force beyond the load's
weight.

Everything is SI inside; only the output columns and the ``*_mm*`` metric keys use mm.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal, Protocol

import numpy as np
from numpy.typing import NDArray
from scipy import signal

from ftcomp.compensation import GravityCompensator
from ftcomp.control import (
    AdmittanceController,
    CombinedLaw,
    LowPassFilter,
    SafetyLimits,
    selection_matrix,
)
from ftcomp.errors import ParameterError
from ftcomp.interfaces import Robot, WrenchSample, WrenchSensor
from ftcomp.model import GravityModel

__all__ = [
    "COLUMNS",
    "DEFAULT_GAINS",
    "FaultKind",
    "FaultySensor",
    "PlacementCell",
    "PlacementConfig",
    "PlacementControl",
    "PlacementResult",
    "SimPlacementCell",
    "plot_placement",
    "run_placement",
    "sweep_gains",
    "write_placement_outputs",
]

PlacementControl = Literal["position", "admittance"]

#: Admittance gains (K1 [m/N], K2 [m/(s*N)]) that place 500 g gently on each surface of the
#: simulated cell. The book's contact (with the arm's servo) is ~1.5e5 N/m stiff: the K1 term
#: needs K1 * stiffness < 1 (0.1 mm/N gives 15 and rings), and K2 * stiffness must stay below the
#: filter's bandwidth, so the book gets K1 = 0 and the paper's K2 = 0.1 mm/(s*N). The sponge
#: (1500 N/m) takes the paper's K1 and a K2 ten times the paper's to settle in seconds.
DEFAULT_GAINS: dict[str, tuple[float, float]] = {"sponge": (1e-4, 1e-3), "book": (0.0, 1e-4)}
FaultKind = Literal["nan", "repeat", "spike", "stop"]

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


class SimPlacementCell:
    """The MuJoCo cell (:class:`ftcomp.sim.cell.SimCell`) as a :class:`PlacementCell`.

    Args:
        surface: ``"sponge"`` or ``"book"``.
        load_kg: mass of the grasped load [kg].
        seed: sensor-noise seed.
        sensor_spec: the sensor model (default: the paper's).

    Attributes:
        cell: the underlying :class:`~ftcomp.sim.cell.SimCell`.
        tool_model: the true gravity model of the tool *without* the load (what a calibration
            of the empty gripper finds), taken before grasping.
    """

    def __init__(
        self,
        surface: str,
        load_kg: float = 0.5,
        *,
        seed: int | None = 0,
        sensor_spec: Any = None,
    ) -> None:
        from ftcomp.sim.cell import SimCell
        from ftcomp.sim.scene import SceneConfig
        from ftcomp.sim.tool import LoadSpec

        if surface not in ("sponge", "book"):
            raise ParameterError(f"surface must be 'sponge' or 'book', got {surface!r}")
        if not (math.isfinite(load_kg) and load_kg > 0.0):
            raise ParameterError(f"load_kg must be > 0, got {load_kg}")
        load = LoadSpec(load_kg)
        self._weight_N = load.weight_N
        self.cell = SimCell(
            SceneConfig(load=load, surface=surface),  # type: ignore[arg-type]
            sensor_spec,
            seed=seed,
        )
        self.cell.hold_above_surface(0.02, 0.5)
        self.tool_model = self.cell.true_gravity_model()
        self.cell.grasp()

    @property
    def robot(self) -> Robot:
        """The arm."""
        return self.cell

    @property
    def sensor(self) -> WrenchSensor:
        """The wrist F/T sensor."""
        return self.cell.sensor

    def move_to_clearance(self, clearance_m: float) -> None:
        """Blocking move holding the load ``clearance_m`` [m] above the surface."""
        self.cell.hold_above_surface(clearance_m, 0.3)

    def true_contact_force_N(self) -> float:
        """The simulator's vertical contact force on the load [N]."""
        return self.cell.true_contact_force_N()

    def load_weight_N(self) -> float:
        """The load's weight [N]."""
        return self._weight_N

    def release(self) -> None:
        """Open the gripper."""
        self.cell.release()


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
        approach_gap_m: clearance between load and surface at the start [m].
        position_speed_m_per_s: descent speed of the position-only mode [m/s].
        position_depth_m: position-only end point below the surface top [m] (the planned
            height is wrong by this much, as a camera-located surface would be).
        travel_margin_m: the maximum travel is ``approach_gap_m + travel_margin_m`` (plus the
            depth in position mode) [m].
        max_force_N: protective stop above this contact-force norm [N].
        max_speed_m_per_s: velocity limit [m/s].
        max_accel_m_per_s2: acceleration limit [m/s^2].
        stale_after_s: watchdog age limit of a sample [s].
        max_duration_s: give up (``"timeout"``) after this long [s].
        hold_s: time recorded after the decision, before releasing [s].
        retract_m: lift after releasing [m].
    """

    control: PlacementControl
    compensation: bool = True
    k1_m_per_N: float = 1e-4
    k2_m_per_s_N: float = 1e-3
    filter_cutoff_hz: float = 20.0
    decision_cutoff_hz: float = 2.0
    band_N: float = 0.05
    settle_time_s: float = 0.3
    approach_gap_m: float = 0.002
    position_speed_m_per_s: float = 0.004
    position_depth_m: float = 0.004
    travel_margin_m: float = 0.008
    max_force_N: float = 40.0
    max_speed_m_per_s: float = 0.02
    max_accel_m_per_s2: float = 0.5
    stale_after_s: float = 0.005
    max_duration_s: float = 30.0
    hold_s: float = 0.2
    retract_m: float = 0.01

    def __post_init__(self) -> None:
        if self.control not in ("position", "admittance"):
            raise ParameterError(
                f"control must be 'position' or 'admittance', got {self.control!r}"
            )
        for name in ("k1_m_per_N", "k2_m_per_s_N", "hold_s", "retract_m", "position_depth_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ParameterError(f"{name} must be finite and >= 0, got {value}")
        for name in (
            "filter_cutoff_hz",
            "decision_cutoff_hz",
            "band_N",
            "settle_time_s",
            "approach_gap_m",
            "position_speed_m_per_s",
            "travel_margin_m",
            "max_force_N",
            "max_speed_m_per_s",
            "max_accel_m_per_s2",
            "stale_after_s",
            "max_duration_s",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(f"{name} must be finite and > 0, got {value}")


@dataclass(frozen=True)
class PlacementResult:
    """One run: its configuration, timeseries (columns of :data:`COLUMNS`) and metrics."""

    config: PlacementConfig
    timeseries: dict[str, NDArray[np.float64]] = field(repr=False)
    metrics: dict[str, Any]


class FaultySensor:
    """Wraps a sensor and injects one fault from ``t_fault_s`` on (robot clock).

    Kinds: ``"nan"`` (NaN readings), ``"repeat"`` (one sample repeated with its old stamp),
    ``"spike"`` (one 100 N spike along the sensor's z), ``"stop"`` (the stream stops: the last
    reading is returned forever, as a driver whose connection died).
    """

    def __init__(self, sensor: WrenchSensor, kind: FaultKind, t_fault_s: float) -> None:
        if kind not in ("nan", "repeat", "spike", "stop"):
            raise ParameterError(f"unknown fault {kind!r}; valid: nan, repeat, spike, stop")
        self._sensor = sensor
        self.kind = kind
        self.t_fault_s = t_fault_s
        self._last: WrenchSample | None = None
        self._fired = False

    def read(self) -> WrenchSample:
        """The underlying reading, or the fault."""
        sample = self._sensor.read()
        if sample.t < self.t_fault_s or (self._fired and self.kind in ("repeat", "spike")):
            self._last = sample
            return sample
        self._fired = True
        if self.kind == "nan":
            return WrenchSample(sample.t, np.full(6, math.nan))
        if self.kind == "spike":
            return WrenchSample(sample.t, sample.wrench_sensor + np.array([0, 0, 100.0, 0, 0, 0]))
        previous = self._last if self._last is not None else sample
        if self.kind == "stop":
            self._last = previous
        return previous


def _ripple(values: NDArray[np.float64], dt: float) -> float:
    """RMS of ``values`` about their 1 Hz zero-phase trend (0 when too short to tell)."""
    sos = signal.butter(2, 1.0, fs=1.0 / dt, output="sos")
    if len(values) < 200:
        return 0.0
    trend = signal.sosfiltfilt(sos, values)
    return float(np.sqrt(np.mean((values - trend) ** 2)))


def run_placement(
    cell: PlacementCell,
    model: GravityModel,
    config: PlacementConfig,
    *,
    sensor: WrenchSensor | None = None,
) -> PlacementResult:
    """Set the grasped load down on the surface; never raises on bad sensor data.

    Args:
        cell: the cell, load grasped.
        model: the calibrated gravity model (bias, tool weight and centre of gravity, tilt): the
            compensator's parameters, and the gravity direction in the base frame.
        config: the run's settings.
        sensor: read this instead of ``cell.sensor`` (e.g. a :class:`FaultySensor`).

    Returns:
        The timeseries and metrics (see :func:`write_placement_outputs`).
    """
    robot = cell.robot
    sensor = cell.sensor if sensor is None else sensor
    dt = robot.control_period_s
    up_base = -model.gravity_base_N / np.linalg.norm(model.gravity_base_N)

    cell.move_to_clearance(config.approach_gap_m)
    for _ in range(round(0.1 / dt)):
        robot.wait_cycle()

    compensator = GravityCompensator(model) if config.compensation else None
    weight_true = cell.load_weight_N()
    admittance = config.control == "admittance"
    max_travel_z = config.approach_gap_m + config.travel_margin_m
    if not admittance:
        max_travel_z += config.position_depth_m
    limits = SafetyLimits(
        max_twist=np.array([config.max_speed_m_per_s] * 3 + [0.5] * 3),
        max_twist_rate=np.array([config.max_accel_m_per_s2] * 3 + [5.0] * 3),
        max_travel=np.array([0.005, 0.005, max_travel_z, 0.1, 0.1, 0.1]),
        max_force_N=config.max_force_N,
        max_torque_Nm=config.max_force_N * 0.2,
        stale_after_s=config.stale_after_s,
    )
    k1, k2 = (config.k1_m_per_N, config.k2_m_per_s_N) if admittance else (0.0, 0.0)
    controller = AdmittanceController(
        law=CombinedLaw(np.array(k1), np.array(k2), selection_matrix("z")),
        wrench_filter=LowPassFilter(config.filter_cutoff_hz, dt),
        limits=limits,
        frame="base",
    )
    depth_target = config.approach_gap_m + config.position_depth_m
    nominal_down = -config.position_speed_m_per_s * np.concatenate([up_base, np.zeros(3)])

    def contact(sample: WrenchSample, R: NDArray[np.float64]) -> NDArray[np.float64]:
        if compensator is None:
            return np.asarray(sample.wrench_sensor, dtype=float)
        return compensator.compensate(sample.wrench_sensor, R)

    first = sensor.read()
    p_ref, R = robot.sensor_pose()
    w0 = contact(first, R)
    if not np.all(np.isfinite(w0)):
        w0 = np.zeros(6)  # the watchdog stops at the first step
    state = controller.initial_state(w0, R)
    decision_filter = LowPassFilter(config.decision_cutoff_hz, dt, order=1, channels=1)
    f0 = float(-(R @ w0[:3]) @ up_base)
    decision_state = decision_filter.initial_state([f0])
    t0 = robot.time()
    rows: list[tuple[float, ...]] = []
    outcome = "timeout"
    in_band_since: float | None = None
    placed_at: float | None = None
    decision_index: int | None = None
    p_prev = p_ref
    f_dec = np.array([f0])
    while robot.time() - t0 < config.max_duration_s:
        sample = sensor.read()
        p, R = robot.sensor_pose()
        now = robot.time()
        w_c = contact(sample, R)
        descent = float((p_ref - p) @ up_base)
        nominal = None
        if not admittance:
            nominal = nominal_down if descent < depth_target else np.zeros(6)
        state, twist = controller.step(state, sample.t, w_c, R, now, dt, nominal)
        f_raw = float(-(R @ sample.wrench_sensor[:3]) @ up_base)
        f_comp = float(-(R @ w_c[:3]) @ up_base)
        if np.isfinite(f_comp):
            decision_state, f_dec = decision_filter.step(decision_state, [f_comp])
        f_filt = float(f_dec[0]) if np.isfinite(f_comp) else math.nan
        velocity = float((p_prev - p) @ up_base) / dt if rows else 0.0
        p_prev = p
        rows.append(
            (
                now - t0,
                descent * 1e3,
                velocity * 1e3,
                f_raw,
                f_comp,
                f_filt,
                cell.true_contact_force_N(),
            )
        )
        if state.stop_reason is not None:
            robot.stop()
            outcome = state.stop_reason.value
            break
        if admittance:
            if placed_at is not None:
                if now - placed_at >= config.hold_s:  # kept under control while held
                    break
            elif abs(f_filt) <= config.band_N:
                in_band_since = now if in_band_since is None else in_band_since
                if now - in_band_since >= config.settle_time_s:
                    outcome, placed_at, decision_index = "placed", now, len(rows) - 1
            else:
                in_band_since = None
        elif descent >= depth_target and not np.any(twist[:3]):
            outcome = "depth_reached"
            break
        robot.command_twist(twist)
        robot.wait_cycle()
    if decision_index is None:
        decision_index = len(rows) - 1
    robot.stop()
    placed = outcome in ("placed", "depth_reached")
    if outcome == "depth_reached":  # hold still, then let go and lift
        for _ in range(round(config.hold_s / dt)):
            robot.wait_cycle()
            sample = sensor.read()
            p, R = robot.sensor_pose()
            w_c = contact(sample, R)
            rows.append(
                (
                    robot.time() - t0,
                    float((p_ref - p) @ up_base) * 1e3,
                    0.0,
                    float(-(R @ sample.wrench_sensor[:3]) @ up_base),
                    float(-(R @ w_c[:3]) @ up_base),
                    rows[-1][5],
                    cell.true_contact_force_N(),
                )
            )
    hold_end = len(rows)
    if placed:
        cell.release()
        p, R = robot.sensor_pose()
        robot.move_pose(p + config.retract_m * up_base, R, 0.3)

    data = np.array(rows, dtype=float).reshape(-1, len(COLUMNS))
    series = {name: data[:, i].copy() for i, name in enumerate(COLUMNS)}
    metrics = _metrics(series, decision_index, hold_end, outcome, placed, weight_true, config, dt)
    return PlacementResult(config, series, metrics)


def _metrics(
    s: dict[str, NDArray[np.float64]],
    decision: int,
    hold_end: int,
    outcome: str,
    placed: bool,
    weight_N: float,
    config: PlacementConfig,
    dt: float,
) -> dict[str, Any]:
    run = slice(0, decision + 1)
    true_force = s["force_true_contact_N"][run]
    in_contact = np.flatnonzero(true_force > 0.05 * weight_N)
    contact = slice(int(in_contact[0]), decision + 1) if len(in_contact) else slice(0, 0)
    hold = s["force_compensated_N"][decision + 1 : hold_end]
    final_force = float(np.mean(hold)) if len(hold) > 10 else float(s["force_filtered_N"][decision])
    return {
        "placed": placed,
        "stop_reason": outcome,
        "control": config.control,
        "compensation": config.compensation,
        "k1_mm_per_N": config.k1_m_per_N * 1e3,
        "k2_mm_per_s_per_N": config.k2_m_per_s_N * 1e3,
        "load_weight_N": weight_N,
        "final_force_N": final_force,
        "final_true_contact_N": float(true_force[-1]) if len(true_force) else 0.0,
        "peak_press_N": max(0.0, float(np.max(s["force_true_contact_N"], initial=0.0)) - weight_N),
        "settle_time_s": float(s["t_s"][decision]) if placed else None,
        "descent_mm": float(s["displacement_mm"][decision]),
        "max_velocity_mm_s": float(np.max(np.abs(s["velocity_mm_s"][run]), initial=0.0)),
        "force_ripple_N": _ripple(s["force_filtered_N"][contact], dt),
        "velocity_ripple_mm_s": _ripple(s["velocity_mm_s"][contact], dt),
    }


def sweep_gains(
    make_cell: Callable[[], PlacementCell],
    model: GravityModel,
    base: PlacementConfig,
    *,
    k1_values_m_per_N: Sequence[float] = (),
    k2_values_m_per_s_N: Sequence[float] = (),
) -> dict[str, list[PlacementResult]]:
    """The paper's Fig. 7 sweeps: K1 with ``base``'s K2 fixed, then K2 with its K1 fixed.

    Returns:
        ``{"k1": [...], "k2": [...]}``, one admittance run per value, each on a fresh cell.
    """
    base = replace(base, control="admittance")
    return {
        "k1": [
            run_placement(make_cell(), model, replace(base, k1_m_per_N=k))
            for k in k1_values_m_per_N
        ],
        "k2": [
            run_placement(make_cell(), model, replace(base, k2_m_per_s_N=k))
            for k in k2_values_m_per_s_N
        ],
    }


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

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(COLUMNS)
    data = np.column_stack([result.timeseries[c] for c in COLUMNS])
    for row in data:
        writer.writerow([f"{v:.6g}" for v in row])
    paths = {
        "csv": out / "timeseries.csv",
        "metrics": out / "metrics.json",
        "plot": out / "placement.png",
    }
    atomic_write_text(paths["csv"], buffer.getvalue())
    metrics = {k: _json_safe(v) for k, v in result.metrics.items()}
    atomic_write_text(paths["metrics"], json.dumps(metrics, indent=2) + "\n")
    plot_placement([result], paths["plot"], title=title)
    return paths


def plot_placement(
    results: Sequence[PlacementResult],
    path: str | os.PathLike[str],
    *,
    labels: Sequence[str] | None = None,
    title: str = "",
) -> None:
    """Force, displacement and velocity over time (the paper's Fig. 6/7), one line per run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(7, 7.5), sharex=True)
    for i, result in enumerate(results):
        s = result.timeseries
        label = labels[i] if labels is not None else None
        line = axes[0].plot(s["t_s"], s["force_filtered_N"], label=label)[0]
        if len(results) == 1:
            axes[0].plot(
                s["t_s"],
                s["force_compensated_N"],
                lw=0.4,
                alpha=0.4,
                color=line.get_color(),
                label="compensated (raw samples)",
            )
            axes[0].plot(
                s["t_s"],
                s["force_true_contact_N"] - result.metrics["load_weight_N"],
                "--",
                lw=1,
                label="true press (contact - weight)",
            )
        axes[1].plot(s["t_s"], s["displacement_mm"], color=line.get_color())
        axes[2].plot(s["t_s"], s["velocity_mm_s"], color=line.get_color())
    band = results[0].config.band_N if results else 0.05
    axes[0].axhspan(-band, band, color="green", alpha=0.15, label=f"±{band:g} N band")
    axes[0].set_ylabel("force along gravity [N]")
    axes[1].set_ylabel("displacement [mm]")
    axes[2].set_ylabel("velocity [mm/s]")
    axes[2].set_xlabel("time [s]")
    axes[0].legend(fontsize=7)
    for ax in axes:
        ax.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
