"""realtime_loop: the switch interval while the loop runs, real-time scheduling where allowed,
and one plain line with how to allow it where refused."""

from __future__ import annotations

import logging
import os
import sys

import pytest

from ftcomp.hardware import pacing
from ftcomp.hardware.pacing import LOOP_SWITCH_INTERVAL_S, realtime_loop


def test_the_switch_interval_is_short_while_the_loop_runs_and_restored_after() -> None:
    before = sys.getswitchinterval()
    with realtime_loop(realtime=False) as granted:
        assert not granted
        assert sys.getswitchinterval() == pytest.approx(min(before, LOOP_SWITCH_INTERVAL_S))
    assert sys.getswitchinterval() == before


def test_a_refused_real_time_priority_is_said_once_with_how_to_allow_it(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    def refuse(*_: object) -> None:
        raise PermissionError(1, "Operation not permitted")

    monkeypatch.setattr(os, "sched_setscheduler", refuse)
    monkeypatch.setattr(pacing, "_said_refused", False)
    with caplog.at_level(logging.WARNING):
        for _ in range(2):
            with realtime_loop() as granted:
                assert not granted
    lines = [m for m in (r.getMessage() for r in caplog.records) if "priority refused" in m]
    assert len(lines) == 1
    assert "Operation not permitted" in lines[0] and "cap_sys_nice" in lines[0]
    assert "rtprio" in lines[0]


@pytest.mark.live  # a real-time loop in this process: under -n, at the normal policy (conftest)
def test_the_loop_and_python_threads_are_real_time_and_native_threads_keep_their_own() -> None:
    """The loop's thread at its priority, another Python thread (a reader, the log's worker)
    at WORKER_PRIORITY, and a native thread (numpy's OpenBLAS worker, which spins between
    jobs) as its library left it; all restored after."""
    import threading

    import numpy as np

    np.ones((64, 64)) @ np.ones((64, 64))  # numpy's BLAS started
    python_ids = {t.native_id for t in threading.enumerate()}
    native = sorted(int(t) for t in os.listdir("/proc/self/task") if int(t) not in python_ids)
    if not native:
        pytest.skip("numpy runs no thread of its own here (one core, or its BLAS limited to one)")
    release = threading.Event()
    started = threading.Event()

    def wait() -> None:
        started.set()
        release.wait(10.0)

    helper = threading.Thread(target=wait, daemon=True)
    helper.start()
    started.wait(10.0)
    try:
        with realtime_loop(priority=5) as granted:
            if not granted:
                pytest.skip("real-time scheduling is not allowed here")
            assert os.sched_getscheduler(0) == os.SCHED_FIFO
            assert os.sched_getparam(0).sched_priority == 5
            assert helper.native_id is not None
            assert os.sched_getscheduler(helper.native_id) == os.SCHED_FIFO
            assert os.sched_getparam(helper.native_id).sched_priority == pacing.WORKER_PRIORITY
            assert all(os.sched_getscheduler(t) == os.SCHED_OTHER for t in native)
        assert os.sched_getscheduler(0) == os.SCHED_OTHER
        assert os.sched_getscheduler(helper.native_id) == os.SCHED_OTHER
    finally:
        release.set()
        helper.join(10.0)
