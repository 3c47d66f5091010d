"""``ftcomp demo [--out DIR] [--quick] [--seed N]``: the whole paper on the simulated cell."""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from ftcomp.errors import ParameterError
from ftcomp.experiments.demo import DemoSettings, prepare_output, run_demo

__all__ = ["register", "summary_table", "verdict_table"]


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
        "--quick",
        action="store_true",
        help="a shorter run, about 20 s instead of 35 s (fewer readings, shorter sweeps)",
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="seed of every simulated sensor's noise (default: 0)"
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
    out.print(verdict_table(metrics))
    out.print(
        f"report: [bold]{args.out}/report.html[/bold]  ({time.perf_counter() - started:.1f} s)"
    )
    return 0


def summary_table(metrics: dict[str, Any]) -> Table:
    """Every published result beside ours, judged, with the reason where they differ."""
    table = Table(title="ftcomp demo: the paper's results beside ours", show_lines=True)
    for col, ratio in (("quantity", 3), ("paper", 3), ("ftcomp", 4), ("", 1), ("why", 6)):
        table.add_column(col, ratio=ratio)
    for row in metrics["comparisons"]:
        mark = "[green]✓[/green]" if row["reproduced"] else "[bold red]✗[/bold red]"
        note = row["note"] if row["reproduced"] else f"[red]not reproduced[/red]: {row['note']}"
        table.add_row(
            escape(row["quantity"]), escape(row["paper"]), escape(row["ours"]), mark, note
        )
    return table


def verdict_table(metrics: dict[str, Any]) -> Table:
    """Every placement run's verdict, from the true contact force."""
    table = Table(title="placement runs, judged from the true contact force")
    for col in ("run", "verdict", "true press [N]", "sensed final force [N]", "ended by"):
        table.add_column(col, justify="left" if col in ("run", "verdict", "ended by") else "right")
    place = metrics["placement"]
    for name, run in place.items():
        if not isinstance(run, dict) or "verdict" not in run:
            continue
        style = "green" if run["verdict"] == "placed gently" else "bold red"
        table.add_row(
            name,
            f"[{style}]{run['verdict']}[/{style}]",
            f"{run['true_press_N']:+.3f}",
            f"{run['final_force_N']:+.3f}",
            str(run["stop_reason"]).replace("_", " "),
        )
    return table
