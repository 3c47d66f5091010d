"""``ftcomp calibrate SAMPLES.csv [-o calibration.json] [--method paper|joint] [--json]``."""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import get_args

import numpy as np
from rich.console import Console
from rich.table import Table

from ftcomp.calibration.identify import deviations_in_standard_errors
from ftcomp.calibration.identify_extended import (
    BIAS_CHOICES,
    SENSOR_MAP_CHOICES,
    ModelChoice,
    ModelSpec,
    identify,
)
from ftcomp.calibration_record import (
    Calibration,
    Method,
    MountAxes,
    StochasticBiasDrift,
    TemperatureBiasDrift,
)
from ftcomp.cli.common import add_range_argument, print_warnings
from ftcomp.cli.still_options import add_still_arguments, print_segments, still_config
from ftcomp.extras import require_extra
from ftcomp.io.atomic import check_writable
from ftcomp.io.calibration_json import calibration_to_dict, save_calibration
from ftcomp.io.samples_csv import read_samples
from ftcomp.io.truth_json import load_truth
from ftcomp.model import GravityModel
from ftcomp.samples import WRENCH_COLUMNS, Samples

__all__ = [
    "console",
    "print_choice",
    "register",
    "render_calibration",
    "render_truth",
    "tilt_not_identified",
]


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``calibrate`` command's arguments to its parser."""
    parser.description = (
        "Identify F/T sensor bias, tool weight and centre of gravity, and the "
        "robot base's tilt from readings at several poses (sample CSV). Prints every parameter "
        "± its standard error, per-pose residuals and the paper's Table-3 errors; writes the "
        "calibration file with -o, or prints it as JSON with --json."
    )
    parser.add_argument(
        "samples",
        metavar="SAMPLES.csv",
        help="sample CSV: fx..tz [N, N·m] in the sensor frame, one orientation encoding, an "
        "optional pose column (docs/files.md); at least 3 distinct poses, 4+ for the "
        "leave-one-pose-out check",
    )
    parser.add_argument(
        "-o",
        "--output",
        metavar="CALIBRATION.json",
        help="write the calibration file here (ftcomp.calibration/1, docs/files.md) "
        "(default: print only)",
    )
    parser.add_argument(
        "--method",
        choices=get_args(Method),
        default="joint",
        help="paper: the paper's two-stage linear fit; joint: weighted joint nonlinear fit "
        "(docs/calibration.md; default: joint)",
    )
    parser.add_argument(
        "--bias-drift",
        choices=BIAS_CHOICES,
        default="auto",
        help="the bias model: none (constant), a polynomial in each reading's time t, "
        "stochastic (a smooth Matérn 3/2 wander, its size and time constant from the data, 6+ "
        "poses), or temperature (linear in the sensor's temperature, from a temperature_C "
        "column [degC], 4+ poses), with the tool model shared; outside the session's times or "
        "temperatures the bias is held at its nearest estimate; a drift in time needs a t "
        "column; every model but none, the joint method (default: auto, stochastic or "
        "temperature where the data support it over a constant bias, printed with the "
        "evidence)",
    )
    parser.add_argument(
        "--identify-mount",
        choices=get_args(MountAxes),
        default=None,
        help="the orientations are the flange's or TCP's: identify the sensor frame's rotation "
        "in that frame too (yaw about its z axis, 4+ poses; or all three angles, 6+ poses; "
        "joint method; default: the orientations are the sensor's)",
    )
    parser.add_argument(
        "--sensor-map",
        choices=SENSOR_MAP_CHOICES,
        default="auto",
        help="linear: also fit a general linear map of the tool's gravity wrench (gain, "
        "crosstalk, mount misalignment), regularised toward the physical model, and apply it "
        "only where the data support it (joint method, with a constant or stochastic bias); "
        "physical: the paper's model (default: auto, linear wherever the bias model allows it)",
    )
    add_range_argument(parser)
    parser.add_argument(
        "--still-segments",
        action="store_true",
        help="the file is a recording in motion with a t column (a stream --robot log, any "
        "log): find the still segments (thresholds below), list them, and use each as one "
        "pose (default: the rows' pose ids, or orientations, are the poses)",
    )
    add_still_arguments(parser)
    parser.add_argument(
        "--json",
        action="store_true",
        help="print the calibration file's content as JSON on stdout instead of tables "
        "(with or without -o; default: tables)",
    )
    parser.add_argument(
        "--report",
        metavar="CAL.html",
        help="also write one self-contained page to look at: the poses' gravity directions on "
        "the sphere, residuals, leave-one-pose-out, condition and what would improve it, the "
        "drift (needs matplotlib, extra report; default: none)",
    )
    parser.add_argument(
        "--truth",
        metavar="TRUTH.json",
        help="a truth file (ftcomp.truth/1: ftcomp twin --truth, sim collect --truth): print "
        "each identified parameter's distance from the true one in its standard errors "
        "(default: none)",
    )
    parser.add_argument(
        "--force", action="store_true", help="replace an existing -o file (default: refuse)"
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Read, identify, write, print."""
    output = None
    if args.output is not None:
        output = check_writable(args.output, overwrite=args.force, inputs=[args.samples])
    if args.report is not None:
        others = [args.samples, *([args.output] if args.output else [])]
        check_writable(args.report, overwrite=args.force, inputs=others)
        require_extra("report", "calibrate --report")
    truth = load_truth(args.truth) if args.truth is not None else None
    force_range, torque_range = args.range if args.range else (None, None)
    samples = read_samples(args.samples, force_range_N=force_range, torque_range_Nm=torque_range)
    print_warnings(samples.warnings)
    if args.still_segments:
        samples = _still_segments(samples, args)
    spec = ModelSpec(
        method=args.method,
        bias_drift=args.bias_drift,
        identify_mount=args.identify_mount,
        sensor_map=args.sensor_map,
    )
    result, choice = identify(samples, spec)
    if output is not None:
        save_calibration(output, result)
    if args.report is not None:
        from ftcomp.views.calibration_report import write_calibration_report

        write_calibration_report(args.report, result, source=args.samples, samples=samples)
    if args.json:
        print(json.dumps(calibration_to_dict(result), indent=2, allow_nan=False))
        print_choice(choice, Console(stderr=True))
        hidden = tilt_not_identified(result)
        print_warnings([hidden] if hidden is not None else [])
    else:
        out = console()
        print_choice(choice, out)
        render_calibration(result, out, unapplied_map=args.sensor_map == "linear")
        if output is not None:
            out.print(f"calibration written to [bold]{output}[/bold]")
        else:
            out.print("calibration not written (give -o CALIBRATION.json to keep it)")
        if args.report is not None:
            out.print(f"report written to [bold]{args.report}[/bold]")
    if truth is not None:
        render_truth(result, truth, args.truth, Console(stderr=True) if args.json else console())
    print_warnings(w for w in result.warnings if w not in samples.warnings)
    return 0


def render_truth(result: Calibration, truth: GravityModel, source: str, out: Console) -> None:
    """Each identified parameter's distance from the truth in its standard errors."""
    each = deviations_in_standard_errors(result, truth)
    table = Table(title=f"Distance from the truth ({source}) in standard errors |est - true| / SE")
    for col in ("parameter", "x", "y", "z"):
        table.add_column(col, justify="left" if col == "parameter" else "right")
    table.add_row("tool weight G", f"{each['tool_weight_N']:.2f}", "", "")
    table.add_row("base tilt U, V", f"{each['tilt_U_rad']:.2f}", f"{each['tilt_V_rad']:.2f}", "")
    for label, key in (
        ("force bias F0", "force_bias_N"),
        ("torque bias M0", "torque_bias_Nm"),
        ("centre of gravity P", "center_of_gravity_m"),
    ):
        table.add_row(label, *(f"{each[f'{key}[{k}]']:.2f}" for k in range(3)))
    out.print(table)
    worst = max(each, key=lambda k: each[k])
    out.print(f"largest: {worst} at {each[worst]:.2f} standard errors", highlight=False)


def print_choice(choice: ModelChoice, out: Console) -> None:
    """The model chosen from the data, one line per choice with its reason."""
    for reason in choice.reasons:
        out.print(f"model: {reason}", highlight=False)


def _still_segments(samples: Samples, args: argparse.Namespace) -> Samples:
    """The still segments' readings, one pose each; the segments listed (on stderr with
    --json, so that stdout stays JSON)."""
    from ftcomp.calibration.still import still_samples

    found = still_samples(samples, still_config(args))
    out = Console(stderr=True) if args.json else console()
    title = f"Still segments in {samples.source}"
    print_segments(out, title, found.segments, found.t0_ns, found.config)
    out.print(
        f"kept {len(found.samples)} of {found.readings_total} readings in "
        f"{len(found.segments)} still segments (one pose each); {found.unsettled} held "
        "orientation(s) never settled"
    )
    return found.samples


def tilt_not_identified(result: Calibration) -> str | None:
    """A sentence when |U| or |V| is below its standard error (the poses cannot tell the tilt
    from a level base), else None."""
    m, se = result.model, result.std_errors
    hidden = [
        f"|{name}| = {math.degrees(abs(value)):.3f} deg < {math.degrees(error):.3f} deg"
        for name, value, error in (
            ("U", m.tilt_U_rad, se.tilt_U_rad),
            ("V", m.tilt_V_rad, se.tilt_V_rad),
        )
        if math.isfinite(error) and abs(value) < error
    ]
    if not hidden:
        return None
    return (
        f"tilt not identified: {', '.join(hidden)} (its standard error); these poses and "
        "readings cannot tell the tilt from a level base"
    )


def _render_extensions(result: Calibration, console: Console, *, unapplied_map: bool) -> None:
    """The bias drift's rates, the sensor map (``unapplied_map``: also one the data do not
    support) and the mount's angles, each ± its standard error."""
    drift, mount = result.bias_drift, result.mount
    if isinstance(drift, StochasticBiasDrift):
        std = drift.offset_std(np.array([drift.t_max_s + 600.0]))[0]
        console.print(
            f"Bias drift (stochastic, Matérn 3/2, t = {drift.t_min_s:.6g} .. {drift.t_max_s:.6g} "
            f"s; F0, M0 above are the bias at t = {drift.t_max_s:.6g} s): time constant "
            f"{drift.time_constant_s:.4g} s, wander "
            + ", ".join(f"{v:.4g}" for v in drift.scale)
            + " N|N·m per axis; inside the range the smoothed bias, after it the last estimate "
            f"held (10 min later its standard error is {np.max(std[:3]):.3g} N, "
            f"{np.max(std[3:]):.3g} N·m)"
        )
    elif isinstance(drift, TemperatureBiasDrift):
        table = Table(
            title=f"Bias temperature slopes (T = {drift.T_min_C:.4g} .. {drift.T_max_C:.4g} "
            f"degC; F0, M0 above are the bias at T = {drift.T_ref_C:.4g} degC; held at the "
            "nearer end outside that range)"
        )
        table.add_column("coefficient")
        for col in WRENCH_COLUMNS:
            table.add_column(col, justify="right")
        table.add_row(
            "per degC",
            *(
                _pm(v, e, 1.0, 4 if j < 3 else 5)
                for j, (v, e) in enumerate(zip(drift.slopes, drift.std_errors, strict=True))
            ),
        )
        console.print(table)
    elif drift is not None:
        table = Table(
            title=f"Bias drift ({drift.name}, t = {drift.t_min_s:.6g} .. {drift.t_max_s:.6g} s; "
            f"F0, M0 above are the bias at t = {drift.t_ref_s:.6g} s)"
        )
        table.add_column("coefficient")
        for col in WRENCH_COLUMNS:
            table.add_column(col, justify="right")
        for k in range(drift.order):
            unit = "per min" if k == 0 else "per min²"
            scale = 60.0 ** (k + 1)
            table.add_row(
                f"rate {unit}" if k == 0 else f"curvature {unit}",
                *(
                    _pm(v, e, scale, 4 if j < 3 else 5)
                    for j, (v, e) in enumerate(
                        zip(drift.coefficients[k], drift.std_errors[k], strict=True)
                    )
                ),
            )
        console.print(table)
    if result.sensor_map is not None and (result.sensor_map.applied or unapplied_map):
        table = Table(title="Linear sensor map delta (force rows: fraction; torque rows: mm)")
        table.add_column("row")
        for col in ("x", "y", "z"):
            table.add_column(col, justify="right")
        for j, name in enumerate(WRENCH_COLUMNS):
            scale = 1.0 if j < 3 else 1000.0
            cells = zip(result.sensor_map.delta[j], result.sensor_map.std_errors[j], strict=True)
            table.add_row(name, *(_pm(v, e, scale, 4) for v, e in cells))
        console.print(table)
    if mount is not None:
        angles = ", ".join(
            _pm(v, e, math.degrees(1), 3)
            for v, e in zip(mount.angles_rad, mount.std_errors_rad, strict=True)
        )
        what = "yaw about the recorded frame's z" if mount.axes == "yaw" else "rotation vector"
        console.print(f"sensor mount ({what}): {angles} deg")


def _pm(value: float, se: float, scale: float = 1.0, digits: int = 4) -> str:
    se_text = f"{se * scale:.{digits}f}" if math.isfinite(se) else "?"
    return f"{value * scale:+.{digits}f} ± {se_text}"


def _residual_cell(residual: float, relative_percent: float) -> str:
    if math.isfinite(relative_percent):
        return f"{residual:+.4f} ({relative_percent:.2f})"
    return f"{residual:+.4f}"


def console() -> Console:
    """A console 120 columns wide when the output is not a terminal (files, pipes, CI logs)."""
    return Console() if sys.stdout.isatty() else Console(width=120)


#: Poses listed in the per-pose table; beyond it, the worst by residual (the file has them all).
MAX_POSES_SHOWN = 50


def _worst_poses(result: Calibration, n: int) -> list[int]:
    """Indices of the poses to list: all of them up to ``n``, else the ``n`` with the largest
    residuals (force and torque residuals each scaled by their RMS), in pose order."""
    count = len(result.pose_ids)
    if count <= n:
        return list(range(count))
    r = result.residuals
    force_rms, torque_rms = result.residual_rms
    score = np.linalg.norm(r[:, :3], axis=1) / max(force_rms, 1e-300) + np.linalg.norm(
        r[:, 3:], axis=1
    ) / max(torque_rms, 1e-300)
    return sorted(np.argsort(score)[-n:].tolist())


def render_calibration(
    result: Calibration, console: Console, *, unapplied_map: bool = True
) -> None:
    """Print the parameters ± standard error, per-pose residuals, Table 3 and warnings
    (``unapplied_map``: the sensor map's table even where the data do not support it)."""
    m, se = result.model, result.std_errors
    params = Table(title=f"Calibration ({result.method} method, {len(result.pose_ids)} poses)")
    for col in ("parameter", "x", "y", "z", "unit"):
        params.add_column(col, justify="left" if col in ("parameter", "unit") else "right")
    params.add_row("tool weight G", _pm(m.weight_N, se.weight_N), "", "", "N")
    params.add_row(
        "base tilt U, V",
        _pm(m.tilt_U_rad, se.tilt_U_rad, math.degrees(1)),
        _pm(m.tilt_V_rad, se.tilt_V_rad, math.degrees(1)),
        "",
        "deg",
    )
    for label, vec, err, unit in (
        ("force bias F0", m.force_bias_N, se.force_bias_N, "N"),
        ("torque bias M0", m.torque_bias_Nm, se.torque_bias_Nm, "N·m"),
    ):
        params.add_row(label, *(_pm(v, e) for v, e in zip(vec, err, strict=True)), unit)
    cog, cog_se = m.center_of_gravity_m, se.center_of_gravity_m
    params.add_row(
        "centre of gravity P",
        *(_pm(v, e, 1000.0, 2) for v, e in zip(cog, cog_se, strict=True)),
        "mm",
    )
    console.print(params)
    _render_extensions(result, console, unapplied_map=unapplied_map)

    n_poses = len(result.pose_ids)
    shown = _worst_poses(result, MAX_POSES_SHOWN)
    title = "Per-pose residuals (measured − model) and Table-3 relative errors [%]"
    if len(shown) < n_poses:
        title += f": the {len(shown)} worst of {n_poses} poses (all in the calibration file)"
    poses = Table(title=title)
    poses.add_column("pose")
    for col in WRENCH_COLUMNS:
        poses.add_column(col, justify="right")
    for k in shown:
        poses.add_row(
            result.pose_ids[k],
            *(
                _residual_cell(r, p)
                for r, p in zip(result.residuals[k], result.relative_error_percent[k], strict=True)
            ),
        )
    poses.add_row(
        "mean δ",
        *(f"{v:.2f}" for v in result.relative_error_mean_percent),
        style="bold",
    )
    console.print(poses)
    force_rms, torque_rms = result.residual_rms
    loo_force, loo_torque = result.loo_rms
    if math.isfinite(loo_force) and math.isfinite(loo_torque):
        loo = f"force {loo_force:.4f} N, torque {loo_torque:.5f} N·m"
    else:
        loo = f"needs at least 4 poses ({len(result.pose_ids)} given)"
    console.print(
        f"residual RMS: force {force_rms:.4f} N, torque {torque_rms:.5f} N·m; "
        f"leave-one-pose-out RMS: {loo}; "
        f"regressor condition number {result.condition_number:.2f}"
    )
    hidden = tilt_not_identified(result)
    if hidden is not None:
        console.print(f"[bold yellow]{hidden}[/bold yellow]")
