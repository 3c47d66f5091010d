"""A live session's CSV log: rows kept for the slack and flushed, never written twice."""

from __future__ import annotations

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
