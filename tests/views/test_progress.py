"""Progress on long work: a bar with the count and the time left on a terminal, nothing in a
pipe."""

from __future__ import annotations

import io

from ftcomp.cli.live_status import PoseProgress


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_bar_counts_the_poses_on_a_terminal() -> None:
    screen = _Terminal()
    bar = PoseProgress("poses", 9, stream=screen)
    bar.advance()
    bar.advance()
    shown = screen.getvalue()
    assert "poses" in shown and "2/9" in shown and "left" in shown
    bar.close()
    bar.close()  # idempotent


def test_the_bar_is_silent_in_a_pipe() -> None:
    pipe = io.StringIO()
    bar = PoseProgress("poses", 9, stream=pipe)
    bar.advance()
    bar.close()
    assert pipe.getvalue() == "" and not bar.enabled


def test_a_callback_bar_shows_megabytes_read_on_a_terminal_and_nothing_in_a_pipe() -> None:
    from ftcomp.cli.live_status import CallbackProgress

    screen, pipe = _Terminal(), io.StringIO()
    for stream in (screen, pipe):
        bar = CallbackProgress("MB read", 1e6, stream=stream)
        bar(1_500_000, 4_000_000)
        bar(4_000_000, 4_000_000)
        bar.close()
        bar.close()  # idempotent
    assert "MB read" in screen.getvalue() and "4/4" in screen.getvalue()
    assert pipe.getvalue() == ""
