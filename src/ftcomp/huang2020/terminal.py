"""The demo's results for the terminal: the paper beside ours, and every placement's verdict."""

from __future__ import annotations

from rich.markup import escape
from rich.table import Table

from ftcomp.huang2020.demo import DemoResult

__all__ = ["summary_table", "verdict_table"]


def summary_table(result: DemoResult) -> Table:
    """Every published result beside ours, judged, with the reason where they differ."""
    table = Table(title="ftcomp demo: the paper's results beside ours", show_lines=True)
    for col, ratio in (("quantity", 3), ("paper", 3), ("ftcomp", 4), ("", 1), ("why", 6)):
        table.add_column(col, ratio=ratio)
    for row in result.comparisons:
        mark = "[green]✓[/green]" if row.reproduced else "[bold red]✗[/bold red]"
        note = row.note if row.reproduced else f"[red]not reproduced[/red]: {row.note}"
        table.add_row(escape(row.quantity), escape(row.paper), escape(row.ours), mark, note)
    return table


def verdict_table(result: DemoResult) -> Table:
    """Every placement run's verdict, from the true contact force."""
    table = Table(title="placement runs, judged from the true contact force")
    for col in ("run", "verdict", "true press [N]", "sensed final force [N]", "ended by"):
        table.add_column(col, justify="left" if col in ("run", "verdict", "ended by") else "right")
    for name, run in result.placement.runs.items():
        style = "green" if run.verdict == "placed gently" else "bold red"
        table.add_row(
            name,
            f"[{style}]{run.verdict}[/{style}]",
            f"{run.true_press_N:+.3f}",
            f"{run.final_force_N:+.3f}",
            run.stop_reason.replace("_", " "),
        )
    return table
