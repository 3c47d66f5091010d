"""The sample CSV: F/T readings with the sensor's orientation, one row per reading.

Format: a header row; columns ``fx,fy,fz,tx,ty,tz`` (N, N*m, sensor frame); exactly one
orientation encoding of ``R_base_sensor`` (``qx,qy,qz,qw`` | ``rx,ry,rz`` [rad] |
``alpha_deg,beta_deg,gamma_deg``, see :mod:`ftcomp.frames`); optional ``pose`` (an id: rows with
the same id are readings at one pose) and ``t`` [s]; any other column is carried along and
otherwise ignored. Comma-delimited, UTF-8.

Every problem is reported as one :class:`~ftcomp.errors.InputFileError` naming the file, the data
row (1 = first row after the header), the line and the column.
"""

from __future__ import annotations

import csv
import difflib
import io
import math
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from ftcomp.errors import InputFileError, ParameterError
from ftcomp.frames import ENCODING_COLUMNS, OrientationEncoding, encode_orientation
from ftcomp.io.atomic import atomic_write_text
from ftcomp.samples import WRENCH_COLUMNS, Samples

__all__ = ["read_samples", "write_samples", "write_table"]

_OTHER_DELIMITERS = (";", "\t", "|")
_QUATERNION_NORM_TOLERANCE = 0.01


def _suggest(name: str, header: Sequence[str]) -> str:
    lowered = {h.lower(): h for h in header}
    if name in lowered and lowered[name] != name:
        return f" (found {lowered[name]!r}: column names are case-sensitive)"
    close = difflib.get_close_matches(name, header, n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _find_encoding(header: Sequence[str], where: str) -> OrientationEncoding:
    present = set(header)
    complete = [enc for enc, cols in ENCODING_COLUMNS.items() if present.issuperset(cols)]
    if len(complete) > 1:
        names = " and ".join(f"{enc} ({','.join(ENCODING_COLUMNS[enc])})" for enc in complete)
        raise InputFileError(f"{where}: two orientation encodings at once, {names}: keep one")
    if complete:
        return complete[0]
    for enc, cols in ENCODING_COLUMNS.items():
        found = [c for c in cols if c in present]
        if found:
            missing = next(c for c in cols if c not in present)
            raise InputFileError(
                f"{where}: missing column {missing!r} of the {enc} orientation "
                f"({','.join(cols)}){_suggest(missing, header)}"
            )
    options = " | ".join(",".join(cols) for cols in ENCODING_COLUMNS.values())
    hint = ""
    for cols in ENCODING_COLUMNS.values():
        for col in cols:
            suggestion = _suggest(col, header)
            if suggestion:
                hint = f"; for {col!r}{suggestion}"
                break
        if hint:
            break
    raise InputFileError(f"{where}: no orientation columns; give one of {options}{hint}")


def _cell_value(cell: str, where: str) -> float:
    try:
        value = float(cell)
    except ValueError:
        raise InputFileError(f"{where}: {cell.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise InputFileError(f"{where}: {cell.strip()} is not finite")
    return value


def read_samples(
    path: str | os.PathLike[str],
    *,
    force_range_N: float | None = None,
    torque_range_Nm: float | None = None,
) -> Samples:
    """Read and check a sample CSV.

    Args:
        path: the CSV file.
        force_range_N: if given, a force reading beyond +-this [N] is an error (saturated sensor).
        torque_range_Nm: if given, a torque reading beyond +-this [N*m] is an error.

    Raises:
        InputFileError: naming file, row, line and column of the first problem found.
    """
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise InputFileError(f"{source}: no such file") from None
    except IsADirectoryError:
        raise InputFileError(f"{source}: is a directory, expected a CSV file") from None
    except UnicodeDecodeError as exc:
        raise InputFileError(f"{source}: not UTF-8 text ({exc.reason})") from None
    except OSError as exc:
        raise InputFileError(f"{source}: cannot read ({exc.strerror})") from None
    if not text.strip():
        raise InputFileError(
            f"{source}: empty file; expected a header with {','.join(WRENCH_COLUMNS)} "
            "and one orientation encoding"
        )

    reader = csv.reader(io.StringIO(text))
    raw_header = next(reader)
    header = tuple(name.strip() for name in raw_header)
    where = f"{source}, header (line 1)"
    if len(header) == 1:
        for delim in _OTHER_DELIMITERS:
            if delim in header[0]:
                raise InputFileError(
                    f"{where}: one column {header[0][:40]!r}; the delimiter must be ',' "
                    f"(found {delim!r})"
                )
    duplicates = sorted({name for name in header if header.count(name) > 1 and name})
    if duplicates:
        raise InputFileError(f"{where}: column {duplicates[0]!r} appears more than once")
    for name in WRENCH_COLUMNS:
        if name not in header:
            raise InputFileError(f"{where}: missing column {name!r}{_suggest(name, header)}")
    encoding = _find_encoding(header, where)
    orientation_cols = ENCODING_COLUMNS[encoding]
    index = {name: i for i, name in enumerate(header)}
    numeric_cols = (*WRENCH_COLUMNS, *orientation_cols, *(("t",) if "t" in index else ()))

    rows: list[tuple[str, ...]] = []
    values: list[list[float]] = []
    poses: list[str] = []
    for cells in reader:
        if not cells or all(not c.strip() for c in cells):
            continue
        row_no = len(rows) + 1
        line = reader.line_num
        if len(cells) != len(header):
            raise InputFileError(
                f"{source}, row {row_no} (line {line}): {len(cells)} cells but the header "
                f"has {len(header)} columns"
            )
        parsed = [
            _cell_value(cells[index[c]], f"{source}, row {row_no} (line {line}), column {c!r}")
            for c in numeric_cols
        ]
        if "pose" in index:
            pose_id = cells[index["pose"]].strip()
            if not pose_id:
                raise InputFileError(
                    f"{source}, row {row_no} (line {line}), column 'pose': empty pose id"
                )
            poses.append(pose_id)
        for col, limit in (("f", force_range_N), ("t", torque_range_Nm)):
            if limit is None:
                continue
            for axis, value in zip("xyz", parsed[(0 if col == "f" else 3) :][:3], strict=True):
                if abs(value) > limit:
                    unit = "N" if col == "f" else "N*m"
                    raise InputFileError(
                        f"{source}, row {row_no} (line {line}), column '{col}{axis}': "
                        f"{value:g} {unit} is beyond the sensor range +-{limit:g} {unit}"
                    )
        rows.append(tuple(cells))
        values.append(parsed)
    if not rows:
        raise InputFileError(f"{source}: a header but no data rows")

    data = np.array(values)
    wrench = data[:, :6]
    orient = data[:, 6 : 6 + len(orientation_cols)]
    t = data[:, -1] if "t" in index else None
    warnings: list[str] = []
    if encoding == "quaternion":
        norms = np.linalg.norm(orient, axis=1)
        bad = np.flatnonzero(norms < 1e-12)
        if bad.size:
            raise InputFileError(
                f"{source}, row {bad[0] + 1}, columns qx,qy,qz,qw: zero-norm quaternion"
            )
        off = np.flatnonzero(np.abs(norms - 1.0) > _QUATERNION_NORM_TOLERANCE)
        if off.size:
            warnings.append(
                f"{source}: {off.size} quaternion(s) not of unit norm (row {off[0] + 1}: "
                f"{norms[off[0]]:.4g}); normalised"
            )
        rotations = Rotation.from_quat(orient)
    elif encoding == "rotvec":
        rotations = Rotation.from_rotvec(orient)
    else:
        if 0.0 < np.max(np.abs(orient)) <= math.pi + 1e-3:  # radians, rounded
            warnings.append(
                f"{source}: every alpha_deg, beta_deg, gamma_deg is within +-pi: were the "
                "angles given in radians? They are read as degrees"
            )
        rotations = Rotation.from_euler("ZYX", orient, degrees=True)
    return Samples(
        wrench_sensor=wrench,
        R_base_sensor=rotations.as_matrix().reshape(-1, 3, 3),
        encoding=encoding,
        pose=np.array(poses) if "pose" in index else None,
        t=t,
        header=header,
        rows=tuple(rows),
        source=source,
        warnings=tuple(warnings),
    )


def write_table(
    path: str | os.PathLike[str], header: Sequence[str], rows: Sequence[Sequence[object]]
) -> None:
    """Write a CSV table atomically (temporary file, then rename)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
    atomic_write_text(path, buffer.getvalue())


def _fmt(value: float) -> str:
    return f"{value:.10g}"


def write_samples(
    path: str | os.PathLike[str],
    wrench_sensor: ArrayLike,
    rotations: Rotation,
    *,
    encoding: OrientationEncoding,
    pose: ArrayLike | None = None,
    t: ArrayLike | None = None,
) -> None:
    """Write readings as a sample CSV, atomically.

    Args:
        path: output file (replaced if it exists: callers decide whether that is allowed).
        wrench_sensor: [N, N*m], sensor frame, shape (N, 6).
        rotations: ``R_base_sensor`` of each row (N rotations).
        encoding: the orientation encoding to write.
        pose: optional pose id per row, shape (N,).
        t: optional time stamp per row [s], shape (N,).
    """
    wrench = np.asarray(wrench_sensor, dtype=float).reshape(-1, 6)
    orient = encode_orientation(rotations, encoding).reshape(len(wrench), -1)
    header: list[str] = []
    columns: list[list[str]] = []
    if pose is not None:
        header.append("pose")
        columns.append([str(p) for p in np.asarray(pose).ravel()])
    if t is not None:
        header.append("t")
        columns.append([_fmt(v) for v in np.asarray(t, dtype=float).ravel()])
    header.extend(ENCODING_COLUMNS[encoding])
    columns.extend([_fmt(v) for v in orient[:, j]] for j in range(orient.shape[1]))
    header.extend(WRENCH_COLUMNS)
    columns.extend([_fmt(v) for v in wrench[:, j]] for j in range(6))
    if any(len(col) != len(wrench) for col in columns):
        raise ParameterError("write_samples: pose, t and rotations must have one entry per row")
    write_table(path, header, list(zip(*columns, strict=True)))
