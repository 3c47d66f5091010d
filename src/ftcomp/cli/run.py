"""``ftcomp run``: the live compliant loop on a robot, with the identified calibration.

``ftcomp run --robot URI --sensor URI -c calibration.json --control admittance [--law ...]
[--axes z --frame base] [--dry-run] -o run.csv``

Each cycle: read, compensate (bias and tool gravity of the calibration), the admittance law on
the selected axes (the paper's combined law ΔV = S (K1 dΔF/dt + K2 ΔF), its position or
velocity form, or mass-damper-spring), the safety envelope (speed, acceleration, travel, force
and torque limits, a sample watchdog), then the twist to the robot. ``--dry-run`` computes and
logs every command and sends none. The run ends after ``--seconds``, or once the selected force
error has stayed within ``--settle-band-N`` (e.g. a load set down), with exit 0. A protective
stop, a sensor fault, a lost connection or a loop that keeps missing its period stops the robot
at once and exits 1 with the reason; Ctrl-C stops the robot first and exits 130.

``--online-load`` also weighs what the gripper grasps during the run and, once the estimate has
converged, compensates it like the tool, so that after a grasp the controller sees only contact
forces. The estimator runs once per cycle (its rate is 1 / the robot's control period); the log
gains the load columns of ``ftcomp stream --online-load`` and the end lists the events. Start
with the gripper empty: a load held from the start is no step and counts as contact.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from ftcomp.cli.common import (
    add_accelerometer_argument,
    add_rebias_argument,
    add_track_bias_argument,
    check_rebias_argument,
    live_end_lines,
    warn_live_drift,
)
from ftcomp.cli.hardware_options import add_hardware_arguments, open_hardware
from ftcomp.cli.live_status import add_view_arguments
from ftcomp.cli.options import add_field_option, map_field
from ftcomp.control.safety import UniformLimits
from ftcomp.session.compliant import SettleRule
from ftcomp.session.interrupts import InterruptHold
from ftcomp.session.run import (
    FILTER_HZ,
    FILTER_SHARE_OF_RATE,
    INTEGRAL_FILTER_HZ,
    STALE_SENSOR_PERIODS,
    AdmittanceConfig,
    RunConfig,
    RunResult,
)

if TYPE_CHECKING:
    from ftcomp.calibration_record import Calibration

__all__ = ["register", "run"]


#: Help that says more than the field's own (what run adds to the rule).
_HELP = {
    "stale_after_s": f"a reading older than this, and than {STALE_SENSOR_PERIODS} of a slower "
    "sensor's periods, stops",
}


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``run`` command's arguments to its parser."""
    parser.description = __doc__.split("\n\n", 1)[1].replace("``", "") if __doc__ else None
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    add_hardware_arguments(parser, robot_required=True)
    p = parser.add_argument
    p(
        "-c",
        "--calibration",
        required=True,
        metavar="CALIBRATION.json",
        help="from ftcomp calibrate",
    )
    p("--control", choices=("admittance",), required=True, help="the controller")
    p(
        "--online-load",
        action="store_true",
        help="weigh a grasped load online (rate: 1 / the robot's control period [Hz]) and "
        "compensate it too (default: off, the tool alone)",
    )
    add_accelerometer_argument(parser)
    add_track_bias_argument(parser)
    add_rebias_argument(parser)
    map_field(parser, "online_load", "--online-load")
    map_field(parser, "accelerometer", "--accelerometer")
    map_field(parser, "track_bias", "--track-bias")
    add_field_option(parser, AdmittanceConfig, "law")
    add_field_option(parser, AdmittanceConfig, "axes")
    add_field_option(parser, AdmittanceConfig, "frame", help="frame of --axes and the gains")
    mm, deg = 1e-3, math.radians(1.0)
    for name, unit, metavar in (("k1", "{}/N", "{}_PER_N"), ("k2", "{}/(s*N)", "{}_PER_S_N")):
        add_field_option(
            parser,
            AdmittanceConfig,
            name,
            scale=mm,
            unit=unit.format("mm"),
            element=0,
            help=f"{name.upper()} on x, y, z",
            metavar=metavar.format("MM"),
        )
        add_field_option(
            parser,
            AdmittanceConfig,
            name,
            f"--{name}-rot",
            scale=deg,
            unit=unit.format("deg").replace("N)", "N*m)").replace("/N", "/(N*m)"),
            element=3,
            help=f"{name.upper()} on rotations",
            metavar=metavar.format("DEG").replace("_N", "_NM"),
        )
    add_field_option(parser, AdmittanceConfig, "mass", "--mass-kg", element=0)
    add_field_option(parser, AdmittanceConfig, "damping", element=0, metavar="N_S_PER_M")
    add_field_option(parser, AdmittanceConfig, "stiffness", element=0, metavar="N_PER_M")
    add_field_option(
        parser,
        AdmittanceConfig,
        "wrench_desired",
        type=lambda s: [float(v) for v in s.split(",")],
        metavar="FX,FY,FZ,TX,TY,TZ",
    )
    add_field_option(
        parser,
        AdmittanceConfig,
        "filter_hz",
        none_means=f"{FILTER_HZ:g}, or a slower sensor's rate / {1 / FILTER_SHARE_OF_RATE:g}; "
        f"{INTEGRAL_FILTER_HZ:g} with no K1 on an axis that yields",
    )
    for field, flag, scale, unit in (
        ("max_speed_m_s", "--max-speed-mm-s", mm, "mm/s"),
        ("max_accel_m_s2", "--max-accel-mm-s2", mm, "mm/s^2"),
        ("max_travel_m", "--max-travel-mm", mm, "mm"),
        ("max_rotation_rad", "--max-rotation-deg", deg, "deg"),
        ("max_force_N", "--max-force-N", 1.0, "N"),
        ("max_torque_Nm", "--max-torque-Nm", 1.0, "N*m"),
        ("stale_after_s", "--stale-ms", mm, "ms"),
    ):
        add_field_option(
            parser, UniformLimits, field, flag, scale=scale, unit=unit, help=_HELP.get(field)
        )
    add_field_option(
        parser,
        UniformLimits,
        "max_identical_samples",
        off=0,
        metavar="N",
        help="new readings identical to the last that stop as a frozen sensor, beyond N "
        "(off for a noiseless simulation; docs/control.md)",
    )
    add_field_option(parser, RunConfig, "max_late_cycles")
    add_field_option(parser, RunConfig, "duration_s", "--seconds")
    add_field_option(parser, SettleRule, "band_N", "--settle-band-N", none_means="run --seconds")
    add_field_option(parser, SettleRule, "hold_s", "--settle-s")
    add_field_option(parser, SettleRule, "then_hold_s", "--settle-then-s")
    p("--dry-run", action="store_true", help="compute and log commands, send none")
    p("-o", "--output", required=True, metavar="RUN.csv", help="the log, one row per cycle")
    p("--force", action="store_true", help="replace an existing output file")
    add_view_arguments(parser)
    parser.set_defaults(handler=run)


def _check(args: argparse.Namespace) -> None:
    check_rebias_argument(args)


def _config(args: argparse.Namespace) -> RunConfig:
    """The run's configuration from the arguments, in SI units."""

    from ftcomp.compensation.bias_tracking import BiasTrackingConfig

    limits = UniformLimits(
        max_speed_m_s=args.max_speed_mm_s * 1e-3,
        max_accel_m_s2=args.max_accel_mm_s2 * 1e-3,
        max_travel_m=args.max_travel_mm * 1e-3,
        max_rotation_rad=math.radians(args.max_rotation_deg),
        max_force_N=args.max_force_N,
        max_torque_Nm=args.max_torque_Nm,
        stale_after_s=args.stale_ms * 1e-3,
        max_identical_samples=args.max_identical_samples or None,
    ).safety_limits()
    admittance = AdmittanceConfig(
        limits,
        law=args.law,
        axes=args.axes,
        frame=args.frame,
        k1=(args.k1 * 1e-3,) * 3 + (math.radians(args.k1_rot),) * 3,
        k2=(args.k2 * 1e-3,) * 3 + (math.radians(args.k2_rot),) * 3,
        mass=(args.mass_kg,) * 6,
        damping=(args.damping,) * 6,
        stiffness=(args.stiffness,) * 6,
        wrench_desired=tuple(args.wrench_desired),
        filter_hz=args.filter_hz,
    )
    settle = (
        SettleRule(args.settle_band_N, args.settle_s, then_hold_s=args.settle_then_s)
        if args.settle_band_N
        else None
    )
    return RunConfig(
        admittance,
        duration_s=args.seconds,
        settle=settle,
        dry_run=args.dry_run,
        max_late_cycles=args.max_late_cycles,
        online_load=args.online_load,
        track_bias=BiasTrackingConfig() if args.track_bias else None,
        accelerometer=args.accelerometer,
    )


def run(args: argparse.Namespace) -> int:
    """Open, run, report."""
    from ftcomp.io.atomic import check_writable
    from ftcomp.io.calibration_json import load_calibration
    from ftcomp.session.online_load import event_lines

    _check(args)
    config = _config(args)
    output = check_writable(args.output, overwrite=args.force, inputs=[args.calibration])
    if args.log is not None:
        check_writable(args.log, overwrite=args.force, inputs=[args.calibration, args.output])
    calibration = load_calibration(args.calibration)
    if args.rebias_s is None:  # a re-bias drops the drift model
        warn_live_drift(calibration, args.calibration, tracking=args.track_bias)
    # Ctrl-C held from before the hardware opens until it is closed (the robot stopped): the
    # session's own hold ends with the loop, and a second Ctrl-C while the robot was being
    # stopped and disconnected cut that short, with no summary (issue 34's trial).
    with InterruptHold() as hold:
        hold.what = f"stopping the robot and finishing {output}"
        try:
            result = _run_session(args, calibration, config, output, hold)
        except KeyboardInterrupt:
            print(
                "error: interrupted (Ctrl-C) before the loop started; the robot was stopped",
                file=sys.stderr,
            )
            return 130
    summary = (
        f"{result.cycles} cycles in {result.duration_s:.2f} s, wrench filter "
        f"{result.filter_hz:.3g} Hz, stale after {result.stale_after_s * 1e3:.3g} ms, "
        f"log {output}"
    )
    if args.log is not None:
        summary += f", MCAP {args.log}"
    if result.cycles:
        t, e, window_s = result.travel_m * 1e3, result.final_error, config.final_error_window_s
        summary += (
            f"; travel [{t[0]:+.2f} {t[1]:+.2f} {t[2]:+.2f}] mm, "
            f"mean force error over the last {window_s:g} s "
            f"[{e[0]:+.3f} {e[1]:+.3f} {e[2]:+.3f}] N ({args.frame} frame)"
        )
    for line in live_end_lines(result):
        print(line)
    if config.online_load:
        print(f"online load: rate {1.0 / result.period_s:.1f} Hz (1 / the robot's control period)")
        print("\n".join(event_lines(list(result.load_events))))
    if result.faulted:
        code = 130 if result.outcome == "interrupted" else 1
        print(f"error: {result.message}; the robot was stopped; {summary}", file=sys.stderr)
        return code
    print(f"{result.outcome}: {summary}")
    return 0


def _run_session(
    args: argparse.Namespace,
    calibration: Calibration,
    config: RunConfig,
    output: Path,
    hold: InterruptHold,
) -> RunResult:
    """Open the hardware, run the loop, close the hardware (the robot stopped); Ctrl-C held
    by ``hold`` once the loop has ended."""
    from ftcomp.session.rebias_live import rebias_still
    from ftcomp.session.run import run_compliant
    from ftcomp.views.live import session_observers

    with (
        session_observers(
            args.log, args.view, overwrite=args.force, control_frame=args.frame
        ) as observers,
        open_hardware(args) as (robot, sensor, mount),
    ):
        if args.rebias_s is not None:
            rebiased = rebias_still(robot, sensor, calibration, args.rebias_s, mount=mount)
            print(rebiased.line(), flush=True)
            calibration = rebiased.calibration
        print(
            f"{'dry run' if args.dry_run else 'running'}: {args.law} admittance on "
            f"{args.axes} ({args.frame} frame), calibration {args.calibration}",
            flush=True,
        )
        result = run_compliant(
            robot,
            sensor,
            calibration,
            config,
            output,
            mount=mount,
            source=args.calibration,
            observers=observers,
        )
        hold.finishing(f"stopping the robot and finishing {output}")
    return result
