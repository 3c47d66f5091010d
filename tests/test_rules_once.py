"""Configs own their rules: no range, limit or choice list written both in ``cli/`` and in the
library, and no library message naming a command-line flag (issue 33, item 5).

Read from the source text (as ``test_architecture.py`` reads imports):

- **Messages.** Every string literal of the library (``src/ftcomp`` but ``cli/`` and the
  applications' ``huang2020/``) that is not a docstring counts as a message: what is passed to
  an exception, a warning, a log call or a note, or built into one. None may name a flag of the
  ``ftcomp`` command (the set is read from the commands' parsers, so a flag of another tool,
  ``docker --cap-add``, is no flag of ours). Docstrings (the first statement of a module, class
  or function) and comments may name flags: they say which option of a command maps to a call.
  A message names the field or argument instead (``bias_drift stochastic needs ...``, with
  ``field="bias_drift"`` on the error) and the CLI puts the flag the user typed in its place
  (:func:`ftcomp.cli.options.error_line`).
- **Ranges.** No ``if`` in ``cli/`` compares a value with a number and raises a
  ``ParameterError`` or ``argparse.ArgumentTypeError``: a range is declared on its config's
  field (:func:`ftcomp.config_fields.param`) or as an argument's rule
  (:class:`ftcomp.config_fields.FieldSpec`), and the CLI checks an option by it
  (:func:`ftcomp.cli.options.add_field_option`).
- **Choices.** No ``choices=`` in ``cli/`` is a literal list of names that the library also
  writes as a literal (a tuple, a list, a set or a ``Literal[...]``): the CLI reads the
  library's (``get_args(DriftModel)``, ``DISTROS``, a config field's ``choices``).

What other work still holds is listed in the ``_PENDING`` sets (each entry says whose it is):
the tests fail on anything new, and an entry may only go.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "ftcomp"
_APPLICATIONS = ("cli/", "huang2020/")
_FLAG = re.compile(r"(?<![\w-])--[a-zA-Z][a-zA-Z0-9-]*")

#: Library messages still naming a flag: (module, flag).
_PENDING_MESSAGES: set[tuple[str, str]] = set()
#: Range checks still in cli/: (module, the condition's source).
_PENDING_RANGES: set[tuple[str, str]] = set()


def _library_modules() -> list[tuple[str, ast.Module]]:
    out = []
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        if not rel.startswith(_APPLICATIONS):
            out.append((rel, ast.parse(path.read_text(encoding="utf-8"))))
    return out


def _cli_modules() -> list[tuple[str, ast.Module]]:
    return [
        (path.name, ast.parse(path.read_text(encoding="utf-8")))
        for path in sorted((SRC / "cli").glob("*.py"))
    ]


def _docstrings(tree: ast.Module) -> set[int]:
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            first = node.body[0] if node.body else None
            if (
                isinstance(first, ast.Expr)
                and isinstance(first.value, ast.Constant)
                and isinstance(first.value.value, str)
            ):
                found.add(id(first.value))
    return found


def _ftcomp_flags() -> set[str]:
    """Every long flag of every ``ftcomp`` command, from the parsers themselves."""
    import argparse

    from ftcomp.cli import COMMANDS, SIM_COMMANDS, build_parser

    flags: set[str] = set()

    def walk(parser: argparse.ArgumentParser) -> None:
        for action in parser._actions:
            flags.update(o for o in action.option_strings if o.startswith("--"))
            if isinstance(action, argparse._SubParsersAction):
                for sub in action.choices.values():
                    walk(sub)

    for name in COMMANDS:
        walk(build_parser([name]))
    for name in SIM_COMMANDS:
        walk(build_parser(["sim", name]))
    return flags - {"--help", "--version"}


def library_messages_naming_flags(flags: set[str]) -> set[tuple[str, str]]:
    """``(module, flag)`` for each non-docstring string literal of the library naming a flag."""
    found = set()
    for rel, tree in _library_modules():
        docs = _docstrings(tree)
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Constant)
                and isinstance(node.value, str)
                and id(node) not in docs
            ):
                found.update((rel, f) for f in _FLAG.findall(node.value) if f in flags)
    return found


def _raises_bad_input(body: list[ast.stmt]) -> bool:
    for statement in body:
        for node in ast.walk(statement):
            if isinstance(node, ast.Raise) and node.exc is not None:
                target = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
                name = getattr(target, "id", getattr(target, "attr", ""))
                if name in ("ParameterError", "ArgumentTypeError"):
                    return True
    return False


def _compares_with_a_number(test: ast.expr) -> bool:
    for node in ast.walk(test):
        if isinstance(node, ast.Compare):
            for side in (node.left, *node.comparators):
                if isinstance(side, ast.UnaryOp):
                    side = side.operand
                if (
                    isinstance(side, ast.Constant)
                    and isinstance(side.value, (int, float))
                    and not isinstance(side.value, bool)
                ):
                    return True
    return False


def cli_range_checks() -> set[tuple[str, str]]:
    """``(module, condition)`` for each ``if`` in ``cli/`` that checks a number against a bound
    and raises a user error."""
    found = set()
    for name, tree in _cli_modules():
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.If)
                and _compares_with_a_number(node.test)
                and _raises_bad_input(node.body)
            ):
                found.add((name, ast.unparse(node.test)))
    return found


def _names(node: ast.AST) -> frozenset[str] | None:
    """The names of a literal list of at least two strings (a tuple, list, set display or a
    ``Literal[...]``), or None."""
    elements: list[ast.expr] | None = None
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        elements = node.elts
    elif isinstance(node, ast.Subscript) and getattr(node.value, "id", None) == "Literal":
        elements = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
    if not elements or len(elements) < 2:
        return None
    if not all(isinstance(e, ast.Constant) and isinstance(e.value, str) for e in elements):
        return None
    return frozenset(e.value for e in elements)  # type: ignore[attr-defined]


def cli_choices_copied_from_the_library() -> set[tuple[str, tuple[str, ...]]]:
    """``(module, names)`` for each ``choices=`` literal in ``cli/`` the library also writes."""
    library = {
        names
        for _, tree in _library_modules()
        for node in ast.walk(tree)
        if (names := _names(node)) is not None
    }
    found = set()
    for name, tree in _cli_modules():
        for node in ast.walk(tree):
            if isinstance(node, ast.keyword) and node.arg == "choices":
                names = _names(node.value)
                if names is not None and names in library:
                    found.add((name, tuple(sorted(names))))
    return found


def test_no_library_message_names_a_flag_of_ftcomp() -> None:
    flags = _ftcomp_flags()
    assert {"--force", "--bias-drift", "--wrench-frame", "--view"} <= flags  # the set is real
    found = library_messages_naming_flags(flags)
    assert found <= _PENDING_MESSAGES, sorted(found - _PENDING_MESSAGES)


def test_cli_checks_no_range_of_its_own() -> None:
    found = cli_range_checks()
    assert found <= _PENDING_RANGES, sorted(found - _PENDING_RANGES)


def test_cli_copies_no_choice_list_of_the_library() -> None:
    assert cli_choices_copied_from_the_library() == set()


@pytest.mark.parametrize(
    ("source", "kind"),
    [
        ('def f(x):\n    if x < 0:\n        raise ParameterError("x")\n', "range"),
        ('p.add_argument("--law", choices=("combined", "position"))\n', "choice"),
        ('raise ParameterError("give --force to replace it")\n', "message"),
    ],
)
def test_each_check_catches_what_it_forbids(source: str, kind: str) -> None:
    """The scanners on a snippet holding one violation each (they would pass vacuously
    otherwise)."""
    tree = ast.parse(source)
    if kind == "range":
        ifs = [n for n in ast.walk(tree) if isinstance(n, ast.If)]
        assert _compares_with_a_number(ifs[0].test) and _raises_bad_input(ifs[0].body)
    elif kind == "choice":
        keyword = next(n for n in ast.walk(tree) if isinstance(n, ast.keyword))
        assert _names(keyword.value) == frozenset({"combined", "position"})
    else:
        docs = _docstrings(tree)
        texts = [
            n.value
            for n in ast.walk(tree)
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs
        ]
        assert _FLAG.findall(texts[0]) == ["--force"]
