"""Start stand-ins, each in its own process, and stop them: ``with running(...)``.

Every stand-in gets its own loopback address (:func:`loopback_address`), prints ``ready`` once
it listens, ends by itself after its scenario's ``max_s`` and is killed when the block ends.
"""

from __future__ import annotations

import collections
import os
import select
import subprocess
import sys
import threading
import time
import zlib
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import IO

__all__ = ["Drain", "loopback_address", "running", "running_all"]

_TESTS = Path(__file__).resolve().parent.parent


def loopback_address(name: str, salt: int = 0) -> str:
    """A 127.x.y.z address of a test's own (from its name and a salt), never 127.0.0.1."""
    h = zlib.crc32(f"{name}/{salt}".encode())
    return f"127.{10 + h % 200}.{(h >> 8) % 250 + 1}.{(h >> 16) % 250 + 2}"


class Drain:
    """Reads a process's stdout and stderr to their ends on two threads, keeping the last lines.

    A pipe nobody reads fills (64 KiB) and then blocks the writer: a twin that logged a line
    per late cycle once stopped dead in its loop after about a thousand of them, its clients
    lost the controller, and the test hung. Start it once the ready line has been read.
    """

    def __init__(self, proc: subprocess.Popen[str], keep_lines: int = 200) -> None:
        self.lines = {
            name: collections.deque[str](maxlen=keep_lines) for name in ("stdout", "stderr")
        }
        self._threads = [
            threading.Thread(target=self._read, args=(stream, self.lines[name]), daemon=True)
            for name, stream in (("stdout", proc.stdout), ("stderr", proc.stderr))
            if stream is not None
        ]
        for thread in self._threads:
            thread.start()

    @staticmethod
    def _read(stream: IO[str], lines: collections.deque[str]) -> None:
        for line in stream:
            lines.append(line)

    def join(self, timeout_s: float = 5.0) -> None:
        """Wait until both streams ended (the process exited)."""
        for thread in self._threads:
            thread.join(timeout_s)

    def text(self) -> str:
        """The kept lines of stdout, then of stderr."""
        return "".join(self.lines["stdout"]) + "".join(self.lines["stderr"])


def _wait_ready(module: str, proc: subprocess.Popen[str], deadline: float) -> None:
    assert proc.stdout is not None
    line = ""
    while time.monotonic() < deadline and proc.poll() is None:
        ready, _, _ = select.select([proc.stdout], [], [], 0.1)
        if ready:
            line = proc.stdout.readline()
            break
    if line.strip() != "ready":
        proc.kill()
        _, err = proc.communicate(timeout=5)
        raise RuntimeError(f"stand-in {module} did not start: {err[-2000:]}")


@contextmanager
def running_all(
    commands: Sequence[tuple[str, Sequence[str]]], ready_timeout_s: float = 20.0
) -> Iterator[list[subprocess.Popen[str]]]:
    """Start ``python -m standins.<module> args...`` for each, all at once; wait until every one
    is ready; kill them at the end.

    Raises:
        RuntimeError: one did not become ready in time (its stderr is in the message).
    """
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(_TESTS), env.get("PYTHONPATH", "")]))
    procs: list[subprocess.Popen[str]] = []
    drains: list[Drain] = []
    try:
        for module, args in commands:
            procs.append(
                subprocess.Popen(
                    [sys.executable, "-m", f"standins.{module}", *args],
                    stdout=subprocess.PIPE,
                    stderr=subprocess.PIPE,
                    text=True,
                    env=env,
                )
            )
        deadline = time.monotonic() + ready_timeout_s
        for (module, _), proc in zip(commands, procs, strict=True):
            _wait_ready(module, proc, deadline)
            drains.append(Drain(proc))
        yield procs
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
            proc.wait(timeout=5)
        for drain in drains:
            drain.join()
        for proc in procs:
            for stream in (proc.stdout, proc.stderr):
                if stream is not None:
                    stream.close()


@contextmanager
def running(module: str, *args: str) -> Iterator[subprocess.Popen[str]]:
    """One stand-in (see :func:`running_all`)."""
    with running_all([(module, args)]) as procs:
        yield procs[0]
