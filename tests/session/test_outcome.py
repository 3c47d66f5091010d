"""One outcome type and one fault predicate for every live session."""

from __future__ import annotations

import json

import pytest

from ftcomp.control.safety import StopReason
from ftcomp.session.outcome import Outcome


@pytest.mark.parametrize("reason", list(StopReason))
def test_every_protective_stop_is_an_outcome_and_a_fault(reason: StopReason) -> None:
    outcome = Outcome.stopped_by(reason)
    assert outcome == reason.value and outcome.protective_stop and outcome.faulted


def test_only_the_time_a_settled_contact_a_replay_run_out_or_every_pose_end_normally() -> None:
    normal = {o for o in Outcome if not o.faulted}
    assert normal == {Outcome.DURATION, Outcome.SETTLED, Outcome.END_OF_REPLAY, Outcome.COMPLETE}
    assert Outcome.LOOP_LATE.faulted and Outcome.INTERRUPTED.faulted and Outcome.ERROR.faulted
    assert not any(o.protective_stop for o in (Outcome.LOOP_LATE, Outcome.ERROR))


def test_an_outcome_prints_and_serialises_as_its_word() -> None:
    assert f"{Outcome.SETTLED}: ok" == "settled: ok"
    assert json.dumps({"stop_reason": Outcome.STALE_SAMPLE}) == '{"stop_reason": "stale_sample"}'
    assert Outcome("loop_late") is Outcome.LOOP_LATE
