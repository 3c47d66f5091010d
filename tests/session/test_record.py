"""A recording session as a library call, on a scripted cell in pure Python (no MuJoCo)."""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.calibration.identify import calibrate, max_deviations_in_standard_errors
from ftcomp.cli import main
from ftcomp.errors import HardwareError, ParameterError, UnreachablePoseError
from ftcomp.hardware.protocols import PoseSample, ReportsExtraChannels, WrenchSample
from ftcomp.io.samples_csv import read_samples
from ftcomp.model import GravityModel
from ftcomp.paper import paper_poses
from ftcomp.samples import PoseList
from ftcomp.session.hand_guided import StillCriteria
from ftcomp.session.pose_record import PoseEvent
from ftcomp.session.record import OBSERVED_COLUMNS, HandGuided, RecordConfig, RobotDriven, record

from conftest import FORCE_NOISE_N, TORQUE_NOISE_NM, TRUE_MODEL

PERIOD_NS = 2_000_000  # a 500 Hz loop, two readings per cycle
#: Three standard errors hold with 99.7 % probability per identified number.
SE_BOUND = 3.0


class FakeCell:
    """A robot and its sensor on one clock: each cycle brings two readings of ``model`` at the
    held orientation with seeded noise. ``hold(t_ns)`` scripts the orientation of a hand-guided
    arm; ``fail`` raises ``error`` at that move (robot-driven) or time [ns] (hand-guided)."""

    control_period_s = PERIOD_NS * 1e-9

    def __init__(
        self,
        model: GravityModel,
        rng: np.random.Generator,
        *,
        hold: Callable[[int], Rotation] | None = None,
        fail_at_move: int | None = None,
        fail_at_ns: int | None = None,
        error: BaseException | None = None,
    ) -> None:
        self.model, self.rng, self.hold = model, rng, hold
        self.fail_at_move, self.fail_at_ns, self.error = fail_at_move, fail_at_ns, error
        self.now, self.moves, self.stops = 0, 0, 0
        self.p, self.R = np.array([0.4, 0.0, 0.3]), np.eye(3)
        self.pending: list[WrenchSample] = []
        self.latest = WrenchSample(0, model.predict(self.R))

    def __enter__(self) -> FakeCell:
        return self

    def __exit__(self, *exc: object) -> None:
        pass

    def now_ns(self) -> int:
        return self.now

    def pose(self) -> PoseSample:
        return PoseSample(self.now, self.p, self.R)

    def move_pose(self, p: np.ndarray, R: np.ndarray, duration_s: float) -> None:
        self.moves += 1
        if self.moves == self.fail_at_move:
            assert self.error is not None
            raise self.error
        self.p, self.R = np.array(p), np.array(R)
        self.now += round(duration_s * 1e9)

    def settle(self, max_duration_s: float) -> float:
        return 0.0

    def command_twist(self, twist_base: np.ndarray) -> None:
        pass

    def wait_cycle(self) -> None:
        self.now += PERIOD_NS
        if self.fail_at_ns is not None and self.now >= self.fail_at_ns:
            assert self.error is not None
            raise self.error
        if self.hold is not None:
            self.R = self.hold(self.now).as_matrix()
        noise = np.repeat([FORCE_NOISE_N, TORQUE_NOISE_NM], 3)
        for k in (1, 0):
            w = self.model.predict(self.R) + self.rng.normal(size=6) * noise
            self.pending.append(WrenchSample(self.now - k * PERIOD_NS // 2, w))

    def stop(self) -> None:
        self.stops += 1

    def read(self) -> WrenchSample:
        return self.pending[-1] if self.pending else self.latest

    def read_new(self) -> list[WrenchSample]:
        out, self.pending = self.pending, []
        if out:
            self.latest = out[-1]
        return out


class ReachesNotTheThird(FakeCell):
    """A cell that can check a target: the third paper pose is out of reach."""

    def is_reachable(self, p_base_tcp: np.ndarray, R_base_tcp: np.ndarray) -> bool:
        third = paper_poses().rotations[2].as_matrix()
        return not np.allclose(R_base_tcp, third)


def driven(out: Path, poses: PoseList | None = None, **plan: Any) -> RecordConfig:
    plan.setdefault("samples_per_pose", 50)
    plan.setdefault("move_duration_s", 1.0)
    return RecordConfig(out, RobotDriven(poses or paper_poses(), **plan))


def test_a_robot_driven_session_writes_every_pose_and_its_file_calibrates_to_the_truth(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    cell, events = FakeCell(TRUE_MODEL, rng), []
    result = record(cell, cell, driven(tmp_path / "s.csv"), on_event=events.append)
    assert (result.ended, result.reason) == ("complete", "")
    assert result.poses_recorded == result.poses_planned == 9 and result.readings == 450
    assert [e.number for e in events] == list(range(1, 10))
    assert all(e.kind == "recorded" for e in events) and math.isinf(events[0].angle_rad)
    written = read_samples(result.output)
    assert result.samples is not None
    assert written.pose is not None and list(written.pose) == list(result.samples.pose)
    np.testing.assert_allclose(written.wrench_sensor, result.samples.wrench_sensor, rtol=1e-9)
    deviations = max_deviations_in_standard_errors(calibrate(written), TRUE_MODEL)
    assert max(deviations.values()) < SE_BOUND, deviations
    assert cell.stops >= 1


class WarmCell(FakeCell):
    """A cell whose sensor also reports its temperature (a ReportsExtraChannels sensor): each
    reading carries its own, ``30 + t`` [degC] with ``t`` its stamp [s]."""

    extra_channels = ("temperature_C",)

    def wait_cycle(self) -> None:
        super().wait_cycle()
        self.pending[-2:] = [
            WrenchSample(s.t_ns, s.wrench_sensor, (30.0 + s.t_ns * 1e-9,))
            for s in self.pending[-2:]
        ]


def test_a_recording_writes_each_readings_extra_channels_and_still_calibrates(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    cell = WarmCell(TRUE_MODEL, rng)
    assert isinstance(cell, ReportsExtraChannels)
    seen: list[tuple[str, ...]] = []

    class Columns:
        def open(self, columns: Any) -> None:
            seen.append(tuple(columns))

        def row(self, t_ns: int, row: Any) -> None:
            assert row[-1] == 30.0 + t_ns * 1e-9

        def event(self, t_ns: int, kind: str, text: str) -> None:
            pass

        def close(self) -> None:
            pass

    result = record(cell, cell, driven(tmp_path / "s.csv"), observers=[Columns()])
    assert result.ended == "complete" and result.samples is not None
    assert seen == [(*OBSERVED_COLUMNS, "temperature_C")]
    written = read_samples(result.output)
    assert written.header[-1] == "temperature_C"
    assert written.t is not None
    # each row the temperature of its own reading (30 + its stamp), written as every number of
    # a sample file, to 10 significant digits
    temperature = np.array([float(row[-1]) for row in written.rows])
    np.testing.assert_allclose(temperature, result.samples.extras["temperature_C"], rtol=1e-9)
    np.testing.assert_allclose(temperature, 30.0 + result.samples.t, rtol=1e-9)
    deviations = max_deviations_in_standard_errors(calibrate(written), TRUE_MODEL)
    assert max(deviations.values()) < SE_BOUND, deviations
    # and ftcomp calibrate reads it as any other sample file
    assert main(["calibrate", str(result.output), "-o", str(tmp_path / "c.json")]) == 0


def test_a_hand_guided_recording_keeps_each_readings_extra_channels(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    A, B = Rotation.from_euler("x", 180, degrees=True), Rotation.from_euler("y", 90, degrees=True)
    C, moving = (
        Rotation.from_euler("x", 60, degrees=True),
        Rotation.from_euler("y", 20, degrees=True),
    )
    timeline = [(0.5, A), (0.01, moving), (0.5, B), (0.01, moving), (0.5, C), (10.0, A)]
    cell = WarmCell(TRUE_MODEL, rng, hold=_held(timeline))
    plan = HandGuided(3, StillCriteria(still_s=0.2), samples_per_pose=100)
    result = record(cell, cell, RecordConfig(tmp_path / "s.csv", plan))
    assert result.ended == "complete" and result.poses_recorded == 3
    for pose in result.records:
        np.testing.assert_array_equal(pose.extras["temperature_C"], 30.0 + pose.t_ns * 1e-9)
    written = read_samples(result.output)
    assert written.header[-1] == "temperature_C" and len(written) == 300


def test_a_fault_after_the_first_pose_keeps_the_poses_so_far_and_stops_the_robot(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    error = HardwareError("ur://127.0.0.1: lost the connection")
    cell = FakeCell(TRUE_MODEL, rng, fail_at_move=3, error=error)
    result = record(cell, cell, driven(tmp_path / "s.csv"))
    assert result.ended == "error" and result.faulted and "lost the connection" in result.reason
    assert result.poses_recorded == 2 and cell.stops >= 1
    kept = read_samples(result.output)
    assert kept.pose is not None and sorted(set(kept.pose)) == ["1", "2"]


def test_ctrl_c_ends_the_session_as_interrupted_with_the_file_as_far_as_it_got(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    cell = FakeCell(TRUE_MODEL, rng, fail_at_move=2, error=KeyboardInterrupt())
    result = record(cell, cell, driven(tmp_path / "s.csv"))
    assert result.ended == "interrupted" and "Ctrl-C" in result.reason
    assert result.poses_recorded == 1 and cell.stops >= 1
    assert len(read_samples(result.output)) == 50


def test_a_failure_before_the_first_pose_is_raised_and_writes_nothing(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    cell = FakeCell(TRUE_MODEL, rng, fail_at_move=1, error=HardwareError("silent sensor"))
    with pytest.raises(HardwareError, match="silent sensor"):
        record(cell, cell, driven(tmp_path / "s.csv"))
    assert not (tmp_path / "s.csv").exists() and cell.stops >= 1


def test_a_pose_out_of_reach_is_skipped_with_a_line_and_the_session_goes_on(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    cell = ReachesNotTheThird(TRUE_MODEL, rng)
    lines: list[str] = []
    result = record(cell, cell, driven(tmp_path / "s.csv"), on_skip=lines.append)
    assert len(lines) == 1 and re.search(
        r"pose 3 of .* skipped: the robot does not reach", lines[0]
    )
    assert result.ended == "complete" and result.poses_recorded == 8
    kept = read_samples(result.output)
    assert kept.pose is not None and "3" not in set(kept.pose) and len(set(kept.pose)) == 8


def test_a_pose_file_the_robot_reaches_none_of_is_refused_before_anything_moves(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    cell = ReachesNotTheThird(TRUE_MODEL, rng)
    third = PoseList(("3",), paper_poses().rotations[2:3], "third.csv")
    with pytest.raises(UnreachablePoseError, match=r"no pose of third.csv .* nothing was moved"):
        record(cell, cell, driven(tmp_path / "s.csv", third))
    assert cell.moves == 0 and not (tmp_path / "s.csv").exists()


def test_an_existing_output_is_kept_unless_overwrite(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    out = tmp_path / "s.csv"
    out.write_text("keep me")
    cell = FakeCell(TRUE_MODEL, rng)
    with pytest.raises(ParameterError, match="exists; pass overwrite=True"):
        record(cell, cell, driven(out))
    assert out.read_text() == "keep me" and cell.moves == 0
    config = RecordConfig(out, RobotDriven(paper_poses(), samples_per_pose=10), overwrite=True)
    assert record(cell, cell, config).ended == "complete"
    assert len(read_samples(out)) == 90


def _held(timeline: list[tuple[float, Rotation]]) -> Callable[[int], Rotation]:
    """The orientation at ``t_ns`` of an arm held at each rotation for its seconds in turn."""
    ends = np.cumsum([seconds for seconds, _ in timeline]) * 1e9

    def at(t_ns: int) -> Rotation:
        return timeline[min(int(np.searchsorted(ends, t_ns, side="right")), len(ends) - 1)][1]

    return at


def test_a_hand_guided_session_records_each_still_period_and_ignores_a_repeat(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    A = Rotation.from_euler("x", 180, degrees=True)
    B = Rotation.from_euler("y", 40, degrees=True) * A
    C = Rotation.from_euler("x", 60, degrees=True)
    moving = Rotation.from_euler("y", 20, degrees=True) * A
    near_A = Rotation.from_euler("z", 2, degrees=True) * A
    timeline = [(0.5, A), (0.01, moving), (0.5, near_A), (0.01, moving), (0.5, B)]
    timeline += [(0.01, moving), (0.5, C), (10.0, A)]
    cell, events = FakeCell(TRUE_MODEL, rng, hold=_held(timeline)), []
    plan = HandGuided(3, StillCriteria(still_s=0.2), samples_per_pose=100)
    result = record(cell, cell, RecordConfig(tmp_path / "s.csv", plan), on_event=events.append)
    assert result.ended == "complete" and result.poses_recorded == 3
    assert [(e.kind, e.number) for e in events] == [
        ("recorded", 1),
        ("too_close", 1),
        ("recorded", 2),
        ("recorded", 3),
    ]
    assert abs(math.degrees(events[1].angle_rad) - 2.0) < 1e-9
    for record_, R in zip(result.records, (A, B, C), strict=True):
        np.testing.assert_allclose(record_.R_base_sensor, R.as_matrix(), atol=1e-12)
        assert len(record_.wrench_sensor) == 100
    assert len(read_samples(result.output)) == 300 and cell.stops >= 1
    assert cell.now < 3e9  # the session ended with the third pose


def test_ctrl_c_in_a_hand_guided_session_keeps_the_poses_so_far(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    A, B = Rotation.identity(), Rotation.from_euler("y", 90, degrees=True)
    cell = FakeCell(
        TRUE_MODEL,
        rng,
        hold=_held([(0.5, A), (60.0, B)]),
        fail_at_ns=round(0.6e9),
        error=KeyboardInterrupt(),
    )
    plan = HandGuided(3, StillCriteria(still_s=0.2))
    result = record(cell, cell, RecordConfig(tmp_path / "s.csv", plan))
    assert result.ended == "interrupted" and result.poses_recorded == 1
    assert read_samples(result.output).pose is not None and cell.stops >= 1


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: HandGuided(2), "n_poses must be >= 3"),
        (
            lambda: HandGuided(3, samples_per_pose=1),
            r"samples_per_pose must be in \[2, 100000\]",
        ),
        (lambda: RobotDriven(paper_poses(), samples_per_pose=1), "samples_per_pose"),
        (lambda: RobotDriven(paper_poses(), move_duration_s=0.0), "move_duration_s must be"),
        (lambda: RobotDriven(paper_poses(), settle_max_s=math.nan), "settle_max_s must be"),
        (lambda: RobotDriven(paper_poses(), position_base_m=[0.4, 0.0]), "position_base_m"),
        (lambda: RecordConfig("s.csv", HandGuided(3), encoding="euler"), "encoding must be"),  # type: ignore[arg-type]
        (lambda: RecordConfig("s.csv", paper_poses()), "plan must be"),  # type: ignore[arg-type]
    ],
)
def test_configs_refuse_bad_values_naming_the_parameter(build: Any, match: str) -> None:
    with pytest.raises(ParameterError, match=match):
        build()


def test_an_event_carries_a_record_exactly_when_a_pose_was_recorded() -> None:
    with pytest.raises(ParameterError, match="record"):
        PoseEvent("recorded", 1, math.inf, None)


def test_an_error_in_the_callers_callback_stops_the_robot_and_goes_through(
    tmp_path: Path, rng: np.random.Generator
) -> None:
    cell = FakeCell(TRUE_MODEL, rng)

    def broken(event: PoseEvent) -> None:
        raise RuntimeError("announcer broke")

    with pytest.raises(RuntimeError, match="announcer broke"):
        record(cell, cell, driven(tmp_path / "s.csv"), on_event=broken)
    assert cell.stops >= 1 and len(read_samples(tmp_path / "s.csv")) == 50
