"""A placement's verdict comes from the true contact force, whatever the controller sensed."""

from __future__ import annotations

import pytest

from ftcomp.errors import ParameterError
from ftcomp.session.verdicts import judge_placement

WEIGHT_N = 4.903325  # 500 g
TOL_N = 0.25


def test_a_placement_that_leaves_the_weight_on_the_surface_is_gentle() -> None:
    v = judge_placement("placed", WEIGHT_N - 0.03, 0.0, WEIGHT_N, TOL_N)
    assert v.verdict == "placed gently" and not v.failed
    assert v.true_press_N == pytest.approx(-0.03, abs=1e-12)


def test_a_decision_with_the_load_pushed_into_the_surface_is_pressed() -> None:
    """The uncompensated run: sensed force 0 N, surface carrying tool weight and bias too."""
    v = judge_placement("placed", WEIGHT_N + 3.33, 3.34, WEIGHT_N, TOL_N)
    assert v.verdict == "pressed" and "3.340 N" in v.reason
    assert v.true_press_N == pytest.approx(3.33, abs=1e-12)


def test_a_press_before_the_decision_counts_even_if_it_ended_gently() -> None:
    v = judge_placement("placed", WEIGHT_N, 1.0, WEIGHT_N, TOL_N)
    assert v.verdict == "pressed" and "peak" in v.reason


def test_a_decision_while_the_gripper_still_holds_the_load_is_early() -> None:
    v = judge_placement("placed", WEIGHT_N - 1.0, 0.0, WEIGHT_N, TOL_N)
    assert v.verdict == "released early"


@pytest.mark.parametrize("outcome", ["force_limit", "timeout", "stale_sample"])
def test_a_run_without_a_decision_is_stopped_and_says_why(outcome: str) -> None:
    v = judge_placement(outcome, WEIGHT_N + 37.0, 37.0, WEIGHT_N, TOL_N)
    assert v.verdict == "stopped" and v.failed
    assert outcome.replace("_", " ") in v.reason


def test_the_tolerance_must_be_positive() -> None:
    with pytest.raises(ParameterError, match="tolerance_N"):
        judge_placement("placed", WEIGHT_N, 0.0, WEIGHT_N, 0.0)
