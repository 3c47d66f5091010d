"""``ftcomp demo``: every experiment of the paper on the simulated cell, with a report.

Sections (each a function returning its metrics and its report section):
calibration (2.2.1, Tables 1-2), continuous pose change (Fig. 5), Tables 3 and 4
(:mod:`ftcomp.huang2020.demo_gravity`), placement (2.2.2, Fig. 6 and 7,
:mod:`ftcomp.huang2020.demo_placement`). Then every published result is set beside ours
(:mod:`ftcomp.huang2020.comparisons`): a summary at the top of the report, the same rows in
each section and in the terminal. Output folder: ``report.html`` with PNG figures beside it,
``metrics.json``, the calibration files and every run's CSV.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ftcomp import paper
from ftcomp.errors import ParameterError
from ftcomp.huang2020.comparisons import Comparison, compare_with_paper, comparison_rows
from ftcomp.huang2020.demo_beyond import BeyondMetrics, beyond_section
from ftcomp.huang2020.demo_calibration import CalibrationMetrics, calibration_section
from ftcomp.huang2020.demo_gravity import (
    ContinuousPoseMetrics,
    Table3Metrics,
    Table4Metrics,
    continuous_section,
    tables_section,
)
from ftcomp.huang2020.demo_placement import PlacementMetrics, placement_section
from ftcomp.huang2020.settings import Advance, DemoSettings
from ftcomp.io.atomic import atomic_write_text, prepare_output_dir
from ftcomp.views.html import Cell, Mark, Section, Table, write_report

__all__ = [
    "MARKER_FILE",
    "DemoResult",
    "DemoTiming",
    "comparison_table",
    "json_ready",
    "prepare_output",
    "run_demo",
]

#: A file the demo leaves in its output folder, so a later run knows the folder is its own.
MARKER_FILE = ".ftcomp-demo"


@dataclass(frozen=True)
class DemoTiming:
    """Wall-clock time of each section and of the whole demo [s]."""

    calibration_s: float
    continuous_pose_s: float
    tables_s: float
    placement_s: float
    beyond_paper_s: float
    total_s: float

    def __post_init__(self) -> None:
        negative = {k: v for k, v in vars(self).items() if not v >= 0}
        if negative:
            raise ParameterError(f"durations must be >= 0, got {negative}")


@dataclass(frozen=True)
class DemoResult:
    """Everything the demo found, section by section, and the paper's results beside ours.

    Attributes:
        settings: what was run.
        calibration: section 1 (Tables 1-2).
        continuous_pose: section 2 (Fig. 5).
        table3: section 3, Table 3.
        table4: section 3, Table 4.
        placement: section 4 (Fig. 6 and 7).
        beyond_paper: online load estimation and inertial compensation.
        comparisons: every published result beside ours, judged.
        timing: how long each section took.
    """

    settings: DemoSettings
    calibration: CalibrationMetrics
    continuous_pose: ContinuousPoseMetrics
    table3: Table3Metrics
    table4: Table4Metrics
    placement: PlacementMetrics
    beyond_paper: BeyondMetrics
    comparisons: tuple[Comparison, ...]
    timing: DemoTiming

    def __post_init__(self) -> None:
        if not self.comparisons:
            raise ParameterError("a demo result needs its comparisons with the paper")

    def to_json(self) -> dict[str, Any]:
        """``metrics.json``: JSON-ready (numpy converted, non-finite numbers as null)."""
        return json_ready(
            {
                "calibration": self.calibration.to_json(),
                "continuous_pose": self.continuous_pose.to_json(),
                "table3": self.table3.to_json(),
                "table4": self.table4.to_json(),
                "placement": self.placement.to_json(),
                "beyond_paper": self.beyond_paper.to_json(),
                "settings": {
                    "samples_per_pose": self.settings.samples_per_pose,
                    "weighing_samples_per_pose": self.settings.weighing_samples_per_pose,
                    "seed": self.settings.seed,
                    "simulated_tilt_deg": list(paper.TILT_DEG),
                },
                "timing": dict(vars(self.timing)),
                "comparisons": comparison_rows(self.comparisons),
            }
        )


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
) -> DemoResult:
    """Run every section, write the files (``metrics.json``, ``report.html``, figures, CSVs)
    and return what was found."""
    out = prepare_output(out_dir, overwrite=overwrite)
    started = time.perf_counter()
    t0 = time.perf_counter()
    calibration, calib_section = calibration_section(out, settings, advance)
    calibration_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    continuous, cont_section = continuous_section(out, settings, advance)
    continuous_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    table3, table4, tables_sec = tables_section(
        out, settings, calibration.joint, calibration.paper_data, advance
    )
    tables_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    placement, place_section = placement_section(out, settings, calibration.joint, advance)
    placement_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    beyond, beyond_sec = beyond_section(out, settings, advance)
    beyond_s = time.perf_counter() - t0
    timing = DemoTiming(
        calibration_s=calibration_s,
        continuous_pose_s=continuous_s,
        tables_s=tables_s,
        placement_s=placement_s,
        beyond_paper_s=beyond_s,
        total_s=time.perf_counter() - started,
    )
    comparisons = tuple(compare_with_paper(calibration, table3, table4, placement))
    result = DemoResult(
        settings=settings,
        calibration=calibration,
        continuous_pose=continuous,
        table3=table3,
        table4=table4,
        placement=placement,
        beyond_paper=beyond,
        comparisons=comparisons,
        timing=timing,
    )
    atomic_write_text(out / "metrics.json", json.dumps(result.to_json(), indent=2) + "\n")
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
            f"Run time {timing.total_s:.1f} s, seed {settings.seed}.",
        ],
        [summary, *(_with_comparisons(s, comparisons) for s in sections)],
    )
    return result


def json_ready(value: Any) -> Any:
    """``value`` with numpy arrays and scalars as Python values and non-finite floats as None
    (JSON has no NaN), dict keys as strings, tuples as lists."""
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist())
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value
