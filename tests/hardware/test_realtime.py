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
