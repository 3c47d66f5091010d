"""``ftcomp sim place``: set a grasped load down on the simulated sponge or book (paper 2.2.2)."""

from __future__ import annotations

import argparse

from ftcomp.errors import ParameterError

__all__ = ["register"]


def register(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``place`` command to the ``sim`` group."""
    p = commands.add_parser(
        "place",
        help="place a grasped load on a sponge or a book (position-only or admittance)",
        description="Writes timeseries.csv, metrics.json and placement.png into --out.",
    )
    p.add_argument("--surface", choices=("sponge", "book"), required=True)
    p.add_argument("--control", choices=("position", "admittance"), required=True)
    p.add_argument(
        "--no-compensation", action="store_true", help="control on raw readings (Fig. 7)"
    )
    p.add_argument("--k1", type=float, metavar="MM_PER_N", help="k13 [mm/N] (default per surface)")
    p.add_argument(
        "--k2", type=float, metavar="MM_PER_S_PER_N", help="k23 [mm/(s*N)] (default per surface)"
    )
    p.add_argument("--load-kg", type=float, default=0.5)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", required=True, metavar="DIR")
    p.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    from ftcomp.experiments.placement import (
        DEFAULT_GAINS,
        PlacementConfig,
        SimPlacementCell,
        run_placement,
        write_placement_outputs,
    )

    k1_default, k2_default = DEFAULT_GAINS[args.surface]
    k1_m = k1_default if args.k1 is None else args.k1 * 1e-3
    k2_m = k2_default if args.k2 is None else args.k2 * 1e-3
    for name, value in (("--k1", k1_m), ("--k2", k2_m)):
        if not value >= 0.0:
            raise ParameterError(f"{name} must be >= 0, got {value * 1e3:g}")
    config = PlacementConfig(
        args.control,
        compensation=not args.no_compensation,
        k1_m_per_N=k1_m,
        k2_m_per_s_N=k2_m,
    )
    cell = SimPlacementCell(args.surface, args.load_kg, seed=args.seed)
    result = run_placement(cell, cell.tool_model, config)
    title = f"{args.control} on {args.surface}" + (
        ", no compensation" if args.no_compensation else ""
    )
    paths = write_placement_outputs(result, args.out, title=title)
    m = result.metrics
    print(
        f"{title}: {m['stop_reason']}, final force {m['final_force_N']:+.3f} N, "
        f"peak press {m['peak_press_N']:.3f} N, descent {m['descent_mm']:.2f} mm"
    )
    print(f"wrote {paths['csv'].parent}")
    return 0
