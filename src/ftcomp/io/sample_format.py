"""The sample file format and every check of it, in one place, for CSV and Parquet alike.

Columns: ``fx,fy,fz,tx,ty,tz`` (N, N*m, sensor frame); exactly one orientation encoding of
``R_base_sensor`` (``qx,qy,qz,qw`` | ``rx,ry,rz`` [rad] | ``alpha_deg,beta_deg,gamma_deg``, see
:mod:`ftcomp.frames`); optional ``pose`` (an id: rows with the same id are readings at one pose)
and ``t`` [s]; any other column is carried along and otherwise ignored.

The readers (:mod:`ftcomp.io.samples_csv`, :mod:`ftcomp.io.parquet`) check whole blocks of rows
at once with numpy and only when a block fails do they look for the first bad cell, with the
rules here, to name its row and column: a message costs nothing until a cell is bad.

**Numbers** are decimal: an optional sign, digits with an optional point, an optional exponent
(``12``, ``-0.5``, ``.5``, ``3.``, ``1e-3``), with spaces around allowed. Python's ``float``
accepts more (``3_3445`` as 33445, ``١٢``, ``infinity``); those are errors here, and ``nan`` and
``inf`` are read only to be rejected as not finite.

**Limits.** A force beyond 1e6 N or a torque beyond 1e5 N*m is no sensor's reading (an error
without a sensor range too; :mod:`ftcomp.constants`). Lines are bounded
(:mod:`ftcomp.io.chunks`); the header must be the first line (a blank first line is an error).
"""

from __future__ import annotations

import difflib
import math
import re
import sys
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.constants import PLAUSIBLE_FORCE_N, PLAUSIBLE_TORQUE_NM
from ftcomp.errors import InputFileError
from ftcomp.frames import ENCODING_COLUMNS, OrientationEncoding
from ftcomp.samples import WRENCH_COLUMNS

__all__ = [
    "MAX_ORIENTATION_VALUE",
    "OrientationCheck",
    "SampleBlock",
    "SampleLayout",
    "check_header",
    "check_row_limits",
    "check_values",
    "first_bad_value",
    "parse_number",
]

_OTHER_DELIMITERS = (";", "\t", "|")
_SUGGEST_MAX_COLUMNS = 1000  # beyond, no spelling suggestions (difflib is slow on wide headers)
_QUATERNION_NORM_TOLERANCE = 0.01
#: An orientation value (quaternion component, rad or deg) beyond +-this is none.
MAX_ORIENTATION_VALUE = 1e6
#: A number as the sample files write it (see the module docstring); nan/inf only to reject.
_NUMBER = re.compile(
    r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|inf|infinity|nan)",
    re.IGNORECASE | re.ASCII,
)


def _suggest(name: str, header: Sequence[str]) -> str:
    if len(header) > _SUGGEST_MAX_COLUMNS:
        return ""
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
    for col in (c for cols in ENCODING_COLUMNS.values() for c in cols):
        suggestion = _suggest(col, header)
        if suggestion:
            hint = f"; for {col!r}{suggestion}"
            break
    raise InputFileError(f"{where}: no orientation columns; give one of {options}{hint}")


@dataclass(frozen=True)
class SampleLayout:
    """A sample file's columns, checked: where each quantity is and which limits apply.

    Attributes:
        source: the file, for messages.
        header: the column names, stripped, in file order.
        encoding: the orientation encoding present.
        numeric: the columns read as numbers, in the order of checks and of ``values`` arrays:
            the wrench, the orientation, then ``t`` if present.
        force_range_N, torque_range_Nm: a reading beyond +- these is an error (None: no limit).
    """

    source: str
    header: tuple[str, ...]
    encoding: OrientationEncoding
    numeric: tuple[str, ...]
    force_range_N: float | None = None
    torque_range_Nm: float | None = None
    index: dict[str, int] = field(init=False, repr=False, compare=False)
    limits: list[tuple[float, str, str]] = field(init=False, repr=False, compare=False)
    bounds: NDArray[np.float64] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "index", {name: i for i, name in enumerate(self.header)})
        object.__setattr__(self, "limits", _limits(self))
        object.__setattr__(self, "bounds", np.array([limit for limit, _, _ in self.limits]))

    @property
    def has_pose(self) -> bool:
        """Whether a ``pose`` column groups the rows."""
        return "pose" in self.index

    @property
    def has_t(self) -> bool:
        """Whether a ``t`` [s] column is present."""
        return "t" in self.index


def check_header(
    header: Sequence[str],
    source: str,
    *,
    where: str,
    force_range_N: float | None = None,
    torque_range_Nm: float | None = None,
) -> SampleLayout:
    """Check the column names; ``where`` names them in messages (``"f.csv, header (line 1)"``).

    Raises:
        InputFileError: wrong delimiter, a duplicated or missing column, no or two encodings.
    """
    names = tuple(name.strip() for name in header)
    if len(names) == 1:
        for delim in _OTHER_DELIMITERS:
            if delim in names[0]:
                raise InputFileError(
                    f"{where}: one column {names[0][:40]!r}; the delimiter must be ',' "
                    f"(found {delim!r})"
                )
    duplicates = sorted(name for name, n in Counter(names).items() if n > 1 and name)
    if duplicates:
        raise InputFileError(f"{where}: column {duplicates[0]!r} appears more than once")
    for name in WRENCH_COLUMNS:
        if name not in names:
            # Suggest only a column ftcomp does not read otherwise ('t' is a time, not 'tz').
            known = {*WRENCH_COLUMNS, *(c for cs in ENCODING_COLUMNS.values() for c in cs)}
            others = [n for n in names if n not in known | {"t", "t_ns", "pose"}]
            found = [c for c in WRENCH_COLUMNS if c in names]
            raise InputFileError(
                f"{where}: missing column {name!r}{_suggest(name, others)}: the wrench is the "
                f"six columns {','.join(WRENCH_COLUMNS)} [N, N*m] in the sensor frame"
                + (f" (found {','.join(found)})" if found else "")
            )
    encoding = _find_encoding(names, where)
    numeric = (*WRENCH_COLUMNS, *ENCODING_COLUMNS[encoding], *(("t",) if "t" in names else ()))
    return SampleLayout(source, names, encoding, numeric, force_range_N, torque_range_Nm)


def parse_number(cell: str, where: str) -> float:
    """One cell as a finite number, by the rule of the module docstring.

    Raises:
        InputFileError: ``"<where>: 'x' is not a number"`` or ``"<where>: nan is not finite"``.
    """
    text = cell.strip()
    if not _NUMBER.fullmatch(text):
        raise InputFileError(f"{where}: {text!r} is not a number")
    value = float(text)
    if not math.isfinite(value):
        raise InputFileError(f"{where}: {text} is not finite")
    return value


def _limits(layout: SampleLayout) -> list[tuple[float, str, str]]:
    """(bound, unit, what) of each numeric column: the sensor range or the plausible bound
    (wrench), :data:`MAX_ORIENTATION_VALUE`, none for ``t`` (the largest float)."""
    force = (layout.force_range_N, PLAUSIBLE_FORCE_N, " N")
    torque = (layout.torque_range_Nm, PLAUSIBLE_TORQUE_NM, " N*m")
    out = [
        (bound, unit, "any plausible F/T reading")
        if given is None
        else (given, unit, "the sensor range")
        for given, bound, unit in [force] * 3 + [torque] * 3
    ]
    out += [(MAX_ORIENTATION_VALUE, "", "any orientation value")] * len(layout.numeric[6:])
    return out[: len(layout.numeric) - layout.has_t] + [(sys.float_info.max, "", "")] * layout.has_t


def check_row_limits(values: Sequence[float], layout: SampleLayout, where: str) -> None:
    """Raise for the first of one row's numeric ``values`` (in ``layout.numeric`` order)
    beyond its limit: the sensor range or the plausible bound (wrench), or
    :data:`MAX_ORIENTATION_VALUE`; ``where`` names the row in the message.

    Raises:
        InputFileError: ``"<where>, column 'fx': 2e+06 N is beyond ..."``.
    """
    for name, value, (limit, unit, what) in zip(layout.numeric, values, layout.limits, strict=True):
        if abs(value) > limit:
            raise InputFileError(
                f"{where}, column {name!r}: {value:g}{unit} is beyond {what} +-{limit:g}{unit}"
            )


def check_values(values: NDArray[np.float64], layout: SampleLayout) -> bool:
    """Whether a block of ``values`` (N, len(layout.numeric)) passes every value check at once:
    all finite and within the limits. When it does not, the reader names the first bad cell
    with :func:`ftcomp.io.samples_csv.parse_rows` (CSV, with line numbers) or
    :func:`first_bad_value`."""
    return bool((np.abs(values) <= layout.bounds).all())


def first_bad_value(values: NDArray[np.float64], layout: SampleLayout, first_row: int) -> None:
    """Raise for the first row of ``values`` (row-major, then column order) that fails
    :func:`check_values` (for files without line numbers, e.g. Parquet)."""
    for i in np.flatnonzero(~(np.abs(values) <= layout.bounds).all(axis=1)):
        where = f"{layout.source}, row {first_row + int(i)}"
        for name, value in zip(layout.numeric, values[i].tolist(), strict=True):
            if not math.isfinite(value):
                raise InputFileError(f"{where}, column {name!r}: {value} is not finite")
        check_row_limits(values[i].tolist(), layout, where)


@dataclass(frozen=True)
class SampleBlock:
    """Consecutive rows of a sample file, checked, with their orientations.

    Attributes:
        first_row: data-row number of the first row (1 = first after the header).
        wrench_sensor: [N, N*m], sensor frame, (N, 6).
        R_base_sensor: (N, 3, 3).
        t: time stamps [s], (N,), or None.
        pose: pose ids, (N,), or None.
        text: the rows as CSV lines ending in ``\\n`` (as read, for writing them back out), or
            None when not asked for.
        text_ends: the position of each ``\\n`` in ``text`` (one per row unless a quoted cell
            spans lines).
        table: every input column as a ``pyarrow.Table`` (when the reader was asked for it).
        byte_range: where the rows lie in the file (CSV only).
    """

    first_row: int
    wrench_sensor: NDArray[np.float64]
    R_base_sensor: NDArray[np.float64]
    t: NDArray[np.float64] | None = None
    pose: NDArray[np.str_] | None = None
    text: bytes | None = None
    text_ends: NDArray[np.intp] | None = None
    table: Any = None
    byte_range: tuple[int, int] | None = None

    def __len__(self) -> int:
        return len(self.wrench_sensor)


class OrientationCheck:
    """Turns each block's orientation values into ``R_base_sensor``, checking them.

    A zero-norm quaternion is an error at once; quaternions off unit norm and paper angles that
    look like radians are counted over the whole file and reported by :attr:`warnings`.
    """

    def __init__(self, layout: SampleLayout) -> None:
        self.layout = layout
        self._off_norm = 0
        self._first_off: tuple[int, float] | None = None
        self._max_abs_angle = 0.0
        self._first_long_rotvec: tuple[int, float] | None = None

    def rotations(self, orient: NDArray[np.float64], first_row: int) -> NDArray[np.float64]:
        """``R_base_sensor`` (N, 3, 3) of a block's orientation values (N, k)."""
        encoding = self.layout.encoding
        if encoding == "quaternion":
            norms = np.linalg.norm(orient, axis=1)
            zero = np.flatnonzero(norms < 1e-12)
            if zero.size:
                raise InputFileError(
                    f"{self.layout.source}, row {first_row + int(zero[0])}, columns "
                    "qx,qy,qz,qw: zero-norm quaternion"
                )
            off = np.flatnonzero(np.abs(norms - 1.0) > _QUATERNION_NORM_TOLERANCE)
            if off.size and self._first_off is None:
                self._first_off = (first_row + int(off[0]), float(norms[off[0]]))
            self._off_norm += off.size
            rotations = Rotation.from_quat(orient)
        elif encoding == "rotvec":
            norms = np.linalg.norm(orient, axis=1)
            long = np.flatnonzero(norms > math.pi + 1e-3)  # degrees?
            if long.size and self._first_long_rotvec is None:
                self._first_long_rotvec = (first_row + int(long[0]), float(norms[long[0]]))
            rotations = Rotation.from_rotvec(orient)
        else:
            self._max_abs_angle = max(self._max_abs_angle, float(np.abs(orient).max(initial=0.0)))
            rotations = Rotation.from_euler("ZYX", orient, degrees=True)
        return np.asarray(rotations.as_matrix(), dtype=float).reshape(-1, 3, 3)

    @property
    def warnings(self) -> tuple[str, ...]:
        """What looked wrong but was accepted, over every block seen so far."""
        source = self.layout.source
        out = []
        if self._first_off is not None:
            row, norm = self._first_off
            out.append(
                f"{source}: {self._off_norm} quaternion(s) not of unit norm (row {row}: "
                f"{norm:.4g}); normalised"
            )
        if 0.0 < self._max_abs_angle <= math.pi + 1e-3:  # radians, rounded
            out.append(
                f"{source}: every alpha_deg, beta_deg, gamma_deg is within +-pi: were the "
                "angles given in radians? They are read as degrees"
            )
        if self._first_long_rotvec is not None:
            row, norm = self._first_long_rotvec
            out.append(
                f"{source}: columns rx,ry,rz: a rotation vector longer than pi (row {row}: "
                f"norm {norm:.4g}): were they given in degrees? They are read as radians"
            )
        return tuple(out)
