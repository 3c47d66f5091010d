"""``ftcomp demo [--out DIR] [--quick] [--seed N]``: the whole paper on the simulated cell."""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from ftcomp import paper
from ftcomp.errors import ParameterError
from ftcomp.experiments.demo import DemoSettings, prepare_output, run_demo

__all__ = ["register", "summary_table"]


def register(parser: argparse.ArgumentParser) -> None:
    """Add the ``demo`` command's arguments to its parser."""
    parser.description = (
        "Run every experiment of Huang et al. 2020 on the simulated MuJoCo cell "
        "and write report.html, figures, metrics.json and every run's CSV."
    )
    parser.add_argument(
        "--out", default="ftcomp-demo", help="output folder (default: ./ftcomp-demo)"
    )
    parser.add_argument(
        "--quick", action="store_true", help="a shorter run (fewer readings, shorter sweeps)"
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="seed of every simulated sensor's noise"
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="write into an --out folder that already holds files (an earlier demo's are replaced)",
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Run the demo with a progress bar, then print the summary table."""
    if args.seed < 0:
        raise ParameterError(f"--seed must be >= 0, got {args.seed}")
    settings = DemoSettings.quick(args.seed) if args.quick else DemoSettings.full(args.seed)
    prepare_output(args.out, overwrite=args.force)  # before the progress bar: fail fast
    console = Console(stderr=True)
    started = time.perf_counter()
    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeElapsedColumn(),
        console=console,
        transient=not sys.stderr.isatty(),
    ) as progress:
        task = progress.add_task("ftcomp demo", total=settings.steps)

        def advance(label: str) -> None:
            progress.update(task, advance=1, description=label)

        metrics = run_demo(args.out, settings, advance, overwrite=True)
    out = Console() if sys.stdout.isatty() else Console(width=120)
    out.print(summary_table(metrics))
    out.print(
        f"report: [bold]{args.out}/report.html[/bold]  ({time.perf_counter() - started:.1f} s)"
    )
    return 0


def _f(value: Any, digits: int = 3) -> str:
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, (int, float)):
        return f"{value:.{digits}f}"
    if isinstance(value, list):
        return "(" + ", ".join(f"{v:.{digits}f}" for v in value) + ")"
    return "-" if value is None else str(value)


def summary_table(metrics: dict[str, Any]) -> Table:
    """Our numbers beside the paper's, one row per published quantity."""
    table = Table(title="ftcomp demo: ours beside the paper's")
    for col in ("quantity", "paper", "ftcomp", "note"):
        table.add_column(col)
    cal = metrics["calibration"]
    data, sim, pub = cal["paper_data"], cal["simulation"]["joint"], metrics["table3"]["published"]
    truth = cal["simulation_truth"]
    pub_cal = paper.PUBLISHED
    table.add_row(
        "tool weight G [N]",
        _f(pub_cal["tool_weight_N"]),
        _f(data["tool_weight_N"]),
        "paper's data, paper method",
    )
    table.add_row(
        "",
        "",
        _f(sim["tool_weight_N"]),
        f"simulation, joint method (true {truth['tool_weight_N']:.3f})",
    )
    table.add_row(
        "base tilt U, V [deg]",
        f"{pub_cal['base_tilt_deg']['U']}, {pub_cal['base_tilt_deg']['V']}",
        f"{data['base_tilt_deg']['U']:.3f}, {data['base_tilt_deg']['V']:.3f}",
        "paper's data",
    )
    table.add_row(
        "F0 [N]", _f(pub_cal["force_bias_N"], 4), _f(data["force_bias_N"], 4), "paper's data"
    )
    table.add_row(
        "M0 [N·m]", _f(pub_cal["torque_bias_Nm"], 4), _f(data["torque_bias_Nm"], 4), "paper's data"
    )
    table.add_row(
        "P [m]",
        _f(pub_cal["center_of_gravity_m"], 4),
        _f(data["center_of_gravity_m"], 4),
        "paper's data",
    )
    bare = cal["no_gripper"]
    table.add_row(
        "sensing end weight [N]",
        _f(bare["published_N"]),
        _f(bare["identified_sensing_end_weight_N"]),
        "simulation, no gripper",
    )
    table.add_row(
        "Table 3 mean δ [%]",
        _f(pub["mean"], 2),
        _f(metrics["table3"]["paper_data"]["mean"], 2),
        "paper's data",
    )
    t4 = metrics["table4"]
    table.add_row(
        "Table 4 δc [%]",
        _f(t4["published"]["relative_error_percent"], 2),
        _f(t4["relative_error_percent"], 2),
        "simulated loads",
    )
    place = metrics["placement"]
    for surface in ("sponge", "book"):
        table.add_row(
            f"position-only final force, {surface} [N]",
            _f(place["published"]["position_only_final_force_N"][surface]),
            _f(place[f"position_{surface}"].get("final_force_N")),
            f"peak press {_f(place[f'position_{surface}'].get('peak_press_N'))} N",
        )
    for surface in ("sponge", "book"):
        run = place[f"admittance_{surface}"]
        table.add_row(
            f"admittance placed, {surface}",
            f"within ±{place['published']['stop_band_N']} N",
            f"{_f(run.get('placed'))}, final {_f(run.get('final_force_N'))} N",
            f"peak press {_f(run.get('peak_press_N'))} N, "
            f"settle {_f(run.get('settle_time_s'), 2)} s",
        )
    unc, comp = place["admittance_uncompensated_sponge"], place["admittance_sponge"]
    table.add_row(
        "without compensation (sponge)",
        "decision wrong, too deep",
        f"descent {_f(unc.get('descent_mm'), 2)} mm vs {_f(comp.get('descent_mm'), 2)} mm",
        f"ended by {unc.get('stop_reason')}, peak press {_f(unc.get('peak_press_N'))} N",
    )
    return table
