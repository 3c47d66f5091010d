"""CSV tables written atomically: rows under a header, or named columns of equal length.

:func:`write_table` writes rows as they are given (text or numbers); :func:`write_timeseries_csv`
writes a time series, one row per cycle, to a number of significant digits.
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import ParameterError
from ftcomp.io.atomic import atomic_write_text

__all__ = ["write_table", "write_timeseries_csv"]


def write_timeseries_csv(
    path: str | os.PathLike[str],
    series: Mapping[str, NDArray[np.float64]],
    columns: Sequence[str],
    *,
    digits: int = 6,
) -> None:
    """Write ``series[c]`` for each ``c`` in ``columns`` as CSV (``digits`` significant digits).

    Raises:
        ParameterError: a column is missing or the columns differ in length.
    """
    missing = [c for c in columns if c not in series]
    if missing:
        raise ParameterError(f"{path}: no data for column {missing[0]!r}")
    data = np.column_stack([np.asarray(series[c], dtype=float) for c in columns])
    fmt = f"{{:.{digits}g}}"
    write_table(path, columns, [[fmt.format(v) for v in row] for row in data])


def write_table(
    path: str | os.PathLike[str], header: Sequence[str], rows: Sequence[Sequence[object]]
) -> None:
    """Write a CSV table atomically (temporary file, then rename)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
    atomic_write_text(path, buffer.getvalue())
