"""Ctrl-C while a stopped session finishes its files.

A live session ends on Ctrl-C with the robot stopped, then writes the end of its log (the last
rows, the end event, the timing summary, the MCAP index). A user who presses Ctrl-C twice, as
many do, would otherwise cut that short and lose the log of the very run they stopped.
:class:`InterruptHold` lets the first Ctrl-C stop the session, then holds the next one while the
files are finished: it says what it is waiting for, and one more Ctrl-C abandons the files (a
stalled disk must not trap the user). Installed before the session starts, it leaves no moment
between the first Ctrl-C and the hold where a second one would cut the files short.

Signal handlers belong to the main thread: a session run on another thread (a test, an
application's worker) holds nothing and behaves as before; so does a process where Ctrl-C is
ignored (a batch job) or handled by the application's own handler.
"""

from __future__ import annotations

import signal
import sys
import threading
from types import FrameType, TracebackType
from typing import Any, TextIO

__all__ = ["InterruptHold"]


class InterruptHold:
    """A context manager around a live session, entered before its log is opened.

    The first Ctrl-C stops the session as always (a :class:`KeyboardInterrupt`: the loop stops
    the robot). Once the session is finishing its files (:meth:`finishing`, or after that first
    Ctrl-C) a Ctrl-C is held: the first held one prints what it waits for, the next one raises.
    Leaving the ``with`` block puts the previous handler back.

    Args:
        out: where the one line about a held Ctrl-C goes (standard error by default).
    """

    def __init__(self, out: TextIO | None = None) -> None:
        self.out = out
        self.presses = 0
        self.held = 0
        self.what = "finishing the session's files"
        self._finishing = False
        self._previous: Any = None
        self._installed = False

    def __enter__(self) -> InterruptHold:
        if (
            threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) is signal.default_int_handler
        ):
            self._previous = signal.signal(signal.SIGINT, self._pressed)
            self._installed = True
        return self

    def finishing(self, what: str) -> None:
        """The loop has ended: hold Ctrl-C while ``what`` (e.g. "finishing the log run.csv")."""
        self.what = what
        self._finishing = True

    def _pressed(self, signum: int, frame: FrameType | None) -> None:
        self.presses += 1
        if not self._finishing and self.presses == 1:
            raise KeyboardInterrupt
        self.held += 1
        if self.held == 1:
            out = self.out if self.out is not None else sys.stderr
            print(f"{self.what}: Ctrl-C again to abandon it", file=out, flush=True)
            return
        self._restore()
        raise KeyboardInterrupt

    def _restore(self) -> None:
        if self._installed:
            signal.signal(signal.SIGINT, self._previous)
            self._installed = False

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._restore()
