"""A config field declared once with its rules (:mod:`ftcomp.config_fields`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import pytest

from ftcomp.config_fields import FieldSpec, check_fields, check_value, param, spec_of, specs_of
from ftcomp.errors import ParameterError


@dataclass(frozen=True)
class _Config:
    duration_s: float = param(gt=0.0, le=60.0, unit="s", help="how long")
    law: str = param("a", choices=("a", "b"), help="which")
    gains: tuple[float, ...] = param((1.0, 2.0, 3.0), ge=0.0, length=3, unit="m/N", help="K")
    count: int | None = param(None, ge=1, integer=True, optional=True, help="how many")
    limit: float = param(math.inf, gt=0.0, allow_inf=True, unit="N", help="stop above")
    free: str = param("z", help="text the config checks itself")

    def __post_init__(self) -> None:
        check_fields(self)


def test_a_valid_config_keeps_its_values_and_stores_a_vector_as_floats() -> None:
    config = _Config(1.5, gains=[0, 1, 2], count=3)  # type: ignore[arg-type]
    assert config.gains == (0.0, 1.0, 2.0) and all(type(g) is float for g in config.gains)
    assert config.count == 3 and config.limit == math.inf and config.free == "z"


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"duration_s": 0.0}, r"^duration_s must be in \(0, 60\] s, got 0$"),
        ({"duration_s": math.nan}, r"^duration_s must be in \(0, 60\] s, got nan$"),
        ({"duration_s": 61.0}, r"^duration_s must be in \(0, 60\] s, got 61$"),
        ({"duration_s": True}, r"^duration_s must be a number in"),
        ({"law": "c"}, r"^law must be one of a, b, got 'c'$"),
        ({"gains": (1.0, -1.0, 0.0)}, r"^gains must be >= 0 m/N on every axis, got \[1, -1, 0\]$"),
        ({"gains": (1.0, 2.0)}, r"^gains needs 3 values >= 0 m/N, got \[1, 2\]$"),
        ({"gains": (1.0, math.inf, 0.0)}, r"^gains must be >= 0 m/N on every axis"),
        ({"count": 0}, r"^count must be >= 1, got 0$"),
        ({"count": 1.5}, r"^count must be an integer >= 1, got 1.5$"),
        ({"limit": math.nan}, r"^limit must be > 0 N, got nan$"),
    ],
)
def test_a_bad_field_is_one_error_naming_it_and_what_is_valid(
    kwargs: dict[str, object], message: str
) -> None:
    values = {"duration_s": 1.0, **kwargs}
    with pytest.raises(ParameterError, match=message) as info:
        _Config(**values)  # type: ignore[arg-type]
    assert info.value.fields == (next(iter(kwargs)),)


def test_the_rules_are_read_from_the_class() -> None:
    spec = spec_of(_Config, "duration_s")
    assert spec.unit == "s" and spec.rule() == "in (0, 60] s"
    assert spec.rule(scale=1e-3, unit="ms") == "in (0, 60000] ms"
    assert list(specs_of(_Config)) == ["duration_s", "law", "gains", "count", "limit", "free"]
    with pytest.raises(KeyError, match="has no rules"):
        spec_of(_Config, "nothing")


@pytest.mark.parametrize(
    ("spec", "rule"),
    [
        (FieldSpec("x", unit="deg", gt=-30.0, lt=30.0), "within +-30 deg"),
        (FieldSpec("x", ge=2, le=100_000, integer=True), "in [2, 100000]"),
        (FieldSpec("x", lt=5.0), "< 5"),
        (FieldSpec("x"), "finite"),
    ],
)
def test_a_rule_reads_as_text(spec: FieldSpec, rule: str) -> None:
    assert spec.rule() == rule


def test_an_arguments_rule_checks_a_value_alone() -> None:
    rule = FieldSpec("how long", unit="s", gt=0.0, le=60.0)
    assert check_value("duration_s", rule, 2.0) == 2.0
    with pytest.raises(ParameterError, match=r"duration_s must be in \(0, 60\] s, got 0"):
        check_value("duration_s", rule, 0.0)
