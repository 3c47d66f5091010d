"""``ftcomp demo``: every experiment of the paper on the simulated cell, with a report.

Sections (each a function returning its metrics and its report section):
calibration (2.2.1, Tables 1-2), continuous pose change (Fig. 5), Tables 3 and 4, placement
(2.2.2, Fig. 6 and 7). Output folder: ``report.html`` with PNG figures beside it,
``metrics.json``, the calibration files and every run's CSV.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ftcomp import paper
from ftcomp.calibration.identify import Calibration
from ftcomp.errors import ParameterError
from ftcomp.experiments.demo_gravity import (
    calibration_section,
    continuous_section,
    tables_section,
)
from ftcomp.experiments.placement import run_placement, sweep_gains, write_placement_outputs
from ftcomp.experiments.placement_config import DEFAULT_GAINS, PlacementConfig, PlacementResult
from ftcomp.io.atomic import atomic_write_text, prepare_output_dir
from ftcomp.io.calibration_json import model_to_dict
from ftcomp.report.figures import plot_placement
from ftcomp.report.html import Figure, Section, Table, write_report
from ftcomp.sim.placement_cell import SimPlacementCell

__all__ = ["MARKER_FILE", "DemoSettings", "prepare_output", "run_demo"]

#: A file the demo leaves in its output folder, so a later run knows the folder is its own.
MARKER_FILE = ".ftcomp-demo"

Advance = Callable[[str], None]


@dataclass(frozen=True)
class DemoSettings:
    """What the demo runs.

    Attributes:
        samples_per_pose: readings per calibration pose (the paper: 500).
        weighing_samples_per_pose: readings per pose when weighing the Table-4 loads.
        continuous_duration_s: duration of the continuous orientation change [s].
        k13_values_mm_per_N: the K1 sweep on the sponge, K2 fixed at the sponge's default.
        k23_values_mm_per_s_N: the K2 sweep on the sponge, K1 fixed at the paper's 0.1 mm/N.
        seed: seeds every sensor's noise.
    """

    samples_per_pose: int
    weighing_samples_per_pose: int
    continuous_duration_s: float
    k13_values_mm_per_N: tuple[float, ...]
    k23_values_mm_per_s_N: tuple[float, ...]
    seed: int

    @classmethod
    def full(cls, seed: int) -> DemoSettings:
        """The paper's settings: 500 readings per pose, three-value gain sweeps."""
        return cls(500, 200, 4.0, (0.05, 0.1, 0.2), (0.5, 1.0, 2.0), seed)

    @classmethod
    def quick(cls, seed: int) -> DemoSettings:
        """A shorter run with the same sections (for tests)."""
        return cls(60, 30, 1.5, (0.05, 0.2), (1.0, 2.0), seed)

    @property
    def steps(self) -> int:
        """Progress steps: 2 calibrations, 2 continuous-pose steps, 6 loads, placement runs."""
        placement = 5 + len(self.k13_values_mm_per_N) + len(self.k23_values_mm_per_s_N)
        return 2 + 2 + 6 + placement


def _placement_section(
    out: Path, settings: DemoSettings, calibration: Calibration, advance: Advance
) -> tuple[dict[str, Any], Section]:
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
    runs: dict[str, PlacementResult] = {}
    labels: dict[str, str] = {}

    def keep(name: str, title: str, result: PlacementResult) -> None:
        runs[name], labels[name] = result, title
        write_placement_outputs(result, out / "placement" / name, title=title)
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
    for name, surface, config, title in plan:
        cell = SimPlacementCell(surface, 0.5, seed=next(seeds))
        keep(name, title, run_placement(cell, model, config))

    def sweep_title(gain: str, value: float) -> tuple[str, str]:
        if gain == "k1":
            k = value * 1e3
            return f"k13_{k:g}", f"k13 = {k:g} mm/N, k23 = {k23:g} mm/(s·N)"
        k = value * 1e3
        return f"k23_{k:g}", f"k23 = {k:g} mm/(s·N), k13 = {k13:g} mm/N"

    sweep_gains(
        lambda: SimPlacementCell("sponge", 0.5, seed=next(seeds)),
        model,
        sponge,
        k1_values_m_per_N=[k * 1e-3 for k in settings.k13_values_mm_per_N],
        k2_values_m_per_s_N=[k * 1e-3 for k in settings.k23_values_mm_per_s_N],
        on_run=lambda gain, value, result: keep(*sweep_title(gain, value), result),
    )
    plot_placement(
        [runs["position_sponge"], runs["position_book"]],
        out / "fig6_position_only.png",
        labels=["sponge", "book"],
        title="Fig. 6: position-only placement",
    )
    plot_placement(
        [runs["admittance_sponge"], runs["admittance_uncompensated_sponge"]],
        out / "fig7_compensation.png",
        labels=["with compensation", "without compensation"],
        title="Fig. 7a/b: admittance with and without compensation (sponge)",
    )
    k13_names = [f"k13_{k:g}" for k in settings.k13_values_mm_per_N]
    k23_names = [f"k23_{k:g}" for k in settings.k23_values_mm_per_s_N]
    plot_placement(
        [runs[n] for n in k13_names],
        out / "fig7_k13_sweep.png",
        labels=[labels[n] for n in k13_names],
        title="Fig. 7a: k13 sweep (sponge)",
    )
    plot_placement(
        [runs[n] for n in k23_names],
        out / "fig7_k23_sweep.png",
        labels=[labels[n] for n in k23_names],
        title="Fig. 7c: k23 sweep (sponge)",
    )
    keys = (
        "placed",
        "final_force_N",
        "peak_press_N",
        "settle_time_s",
        "descent_mm",
        "max_velocity_mm_s",
    )
    metrics: dict[str, Any] = {name: dict(r.metrics) for name, r in runs.items()}
    metrics["published"] = published
    metrics["calibration_used"] = model_to_dict(model)
    rows = [
        [
            labels[name],
            *(_cell_text(runs[name].metrics.get(k)) for k in keys),
            str(runs[name].metrics.get("stop_reason", "")),
        ]
        for name in runs
    ]
    section = Section(
        title="4. Compliant placement (paper 2.2.2, Fig. 6 and 7)",
        anchor="placement",
        paragraphs=[
            "A 500 g load is held 2 mm above a sponge (spring) or a book (stiff) and set down. "
            "Position-only control descends at constant speed to a fixed depth and presses the "
            "load into the surface (paper: final force "
            f"{published['position_only_final_force_N']['sponge']} N "
            f"on the sponge, {published['position_only_final_force_N']['book']} N on the book). "
            "Admittance control on the compensated force lowers it, slows as the surface takes the "
            f"weight and stops inside ±{published['stop_band_N']} N. Without compensation the bias "
            "and tool weight stay in the signal and the placement decision goes wrong.",
            f"Gains: sponge k13 = {sponge_k1 * 1e3:g} mm/N, k23 = {sponge_k2 * 1e3:g} mm/(s·N); "
            f"book k13 = {book_k1 * 1e3:g}, k23 = {book_k2 * 1e3:g}. The book's contact with the "
            "arm's servo in series is about 1.5e5 N/m, so the paper's k13 = 0.1 mm/N would make "
            "the loop unstable there; and on our sponge (1500 N/m) the paper's k23 = 0.1 "
            "mm/(s·N) settles with a 7 s time constant, so the sweeps fix k23 at 1 mm/(s·N) "
            "(docs/control.md). Larger k23 places faster with more force ripple, as the paper "
            "reports; larger k13 adds ripple but cannot place faster: on a contact of stiffness "
            "k the force error decays at k·k23/(1 + k13·k).",
            "Every run compensates with the calibration identified on the simulated cell in "
            f"section 1 (joint method): G = {model.weight_N:.4f} N, "
            f"P = {_vec(model.center_of_gravity_m)} m, F0 = {_vec(model.force_bias_N)} N, "
            f"M0 = {_vec(model.torque_bias_Nm)} N·m, U = {math.degrees(model.tilt_U_rad):.3f}°, "
            f"V = {math.degrees(model.tilt_V_rad):.3f}°; the placement scene has the same tilted "
            "base. The simulator's truth only scores the runs (true contact force).",
            "Each run's timeseries.csv, metrics.json and plot are in placement/<run>/.",
        ],
        tables=[Table("Placement runs", ["run", *keys, "ended by"], rows)],
        figures=[
            Figure("fig6_position_only.png", "Fig. 6: position-only placement on sponge and book"),
            Figure(
                "fig7_compensation.png",
                "Fig. 7: admittance control with and without gravity compensation",
            ),
            Figure("fig7_k13_sweep.png", "Fig. 7: k13 sweep with k23 fixed"),
            Figure("fig7_k23_sweep.png", "Fig. 7: k23 sweep with k13 fixed"),
        ],
    )
    return metrics, section


def _cell_text(value: Any) -> str:
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.3f}" if math.isfinite(value) else "-"
    return "-" if value is None else str(value)


def prepare_output(out_dir: str | Path, *, overwrite: bool = False) -> Path:
    """Create the output folder; an existing one with files needs ``overwrite`` (``--force``).

    Raises:
        ParameterError: the folder holds files and ``overwrite`` is false (the message says
            whether an earlier demo wrote them), or it cannot be written.
    """
    out = Path(out_dir)
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        if (out / MARKER_FILE).exists():
            raise ParameterError(
                f"{out}: holds an earlier demo's results; pass --force to replace them"
            )
        raise ParameterError(
            f"{out}: folder exists with files the demo did not write; choose another --out "
            "(or pass --force to write into it)"
        )
    prepare_output_dir(out, overwrite=True)
    (out / MARKER_FILE).write_text("written by ftcomp demo\n")
    return out


def run_demo(
    out_dir: str | Path, settings: DemoSettings, advance: Advance, *, overwrite: bool = False
) -> dict[str, Any]:
    """Run every section, write the files and the report; returns the metrics."""
    out = prepare_output(out_dir, overwrite=overwrite)
    started = time.perf_counter()
    timing: dict[str, float] = {}

    t0 = time.perf_counter()
    calib_metrics, calib_section, joint, paper_data = calibration_section(out, settings, advance)
    timing["calibration_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    cont_metrics, cont_section = continuous_section(out, settings, advance)
    timing["continuous_pose_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    table3, table4, tables_sec = tables_section(out, settings, joint, paper_data, advance)
    timing["tables_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    place_metrics, place_section = _placement_section(out, settings, joint, advance)
    timing["placement_s"] = time.perf_counter() - t0
    timing["total_s"] = time.perf_counter() - started

    metrics = {
        "calibration": calib_metrics,
        "continuous_pose": cont_metrics,
        "table3": table3,
        "table4": table4,
        "placement": place_metrics,
        "settings": {
            "samples_per_pose": settings.samples_per_pose,
            "weighing_samples_per_pose": settings.weighing_samples_per_pose,
            "seed": settings.seed,
            "simulated_tilt_deg": list(paper.TILT_DEG),
        },
        "timing": timing,
    }
    atomic_write_text(out / "metrics.json", json.dumps(_json_ready(metrics), indent=2) + "\n")
    write_report(
        out / "report.html",
        "ftcomp: Huang et al. 2020 reproduced on a simulated robot cell",
        [
            "Every experiment of the paper, run on a MuJoCo model of a six-axis arm with a wrist "
            "F/T sensor, a gripper, loads, a sponge and a book; the paper's published numbers "
            "beside ours. Numbers: metrics.json; raw data: the CSV files in this folder.",
            f"Run time {timing['total_s']:.1f} s, seed {settings.seed}.",
        ],
        [calib_section, cont_section, tables_sec, place_section],
    )
    return metrics


def _json_ready(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return _json_ready(value.tolist())
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def _vec(v: np.ndarray, digits: int = 4) -> str:
    return "(" + ", ".join(f"{x:+.{digits}f}" for x in v) + ")"
