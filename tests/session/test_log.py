"""A live session's CSV log: rows kept for the slack and flushed, never written twice."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ftcomp.session.log import csv_log


def test_a_flush_cut_short_by_ctrl_c_writes_every_row_once(tmp_path: Path) -> None:
    path = tmp_path / "log.csv"
    with csv_log(path, ("t", "x")) as log:
        for k in range(5):
            log.write_later([float(k), 10.0 * k])
        write, calls = log.write, [0]

        def interrupted(row: Any, t_ns: int | None = None) -> None:
            calls[0] += 1
            if calls[0] == 3:  # Ctrl-C while the third row is formatted
                raise KeyboardInterrupt
            write(row, t_ns)

        log.write = interrupted  # type: ignore[method-assign]
        with pytest.raises(KeyboardInterrupt):
            log.flush()
        log.write = write  # type: ignore[method-assign]
    rows = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    # The row being formatted stays kept and is written by the closing flush: every row once,
    # in order (the log's count is the file's).
    assert rows[:, 0].tolist() == [0.0, 1.0, 2.0, 3.0, 4.0]
    assert log.rows == 5


@pytest.mark.parametrize("when", ["before", "after"])
def test_a_ctrl_c_inside_a_write_to_the_file_loses_and_repeats_no_row(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, when: str
) -> None:
    """Ctrl-C inside the write that hands kept rows to the file: before it wrote (the system
    call interrupted) or just after it returned (Python raises it at the call's end). Python's
    buffered text file raised it from inside a row's write and dropped that row after it was
    counted (a stream's log 234 rows where it said 235)."""
    import ftcomp.session.log as log_module

    path = tmp_path / "log.csv"
    real_write, calls = os.write, [0]

    def interrupted(fd: int, data: bytes) -> int:
        calls[0] += 1
        if calls[0] % 3 == 0:
            if when == "after":
                real_write(fd, data)
            raise KeyboardInterrupt
        return real_write(fd, data)

    monkeypatch.setattr(log_module.CsvLog, "WRITE_BYTES", 64)  # a write every few rows
    stops = 0
    with csv_log(path, ("t", "x")) as log:
        monkeypatch.setattr(log_module.os, "write", interrupted)
        for k in range(200):
            try:
                log.write([float(k), 10.0 * k])
            except KeyboardInterrupt:
                stops += 1
        monkeypatch.setattr(log_module.os, "write", real_write)
    rows = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    assert stops > 10  # the interrupts landed
    assert rows[:, 0].tolist() == [float(k) for k in range(200)]
    assert rows[:, 1].tolist() == [10.0 * k for k in range(200)]
    assert log.rows == 200
