"""One test at a time, over pytest-xdist's workers, that counts the packets the host sends or
may send one itself: ``with off_host_turn():``.

The ROS 2 tests check that no non-loopback interface sent a packet while they ran (the kernel's
counters, the whole machine's: tests/ros2/ros2_graph.py); headless Chromium (tests/views/
headless_chromium.py) is kept quiet by its flags, but a browser is the one program of the suite
that might speak to the network. Under ``-n 2`` the two would run side by side on the two
workers; an exclusive lock on a file of the run's own (``PYTEST_XDIST_TESTRUNUID``, the same in
every worker) keeps them apart. In one process there is no one to wait for.
"""

from __future__ import annotations

import fcntl
import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["off_host_turn"]


@contextmanager
def off_host_turn() -> Iterator[None]:
    """Hold the run's off-host lock (waiting for it) for the block."""
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID")
    if run is None:
        yield
        return
    path = Path(tempfile.gettempdir()) / f"ftcomp-off-host-{run}.lock"
    with path.open("a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
