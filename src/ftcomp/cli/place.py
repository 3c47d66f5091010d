"""``ftcomp sim place``: set a grasped load down on the simulated sponge or book (paper 2.2.2).

The compensation uses an *identified* calibration: the one given with ``-c``, or else one
identified on the same simulated cell first (the empty gripper at the paper's nine poses).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from ftcomp.cli.common import warn_live_drift
from ftcomp.cli.options import add_field_option, map_field
from ftcomp.errors import ParameterError
from ftcomp.session.placement import DEFAULT_GAINS, PlacementConfig

__all__ = ["register"]

#: Readings per pose when ``sim place`` identifies the tool itself.
IDENTIFY_SAMPLES_PER_POSE = 200


def register(p: argparse.ArgumentParser) -> None:
    """Add the ``place`` command's arguments to its parser."""
    gains = "; ".join(
        f"{surface} k13 = {k1 * 1e3:g} mm/N, k23 = {k2 * 1e3:g} mm/(s*N)"
        for surface, (k1, k2) in DEFAULT_GAINS.items()
    )
    default = PlacementConfig("admittance")
    p.description = (
        "Set a grasped load down on the simulated sponge or book. 'admittance' is the paper's "
        "combined law (Eq. 27), dV = k13 d(dF)/dt + k23 dF along the base's z axis, on the "
        "gravity-compensated force with desired force 0; default gains per surface: "
        f"{gains}. The run counts as placed when the force it senses along gravity, filtered "
        f"at {default.decision_cutoff_hz:g} Hz, stays within +-{default.band_N:g} N for "
        f"{default.settle_time_s:g} s (position: when the descent reaches "
        f"{default.position_depth_m * 1e3:g} mm below the surface's top); the gripper then "
        "opens. The verdict comes from the true contact force: placed gently (the surface "
        f"carries the load's weight within +-{default.gentle_press_N:g} N), pressed, released "
        "early, or stopped (a safety limit or the "
        f"{default.max_duration_s:g} s time-out ended the run: exit code 1). Writes "
        "timeseries.csv, metrics.json, placement.png and the calibration used into --out."
    )
    p.add_argument(
        "--surface",
        choices=tuple(DEFAULT_GAINS),
        required=True,
        help="sponge: a 1500 N/m spring pad; book: a stiff block (required)",
    )
    add_field_option(
        p,
        PlacementConfig,
        "control",
        required=True,
        help="position: constant-speed descent to a fixed depth, no force feedback (Fig. 6); "
        "admittance: the combined law above (Fig. 7)",
    )
    p.add_argument(
        "-c",
        "--calibration",
        metavar="CALIBRATION.json",
        help="the calibration to compensate with (default: identify the tool on the same "
        f"simulated cell first, {IDENTIFY_SAMPLES_PER_POSE} readings at each of the paper's "
        "9 poses)",
    )
    p.add_argument(
        "--no-compensation",
        action="store_true",
        help="control on raw readings, bias and tool weight left in (Fig. 7) "
        "(default: compensated)",
    )
    for name, field, unit in (("k1", "k1_m_per_N", "mm/N"), ("k2", "k2_m_per_s_N", "mm/(s*N)")):
        add_field_option(
            p,
            PlacementConfig,
            field,
            f"--{name}",
            scale=1e-3,
            unit=unit,
            default=None,
            none_means="per surface, see above; not with --control position",
            help=f"admittance {name}3",
            metavar=unit.upper().replace("/", "_PER_").replace("(S*N)", "S_N"),
        )
    p.add_argument("--load-kg", type=float, default=0.5, help="the load's mass [kg] (default: 0.5)")
    p.add_argument("--seed", type=int, default=0, help="sensor-noise seed (default: 0)")
    p.add_argument(
        "--out", required=True, metavar="DIR", help="output folder for the run's files (required)"
    )
    p.add_argument(
        "--log",
        metavar="RUN.mcap",
        help="also log every cycle as MCAP (ROS 2 profile: raw and compensated WrenchStamped, "
        "/tf, the wrench error, commanded twist, the end as an event) for rosbags, Foxglove, "
        "Lichtblick (default: no log)",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="write into an --out folder that already holds files (default: refuse)",
    )
    for field, flag in (("seed", "--seed"), ("load_kg", "--load-kg"), ("surface", "--surface")):
        map_field(p, field, flag)
    p.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    from ftcomp.io.atomic import prepare_output_dir
    from ftcomp.io.calibration_json import load_calibration, save_calibration
    from ftcomp.session.placement import run_placement, write_placement_outputs
    from ftcomp.sim.placement_cell import SimPlacementCell
    from ftcomp.views.figures import plot_placement

    if args.control == "position" and (args.k1 is not None or args.k2 is not None):
        raise ParameterError(
            "--k1/--k2 are admittance gains; --control position descends without force "
            "feedback and would ignore them"
        )
    k1_default, k2_default = DEFAULT_GAINS[args.surface]
    k1_m = k1_default if args.k1 is None else args.k1 * 1e-3
    k2_m = k2_default if args.k2 is None else args.k2 * 1e-3
    config = PlacementConfig(
        args.control,
        compensation=not args.no_compensation,
        k1_m_per_N=k1_m,
        k2_m_per_s_N=k2_m,
    )
    inputs = [args.calibration] if args.calibration is not None else []
    # Checked now, made once every input has been accepted (a bad --load-kg or calibration
    # leaves no folder behind).
    prepare_output_dir(args.out, overwrite=args.force, inputs=inputs, create=False)
    given = load_calibration(args.calibration) if args.calibration is not None else None
    if given is not None:
        warn_live_drift(given, args.calibration)
    cell = SimPlacementCell(
        args.surface,
        args.load_kg,
        seed=args.seed,
        identify_samples_per_pose=None if given is not None else IDENTIFY_SAMPLES_PER_POSE,
    )
    prepare_output_dir(args.out, overwrite=args.force, inputs=inputs)
    calibration = given if given is not None else cell.identified
    assert calibration is not None  # identified on the cell when none was given
    model = calibration.model
    source = args.calibration if given is not None else "identified on this cell"
    print(
        f"calibration ({source}): G {model.weight_N:.4f} N, "
        f"U {math.degrees(model.tilt_U_rad):+.3f} deg, V {math.degrees(model.tilt_V_rad):+.3f} deg"
    )
    if args.log is None:
        result = run_placement(cell, model, config)
    else:
        from ftcomp.ros2.mcap_log import SessionMcapLog

        with SessionMcapLog(args.log, overwrite=args.force) as log:
            result = run_placement(cell, model, config, observers=[log])
        print(f"wrote {args.log} ({sum(log.counts.values())} messages)")
    title = f"{args.control} on {args.surface}" + (
        ", no compensation" if args.no_compensation else ""
    )
    paths = write_placement_outputs(result, args.out)
    plot_placement([result], Path(args.out) / "placement.png", title=title)
    save_calibration(paths["csv"].parent / "calibration_used.json", calibration)
    m = result.metrics
    print(
        f"{title}: {m['stop_reason']}, sensed final force {m['final_force_N']:+.3f} N, "
        f"peak press {m['peak_press_N']:.3f} N, descent {m['descent_mm']:.2f} mm"
    )
    print(f"verdict (true contact): {m['verdict']}: {m['verdict_reason']}")
    print(f"wrote {paths['csv'].parent}")
    if m["verdict"] == "stopped":
        print(f"error: placement failed: {m['verdict_reason']}", file=sys.stderr)
        return 1
    return 0
