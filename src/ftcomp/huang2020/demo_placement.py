"""The demo's placement section (paper 2.2.2, Fig. 6 and 7): every run, judged from the truth.

Each run is set down on a fresh simulated cell with the calibration identified in the demo's
first section, written to ``placement/<run>/`` and judged from the *true* contact force
(:mod:`ftcomp.session.verdicts`); the figures draw the true force beside the sensed one.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from ftcomp import paper
from ftcomp.calibration_record import Calibration
from ftcomp.errors import ParameterError
from ftcomp.huang2020.settings import Advance, DemoSettings
from ftcomp.io.calibration_json import model_to_dict
from ftcomp.model import GravityModel
from ftcomp.session.placement import (
    DEFAULT_GAINS,
    PlacementConfig,
    PlacementResult,
    run_placement,
    sweep_gains,
    write_placement_outputs,
)
from ftcomp.sim.placement_cell import SimPlacementCell
from ftcomp.views.figures import plot_placement
from ftcomp.views.html import Cell, Figure, Link, Mark, Section, Table

__all__ = [
    "PlacementMetrics",
    "PlacementRun",
    "PlacementSetup",
    "placement_section",
    "verdict_mark",
]


def _optional(value: Any) -> float | None:
    return None if value is None else float(value)


@dataclass(frozen=True)
class PlacementRun:
    """One placement run of the demo, with what the comparisons and tables read of it.

    Attributes:
        name: the run's name (its folder under ``placement/``).
        label: how the report names it.
        result: the run itself (settings, timeseries and every metric, as written to its
            ``metrics.json``).
        verdict: from the true contact (``placed gently``, ``pressed``, ``stopped``).
        verdict_reason: why, in words.
        stop_reason: what ended the run.
        placed: whether the controller decided the load was placed.
        true_press_N: surface force beyond the load's weight at the decision [N].
        final_force_N: the sensed force along gravity at the end [N].
        peak_press_N: the largest true press [N].
        load_weight_N: the load's weight [N].
        settle_time_s: time of the placement decision [s] (None: not placed).
        contact_stiffness_N_per_mm: measured in contact [N/mm] (None: too little contact).
        force_ripple_N: RMS of the filtered force about its 1 Hz trend in contact [N].
        k1_mm_per_N, k2_mm_per_s_per_N: the run's gains [mm/N], [mm/(s*N)].
        descent_mm: descent at the decision [mm]; max_velocity_mm_s: fastest descent [mm/s].
    """

    name: str
    label: str
    result: PlacementResult = field(repr=False)
    verdict: str
    verdict_reason: str
    stop_reason: str
    placed: bool
    true_press_N: float
    final_force_N: float
    peak_press_N: float
    load_weight_N: float
    settle_time_s: float | None
    contact_stiffness_N_per_mm: float | None
    force_ripple_N: float
    k1_mm_per_N: float
    k2_mm_per_s_per_N: float
    descent_mm: float
    max_velocity_mm_s: float

    def __post_init__(self) -> None:
        if not self.name:
            raise ParameterError("a placement run needs a name")

    @classmethod
    def of(cls, name: str, label: str, result: PlacementResult) -> PlacementRun:
        """The run ``result`` under ``name``, its metrics read once."""
        m = result.metrics
        return cls(
            name=name,
            label=label,
            result=result,
            verdict=str(m["verdict"]),
            verdict_reason=str(m["verdict_reason"]),
            stop_reason=str(m["stop_reason"]),
            placed=bool(m["placed"]),
            true_press_N=float(m["true_press_N"]),
            final_force_N=float(m["final_force_N"]),
            peak_press_N=float(m["peak_press_N"]),
            load_weight_N=float(m["load_weight_N"]),
            settle_time_s=_optional(m["settle_time_s"]),
            contact_stiffness_N_per_mm=_optional(m["contact_stiffness_N_per_mm"]),
            force_ripple_N=float(m["force_ripple_N"]),
            k1_mm_per_N=float(m["k1_mm_per_N"]),
            k2_mm_per_s_per_N=float(m["k2_mm_per_s_per_N"]),
            descent_mm=float(m["descent_mm"]),
            max_velocity_mm_s=float(m["max_velocity_mm_s"]),
        )


@dataclass(frozen=True)
class PlacementSetup:
    """What every placement run shares.

    Attributes:
        load_kg: the load [kg].
        approach_gap_m: gap between load and surface at the start [m].
        position_depth_m: how far below the surface's top position-only control descends [m].
        max_force_N: the force limit that stops a run [N].
        band_N: the band the filtered force settles in to count as placed [N].
        gentle_press_N: the largest true press still judged gentle [N].
    """

    load_kg: float
    approach_gap_m: float
    position_depth_m: float
    max_force_N: float
    band_N: float
    gentle_press_N: float

    def __post_init__(self) -> None:
        if not self.load_kg > 0:
            raise ParameterError(f"load_kg must be > 0, got {self.load_kg}")

    def to_json(self) -> dict[str, Any]:
        """The setup as ``metrics.json`` shows it (lengths in mm)."""
        return {
            "load_kg": self.load_kg,
            "approach_gap_mm": self.approach_gap_m * 1e3,
            "position_depth_mm": self.position_depth_m * 1e3,
            "max_force_N": self.max_force_N,
            "band_N": self.band_N,
            "gentle_press_N": self.gentle_press_N,
        }


@dataclass(frozen=True)
class PlacementMetrics:
    """The placement section's runs, judged from the true contact.

    Attributes:
        runs: every run by name, in the order they ran.
        k13_sweep: names of the K1 sweep's runs, K1 rising.
        k23_sweep: names of the K2 sweep's runs, K2 rising.
        calibration_used: the model every run compensated with.
        setup: what every run shares.
    """

    runs: Mapping[str, PlacementRun]
    k13_sweep: tuple[str, ...]
    k23_sweep: tuple[str, ...]
    calibration_used: GravityModel
    setup: PlacementSetup

    def __post_init__(self) -> None:
        unknown = [n for n in (*self.k13_sweep, *self.k23_sweep) if n not in self.runs]
        if unknown:
            raise ParameterError(f"sweep runs {unknown} are not among the runs")
        object.__setattr__(self, "runs", MappingProxyType(dict(self.runs)))

    def to_json(self) -> dict[str, Any]:
        """The section's entry of ``metrics.json``: each run's metrics under its name, then the
        published values, the calibration used, the sweeps and the setup."""
        out: dict[str, Any] = {name: dict(r.result.metrics) for name, r in self.runs.items()}
        out["published"] = paper.PUBLISHED["placement_test"]
        out["calibration_used"] = model_to_dict(self.calibration_used)
        out["sweeps"] = {"k13": list(self.k13_sweep), "k23": list(self.k23_sweep)}
        out["setup"] = self.setup.to_json()
        return out


def verdict_mark(verdict: str) -> Mark:
    """A run's verdict as a report cell: green when placed gently, red otherwise."""
    return Mark(verdict, "good" if verdict == "placed gently" else "bad")


def _num(value: Any, digits: int = 3) -> str:
    if isinstance(value, float):
        return f"{value:.{digits}f}" if math.isfinite(value) else "-"
    return "-" if value is None else str(value)


def _vec(v: np.ndarray, digits: int = 4) -> str:
    return "(" + ", ".join(f"{x:+.{digits}f}" for x in v) + ")"


def placement_section(
    out: Path, settings: DemoSettings, calibration: Calibration, advance: Advance
) -> tuple[PlacementMetrics, Section]:
    """Every placement run compensates with ``calibration``, identified on the simulated cell."""
    published = paper.PUBLISHED["placement_test"]
    k13 = float(published["k13_fixed_mm_per_N"])
    sponge_k1, sponge_k2 = DEFAULT_GAINS["sponge"]
    book_k1, book_k2 = DEFAULT_GAINS["book"]
    sponge = PlacementConfig(control="admittance", k1_m_per_N=sponge_k1, k2_m_per_s_N=sponge_k2)
    book = PlacementConfig(control="admittance", k1_m_per_N=book_k1, k2_m_per_s_N=book_k2)
    k23 = sponge_k2 * 1e3
    model = calibration.model
    seeds = iter(range(settings.seed + 300, settings.seed + 400))
    runs: dict[str, PlacementRun] = {}

    def keep(name: str, label: str, result: PlacementResult) -> None:
        run = runs[name] = PlacementRun.of(name, label, result)
        write_placement_outputs(result, out / "placement" / name)
        plot_placement(
            [result], out / "placement" / name / "placement.png", title=f"{label}: {run.verdict}"
        )
        advance(f"placement {name}")

    plan: list[tuple[str, str, PlacementConfig, str]] = [
        ("position_sponge", "sponge", replace(sponge, control="position"), "position only, sponge"),
        ("position_book", "book", replace(book, control="position"), "position only, book"),
        ("admittance_sponge", "sponge", sponge, "admittance, compensated, sponge"),
        ("admittance_book", "book", book, "admittance, compensated, book"),
        (
            "admittance_uncompensated_sponge",
            "sponge",
            replace(sponge, compensation=False),
            "admittance, uncompensated, sponge",
        ),
    ]
    for name, surface, config, label in plan:
        cell = SimPlacementCell(surface, 0.5, seed=next(seeds))
        keep(name, label, run_placement(cell, model, config))

    def sweep_label(gain: str, value: float) -> tuple[str, str]:
        k = value * 1e3
        if gain == "k1":
            return f"k13_{k:g}", f"k13 = {k:g} mm/N, k23 = {k23:g} mm/(s·N)"
        return f"k23_{k:g}", f"k23 = {k:g} mm/(s·N), k13 = {k13:g} mm/N"

    sweep_gains(
        lambda: SimPlacementCell("sponge", 0.5, seed=next(seeds)),
        model,
        sponge,
        k1_values_m_per_N=[k * 1e-3 for k in settings.k13_values_mm_per_N],
        k2_values_m_per_s_N=[k * 1e-3 for k in settings.k23_values_mm_per_s_N],
        on_run=lambda gain, value, result: keep(*sweep_label(gain, value), result),
    )
    k13_names = [f"k13_{k:g}" for k in settings.k13_values_mm_per_N]
    k23_names = [f"k23_{k:g}" for k in settings.k23_values_mm_per_s_N]
    figures = [
        Figure(
            "fig6_position_only.png",
            "Fig. 6: position-only placement on the sponge and the book",
            "Constant-speed descent to a fixed depth, no force feedback. Solid: the sensed "
            "(compensated) force along gravity; dashed: the true force on the same axis, load "
            "weight − surface force.",
        ),
        Figure(
            "fig7_compensation.png",
            "Fig. 7: admittance control on the sponge, with and without gravity compensation",
            "Both runs settle their sensed force at 0 N; the dashed true force shows that "
            "without compensation the load ends up pressed into the sponge.",
        ),
        Figure(
            "fig7_k13_sweep.png",
            f"Fig. 7, k13 sweep on the sponge (k23 = {k23:g} mm/(s·N))",
            "Sensed force solid, true force dashed.",
        ),
        Figure(
            "fig7_k23_sweep.png",
            f"Fig. 7, k23 sweep on the sponge (k13 = {k13:g} mm/N)",
            "Sensed force solid, true force dashed.",
        ),
    ]
    groups = [
        (["position_sponge", "position_book"], ["sponge", "book"]),
        (
            ["admittance_sponge", "admittance_uncompensated_sponge"],
            ["with compensation", "without compensation"],
        ),
        (k13_names, [f"k13 = {k:g} mm/N" for k in settings.k13_values_mm_per_N]),
        (k23_names, [f"k23 = {k:g} mm/(s·N)" for k in settings.k23_values_mm_per_s_N]),
    ]
    for figure, (names, legend) in zip(figures, groups, strict=True):
        plot_placement(
            [runs[n].result for n in names], out / figure.path, labels=legend, title=figure.title
        )

    default = PlacementConfig(control="position")
    metrics = PlacementMetrics(
        runs=runs,
        k13_sweep=tuple(k13_names),
        k23_sweep=tuple(k23_names),
        calibration_used=model,
        setup=PlacementSetup(
            load_kg=0.5,
            approach_gap_m=default.approach_gap_m,
            position_depth_m=default.position_depth_m,
            max_force_N=default.max_force_N,
            band_N=default.band_N,
            gentle_press_N=default.gentle_press_N,
        ),
    )
    section = Section(
        title="4. Compliant placement (paper 2.2.2, Fig. 6 and 7)",
        anchor="placement",
        paragraphs=_paragraphs(runs, published, default, model, (book_k1, book_k2), k23),
        tables=[_runs_table(runs)],
        figures=figures,
    )
    return metrics, section


def _paragraphs(
    runs: Mapping[str, PlacementRun],
    published: Mapping[str, Any],
    default: PlacementConfig,
    model: GravityModel,
    book_gains: tuple[float, float],
    k23: float,
) -> list[str]:
    sponge_k1, sponge_k2 = DEFAULT_GAINS["sponge"]
    unc = runs["admittance_uncompensated_sponge"]
    return [
        f"A 500 g load is held {default.approach_gap_m * 1e3:g} mm above a sponge (a spring) or "
        "a book (stiff) and set down. Position-only control descends at constant speed to "
        f"{default.position_depth_m * 1e3:g} mm below the surface's top, with no force "
        "feedback, and presses the load into it (paper: final force "
        f"{published['position_only_final_force_N']['sponge']} N on the sponge, "
        f"{published['position_only_final_force_N']['book']} N on the book). Admittance "
        "control (the paper's combined law, Eq. 27, ΔV = K1 dΔF/dt + K2 ΔF along the base's z "
        "axis) on the compensated force lowers it, slows as the surface takes up the weight "
        f"and counts it as placed once the filtered force stays within ±{default.band_N:g} N "
        f"for {default.settle_time_s:g} s; the gripper then opens.",
        "Verdicts come from the true contact force (the simulator's truth, which the "
        "controller never sees): placed gently when the surface carries the load's weight "
        f"within ±{default.gentle_press_N:g} N at the decision and never more before it; "
        "pressed beyond that; stopped when a safety limit or the time-out ends the run before "
        "any decision. True press = surface force − load weight (positive: pushed into the "
        "surface).",
        "Without compensation the controller settles its raw force at 0 N, which it reaches "
        "only when the surface carries the tool's weight and the sensor's bias as well as the "
        f"load: the load is {unc.verdict}, {unc.true_press_N:+.2f} N beyond its weight, "
        f"while the sensed force reads {unc.final_force_N:+.3f} N. Fig. 7's dashed lines "
        "show the truth.",
        f"Gains: sponge k13 = {sponge_k1 * 1e3:g} mm/N, k23 = {sponge_k2 * 1e3:g} mm/(s·N); "
        f"book k13 = {book_gains[0] * 1e3:g}, k23 = {book_gains[1] * 1e3:g}. The book's "
        "contact with the arm's servo in series is about 1.5e5 N/m, so the paper's "
        "k13 = 0.1 mm/N would make the loop unstable there; and on our sponge (1500 N/m) the "
        "paper's k23 = 0.1 mm/(s·N) settles with a 7 s time constant, so the sweeps fix k23 at "
        f"{k23:g} mm/(s·N) (docs/control.md).",
        "Every run compensates with the calibration identified on the simulated cell in "
        f"section 1 (joint method): G = {model.weight_N:.4f} N, "
        f"P = {_vec(model.center_of_gravity_m)} m, F0 = {_vec(model.force_bias_N)} N, "
        f"M0 = {_vec(model.torque_bias_Nm)} N·m, U = {math.degrees(model.tilt_U_rad):.3f}°, "
        f"V = {math.degrees(model.tilt_V_rad):.3f}°; the placement scene has the same tilted "
        "base. Each run's name links to its plot; its timeseries.csv and metrics.json lie "
        "beside the plot in placement/<run>/.",
    ]


def _runs_table(runs: Mapping[str, PlacementRun]) -> Table:
    rows: list[list[Cell]] = [
        [
            Link(run.label, f"placement/{name}/placement.png"),
            verdict_mark(run.verdict),
            _num(run.true_press_N),
            _num(run.final_force_N),
            _num(run.peak_press_N),
            _num(run.settle_time_s, 2),
            _num(run.descent_mm, 2),
            _num(run.max_velocity_mm_s, 1),
            run.stop_reason.replace("_", " "),
        ]
        for name, run in runs.items()
    ]
    return Table(
        "Placement runs",
        [
            "run (plot)",
            "verdict (true contact)",
            "true press [N]",
            "sensed final force [N]",
            "peak press [N]",
            "settle time [s]",
            "descent [mm]",
            "max speed [mm/s]",
            "ended by",
        ],
        rows,
        text_columns=2,
        note="Sensed final force: the force the controller saw along gravity (+ the load "
        "hangs), averaged over the hold after its decision, or the reading that stopped it. "
        "True press and peak press: surface force beyond the load's weight.",
    )
