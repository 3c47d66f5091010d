"""Reading ahead in a worker thread: it stops when the consumer stops and hands on its errors."""

from __future__ import annotations

import pytest

from ftcomp.errors import InputFileError
from ftcomp.session.read_ahead import read_ahead


def test_the_reading_thread_stops_when_the_writer_stops_and_hands_on_its_errors() -> None:
    def blocks(fail_at: int | None):
        for i in range(1000):
            if i == fail_at:
                raise InputFileError(f"bad block {i}")
            yield i

    stream = read_ahead(blocks(None))
    assert [next(stream), next(stream)] == [0, 1]
    stream.close()  # the consumer leaves with the worker waiting to hand on block 2 or 3
    assert list(read_ahead(blocks(None))) == list(range(1000))
    with pytest.raises(InputFileError, match="bad block 7"):
        list(read_ahead(blocks(7)))
