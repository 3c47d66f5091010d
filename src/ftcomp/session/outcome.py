"""Why a live session ended, and whether that was a fault: one type and one predicate.

Every live session says how it ended with an :class:`Outcome`: ``ftcomp run`` and the compliant
step under it (:class:`~ftcomp.session.compliant.CompliantStep`, which placements map to their
own verdicts), ``ftcomp stream`` and ``ftcomp record``. A session ends normally when its time is
up, its contact settled, a replayed recording ran out or a recording has every pose it planned;
every other ending is a fault
(:attr:`Outcome.faulted`), and the robot has been stopped: a protective stop of the controller
(one member per :class:`~ftcomp.control.safety.StopReason`, with its value), a loop too late,
an error of the hardware or the loop, or Ctrl-C.

An :class:`Outcome` is a :class:`str` (its value): it prints, compares and serialises as the
plain word (``"settled"``, ``"stale_sample"``).
"""

from __future__ import annotations

import enum

from ftcomp.control.safety import StopReason

__all__ = ["Outcome"]


class Outcome(enum.StrEnum):
    """How a live session ended (see the module docstring)."""

    #: Its time was up (normal).
    DURATION = "duration"
    #: The contact settled by the settle rule, and was held for the time asked (normal).
    SETTLED = "settled"
    #: A replayed recording ran out (normal).
    END_OF_REPLAY = "end_of_replay"
    #: A calibration recording has every pose it planned (normal).
    COMPLETE = "complete"
    #: The loop fell too many periods behind the robot's schedule (a fault).
    LOOP_LATE = "loop_late"
    #: Ctrl-C (the session was cut short).
    INTERRUPTED = "interrupted"
    #: A fault of the hardware, its connection or the loop (its message says which).
    ERROR = "error"
    # The controller's protective stops, one per StopReason (tests/session/test_outcome.py).
    NON_FINITE_SAMPLE = StopReason.NON_FINITE_SAMPLE.value
    REPEATED_SAMPLE = StopReason.REPEATED_SAMPLE.value
    STALE_SAMPLE = StopReason.STALE_SAMPLE.value
    FROZEN_SAMPLE = StopReason.FROZEN_SAMPLE.value
    SENSOR_SATURATED = StopReason.SENSOR_SATURATED.value
    CLOCK_FAULT = StopReason.CLOCK_FAULT.value
    NON_FINITE_POSE = StopReason.NON_FINITE_POSE.value
    INVALID_INPUT = StopReason.INVALID_INPUT.value
    NON_FINITE_COMMAND = StopReason.NON_FINITE_COMMAND.value
    FORCE_LIMIT = StopReason.FORCE_LIMIT.value
    TORQUE_LIMIT = StopReason.TORQUE_LIMIT.value
    TRAVEL_LIMIT = StopReason.TRAVEL_LIMIT.value

    @classmethod
    def stopped_by(cls, reason: StopReason) -> Outcome:
        """The outcome of the controller's protective stop ``reason``."""
        return cls(reason.value)

    @property
    def faulted(self) -> bool:
        """Whether the session ended on a fault (the one predicate): anything but its
        duration, a settled contact, the end of a replayed recording or a complete recording."""
        return self not in _NORMAL

    @property
    def protective_stop(self) -> bool:
        """Whether it is one of the controller's protective stops."""
        return self.value in _STOPS


_NORMAL = frozenset({Outcome.DURATION, Outcome.SETTLED, Outcome.END_OF_REPLAY, Outcome.COMPLETE})
_STOPS = frozenset(reason.value for reason in StopReason)
