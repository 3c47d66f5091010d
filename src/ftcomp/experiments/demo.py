"""``ftcomp demo``: every experiment of the paper on the simulated cell, with a report.

Sections (each a function returning its metrics and its report section):
calibration (2.2.1, Tables 1-2), continuous pose change (Fig. 5), Tables 3 and 4
(:mod:`ftcomp.experiments.demo_gravity`), placement (2.2.2, Fig. 6 and 7,
:mod:`ftcomp.experiments.demo_placement`). Then every published result is set beside ours
(:mod:`ftcomp.experiments.comparisons`): a summary at the top of the report, the same rows in
each section and in the terminal. Output folder: ``report.html`` with PNG figures beside it,
``metrics.json``, the calibration files and every run's CSV.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ftcomp import paper
from ftcomp.errors import ParameterError
from ftcomp.experiments.comparisons import Comparison, compare_with_paper, comparison_rows
from ftcomp.experiments.demo_beyond import beyond_section
from ftcomp.experiments.demo_calibration import calibration_section
from ftcomp.experiments.demo_gravity import continuous_section, tables_section
from ftcomp.experiments.demo_placement import placement_section
from ftcomp.io.atomic import atomic_write_text, prepare_output_dir
from ftcomp.report.html import Cell, Mark, Section, Table, write_report

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
        beyond_no_grasp_s: motion without grasping in the "beyond the paper" section [s].
    """

    samples_per_pose: int
    weighing_samples_per_pose: int
    continuous_duration_s: float
    k13_values_mm_per_N: tuple[float, ...]
    k23_values_mm_per_s_N: tuple[float, ...]
    seed: int
    beyond_no_grasp_s: float = 60.0

    @classmethod
    def full(cls, seed: int) -> DemoSettings:
        """The paper's settings: 500 readings per pose, three-value gain sweeps."""
        return cls(500, 200, 4.0, (0.05, 0.1, 0.2), (0.5, 1.0, 2.0), seed)

    @classmethod
    def quick(cls, seed: int) -> DemoSettings:
        """A shorter run with the same sections (for tests)."""
        return cls(60, 30, 1.5, (0.05, 0.2), (1.0, 2.0), seed, beyond_no_grasp_s=9.0)

    @property
    def steps(self) -> int:
        """Progress steps: 2 calibrations, 2 continuous-pose steps, 6 loads, placement runs."""
        placement = 5 + len(self.k13_values_mm_per_N) + len(self.k23_values_mm_per_s_N)
        return 2 + 2 + 6 + placement + 3  # + 3: beyond the paper


def comparison_table(comparisons: Sequence[Comparison], caption: str) -> Table:
    """Published beside ours, one row per quantity, with the judgement and its reason."""
    rows: list[list[Cell]] = [
        [
            c.quantity,
            c.paper,
            c.ours,
            Mark("yes" if c.reproduced else "no", "good" if c.reproduced else "bad"),
            Mark(c.note, "note"),
        ]
        for c in comparisons
    ]
    header = ["quantity", "paper", "ftcomp", "reproduced", "why"]
    return Table(caption, header, rows, text_columns=len(header))


def _with_comparisons(section: Section, comparisons: Sequence[Comparison]) -> Section:
    mine = [c for c in comparisons if c.section == section.anchor]
    if not mine:
        return section
    table = comparison_table(mine, "Beside the paper")
    return replace(section, tables=[table, *section.tables])


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
    place_metrics, place_section = placement_section(out, settings, joint, advance)
    timing["placement_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    beyond_metrics, beyond_sec = beyond_section(out, settings, advance)
    timing["beyond_paper_s"] = time.perf_counter() - t0
    timing["total_s"] = time.perf_counter() - started

    metrics: dict[str, Any] = {
        "calibration": calib_metrics,
        "continuous_pose": cont_metrics,
        "table3": table3,
        "table4": table4,
        "placement": place_metrics,
        "beyond_paper": beyond_metrics,
        "settings": {
            "samples_per_pose": settings.samples_per_pose,
            "weighing_samples_per_pose": settings.weighing_samples_per_pose,
            "seed": settings.seed,
            "simulated_tilt_deg": list(paper.TILT_DEG),
        },
        "timing": timing,
    }
    metrics = _json_ready(metrics)
    comparisons = compare_with_paper(metrics)
    metrics["comparisons"] = comparison_rows(comparisons)
    atomic_write_text(out / "metrics.json", json.dumps(metrics, indent=2) + "\n")
    missed = [c for c in comparisons if not c.reproduced]
    summary = Section(
        title="Summary: the paper's results beside ours",
        anchor="summary",
        paragraphs=[
            f"{len(comparisons) - len(missed)} of {len(comparisons)} published results "
            "reproduced. Where one is not, the reason stands beside it; the sections below "
            "give the details."
        ],
        tables=[comparison_table(comparisons, "The paper's results and ours")],
    )
    sections = [calib_section, cont_section, tables_sec, place_section, beyond_sec]
    write_report(
        out / "report.html",
        "ftcomp: Huang et al. 2020 reproduced on a simulated robot cell",
        [
            "Every experiment of the paper, run on a MuJoCo model of a six-axis arm with a wrist "
            "F/T sensor, a gripper, loads, a sponge and a book; the paper's published numbers "
            "beside ours. Numbers: metrics.json; raw data: the CSV files in this folder.",
            f"Run time {timing['total_s']:.1f} s, seed {settings.seed}.",
        ],
        [summary, *(_with_comparisons(s, comparisons) for s in sections)],
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
