"""The still-segment options shared by ``import-bag`` and ``calibrate --still-segments``: the
thresholds of :class:`ftcomp.calibration.still.StillConfig`, and the table of segments found."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rich.console import Console

    from ftcomp.calibration.still import Segment, StillConfig

__all__ = ["add_still_arguments", "print_segments", "still_config"]


def add_still_arguments(parser: argparse.ArgumentParser) -> None:
    """The still-segment thresholds as options (``import-bag``, ``calibrate --still-segments``)."""
    from ftcomp.calibration.still import StillConfig

    d = StillConfig()
    still = parser.add_argument_group("still segments")
    for flag, metavar, default, text in (
        ("--still-angle-deg", "DEG", d.angle_deg, "orientation stays within this of the "
         "segment's first [deg]"),
        ("--still-min-s", "S", d.min_duration_s, "shortest segment [s]"),
        ("--still-window-s", "S", d.window_s, "moving-mean window of the settled test [s]"),
        ("--still-force-N", "N", d.force_N, "settled: moving mean within this of the "
         "segment's [N]"),
        ("--still-torque-Nm", "NM", d.torque_Nm, "settled: ... [N*m]"),
    ):  # fmt: skip
        still.add_argument(
            flag, type=float, metavar=metavar, default=default, help=f"{text} ({default:g})"
        )


def still_config(args: argparse.Namespace) -> StillConfig:
    """The thresholds the options give."""
    from ftcomp.calibration.still import StillConfig

    return StillConfig(
        angle_deg=args.still_angle_deg,
        min_duration_s=args.still_min_s,
        window_s=args.still_window_s,
        force_N=args.still_force_N,
        torque_Nm=args.still_torque_Nm,
    )


def print_segments(
    out: Console, title: str, segments: Sequence[Segment], t0_ns: int, config: StillConfig
) -> None:
    """The thresholds, then one row per segment: its pose id, start, length, orientation and
    wrench scatter."""
    from rich.table import Table
    from scipy.spatial.transform import Rotation

    from ftcomp.frames import encode_orientation

    out.print(f"still: {config.describe()}")
    table = Table(title=title)
    for col in ("pose", "start [s]", "duration [s]", "readings", "alpha, beta, gamma [deg]"):
        table.add_column(col, justify="left" if col == "pose" else "right")
    table.add_column("force std [N]", justify="right")
    table.add_column("torque std [N·m]", justify="right")
    for k, seg in enumerate(segments, start=1):
        angles = encode_orientation(Rotation.from_matrix(seg.R_base_sensor), "paper_euler")
        table.add_row(
            str(k),
            f"{(seg.t_start_ns - t0_ns) / 1e9:.3f}",
            f"{seg.duration_s:.3f}",
            str(seg.readings),
            ", ".join(f"{a:+.2f}" for a in angles),
            " ".join(f"{v:.3f}" for v in seg.wrench_std[:3]),
            " ".join(f"{v:.4f}" for v in seg.wrench_std[3:]),
        )
    out.print(table)
