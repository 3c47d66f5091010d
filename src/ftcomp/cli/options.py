"""Command-line options built from config fields (:mod:`ftcomp.config_fields`).

:func:`add_field_option` adds an option whose help, unit, default and rule come from a config
class's field: the command says only how the option maps to the field (its flag, the unit it is
typed in and the factor to SI, which element of a vector it sets). ``ftcomp.cli.main`` checks
every such option by its field's rule before the command runs (:func:`check_field_options`,
one line naming the flag, exit 2), and turns a library error on a field into the same words
with the flag the user typed (:func:`error_line`). Nothing in ``cli/`` restates a range, a
limit or a choice list of the library.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from ftcomp.config_fields import FieldSpec, spec_of
from ftcomp.errors import FtcompError, ParameterError

__all__ = [
    "FieldOption",
    "add_field_option",
    "check_field_options",
    "error_line",
    "map_field",
    "map_options",
    "spec_default",
    "with_flags",
]

#: Options whose destination the library calls by another name: every ``--force`` is the
#: library's ``overwrite``.
_LIBRARY_NAMES = {"force": "overwrite"}
#: The namespace attributes holding a command's field options and its field -> flag map.
_OPTIONS, _FLAGS = "field_options", "field_flags"


@dataclass(frozen=True)
class FieldOption:
    """One option set from a config field.

    Attributes:
        dest: the namespace attribute.
        flag: the flag as typed (``--max-speed-mm-s``).
        field: the field's name (``max_twist``).
        spec: the field's rules.
        scale: the factor from the option's unit to the field's (``1e-3`` for mm -> m).
        unit: the option's unit.
        off: a value that means "no check" on the command line (None: none).
    """

    dest: str
    flag: str
    field: str
    spec: FieldSpec
    scale: float
    unit: str
    off: object = None

    def check(self, value: object) -> None:
        """Refuse a value that breaks the field's rule, in the option's own unit.

        Raises:
            ParameterError: ``--flag must be ..., got ...``.
        """
        if value is None or (self.off is not None and value == self.off):
            return
        spec = self.spec
        if spec.length is not None and isinstance(value, (list, tuple)):
            values: Sequence[object] = value
            if len(values) != spec.length:
                raise ParameterError(
                    f"{self.flag} needs {spec.length} values, got {len(values)}", field=self.field
                )
        else:
            values = [value]
        for v in values:
            scaled = v * self.scale if isinstance(v, float) else v
            if spec.problem(scaled) is not None:
                rule = spec.rule(self.scale, self.unit)
                if self.off is not None:
                    rule += f" (or {self.off}: off)"
                shown = f"{v:g}" if isinstance(v, float) else str(v)
                raise ParameterError(f"{self.flag} must be {rule}, got {shown}", field=self.field)


def _registry(parser: argparse.ArgumentParser, key: str, empty: Callable[[], Any]) -> Any:
    current = parser.get_default(key)
    if current is None:
        current = empty()
        parser.set_defaults(**{key: current})
    return current


def map_field(parser: argparse.ArgumentParser, field: str, flag: str) -> None:
    """Name ``flag`` in place of ``field`` when a library error names that field (an option
    not built by :func:`add_field_option`, e.g. ``--force`` for ``overwrite``)."""
    _registry(parser, _FLAGS, dict).setdefault(field, flag)


def map_options(parser: argparse.ArgumentParser) -> None:
    """Name each option's flag in place of the field of the same name as its destination
    (``--log`` for ``log``); an explicit :func:`map_field` or :func:`add_field_option` wins.
    ``ftcomp.cli`` calls it for the command it registers."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):  # ftcomp poses design, ...
            for sub in action.choices.values():
                map_options(sub)
        long = [o for o in action.option_strings if o.startswith("--")]
        if long and action.dest != "help":
            map_field(parser, action.dest, long[0])
            if action.dest in _LIBRARY_NAMES:
                map_field(parser, _LIBRARY_NAMES[action.dest], long[0])


def add_field_option(
    parser: argparse.ArgumentParser,
    config: type | FieldSpec,
    field: str,
    flag: str | None = None,
    *,
    scale: float = 1.0,
    unit: str | None = None,
    default: Any = dataclasses.MISSING,
    element: int | None = None,
    help: str | None = None,
    off: object = None,
    none_means: str = "none",
    **kwargs: Any,
) -> argparse.Action:
    """Add the option that sets ``config.field`` (``flag``: ``--field-name`` by default).

    Args:
        parser: the command's parser.
        config: the config class (a dataclass whose field was declared with
            :func:`ftcomp.config_fields.param`), or the rule of a function's argument.
        field: the field's name (with a rule alone: the name errors on it use).
        flag: the option's flag.
        scale: the factor from the option's unit to the field's [SI per option unit].
        unit: the option's unit (default: the field's).
        default: the option's default in its unit (default: the field's default divided by
            ``scale``, its element ``element`` for a vector; None when the field has none).
        element: the vector element whose default the option shows (the option sets a part of
            a vector field, e.g. x, y, z of six axes).
        help: the phrase before the unit and default (default: the field's help).
        off: a command-line value meaning "no check" (the field then gets None).
        none_means: what no value means, for the help (when the default is None).
        kwargs: passed to ``add_argument`` (``metavar``, ``required``, ``type``, ...).
    """
    spec = config if isinstance(config, FieldSpec) else spec_of(config, field)
    flag = flag or "--" + field.replace("_", "-")
    unit = spec.unit if unit is None else unit
    if default is dataclasses.MISSING and not isinstance(config, FieldSpec):
        default = _field_default(config, field)
        if isinstance(default, (tuple, list)) and element is not None:
            default = default[element]
        if isinstance(default, float):
            default = default / scale
    elif default is dataclasses.MISSING:
        default = None
    if spec.choices is not None:
        kwargs.setdefault("choices", spec.choices)
    elif "action" not in kwargs and "type" not in kwargs and not isinstance(default, str):
        kwargs["type"] = int if spec.integer else float
    phrase = spec.help if help is None else help
    text = f"{phrase} [{unit}]" if unit else phrase
    if kwargs.get("required"):
        text += " (required)"
    elif default is not None:
        text += f" (default {_shown(default)}" + (f"; {off}: off)" if off is not None else ")")
    else:
        text += f" (default: {none_means})"
    action = parser.add_argument(flag, default=default, help=text, **kwargs)
    _registry(parser, _OPTIONS, list).append(
        FieldOption(action.dest, flag, field, spec, scale, unit, off)
    )
    map_field(parser, field, flag)
    return action


def _shown(default: object) -> str:
    if isinstance(default, (list, tuple)):
        return ",".join(_shown(v) for v in default)
    return f"{default:g}" if isinstance(default, float) else str(default)


def spec_default(config: type, field: str) -> Any:
    """The default of a config class's field (for a help text that must say it another way)."""
    return _field_default(config, field)


def _field_default(config: type, field: str) -> Any:
    for f in dataclasses.fields(config):
        if f.name == field:
            if f.default is not dataclasses.MISSING:
                return f.default
            if f.default_factory is not dataclasses.MISSING:
                return f.default_factory()
            return None
    raise KeyError(field)


def check_field_options(args: argparse.Namespace) -> None:
    """Check every option a command built from a config field, by the field's rule.

    Raises:
        ParameterError: the first bad value, naming its flag.
    """
    for option in getattr(args, _OPTIONS, None) or ():
        option.check(getattr(args, option.dest))


def error_line(exc: FtcompError, args: argparse.Namespace) -> str:
    """The message of ``exc``, each field it names replaced by its command's flag (a switch's
    ``field=True`` too: ``overwrite=True`` is ``--force``)."""
    return with_flags(str(exc), args, exc.fields)


def with_flags(text: str, args: argparse.Namespace, fields: Sequence[str]) -> str:
    """``text`` (a library message or note) with each of ``fields`` replaced by the flag that
    sets it in this command (a field the command has no flag for stays as it is)."""
    flags: dict[str, str] = getattr(args, _FLAGS, None) or {}
    for field in fields:
        if field in flags:
            word = rf"(?<![\w.-]){re.escape(field)}(?:=True)?(?![\w-])"
            text = re.sub(word, flags[field], text)
    return text
