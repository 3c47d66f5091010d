"""Ctrl-C during a live session: the first stops it, the next is held while its files are
finished (a double Ctrl-C must not cut the log of the run it stopped), one more abandons them."""

from __future__ import annotations

import io
import signal
import threading
import time
from collections.abc import Sequence
from pathlib import Path

import pytest

import ftcomp
from ftcomp.session.interrupts import InterruptHold
from ftcomp.session.stream import StreamConfig, StreamProgress, stream


@pytest.fixture
def default_ctrl_c() -> object:
    """Ctrl-C raising KeyboardInterrupt in this process (as in a terminal), then as it was."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


@pytest.mark.usefixtures("default_ctrl_c")
def test_the_first_ctrl_c_stops_the_next_is_held_and_one_more_abandons() -> None:
    out = io.StringIO()
    with InterruptHold(out) as hold:
        with pytest.raises(KeyboardInterrupt):
            signal.raise_signal(signal.SIGINT)  # stops the session, as always
        hold.finishing("finishing the log run.csv")
        signal.raise_signal(signal.SIGINT)  # held
        assert out.getvalue() == "finishing the log run.csv: Ctrl-C again to abandon it\n"
        with pytest.raises(KeyboardInterrupt):
            signal.raise_signal(signal.SIGINT)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.usefixtures("default_ctrl_c")
def test_once_finishing_even_the_first_ctrl_c_is_held() -> None:
    out = io.StringIO()
    with InterruptHold(out) as hold:
        hold.finishing("finishing x")
        signal.raise_signal(signal.SIGINT)
        assert hold.held == 1 and out.getvalue().startswith("finishing x:")
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_ignored_ctrl_c_and_other_threads_are_left_alone() -> None:
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with InterruptHold():
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, before)
    seen: list[object] = []

    def worker() -> None:
        with InterruptHold():
            seen.append(signal.getsignal(signal.SIGINT))

    thread = threading.Thread(target=worker)
    thread.start()
    thread.join()
    assert seen == [signal.getsignal(signal.SIGINT)]


class _CtrlCWhileClosing:
    """An observer pressing Ctrl-C while the session finishes (its end event, on the worker
    thread), then giving the main thread time to see it."""

    def open(self, columns: Sequence[str]) -> None:
        pass

    def row(self, t_ns: int, row: Sequence[float]) -> None:
        pass

    def event(self, t_ns: int, kind: str, text: str) -> None:
        if kind in ("end", "fault"):
            signal.raise_signal(signal.SIGINT)
            time.sleep(0.2)

    def close(self) -> None:
        pass


@pytest.mark.usefixtures("default_ctrl_c")
def test_a_second_ctrl_c_while_the_stream_finishes_keeps_its_log_whole(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "stream.csv"
    calls: list[StreamProgress] = []

    def first_ctrl_c(progress: StreamProgress) -> None:
        calls.append(progress)
        if len(calls) == 3:
            signal.raise_signal(signal.SIGINT)

    config = StreamConfig(duration_s=60.0, progress_period_s=0.01)
    with ftcomp.open_robot("sim://?seed=4") as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        result = stream(
            robot, sensor, config, log, on_progress=first_ctrl_c, observers=[_CtrlCWhileClosing()]
        )
    assert result.outcome == "interrupted"
    assert f"finishing the log {log}: Ctrl-C again to abandon it" in capsys.readouterr().err
    lines = log.read_text().splitlines()
    assert len(lines) == result.readings + 1 > 1
    assert log.with_suffix(".timing.json").exists()
