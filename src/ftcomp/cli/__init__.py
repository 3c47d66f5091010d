"""The ``ftcomp`` command: a thin layer that parses, calls the library and prints.

Each command lives in its own module with a ``register(subparsers)`` function that adds its
parser and sets ``handler``; a handler returns the exit code. ``FtcompError`` becomes one line
``error: ...`` on stderr and exit code 2.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from ftcomp import __version__
from ftcomp.cli import calibrate, collect, compensate, demo, place
from ftcomp.errors import FtcompError

__all__ = ["main"]

EXIT_BAD_INPUT = 2


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser, with every command registered."""
    parser = argparse.ArgumentParser(
        prog="ftcomp",
        description="F/T sensor calibration, gravity compensation and compliant control.",
    )
    parser.add_argument("--version", action="version", version=f"ftcomp {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    calibrate.register(commands)
    compensate.register(commands)
    demo.register(commands)
    sim = commands.add_parser("sim", help="run the simulated MuJoCo robot cell")
    sim_commands = sim.add_subparsers(dest="sim_command", metavar="SIM_COMMAND", required=True)
    collect.register(sim_commands)
    place.register(sim_commands)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``ftcomp`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        code: int = args.handler(args)
    except FtcompError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("error: interrupted", file=sys.stderr)
        return 130
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
