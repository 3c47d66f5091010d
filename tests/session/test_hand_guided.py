"""Recording still periods of a hand-guided arm (ManualRecorder), on scripted cycles."""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

from ftcomp.compensation.pipeline import Compensated
from ftcomp.control.loop import Reading
from ftcomp.session.hand_guided import ManualRecorder, StillCriteria
from ftcomp.session.pose_record import PoseEvent, WrenchTolerance

PERIOD_NS = 2_000_000  # a 500 Hz loop
P = np.array([0.4, 0.0, 0.3])


def _drive(
    recorder: ManualRecorder,
    script: list[tuple[float, Rotation, np.ndarray]],
    rng: np.random.Generator,
) -> int:
    """Run cycles: each script entry holds ``R`` for ``seconds`` with readings ``wrench`` (+
    noise), two a cycle, as the loop hands them on. Returns the cycle at which the recorder ended
    the loop (-1: never)."""
    now, cycle = 0, 0
    for seconds, rotation, wrench in script:
        R = rotation.as_matrix()
        for _ in range(round(seconds * 1e9 / PERIOD_NS)):
            now += PERIOD_NS
            cycle += 1
            new = []
            for k in (1, 0):
                w = wrench + rng.normal(size=6) * 0.01
                new.append(Compensated(now - k * PERIOD_NS // 2, w, w, R, P))
            reading = Reading(now, now, wrench, wrench, P, R, R, tuple(new))
            if recorder(reading) is None:
                return cycle
    return -1


def test_each_still_period_is_recorded_once_and_a_near_repeat_is_ignored(
    rng: np.random.Generator,
) -> None:
    events: list[PoseEvent] = []
    criteria = StillCriteria(still_s=0.2, min_separation_rad=math.radians(5.0))
    recorder = ManualRecorder(2, criteria, events.append)
    A = Rotation.from_euler("x", 180, degrees=True)
    near_A = Rotation.from_euler("z", 2, degrees=True) * A
    B = Rotation.from_euler("y", 40, degrees=True) * A
    w_A, w_B = np.arange(6.0), -np.arange(6.0)
    script = [
        (0.5, A, w_A),  # recorded once, although held for more than twice still_s
        (0.004, Rotation.from_euler("y", 20, degrees=True) * A, w_A),  # moved away ...
        (0.5, near_A, w_A),  # ... and back within 2 degrees: ignored
        (0.004, Rotation.from_euler("y", 20, degrees=True) * A, w_A),
        (0.5, B, w_B),  # recorded: the second pose ends the loop
        (0.5, A, w_A),
    ]
    ended = _drive(recorder, script, rng)
    assert [e.kind for e in events] == ["recorded", "too_close", "recorded"]
    assert events[1].number == 1
    assert abs(math.degrees(events[1].angle_rad) - 2.0) < 1e-9
    assert ended > 0 and len(recorder.records) == 2
    first, second = recorder.records
    assert np.allclose(first.R_base_sensor, A.as_matrix())
    assert np.allclose(second.R_base_sensor, B.as_matrix())
    # Three quarters of a 0.2 s window at 1 kHz of readings, their mean the held wrench.
    assert 140 <= len(first.wrench_sensor) <= 155
    assert np.allclose(first.mean, w_A, atol=5 * 0.01 / math.sqrt(140))


def test_readings_that_still_drift_are_not_recorded_until_they_settle(
    rng: np.random.Generator,
) -> None:
    events: list[PoseEvent] = []
    criteria = StillCriteria(still_s=0.2, wrench=WrenchTolerance(0.05, 0.005))
    recorder = ManualRecorder(1, criteria, events.append)
    A = Rotation.from_euler("x", 180, degrees=True)
    # 1.25 N/s for 0.6 s: a 0.2 s window's halves differ by 0.125 N, beyond the 0.05 N allowed.
    drifting = [(0.004, A, np.full(6, 0.005 * k)) for k in range(150)]
    settled = [(0.4, A, np.full(6, 0.75))]
    _drive(recorder, drifting + settled, rng)
    assert [e.kind for e in events] == ["recorded"]
    record = recorder.records[0]
    # Nothing from the drift but perhaps its last ~40 ms (a drift too small to see there).
    assert record.t_ns[0] > 0.56e9
    assert np.allclose(record.mean, 0.75, atol=0.01)
