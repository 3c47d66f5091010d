"""The ``ftcomp`` command: a thin layer that parses, calls the library and prints.

Each command lives in its own module with a ``register(parser)`` function that adds its
arguments and sets ``handler``; a handler returns the exit code. Only the module of the command
being run is imported (``ftcomp --help`` loads none of them, nor numpy), so the command starts
fast. ``FtcompError`` becomes one line ``error: ...`` on stderr and exit code 2; an option built
from a config field (:mod:`ftcomp.cli.options`) is checked by the field's rule before the
command runs, and an error the library raises on a field names the flag that set it.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence
from typing import NoReturn

from ftcomp import __version__

__all__ = ["COMMANDS", "COMMAND_EXTRAS", "SIM_COMMANDS", "build_parser", "main"]

EXIT_BAD_INPUT = 2
#: Exit code when the reader of standard output went away (128 + SIGPIPE, as a shell's).
EXIT_BROKEN_PIPE = 141

#: Top-level commands: name -> (module, one-line help).
COMMANDS: dict[str, tuple[str, str]] = {
    "calibrate": (
        "ftcomp.cli.calibrate",
        "identify sensor bias, tool weight and centre of gravity, and base tilt",
    ),
    "compensate": ("ftcomp.cli.compensate", "remove bias and tool gravity from every reading"),
    "demo": (
        "ftcomp.cli.demo",
        "run every experiment of the paper on the simulated cell and write a report",
    ),
    "import-bag": (
        "ftcomp.cli.import_bag",
        "sample CSV from a ROS 2 / ROS 1 bag: wrenches, poses from tf or URDF, still segments",
    ),
    "export": ("ftcomp.cli.export", "write a calibration as ros2_control parameters (YAML)"),
    "record": (
        "ftcomp.cli.record",
        "record calibration readings on a robot (robot-driven poses, or by hand with --manual)",
    ),
    "stream": ("ftcomp.cli.stream", "log a sensor's readings, raw and compensated, at its rate"),
    "run": ("ftcomp.cli.run", "run the compliant loop on a robot with a calibration"),
    "twin": ("ftcomp.cli.twin", "serve the simulated cell as a UR e-Series with a Net F/T"),
    "rebias": (
        "ftcomp.cli.rebias",
        "re-estimate only the sensor bias from still readings, the tool model kept",
    ),
    "poses": ("ftcomp.cli.poses", "design calibration poses (D-optimal, reachable, short travel)"),
    "payload": (
        "ftcomp.cli.payload",
        "write a calibration's tool mass and centre of gravity to a UR controller",
    ),
    "ros2": ("ftcomp.cli.ros2", "ROS 2: gravity compensation as a node (ftcomp ros2 node)"),
    "calibrate-dynamic": (
        "ftcomp.cli.calibrate_dynamic",
        "identify the tool's inertia tensor from a recorded fast excitation trajectory",
    ),
}
#: ``ftcomp sim`` commands: name -> (module, one-line help).
SIM_COMMANDS: dict[str, tuple[str, str]] = {
    "collect": (
        "ftcomp.cli.collect",
        "record static calibration readings in the simulated cell (record on sim://)",
    ),
    "place": (
        "ftcomp.cli.place",
        "place a grasped load on a sponge or a book (position-only or admittance)",
    ),
}

#: Commands that need an extra beyond the lean install (``pip install ftcomp``), checked before
#: the command runs so that a missing one is a single line naming it, exit code 2:
#: ``error: ftcomp demo needs MuJoCo and matplotlib: pip install 'ftcomp[demo]'``.
COMMAND_EXTRAS: dict[str, str] = {
    "demo": "demo",
    "twin": "sim",
    "sim collect": "sim",
    "sim place": "demo",
}


def _chosen(argv: Sequence[str], names: Sequence[str]) -> str | None:
    """The first argument that names a command (None for e.g. ``--help`` alone)."""
    return next((a for a in argv if a in names), None)


def _add(
    commands: argparse._SubParsersAction[_Parser],
    table: dict[str, tuple[str, str]],
    chosen: str | None,
) -> None:
    """A parser per command; only the chosen command's module is imported to fill its own."""
    for name, (module, help_text) in table.items():
        parser = commands.add_parser(name, help=help_text, description=help_text)
        if name == chosen:
            importlib.import_module(module).register(parser)
            from ftcomp.cli.options import map_options

            map_options(parser)


class _Parser(argparse.ArgumentParser):
    """Usage errors as one line ``error: ftcomp CMD: ...`` and exit code 2 (not a usage block)."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"error: {self.prog}: {message} (see {self.prog} --help)\n")


def build_parser(argv: Sequence[str] = ()) -> argparse.ArgumentParser:
    """The argument parser, with the command named in ``argv`` fully registered."""
    parser = _Parser(
        prog="ftcomp",
        description="F/T sensor calibration, gravity compensation and compliant control.",
    )
    parser.add_argument("--version", action="version", version=f"ftcomp {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    chosen = _chosen(argv, [*COMMANDS, "sim"])
    _add(commands, COMMANDS, chosen)
    sim = commands.add_parser("sim", help="run the simulated MuJoCo robot cell")
    sim_commands = sim.add_subparsers(dest="sim_command", metavar="SIM_COMMAND", required=True)
    sim_chosen = None
    if chosen == "sim":
        sim_chosen = _chosen(argv[list(argv).index("sim") + 1 :], list(SIM_COMMANDS))
    _add(sim_commands, SIM_COMMANDS, sim_chosen)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``ftcomp`` console script; returns the exit code."""
    code = _main(list(sys.argv[1:] if argv is None else argv))
    # The process's own command (not a call from Python with its arguments): a UR controller
    # that went silent leaves ur_rtde's threads, which abort the interpreter's teardown.
    if argv is None and "ftcomp.hardware.ur" in sys.modules:
        from ftcomp.hardware.ur import exit_process_if_abandoned

        exit_process_if_abandoned(code)
    return code


def _main(args_list: list[str]) -> int:
    from ftcomp.errors import FtcompError

    try:  # before the command's module builds its options (from configs that may need it)
        _require_extra(args_list)
    except FtcompError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    args = build_parser(args_list).parse_args(args_list)
    from ftcomp.cli.options import check_field_options, error_line

    try:
        check_field_options(args)  # each option built from a config field, by its rule
        code: int = args.handler(args)
    except FtcompError as exc:
        print(f"error: {error_line(exc, args)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("error: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        if not _stdout_closed():
            raise
        # The reader went away (``ftcomp ... | head``): stop quietly, as a shell tool does, and
        # keep the interpreter's last flush from failing again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_BROKEN_PIPE
    return code


def _require_extra(argv: Sequence[str]) -> None:
    """The extra the command named in ``argv`` needs, checked (:data:`COMMAND_EXTRAS`).

    Raises:
        MissingExtraError: it is not installed, naming it.
    """
    name = _chosen(argv, [*COMMANDS, "sim"])
    if name == "sim":
        sub = _chosen(argv[list(argv).index("sim") + 1 :], list(SIM_COMMANDS))
        name = f"sim {sub}" if sub else None
    if name in COMMAND_EXTRAS:
        from ftcomp.extras import require_extra

        require_extra(COMMAND_EXTRAS[name], f"ftcomp {name}")


def _stdout_closed() -> bool:
    """Whether standard output is a pipe whose reader has gone (POLLERR on its write end), so
    that a broken socket of a backend is not mistaken for it."""
    import select

    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
    except (AttributeError, OSError, ValueError):  # no real file behind stdout
        return False
    return any(events & select.POLLERR for _, events in poller.poll(0))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
