"""The demo's calibration section (paper 2.2.1, Tables 1-2): the paper's own data, then the
simulated cell at the same poses, every value with its standard error and the truth beside it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

from scipy.spatial.transform import Rotation

from ftcomp import paper
from ftcomp.calibration.identify import calibrate, max_deviations_in_standard_errors
from ftcomp.calibration_record import Calibration, Method
from ftcomp.errors import ParameterError
from ftcomp.huang2020 import gravity
from ftcomp.huang2020.settings import Advance, DemoSettings
from ftcomp.io.atomic import atomic_write_text
from ftcomp.io.calibration_json import calibration_to_dict, model_to_dict, save_calibration
from ftcomp.io.samples_csv import write_samples
from ftcomp.io.truth_json import truth_document
from ftcomp.model import GravityModel
from ftcomp.samples import WRENCH_COLUMNS
from ftcomp.views.html import Section, Table

__all__ = [
    "CalibrationMetrics",
    "NoGripperWeighing",
    "calibration_section",
    "truth_document",
]


@dataclass(frozen=True)
class NoGripperWeighing:
    """The sensing end weighed alone (the cell without its gripper) against the paper's value.

    Attributes:
        true_sensing_end_weight_N: what the cell was built with [N].
        identified_sensing_end_weight_N: the joint-method estimate [N].
        std_error_N: its standard error [N].
        published_N: the paper's sensing end weight [N].
    """

    true_sensing_end_weight_N: float
    identified_sensing_end_weight_N: float
    std_error_N: float
    published_N: float

    def __post_init__(self) -> None:
        if not self.std_error_N >= 0:
            raise ParameterError(f"std_error_N must be >= 0, got {self.std_error_N}")


@dataclass(frozen=True)
class CalibrationMetrics:
    """What the calibration section found.

    Attributes:
        paper_data: the paper's Tables 1-2 identified by the paper's method.
        truth: the simulated cell's true parameters (with the gripper).
        simulation: the simulated readings identified by each method (``paper``, ``joint``).
        truth_error_in_standard_errors: per method, the largest |identified - true| of each
            parameter in standard errors.
        no_gripper: the sensing end weighed alone.
        samples_per_pose: readings per pose in the simulation.
    """

    paper_data: Calibration = field(repr=False)
    truth: GravityModel
    simulation: Mapping[Method, Calibration] = field(repr=False)
    truth_error_in_standard_errors: Mapping[Method, Mapping[str, float]]
    no_gripper: NoGripperWeighing
    samples_per_pose: int

    def __post_init__(self) -> None:
        if set(self.simulation) != {"paper", "joint"}:
            raise ParameterError(
                f"simulation needs the paper and joint methods, got {sorted(self.simulation)}"
            )
        object.__setattr__(self, "simulation", MappingProxyType(dict(self.simulation)))

    @property
    def joint(self) -> Calibration:
        """The simulation's joint-method calibration (the demo compensates with it)."""
        return self.simulation["joint"]

    def to_json(self) -> dict[str, Any]:
        """The section's entry of ``metrics.json``."""
        bare = self.no_gripper
        return {
            "paper_data": calibration_to_dict(self.paper_data),
            "simulation_truth": model_to_dict(self.truth),
            "simulation": {m: calibration_to_dict(r) for m, r in self.simulation.items()},
            "truth_error_in_standard_errors": {
                str(m): dict(e) for m, e in self.truth_error_in_standard_errors.items()
            },
            "no_gripper": {
                "true_sensing_end_weight_N": bare.true_sensing_end_weight_N,
                "identified_sensing_end_weight_N": bare.identified_sensing_end_weight_N,
                "std_error_N": bare.std_error_N,
                "published_N": bare.published_N,
            },
            "samples_per_pose": self.samples_per_pose,
        }


def calibration_section(
    out: Path, settings: DemoSettings, advance: Advance
) -> tuple[CalibrationMetrics, Section]:
    """Identify the paper's data and the simulated cell; write the files; the report section."""
    published = paper.PUBLISHED
    paper_data = calibrate(paper.paper_samples(), method="paper")
    save_calibration(out / "calibration_paper_data.json", paper_data)
    run = gravity.run_calibration(
        samples_per_pose=settings.samples_per_pose,
        seed=settings.seed,
        tilt_deg=paper.TILT_DEG,
        progress=advance,
    )
    for name, samples in (
        ("calibration_samples.csv", run.samples),
        ("calibration_no_gripper_samples.csv", run.bare_samples),
    ):
        write_samples(
            out / name,
            samples.wrench_sensor,
            Rotation.from_matrix(samples.R_base_sensor),
            encoding="paper_euler",
            pose=samples.pose,
            t=samples.t,
        )
    save_calibration(out / "calibration.json", run.results["joint"])
    save_calibration(out / "calibration_paper_method.json", run.results["paper"])
    atomic_write_text(out / "truth.json", json.dumps(truth_document(run.truth), indent=2) + "\n")
    rows = _parameter_rows(paper_data, run.truth, run.results)
    joint = run.results["joint"]
    truth_errors = {
        method: max_deviations_in_standard_errors(result, run.truth)
        for method, result in run.results.items()
    }
    metrics = CalibrationMetrics(
        paper_data=paper_data,
        truth=run.truth,
        simulation=run.results,
        truth_error_in_standard_errors=truth_errors,
        no_gripper=NoGripperWeighing(
            true_sensing_end_weight_N=run.bare_truth.weight_N,
            identified_sensing_end_weight_N=run.bare_result.model.weight_N,
            std_error_N=run.bare_result.std_errors.weight_N,
            published_N=float(published["sensor_sensing_end_weight_N"]),
        ),
        samples_per_pose=settings.samples_per_pose,
    )
    section = Section(
        title="1. Calibration (paper 2.2.1, Tables 1-2)",
        anchor="calibration",
        paragraphs=[
            "Tables 1-2 below are the paper's nine poses and the mean of 500 readings at each. "
            "Identified by the paper's method, they reproduce its published parameters. The "
            f"simulated cell was then driven to the same 9 poses, {settings.samples_per_pose} "
            "readings at each (sensor: ±250 N / ±6 N·m, 1/2000 resolution, noise, the paper's "
            "bias), and identified by both methods.",
            "Every identified value is given ± its standard error. "
            + _tilt_sentence(paper_data, run.results["joint"]),
            f"Largest |identified − true| in standard errors: paper method "
            f"{max(truth_errors['paper'].values()):.2f}, joint method "
            f"{max(truth_errors['joint'].values()):.2f}. Condition number of the poses: "
            f"{joint.condition_number:.2f}.",
            f"Without the gripper the cell identifies the sensing end alone: "
            f"{run.bare_result.model.weight_N:.4f} ± {run.bare_result.std_errors.weight_N:.4f} N "
            f"(true {run.bare_truth.weight_N:.3f} N, "
            f"paper {published['sensor_sensing_end_weight_N']} N).",
        ],
        tables=[
            _paper_tables_1_2(),
            Table(
                "Identified parameters (value ± standard error)",
                [
                    "parameter",
                    "unit",
                    "published",
                    "paper's data, paper method",
                    "simulated truth",
                    "simulation, paper method",
                    "simulation, joint method",
                ],
                rows,
                text_columns=2,
                note="'not identified': the value is smaller than its standard error, so the "
                "poses cannot tell it from zero.",
            ),
        ],
    )
    return metrics, section


#: (label, unit, scale to the unit, getter) per table row; the getter reads a GravityModel or
#: the same attribute of its StandardErrors.
_PARAMETERS: list[tuple[str, str, float, Callable[[Any], Any]]] = [
    ("tool weight G", "N", 1.0, lambda m: m.weight_N),
    ("base tilt U", "deg", math.degrees(1.0), lambda m: m.tilt_U_rad),
    ("base tilt V", "deg", math.degrees(1.0), lambda m: m.tilt_V_rad),
    *(
        (f"force bias F0{axis}", "N", 1.0, lambda m, i=i: m.force_bias_N[i])
        for i, axis in enumerate("xyz")
    ),
    *(
        (f"torque bias M0{axis}", "N·m", 1.0, lambda m, i=i: m.torque_bias_Nm[i])
        for i, axis in enumerate("xyz")
    ),
    *(
        (f"centre of gravity P{axis}", "mm", 1e3, lambda m, i=i: m.center_of_gravity_m[i])
        for i, axis in enumerate("xyz")
    ),
]


def _published_values() -> list[float]:
    p = paper.PUBLISHED
    return [
        p["tool_weight_N"],
        p["base_tilt_deg"]["U"],
        p["base_tilt_deg"]["V"],
        *p["force_bias_N"],
        *p["torque_bias_Nm"],
        *(1e3 * v for v in p["center_of_gravity_m"]),
    ]


def _pm(value: float, se: float, tilt: bool) -> str:
    text = f"{value:+.4f} ± {se:.4f}" if math.isfinite(se) else f"{value:+.4f}"
    if tilt and math.isfinite(se) and abs(value) < se:
        text += " (not identified)"
    return text


def _parameter_rows(
    paper_data: Calibration, truth: GravityModel, results: Mapping[Any, Calibration]
) -> list[list[str]]:
    rows = []
    for (label, unit, scale, get), pub in zip(_PARAMETERS, _published_values(), strict=True):
        tilt = label.startswith("base tilt")
        cells = [label, unit, f"{pub:g}"]
        for source in (paper_data, None, results["paper"], results["joint"]):
            if source is None:
                cells.append(f"{get(truth) * scale:+.4f}")
                continue
            value, se = get(source.model) * scale, get(source.std_errors) * scale
            cells.append(_pm(value, abs(se), tilt))
        rows.append(cells)
    return rows


def _tilt_sentence(paper_data: Calibration, joint: Calibration) -> str:
    """Say plainly when a tilt is smaller than its standard error (not identified)."""
    parts = []
    for name, result in (("the paper's data", paper_data), ("the simulation", joint)):
        m, se = result.model, result.std_errors
        hidden = [
            f"{axis} = {math.degrees(v):+.3f}° ± {math.degrees(e):.3f}°"
            for axis, v, e in (
                ("U", m.tilt_U_rad, se.tilt_U_rad),
                ("V", m.tilt_V_rad, se.tilt_V_rad),
            )
            if abs(v) < e
        ]
        if hidden:
            parts.append(f"on {name} ({', '.join(hidden)})")
    if not parts:
        return "Both tilts are larger than their standard errors."
    return (
        "The base tilt is not identified " + " and ".join(parts) + ": a tilt smaller than its "
        "standard error cannot be told from a level base with these poses and readings."
    )


def _paper_tables_1_2() -> Table:
    """The paper's Table 1 (poses) and Table 2 (mean readings) as shipped."""
    samples = paper.paper_samples()
    columns = ["pose", "alpha_deg", "beta_deg", "gamma_deg", *WRENCH_COLUMNS]
    index = [samples.header.index(c) for c in columns]
    rows = [[row[i] for i in index] for row in samples.rows]
    return Table(
        "Tables 1-2: the paper's poses and mean readings",
        ["pose", "α", "β", "γ", "fx", "fy", "fz", "tx", "ty", "tz"],
        rows,
        groups=[("", 1), ("Table 1: orientation [deg]", 3), ("Table 2: mean reading [N, N·m]", 6)],
    )
