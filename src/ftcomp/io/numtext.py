"""Numbers to CSV text fast: every value as C's ``% .9e``, ten significant digits.

Formatting floats one by one costs about 0.5 us each in Python and 0.2 us in pyarrow's cast on
this project's machines; a long recording's contact wrench is millions of them. Here a value is
always 16 characters (``" 1.963732017e+00"``, ``"-3.365059045e-03"``: a space or minus sign, one
digit, a point, nine digits, a two-digit exponent), so a whole block is built as fixed-width
records with a few dozen numpy operations on cache-sized pieces and no per-value Python.

The digits are those of ``round(|x| * 10**(9 - e))`` in float arithmetic: correctly rounded
except within about 1e-6 of a tie, where the last digit may differ by one from C's. Blocks
holding a value that does not fit the fixed width (non-finite, or ``|exponent| >= 100``) are
formatted by Python's ``%`` operator instead, with the same format. The sign of zero is not
kept (``-0.0`` is written as `` 0.000000000e+00``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["FIELD_WIDTH", "format_rows"]

#: Bytes per value: the separator ``,`` and 16 characters of ``% .9e``.
FIELD_WIDTH = 17
_PIECE_ROWS = 4096  # rows formatted at a time: keeps the temporaries in the CPU cache

_POW10 = np.array([10.0**k for k in range(-110, 111)])  # _POW10[k + 110] = 10**k
_TIE = 0.5 - 4e-6  # |y - rint(y)| beyond this: too close to a tie for float arithmetic


def _tables() -> tuple[NDArray[np.uint64], NDArray[np.uint64], NDArray[np.uint64], NDArray]:
    five = np.frombuffer(b"".join(b"%05d" % i for i in range(100_000)), dtype=np.uint8)
    five = five.reshape(-1, 5).astype(np.uint64)
    shifts = np.arange(5, dtype=np.uint64) * np.uint64(8)
    # Bytes 0-7 of a field: "," sign d0 "." d1 d2 d3 d4 (the first character in the lowest byte
    # of a little-endian word); indexed by the first five digits, negative index = minus sign.
    head = (five[:, 1:] << (shifts[:4] + np.uint64(32))).sum(axis=1, dtype=np.uint64)
    head += five[:, 0] << np.uint64(16)
    head += np.uint64(0x2C | 0x2E << 24)
    signed = np.concatenate([head + np.uint64(0x20 << 8), head + np.uint64(0x2D << 8)])
    signed[100_001:] = signed[199_999:100_000:-1]  # signed[-k] is -k
    # Bytes 8-15: d5 d6 d7 d8 d9 "e" sign e1, by the last five digits and the exponent + 99;
    # byte 16: e0, by the exponent + 99.
    tail = (five << shifts).sum(axis=1, dtype=np.uint64) + np.uint64(0x65 << 40)
    exponents = np.arange(-99, 100)
    sign = np.where(exponents < 0, 0x2D, 0x2B).astype(np.uint64) << np.uint64(48)
    tens = (np.abs(exponents) // 10 + 0x30).astype(np.uint64) << np.uint64(56)
    ones = (np.abs(exponents) % 10 + 0x30).astype(np.uint8)
    return signed, tail, sign + tens, ones


_HEAD, _TAIL, _EXP_WORD, _EXP_LAST = _tables()
_RECORD = np.dtype(
    {
        "names": ["a", "b", "c"],
        "formats": ["<u8", "<u8", "u1"],
        "offsets": [0, 8, 16],
        "itemsize": 17,
    }
)


def _fill(x: NDArray[np.float64], out: NDArray[np.void]) -> bool:
    """Write the records of ``x`` (flat) into ``out`` (same size); False if one does not fit."""
    a = np.abs(x)
    if not np.isfinite(a).all():
        return False
    nonzero = a > 0.0
    e = np.floor(np.log10(a, where=nonzero, out=np.zeros_like(a))).astype(np.int64)
    if e.size and (e.min() < -100 or e.max() > 100):
        return False
    y = a * _POW10[119 - e]  # a * 10**(9 - e): ten digits before the point
    near_tie = np.abs(y - np.rint(y)) > _TIE
    # log10 may be off by one next to a power of ten, and rounding may carry to 1e10.
    e += y >= 1e10 - 0.5
    e -= (y < 1e9 - 0.5) & nonzero
    if e.size and (e.min() < -99 or e.max() > 99):
        return False
    np.multiply(a, _POW10[119 - e], out=y)
    m = np.rint(y)
    near_tie |= np.abs(y - m) > _TIE
    head = np.floor(m / 1e5)
    m -= head * 1e5
    out["a"] = _HEAD[np.copysign(head, x).astype(np.intp)]
    e += 99
    word = _TAIL[m.astype(np.intp)]
    word += _EXP_WORD[e]
    out["b"] = word
    out["c"] = _EXP_LAST[e]
    for i in np.flatnonzero(near_tie).tolist():  # about one value in 100,000: C's own rounding
        out[i] = np.frombuffer(b",% .9e" % x[i], dtype=_RECORD)[0]
    return True


def _format_python(values: NDArray[np.float64]) -> list[bytes]:
    row_format = ",% .9e" * values.shape[1]
    return [(row_format % tuple(row)).encode("ascii") for row in values.tolist()]


def format_rows(values: ArrayLike) -> tuple[NDArray[np.uint8], NDArray[np.int64]]:
    """Each row of ``values`` as CSV text ``,v1,v2,...`` (a separator before every value).

    Args:
        values: shape (N, K), any floats.

    Returns:
        ``(text, offsets)``: row ``i`` is ``text[offsets[i]:offsets[i + 1]]`` (ASCII, no line
        end); ``offsets`` has N + 1 entries. Rows are ``17 * K`` bytes unless a value does not
        fit ``% .9e`` in 16 characters (non-finite, exponent beyond +-99).
    """
    arr = np.ascontiguousarray(values, dtype=np.float64)
    n, k = arr.shape
    width = FIELD_WIDTH * k
    text = np.empty((n, width), dtype=np.uint8)
    records = text.view(_RECORD).reshape(n, k)
    flat = arr.reshape(-1)
    misfits = [
        start
        for start in range(0, n, _PIECE_ROWS)
        if not _fill(
            flat[start * k : (start + _PIECE_ROWS) * k],
            records[start : start + _PIECE_ROWS].reshape(-1),
        )
    ]
    if not misfits:
        return text.reshape(-1), np.arange(n + 1, dtype=np.int64) * width
    rows: list[bytes] = [row.tobytes() for row in text]
    for start in misfits:
        rows[start : start + _PIECE_ROWS] = _format_python(arr[start : start + _PIECE_ROWS])
    lengths = np.fromiter((len(r) for r in rows), dtype=np.int64, count=n)
    offsets = np.concatenate([np.zeros(1, dtype=np.int64), np.cumsum(lengths)])
    return np.frombuffer(b"".join(rows), dtype=np.uint8), offsets
