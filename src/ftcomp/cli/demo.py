"""``ftcomp demo [--out DIR] [--quick] [--seed N]``: the whole paper on the simulated cell."""

from __future__ import annotations

import argparse
import sys
import time

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

__all__ = ["register", "run"]


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
        help="a shorter run, a little over half the full demo's 70 s on a 2-core machine "
        "(fewer readings, shorter sweeps; README)",
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
    from ftcomp.huang2020.demo import prepare_output, run_demo
    from ftcomp.huang2020.settings import DemoSettings
    from ftcomp.huang2020.terminal import summary_table, verdict_table

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

        result = run_demo(args.out, settings, advance, overwrite=True)
    out = Console() if sys.stdout.isatty() else Console(width=120)
    out.print(summary_table(result))
    out.print(verdict_table(result))
    out.print(
        f"report: [bold]{args.out}/report.html[/bold]  ({time.perf_counter() - started:.1f} s)"
    )
    return 0
