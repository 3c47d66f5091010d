"""Configuration fields that carry their own rules: unit, range or choices, help, default.

A typed config (a frozen dataclass) declares each checked field once with :func:`param`; its
``__post_init__`` calls :func:`check_fields`, and a bad value raises
:class:`~ftcomp.errors.ParameterError` whose ``field`` names the field (the message names it
too, never a command-line flag). The CLI reads the same declaration (:func:`spec_of`) to build
an option (its help, unit and default), checks the option's value by the same rule in its own
unit, and maps an error on a field back to the flag that set it. So a range, a limit or a
choice list is written once, here in the config, and nowhere in ``cli/``::

    @dataclass(frozen=True)
    class RunConfig:
        duration_s: float = param(30.0, gt=0.0, unit="s", help="the longest run")
        law: str = param("combined", choices=LAWS, help="the admittance law")

        def __post_init__(self) -> None:
            check_fields(self)

A field of a sequence (``length=6``) is checked element by element and stored as a tuple of
floats; ``optional=True`` lets None through (e.g. "no check"). This module imports nothing but
the standard library and :mod:`ftcomp.errors`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from ftcomp.errors import ParameterError

__all__ = ["FieldSpec", "check_fields", "check_value", "param", "spec_of", "specs_of"]

#: The key of a field's :class:`FieldSpec` in its ``dataclasses.field`` metadata.
_KEY = "ftcomp.field_spec"


@dataclass(frozen=True)
class FieldSpec:
    """The rules of one config field.

    Attributes:
        help: what the field is, one phrase, no unit and no default (both are added where the
            phrase is shown).
        unit: its SI unit as text (``"m/s"``, ``"N*m"``; "" for a count or a name).
        gt, ge, lt, le: the bounds of its range (None: unbounded on that side); a number
            outside them, or not finite, is refused.
        choices: the names it may take (None: not a choice).
        integer: it counts something (an ``int``, not a ``bool``).
        length: a sequence of this many numbers, each checked (None: one value).
        allow_inf: infinity is a valid value (no limit); NaN never is.
        optional: None is allowed (and means what the config's docstring says).
    """

    help: str
    unit: str = ""
    gt: float | None = None
    ge: float | None = None
    lt: float | None = None
    le: float | None = None
    choices: tuple[str, ...] | None = None
    integer: bool = False
    length: int | None = None
    allow_inf: bool = False
    optional: bool = False

    def rule(self, scale: float = 1.0, unit: str | None = None) -> str:
        """The valid values as text (``"> 0 m/s"``, ``"in (0, 60] s"``, ``"one of a, b"``),
        with the bounds divided by ``scale`` and shown in ``unit`` (default: the field's own:
        the CLI shows ``mm/s`` with ``scale=1e-3``)."""
        if self.choices is not None:
            return "one of " + ", ".join(self.choices)
        unit = self.unit if unit is None else unit
        suffix = f" {unit}" if unit else ""
        low = self.gt if self.gt is not None else self.ge
        high = self.lt if self.lt is not None else self.le
        if low is not None and high is not None:
            if self.gt is not None and self.lt is not None and self.gt == -self.lt:
                return f"within +-{_num(high / scale)}{suffix}"
            left, right = "(" if self.gt is not None else "[", ")" if self.lt is not None else "]"
            return f"in {left}{_num(low / scale)}, {_num(high / scale)}{right}{suffix}"
        if low is not None:
            return f"{'>' if self.gt is not None else '>='} {_num(low / scale)}{suffix}"
        if high is not None:
            return f"{'<' if self.lt is not None else '<='} {_num(high / scale)}{suffix}"
        return "a number" if self.allow_inf else "finite"

    def problem(self, value: object) -> str | None:
        """Why one value (of a scalar field, or one element of a sequence) breaks the rule, or
        None when it keeps it."""
        if self.choices is not None:
            return None if value in self.choices else f"must be {self.rule()}"
        if isinstance(value, str) and not self.numeric:
            return None  # free text (checked by the config itself, e.g. an axis list)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            kind = "an integer" if self.integer else "a number"
            return f"must be {kind} {self.rule()}"
        if self.integer and not isinstance(value, int):
            return f"must be an integer {self.rule()}"
        x = float(value)
        if math.isnan(x) or (math.isinf(x) and not self.allow_inf) or not self._in_range(x):
            return f"must be {self.rule()}"
        return None

    @property
    def numeric(self) -> bool:
        """Whether the field holds numbers (a range, a count or a vector)."""
        bounds = (self.gt, self.ge, self.lt, self.le)
        return self.integer or self.length is not None or any(b is not None for b in bounds)

    def _in_range(self, x: float) -> bool:
        return not (
            (self.gt is not None and not x > self.gt)
            or (self.ge is not None and not x >= self.ge)
            or (self.lt is not None and not x < self.lt)
            or (self.le is not None and not x <= self.le)
        )


def _num(x: float) -> str:
    return f"{x:g}"


def param(
    default: Any = dataclasses.MISSING,
    *,
    help: str,
    unit: str = "",
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    choices: Sequence[str] | None = None,
    integer: bool = False,
    length: int | None = None,
    allow_inf: bool = False,
    optional: bool = False,
) -> Any:
    """A dataclass field with its rules (:class:`FieldSpec`); ``default`` as for
    ``dataclasses.field`` (omit it for a required field)."""
    spec = FieldSpec(
        help=help,
        unit=unit,
        gt=gt,
        ge=ge,
        lt=lt,
        le=le,
        choices=None if choices is None else tuple(choices),
        integer=integer,
        length=length,
        allow_inf=allow_inf,
        optional=optional,
    )
    return dataclasses.field(default=default, metadata={_KEY: spec})


def spec_of(config: type | object, name: str) -> FieldSpec:
    """The rules of field ``name`` of a config class (or instance).

    Raises:
        KeyError: the field has none.
    """
    for f in dataclasses.fields(config):  # type: ignore[arg-type]
        if f.name == name and _KEY in f.metadata:
            spec: FieldSpec = f.metadata[_KEY]
            return spec
    raise KeyError(f"{getattr(config, '__name__', type(config).__name__)}.{name} has no rules")


def specs_of(config: type | object) -> dict[str, FieldSpec]:
    """Every declared field's rules, by field name, in declaration order."""
    return {
        f.name: f.metadata[_KEY]
        for f in dataclasses.fields(config)  # type: ignore[arg-type]
        if _KEY in f.metadata
    }


def check_value(name: str, spec: FieldSpec, value: object) -> object:
    """``value`` checked against ``spec`` (a sequence as a tuple of floats).

    Raises:
        ParameterError: naming ``name`` (its ``field``), the value and the valid range.
    """
    if value is None and spec.optional:
        return None
    if spec.length is None:
        reason = spec.problem(value)
        if reason is not None:
            raise ParameterError(f"{name} {reason}, got {_show(value)}", field=name)
        return value
    items = _items(value)
    if items is None or len(items) != spec.length:
        raise ParameterError(
            f"{name} needs {spec.length} values {spec.rule()}, got {_show(value)}", field=name
        )
    for item in items:
        reason = spec.problem(item)
        if reason is not None:
            raise ParameterError(
                f"{name} {reason} on every axis, got {_show(list(items))}", field=name
            )
    numbers: list[Any] = items  # each checked to be a number above
    return tuple(int(v) if spec.integer else float(v) for v in numbers)


def check_fields(config: object, names: Iterable[str] | None = None) -> None:
    """Check every declared field of a dataclass instance (or only ``names``), storing a
    sequence as a tuple (for a frozen dataclass too); call it from ``__post_init__``.

    Raises:
        ParameterError: the first field that breaks its rule, naming it.
    """
    specs = specs_of(config)
    for name in specs if names is None else names:
        spec = specs[name]
        value = getattr(config, name)
        checked = check_value(name, spec, value)
        if spec.length is not None and checked is not value:
            object.__setattr__(config, name, checked)


def _items(value: object) -> list[object] | None:
    if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
        return None
    items = list(value)
    if any(hasattr(v, "__len__") for v in items):  # nested: not a flat vector
        return None
    return [v.item() if hasattr(v, "item") else v for v in items]  # numpy scalars


def _show(value: object) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_show(v) for v in value) + "]"
    if hasattr(value, "tolist"):
        return _show(value.tolist())
    return repr(value)
