"""A placement run's settings, results and metrics (see :mod:`ftcomp.experiments.placement`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from scipy import signal

from ftcomp import paper
from ftcomp.control.safety import SafetyLimits
from ftcomp.errors import ParameterError
from ftcomp.experiments.verdicts import judge_placement

__all__ = [
    "COLUMNS",
    "DEFAULT_GAINS",
    "PlacementConfig",
    "PlacementControl",
    "PlacementResult",
    "placement_metrics",
    "safety_limits",
]

PlacementControl = Literal["position", "admittance"]

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
            :mod:`ftcomp.experiments.verdicts`). Five times the paper's band: the band is on the
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

    control: PlacementControl
    compensation: bool = True
    k1_m_per_N: float = 1e-4
    k2_m_per_s_N: float = 1e-3
    filter_cutoff_hz: float = 20.0
    decision_cutoff_hz: float = 2.0
    band_N: float = 0.05
    settle_time_s: float = 0.3
    gentle_press_N: float = 0.25
    approach_gap_m: float = 0.002
    position_speed_m_per_s: float = 0.004
    position_depth_m: float = 0.0045
    travel_margin_m: float = 0.008
    max_force_N: float = 40.0
    max_speed_m_per_s: float = 0.02
    max_accel_m_per_s2: float = 0.5
    stale_after_s: float = 0.005
    max_identical_samples: int = 50
    sensor_range_N: float = paper.SENSOR["force_range_N"]
    sensor_range_Nm: float = paper.SENSOR["torque_range_Nm"]
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
            "gentle_press_N",
            "approach_gap_m",
            "position_speed_m_per_s",
            "travel_margin_m",
            "max_force_N",
            "max_speed_m_per_s",
            "max_accel_m_per_s2",
            "stale_after_s",
            "sensor_range_N",
            "sensor_range_Nm",
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
        max_twist=np.array([config.max_speed_m_per_s] * 3 + [0.5] * 3),
        max_twist_rate=np.array([config.max_accel_m_per_s2] * 3 + [5.0] * 3),
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
) -> dict[str, Any]:
    """The run's metrics from its timeseries (see the module docstring of
    :mod:`ftcomp.experiments.placement` for signs); ``decision`` is the row where the run was
    decided, ``hold_end`` the end of the hold after it."""
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
    verdict = judge_placement(outcome, final_true, peak_press, weight_N, config.gentle_press_N)
    return {
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
