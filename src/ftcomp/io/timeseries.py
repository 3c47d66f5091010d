"""Time series as CSV: named columns of equal length, one row per cycle, written atomically."""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import ParameterError
from ftcomp.io.atomic import atomic_write_text

__all__ = ["write_timeseries_csv"]


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
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    fmt = f"{{:.{digits}g}}"
    writer.writerows([fmt.format(v) for v in row] for row in data)
    atomic_write_text(path, buffer.getvalue())
