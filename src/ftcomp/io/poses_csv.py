"""The pose file: orientations (and optionally positions) for a robot to visit.

Format: a header row and one orientation encoding's columns, as in the sample CSV
(:mod:`ftcomp.io.samples_csv`); an optional ``pose`` column labels the poses; optional
``x_m,y_m,z_m`` give the sensor origin in the base frame [m]. Any other column is ignored, so a
sample CSV is also a pose file.
"""

from __future__ import annotations

import csv
import difflib
import os
from pathlib import Path
from typing import Final

import numpy as np

from ftcomp.errors import FtcompError, InputFileError
from ftcomp.frames import ENCODING_COLUMNS, OrientationEncoding, rotation_from_encoding
from ftcomp.samples import PoseList

__all__ = ["PAPER_POSES", "read_pose_file"]

#: The name commands that read a pose file also take for the paper's nine poses.
PAPER_POSES: Final = "paper"

#: Optional position columns of a pose file: the sensor origin, base frame [m].
_POSITION_COLUMNS: Final = ("x_m", "y_m", "z_m")
#: Rows of one pose id may differ by this much (Frobenius norm between rotation matrices; the
#: same tolerance as ``calibrate``'s) and by this much in position [m].
_SAME_ORIENTATION: Final = 1e-3
_SAME_POSITION_M: Final = 1e-4


def read_pose_file(path: str | os.PathLike[str]) -> PoseList:
    """Poses from a CSV with one orientation encoding's columns (as in the sample CSV).

    An optional ``pose`` column labels the poses; rows sharing a label are one pose (their
    mean orientation), so a sample CSV can be reused as a pose file. Optional columns
    ``x_m,y_m,z_m`` give the sensor origin in the base frame [m] (default: the collection
    position). Other columns are ignored.

    Raises:
        InputFileError: unreadable file, no or several encodings, a bad cell (file, row,
            column named).
    """
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError as exc:
        hint = ""
        if difflib.get_close_matches(Path(path).name.lower(), [PAPER_POSES], n=1, cutoff=0.6):
            hint = f" (did you mean {PAPER_POSES!r}, the paper's nine poses?)"
        raise InputFileError(f"{source}: no such pose file{hint}") from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(f"{source}: cannot read the pose file: {exc}") from exc
    try:  # a cell over csv's field limit (128 KiB) is a bad file, not a crash
        cells = list(csv.reader(text.splitlines()))
    except csv.Error as exc:
        raise InputFileError(f"{source}: not a readable pose CSV ({exc})") from None
    reader = iter(cells)
    header = [h.strip() for h in next(reader, [])]
    found: list[OrientationEncoding] = [
        enc for enc, cols in ENCODING_COLUMNS.items() if all(c in header for c in cols)
    ]
    if len(found) != 1:
        valid = "; ".join(",".join(cols) for cols in ENCODING_COLUMNS.values())
        what = "no" if not found else "more than one"
        raise InputFileError(
            f"{source}: {what} orientation encoding in the header {header}; "
            f"give exactly one of: {valid}"
        )
    encoding = found[0]
    idx = [header.index(c) for c in ENCODING_COLUMNS[encoding]]
    pose_col = header.index("pose") if "pose" in header else None
    has_position = all(c in header for c in _POSITION_COLUMNS)
    if has_position:
        idx += [header.index(c) for c in _POSITION_COLUMNS]
    width = len(ENCODING_COLUMNS[encoding])
    labels: list[str] = []
    values: list[list[float]] = []
    for row_no, row in enumerate(reader, start=1):
        if not row or all(not cell.strip() for cell in row):
            continue
        if len(row) < len(header):
            raise InputFileError(
                f"{source}: row {row_no} has {len(row)} cells, the header has {len(header)}"
            )
        try:
            values.append([float(row[i]) for i in idx])
        except ValueError:
            bad = next(i for i in idx if not _is_float(row[i]))
            raise InputFileError(
                f"{source}: row {row_no}, column {header[bad]!r}: {row[bad]!r} is not a number"
            ) from None
        labels.append(row[pose_col].strip() if pose_col is not None else str(len(labels) + 1))
    if not values:
        raise InputFileError(f"{source}: no pose rows after the header")
    table = np.array(values)
    try:
        rotations = rotation_from_encoding(encoding, table[:, :width])
    except FtcompError as exc:
        raise InputFileError(f"{source}: {exc}") from exc
    positions = table[:, width:] if has_position else None
    order = list(dict.fromkeys(labels))
    if len(order) == len(labels):
        return PoseList(tuple(labels), rotations, source, positions)
    # One rule with `calibrate`: rows that share a pose id are readings at one pose, so they
    # must agree on where that pose is; the pose is visited once, as given.
    label_arr = np.array(labels)
    matrices = rotations.as_matrix()
    first_rows = []
    for label in order:
        rows = np.flatnonzero(label_arr == label)
        spread = np.linalg.norm(matrices[rows] - matrices[rows[0]], axis=(1, 2))
        moved = (
            np.zeros(len(rows), dtype=bool)
            if positions is None
            else np.any(np.abs(positions[rows] - positions[rows[0]]) > _SAME_POSITION_M, axis=1)
        )
        mismatch = np.flatnonzero((spread > _SAME_ORIENTATION) | moved)
        if mismatch.size:
            raise InputFileError(
                f"{source}: pose {label!r} is given twice at different poses (rows "
                f"{rows[0] + 1} and {rows[mismatch[0]] + 1}); one pose id must be one pose"
            )
        first_rows.append(int(rows[0]))
    kept = positions[first_rows] if positions is not None else None
    return PoseList(tuple(order), rotations[first_rows], source, kept)


def _is_float(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True
