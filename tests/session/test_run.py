"""``run_compliant``: the live compliant loop as a library call, on the simulated cell.

The log carries every input of the controller's step and the error it acted on: replayed through
a new controller it gives back the logged errors and commands (exact algebra, 1e-12).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import ftcomp
from channelled_sensor import CHANNELS, ChannelledSensor
from ftcomp.control.safety import SafetyLimits
from ftcomp.errors import ParameterError
from ftcomp.frames import R_base_sensor_from
from ftcomp.hardware.faults import FaultySensor
from ftcomp.hardware.protocols import NothingToClose, WrenchSample, WrenchSensor
from ftcomp.model import GravityModel
from ftcomp.session.compliant import SettleRule
from ftcomp.session.run import (
    RUN_COLUMNS,
    AdmittanceConfig,
    RunConfig,
    RunResult,
    filter_hz_for,
    run_compliant,
    stale_after_s_for,
)

#: The 500 g load hangs 2 mm above the sponge.
PLACE = "sim://?seed=4&surface=sponge&load_kg=0.5&grasp=1&clearance_mm=2"


@pytest.fixture(scope="module")
def tool() -> GravityModel:
    """The simulated tool's truth (bias, weight, centre of gravity, tilt): the compensation."""
    with ftcomp.open_robot("sim://?seed=4") as robot:
        return robot.true_gravity_model()  # type: ignore[attr-defined, no-any-return]


def _limits() -> SafetyLimits:
    return SafetyLimits(
        max_twist=np.array([0.02] * 3 + [0.5] * 3),
        max_twist_rate=np.array([0.5] * 3 + [5.0] * 3),
        max_travel=np.array([0.02] * 3 + [0.1] * 3),
        max_force_N=40.0,
        max_torque_Nm=8.0,
        stale_after_s=0.02,
        max_repeated_samples=2,
    )


def _read_log(path: Path) -> tuple[list[str], np.ndarray]:
    header = path.read_text().splitlines()[0].split(",")
    return header, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def _run(tool: GravityModel, config: RunConfig, log: Path, kind: str = "") -> RunResult:
    """``run_compliant`` on a fresh cell holding the load above the sponge (``kind``: a sensor
    fault from 0.2 s on)."""
    with ftcomp.open_robot(PLACE) as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        if kind:
            sensor = FaultySensor(sensor, kind, 0.2)  # type: ignore[arg-type]
        return run_compliant(robot, sensor, tool, config, log)


@pytest.mark.parametrize("law", ["combined", "mass-damper-spring"])
@pytest.mark.parametrize("dry_run", [False, True])
def test_a_run_log_replays_through_the_step_to_the_logged_errors_and_commands(
    tool: GravityModel, tmp_path: Path, law: str, dry_run: bool
) -> None:
    admittance = AdmittanceConfig(_limits(), law=law, axes="z", k1=(1e-4,) * 6)  # type: ignore[arg-type]
    config = RunConfig(admittance, duration_s=0.4, dry_run=dry_run)
    result = _run(tool, config, tmp_path / "run.csv")
    assert result.outcome == "duration" and not result.faulted
    header, rows = _read_log(tmp_path / "run.csv")
    assert tuple(header) == RUN_COLUMNS and len(rows) == result.cycles > 150
    col = {name: i for i, name in enumerate(header)}

    def cols(*names: str) -> np.ndarray:
        return rows[:, [col[n] for n in names]]

    raw, contact = (
        cols("fx", "fy", "fz", "tx", "ty", "tz"),
        cols("cfx", "cfy", "cfz", "ctx", "cty", "ctz"),
    )
    quats, errors = cols("qx", "qy", "qz", "qw"), cols("ex", "ey", "ez", "etx", "ety", "etz")
    twists = cols("vx", "vy", "vz", "wx", "wy", "wz")
    assert np.all(rows[:, col["sent"]] == (0.0 if dry_run else 1.0))
    assert np.any(np.abs(twists[:, 2]) > 1e-4)  # the hanging load is lowered (or would be)

    controller = admittance.controller(result.period_s)
    R0 = R_base_sensor_from("quaternion", quats[0])
    state = controller.initial_state(contact[0], R0)
    for k in range(len(rows)):
        R = R_base_sensor_from("quaternion", quats[k])
        state, twist = controller.step(
            state,
            rows[k, col["t_sample_s"]],
            contact[k],
            R,
            rows[k, col["t_s"]],
            result.period_s,
            wrench_raw_sensor=raw[k],
        )
        np.testing.assert_allclose(state.law.wrench_error, errors[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(twist, twists[k], rtol=0, atol=1e-12)


def test_a_run_settles_on_the_sponge_and_reports_its_figures(
    tool: GravityModel, tmp_path: Path
) -> None:
    config = RunConfig(AdmittanceConfig(_limits()), duration_s=20.0, settle=SettleRule(band_N=0.05))
    result = _run(tool, config, tmp_path / "run.csv")
    assert result.outcome == "settled" and not result.faulted, result.message
    # The force error the controller acted on, over the last 0.3 s, is within the band, and it
    # got there by lowering the load (the 2 mm gap plus the sponge's give).
    assert abs(result.final_error[2]) <= 0.05
    assert 2e-3 < -result.travel_m[2] < 10e-3
    assert abs(result.travel_m[0]) < 1e-3 and abs(result.travel_m[1]) < 1e-3


class _SlowSensor(NothingToClose):
    """The cell's sensor, saying it samples at 100 Hz (an FT 300's rate)."""

    sample_rate_hz = 100.0

    def __init__(self, sensor: WrenchSensor) -> None:
        self.sensor = sensor

    def read(self) -> WrenchSample:
        return self.sensor.read()

    def read_new(self) -> list[WrenchSample]:
        return self.sensor.read_new()


def test_the_wrench_filter_is_a_twentieth_of_a_slower_sensors_rate(
    tool: GravityModel, tmp_path: Path
) -> None:
    assert filter_hz_for(None) == 10.0 and filter_hz_for(1000.0) == 10.0
    assert filter_hz_for(100.0) == 5.0  # time constant 32 ms: three of its samples
    # a law with no K1 on a yielding axis only integrates: the lag alone counts
    assert filter_hz_for(None, differentiates=False) == 20.0
    assert filter_hz_for(100.0, differentiates=False) == 20.0
    assert AdmittanceConfig(_limits()).differentiates_force()
    assert not AdmittanceConfig(_limits(), k1=(0.0,) * 6).differentiates_force()
    assert not AdmittanceConfig(_limits(), k1=(1e-4, 0, 0, 0, 0, 0)).differentiates_force()
    assert AdmittanceConfig(_limits(), k1=(1e-4, 0, 0, 0, 0, 0), axes="x").differentiates_force()
    assert not AdmittanceConfig(_limits(), law="velocity").differentiates_force()
    assert AdmittanceConfig(_limits(), law="position").differentiates_force()
    assert not AdmittanceConfig(_limits(), law="mass-damper-spring").differentiates_force()
    config = RunConfig(AdmittanceConfig(_limits()), duration_s=0.1)
    with ftcomp.open_robot(PLACE) as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        assert run_compliant(robot, sensor, tool, config, tmp_path / "a.csv").filter_hz == 10.0
        slow = _SlowSensor(sensor)
        assert run_compliant(robot, slow, tool, config, tmp_path / "b.csv").filter_hz == 5.0
        given = RunConfig(AdmittanceConfig(_limits(), filter_hz=12.0), duration_s=0.1)
        assert run_compliant(robot, slow, tool, given, tmp_path / "c.csv").filter_hz == 12.0


def test_a_reading_is_stale_only_when_older_than_four_of_its_sensors_periods(
    tool: GravityModel, tmp_path: Path
) -> None:
    assert stale_after_s_for(0.02, None) == 0.02 and stale_after_s_for(0.02, 1000.0) == 0.02
    assert stale_after_s_for(0.02, 100.0) == pytest.approx(0.04)
    assert stale_after_s_for(0.075, 100.0) == 0.075
    config = RunConfig(AdmittanceConfig(_limits()), duration_s=0.1)  # limits: 20 ms
    with ftcomp.open_robot(PLACE) as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        fast = run_compliant(robot, sensor, tool, config, tmp_path / "a.csv")
        slow = run_compliant(robot, _SlowSensor(sensor), tool, config, tmp_path / "b.csv")
    assert fast.stale_after_s == 0.02 and slow.stale_after_s == pytest.approx(0.04)


@pytest.mark.parametrize(
    ("kind", "reason"), [("nan", "non_finite_sample"), ("stop", "repeated_sample")]
)
def test_a_sensor_fault_stops_the_run_in_the_period_that_sees_it_and_keeps_the_log(
    tool: GravityModel, tmp_path: Path, kind: str, reason: str
) -> None:
    config = RunConfig(AdmittanceConfig(_limits()), duration_s=2.0)
    result = _run(tool, config, tmp_path / "run.csv", kind)
    assert result.faulted and result.outcome == reason, result
    assert result.message.startswith("protective stop: ")
    _, rows = _read_log(tmp_path / "run.csv")
    assert len(rows) == result.cycles  # every cycle up to the one that stopped is logged
    assert np.all(rows[-1, -7:-1] == 0.0)  # that cycle commanded nothing


def test_a_run_logs_each_cycles_extra_channels_from_the_reading_its_wrench_came_from(
    tool: GravityModel, tmp_path: Path
) -> None:
    config = RunConfig(AdmittanceConfig(_limits()), duration_s=0.3)
    with ftcomp.open_robot(PLACE) as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        result = run_compliant(robot, ChannelledSensor(sensor), tool, config, tmp_path / "r.csv")
    assert result.outcome == "duration", result
    header, rows = _read_log(tmp_path / "r.csv")
    assert tuple(header) == (*RUN_COLUMNS, *CHANNELS)
    assert len(rows) == result.cycles > 100
    # each row's channels are those of the reading whose wrench it logs (they carry its fx, fy)
    np.testing.assert_array_equal(rows[:, -2:], rows[:, [header.index("fx"), header.index("fy")]])


class _FallingBehind:
    """The simulated cell as a paced robot whose loop is ``behind`` periods behind its schedule
    from its 50th cycle on (what a robot's pacer reports after a stall)."""

    def __init__(self, robot: object, behind: int) -> None:
        self._robot, self._behind, self.cycles = robot, behind, 0
        self.late_cycles, self.worst_lateness_s, self.restarts = 0, 0.0, 0

    def __getattr__(self, name: str) -> object:
        return getattr(self._robot, name)

    def wait_cycle(self) -> None:
        self.cycles += 1
        self._robot.wait_cycle()  # type: ignore[attr-defined]

    @property
    def periods_behind(self) -> int:
        return self._behind if self.cycles >= 50 else 0

    def restart_schedule(self) -> None:
        self.restarts += 1


@pytest.mark.parametrize("behind", [2, 3])
def test_a_loop_as_far_behind_as_the_limit_stops_the_run_and_one_period_less_does_not(
    tool: GravityModel, tmp_path: Path, behind: int
) -> None:
    config = RunConfig(AdmittanceConfig(_limits()), duration_s=0.2, max_late_cycles=3)
    log = tmp_path / "run.csv"
    with ftcomp.open_robot(PLACE) as robot, ftcomp.open_sensor("sim://", robot) as sensor:
        paced = _FallingBehind(robot, behind)
        result = run_compliant(paced, sensor, tool, config, log)  # type: ignore[arg-type]
    if behind < 3:
        assert result.outcome == "duration", result.message
        return
    assert paced.restarts == 1  # the loop started the robot's schedule
    assert result.outcome == "loop_late" and result.faulted
    assert result.message.startswith("loop late: the loop fell 3 periods behind"), result.message
    assert result.cycles == 50  # the step that saw it ended the run
    _, rows = _read_log(log)
    assert len(rows) == result.cycles


def test_run_configurations_are_checked(tool: GravityModel) -> None:
    with pytest.raises(ParameterError, match="unknown selection axis 'q'"):
        AdmittanceConfig(_limits(), axes="q")
    with pytest.raises(ParameterError, match="k2 must be >= 0"):
        AdmittanceConfig(_limits(), k2=(-1.0,) * 6)
    with pytest.raises(ParameterError, match="duration_s must be > 0"):
        RunConfig(AdmittanceConfig(_limits()), duration_s=0.0)
