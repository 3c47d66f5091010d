"""Read-only numpy arrays for frozen records.

``@dataclass(frozen=True)`` stops attribute assignment but not writes into a numpy array the
record holds. Every frozen record of ftcomp keeps its arrays through :func:`frozen_array`: a
private copy, checked for shape, marked read-only.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.errors import ParameterError

__all__ = ["freeze_field", "frozen_array"]


def frozen_array(
    value: ArrayLike,
    shape: tuple[int, ...] | None = None,
    *,
    name: str = "array",
    dtype: Any = float,
    finite: bool = False,
) -> NDArray[Any]:
    """A read-only copy of ``value``.

    Args:
        value: anything :func:`numpy.array` accepts.
        shape: the required shape, or None for any.
        name: names the value in an error message.
        dtype: the array's type (float by default).
        finite: also require every element to be finite.

    Raises:
        ParameterError: wrong shape, or a non-finite element when ``finite``.
    """
    arr = np.array(value, dtype=dtype)
    if shape is not None and arr.shape != shape:
        raise ParameterError(f"{name} must have shape {shape}, got {arr.shape}")
    if finite and not np.isfinite(arr).all():
        raise ParameterError(f"{name} must be finite, got {arr.tolist()}")
    arr.setflags(write=False)
    return arr


def freeze_field(
    record: object,
    field_name: str,
    shape: tuple[int, ...] | None = None,
    *,
    dtype: Any = float,
    finite: bool = False,
) -> None:
    """Replace ``record.field_name`` (of a frozen dataclass) by its :func:`frozen_array`."""
    # Hot path (a sample per control cycle): the name is built only for an error message.
    arr = np.array(getattr(record, field_name), dtype=dtype)
    if (shape is not None and arr.shape != shape) or (finite and not np.isfinite(arr).all()):
        name = f"{type(record).__name__}.{field_name}"
        frozen_array(arr, shape, name=name, dtype=dtype, finite=finite)  # raises
    arr.setflags(write=False)
    object.__setattr__(record, field_name, arr)
