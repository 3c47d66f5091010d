"""A live one-line status for streams on hardware: rate, lost packets, contact force.

:class:`StatusLine` shows a :class:`~ftcomp.session.stream.StreamProgress` (the session calls it
a few times a second): it rewrites one line on a terminal (``\\r``), e.g.
``1000 Hz | lost 3 | |F| 0.412 N | 1.2 / 2 s``. Off a terminal (a pipe, a log file, a test) it
stays silent.

:class:`PoseProgress` is a progress bar for work counted in steps (``record``: pose k of n, time
left), on a terminal only.

:func:`add_view_arguments` adds ``--log FILE.mcap`` and ``--view HOST:PORT`` to a live command.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import TYPE_CHECKING, TextIO

from ftcomp.cli.options import map_field
from ftcomp.errors import ParameterError

if TYPE_CHECKING:
    from ftcomp.session.stream import StreamProgress

__all__ = ["CallbackProgress", "PoseProgress", "StatusLine", "add_view_arguments", "view_address"]

#: The live view's address when ``--view`` names only a port (loopback: nothing outside the
#: machine sees it unless asked).
DEFAULT_VIEW_HOST = "127.0.0.1"


def view_address(text: str) -> str:
    """``HOST:PORT`` from ``--view``'s value (``PORT`` alone: on the loopback address)."""
    from ftcomp.views.foxglove_view import parse_address

    host, _, port = text.rpartition(":")
    address = f"{host or DEFAULT_VIEW_HOST}:{port}"
    try:
        parse_address(address)  # the library's rule for an address
    except ParameterError:
        raise argparse.ArgumentTypeError(
            f"expected HOST:PORT or PORT, with a port 1..65535, got {text!r}"
        ) from None
    return f"{host or DEFAULT_VIEW_HOST}:{int(port)}"


def add_view_arguments(parser: argparse.ArgumentParser) -> None:
    """``--log FILE.mcap`` and ``--view HOST:PORT`` (see docs/views.md)."""
    parser.add_argument(
        "--log",
        metavar="FILE.mcap",
        help="also write the session as MCAP (ROS 2 messages: wrenches, /tf, the controller's "
        "error and command, load, events) for Foxglove, Lichtblick, rosbags, import-bag "
        "(default: none)",
    )
    parser.add_argument(
        "--view",
        type=view_address,
        metavar="HOST:PORT",
        help="serve the session live over the Foxglove WebSocket protocol (open "
        f"ws://HOST:PORT in Foxglove or Lichtblick; PORT alone: on {DEFAULT_VIEW_HOST}; "
        "default: none)",
    )
    map_field(parser, "address", "--view")


class StatusLine:
    """The status line (see the module docstring).

    Args:
        stream: where to write (stderr).
    """

    def __init__(self, stream: TextIO | None = None) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = self.stream.isatty()
        self._last_t = time.monotonic()
        self._last_count = 0
        self.shown = False

    @staticmethod
    def text(progress: StreamProgress, rate_hz: float) -> str:
        """The line for a progress and a rate [Hz]."""
        parts = [f"{rate_hz:6.0f} Hz"]
        if progress.lost_packets is not None:
            parts.append(f"lost {progress.lost_packets}")
        if math.isfinite(progress.contact_force_N):
            parts.append(f"|F| {progress.contact_force_N:.3f} N")
        parts.append(f"{progress.elapsed_s:.1f} / {progress.duration_s:g} s")
        return " | ".join([*parts, progress.load] if progress.load else parts)

    def __call__(self, progress: StreamProgress) -> None:
        """Show where the stream is (nothing off a terminal)."""
        if not self.enabled:
            return
        now = time.monotonic()
        rate = (progress.readings - self._last_count) / max(now - self._last_t, 1e-9)
        self._last_t, self._last_count = now, progress.readings
        self.stream.write("\r" + self.text(progress, rate) + "   ")
        self.stream.flush()
        self.shown = True

    def close(self) -> None:
        """End the line."""
        if self.shown:
            self.stream.write("\n")
            self.stream.flush()


class PoseProgress:
    """A progress bar of ``total`` steps with the time left, on stderr when it is a terminal
    (silent in a pipe, a log file, a test). Lines printed meanwhile appear above it.

    Args:
        description: what is counted, e.g. ``"poses"``.
        total: the steps planned.
        stream: where to draw (stderr).
    """

    def __init__(self, description: str, total: int, stream: TextIO | None = None) -> None:
        stream = stream if stream is not None else sys.stderr
        self.enabled = stream.isatty()
        self._progress = None
        if not self.enabled:
            return
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeRemainingColumn,
        )

        self._progress = Progress(
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("left"),
            TimeRemainingColumn(),
            console=Console(file=stream),
            auto_refresh=False,  # redrawn at each step: no display thread
            transient=True,
        )
        self._task = self._progress.add_task(description, total=total)
        self._progress.start()
        self._progress.refresh()

    def advance(self, steps: int = 1) -> None:
        """``steps`` more done."""
        if self._progress is not None:
            self._progress.advance(self._task, steps)
            self._progress.refresh()

    def close(self) -> None:
        """Remove the bar (idempotent)."""
        if self._progress is not None:
            self._progress.stop()
            self._progress = None


class CallbackProgress:
    """A :class:`PoseProgress` fed by a library call's ``progress(done, total)`` callback
    (``compensate``: bytes or rows read; ``import-bag``: messages read), drawn from the first
    call on; silent where :class:`PoseProgress` is.

    Args:
        description: what is counted, e.g. ``"MB read"``.
        scale: the callback's units per unit shown (1e6 to show bytes as MB).
        stream: where to draw (stderr).
    """

    def __init__(self, description: str, scale: float = 1.0, stream: TextIO | None = None):
        self.description, self.scale, self.stream = description, scale, stream
        self.bar: PoseProgress | None = None
        self.shown = 0

    def __call__(self, done: int, total: int) -> None:
        """The work is ``done`` of ``total`` (the callback's units)."""
        if self.bar is None:
            self.bar = PoseProgress(self.description, math.ceil(total / self.scale), self.stream)
        now = math.ceil(done / self.scale)
        if now > self.shown:
            self.bar.advance(now - self.shown)
            self.shown = now

    def close(self) -> None:
        """Remove the bar (idempotent)."""
        if self.bar is not None:
            self.bar.close()
