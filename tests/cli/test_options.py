"""Options built from config fields, checked by their rules, and a field's error named by the
flag the user typed (:mod:`ftcomp.cli.options`)."""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass

import pytest

from ftcomp.cli.options import (
    add_field_option,
    check_field_options,
    error_line,
    map_field,
    map_options,
)
from ftcomp.config_fields import check_fields, param
from ftcomp.errors import ParameterError


@dataclass(frozen=True)
class _Config:
    speed: tuple[float, ...] = param(
        (0.02, 0.02, 0.02, 0.5, 0.5, 0.5), gt=0.0, length=6, unit="m/s, rad/s", help="speed limit"
    )
    law: str = param("a", choices=("a", "b"), help="the law")
    late: int = param(10, ge=1, integer=True, help="late periods tolerated")
    identical: int | None = param(None, ge=1, integer=True, optional=True, help="frozen after")

    def __post_init__(self) -> None:
        check_fields(self)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser()
    add_field_option(
        parser, _Config, "speed", "--max-speed-mm-s", scale=1e-3, unit="mm/s", element=0
    )
    add_field_option(
        parser, _Config, "speed", "--max-turn-deg-s", scale=math.radians(1), unit="deg/s", element=3
    )
    add_field_option(parser, _Config, "law")
    add_field_option(parser, _Config, "late", "--max-late-cycles")
    add_field_option(parser, _Config, "identical", default=5, off=0)
    parser.add_argument("--force", action="store_true")
    map_options(parser)
    return parser


def test_an_option_shows_the_fields_help_unit_and_default_in_its_own_unit() -> None:
    text = " ".join(_parser().format_help().split())
    assert "--max-speed-mm-s MAX_SPEED_MM_S speed limit [mm/s] (default 20)" in text
    assert "speed limit [deg/s] (default 28.6479)" in text
    assert "--law {a,b} the law (default a)" in text
    assert "late periods tolerated (default 10)" in text
    assert "frozen after (default 5; 0: off)" in text


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--max-speed-mm-s", "0"], "--max-speed-mm-s must be > 0 mm/s, got 0"),
        (["--max-turn-deg-s", "nan"], "--max-turn-deg-s must be > 0 deg/s, got nan"),
        (["--max-late-cycles", "0"], "--max-late-cycles must be >= 1, got 0"),
        (["--identical", "-1"], "--identical must be >= 1 (or 0: off), got -1"),
    ],
)
def test_a_value_breaking_its_fields_rule_names_the_flag(argv: list[str], message: str) -> None:
    args = _parser().parse_args(argv)
    with pytest.raises(ParameterError) as info:
        check_field_options(args)
    assert str(info.value) == message


def test_an_off_value_and_the_defaults_pass() -> None:
    check_field_options(_parser().parse_args(["--identical", "0"]))
    check_field_options(_parser().parse_args([]))


def test_a_library_error_on_a_field_names_the_flag_the_user_typed() -> None:
    args = _parser().parse_args([])
    error = ParameterError("late must be >= 1, got 0; late is a count", field="late")
    assert (
        error_line(error, args)
        == "--max-late-cycles must be >= 1, got 0; --max-late-cycles is a count"
    )
    overwrite = ParameterError(
        "x.csv: exists; pass overwrite=True to replace it", field="overwrite"
    )
    assert error_line(overwrite, args) == "x.csv: exists; pass --force to replace it"
    unmapped = ParameterError("speedy must be > 0", field="speedy")
    assert error_line(unmapped, args) == "speedy must be > 0"  # a word, not a field here


def test_an_explicit_mapping_wins_over_the_destination() -> None:
    parser = argparse.ArgumentParser()
    map_field(parser, "joint_states_topic", "--joint-states")
    parser.add_argument("--joint-states")
    map_options(parser)
    args = parser.parse_args([])
    error = ParameterError("urdf and joint_states_topic go together", field="joint_states_topic")
    assert error_line(error, args) == "urdf and --joint-states go together"
