"""The franka:// backend against franky-sim, a third-party Franka simulator (Tim Schneider and
Baris Yazici, Apache-2.0) serving the libfranka network protocol from a MuJoCo FR3.

One simulator serves the module's tests, in its own process under ``nice -n 19``, bound to a
loopback address of this file's own, ended by ``timeout`` if the tests hang and killed at
teardown. franky-control's libfranka talks to it as to an arm.

What franky-sim shows and what it cannot: it steps its physics at most at 1 kHz and slower when
the host is busy (a few hundred steps per wall second on a shared 2-core host), so its time
runs slower than the wall clock; a client that stalls loses nothing (it is never late), and it
simulates no reflexes (its collision thresholds are acknowledged, not applied) and no external
wrench. These tests show the protocol and the motion, not timing: the velocity test measures
its second on the controller's own clock. The fault forced here is the controller going
silent (its process stopped), which libfranka reports as it would on a real arm.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import select
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.cli import main
from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.control.safety import SafetyLimits
from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.franka import FrankaRobot, fault_line
from ftcomp.hardware.protocols import (
    ChecksReachability,
    MovesInJointSpace,
    NothingToClose,
    ReportsLateness,
    WrenchSample,
)
from ftcomp.hardware.registry import open_robot
from ftcomp.io.calibration_json import FORMAT
from ftcomp.io.dynamic_json import FORMAT as DYNAMIC_FORMAT
from ftcomp.model import GravityModel
from ftcomp.session.outcome import Outcome
from ftcomp.session.run import AdmittanceConfig, RunConfig, run_compliant

franky = pytest.importorskip("franky", reason="franky-control is not installed (extra franka)")
pytest.importorskip("franky_sim", reason="franky-sim is not installed (the dev extra)")

from standins.launch import Drain, loopback_address  # noqa: E402

#: The simulator's executable, beside this interpreter.
FRANKY_SIM = Path(sys.executable).with_name("franky-sim")
#: The line franky-sim prints once it listens.
READY = "Connect to the server using"
#: The simulator ends by itself after this long, whatever happens to the tests [s].
SIM_MAX_S = 300
_NICE_AND_BOUNDED = ("nice", "-n", "19", "timeout", "-s", "KILL", str(SIM_MAX_S))


pytestmark = pytest.mark.live


class Sim:
    """The running simulator: its address and process group (to stop and resume it)."""

    def __init__(self, address: str, proc: subprocess.Popen[str], drain: Drain) -> None:
        self.address = address
        self.proc = proc
        self.drain = drain

    def uri(self, options: str = "") -> str:
        """The backend's URI for it (libfranka's real-time check off: not a real-time host)."""
        return f"franka://{self.address}?realtime=ignore" + (f"&{options}" if options else "")

    def pause(self) -> None:
        """Stop the simulator's processes (the controller goes silent)."""
        os.killpg(self.proc.pid, signal.SIGSTOP)

    def resume(self) -> None:
        """Let them go on."""
        os.killpg(self.proc.pid, signal.SIGCONT)


@contextlib.contextmanager
def _launched(command: list[str], ready: str, address: str) -> Iterator[Sim]:
    """A simulator process (its own process group), once it printed ``ready``; killed at the
    end of the block."""
    tests = str(Path(__file__).resolve().parents[1])  # for the stand-ins' modules
    path = os.pathsep.join(filter(None, [tests, os.environ.get("PYTHONPATH", "")]))
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "PYTHONPATH": path}
    proc = subprocess.Popen(
        command,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,  # its own process group: timeout and the simulator
    )
    drain: Drain | None = None
    try:
        assert proc.stdout is not None
        deadline = time.monotonic() + 60.0
        seen = ""
        while ready not in seen:
            if time.monotonic() > deadline or proc.poll() is not None:
                _kill_group(proc)
                _, err = proc.communicate(timeout=5)
                pytest.fail(f"{command[-3:]} did not start: {seen[-500:]}{err[-2000:]}")
            readable, _, _ = select.select([proc.stdout], [], [], 0.5)
            if readable:
                seen += proc.stdout.readline()
        drain = Drain(proc)
        yield Sim(address, proc, drain)
    finally:
        _kill_group(proc)
        proc.wait(timeout=10)
        if drain is not None:
            drain.join()


@pytest.fixture(scope="module")
def sim() -> Iterator[Sim]:
    """franky-sim's MuJoCo FR3 on a loopback address of this file's own (ports 1337/1338)."""
    if not FRANKY_SIM.exists():
        pytest.skip(f"{FRANKY_SIM} not found (franky-sim is installed without its script)")
    address = loopback_address("franky-sim")
    command = [*_NICE_AND_BOUNDED, str(FRANKY_SIM), "-s", "mujoco", "--hostname", address]
    with _launched(command, READY, address) as running:
        yield running


def _kill_group(proc: subprocess.Popen[str]) -> None:
    """Kill the simulator and its ``timeout`` (one process group), stopped or not."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGKILL)
        os.killpg(proc.pid, signal.SIGCONT)  # a stopped process dies once it runs


def _angle_deg(R_a: np.ndarray, R_b: np.ndarray) -> float:
    return math.degrees(Rotation.from_matrix(R_a @ R_b.T).magnitude())


def test_the_backend_reads_the_fr3s_pose_in_its_base_frame(sim: Sim) -> None:
    with open_robot(sim.uri()) as robot:
        assert isinstance(robot, FrankaRobot) and isinstance(robot, ReportsLateness)
        pose = robot.pose()
        q = robot.joint_positions_rad()
    # franky-sim starts at its home joints (0, 0, 0, -pi/2, 0, pi/2, pi/4): the hand's end
    # effector 0.55 m ahead of the base, 0.52 m up, pointing down.
    assert q.shape == (7,)
    assert pose.p_base_tcp[0] == pytest.approx(0.554, abs=0.02)
    assert pose.p_base_tcp[2] == pytest.approx(0.521, abs=0.02)
    assert pose.R_base_tcp[2, 2] == pytest.approx(-1.0, abs=1e-3)  # z down
    assert abs(pose.t_ns - time.monotonic_ns()) < 1e9


def test_ten_mm_per_s_for_one_second_of_the_controllers_time_moves_ten_mm(sim: Sim) -> None:
    # The controller's clock, not the wall's: franky-sim's time runs slower than the wall's on
    # a busy host (see the module docstring); on a real arm the two are one. Run from the
    # simulator's start configuration, before the moves: after large reorientations its elbow
    # has wound up in the null space, and there franky's own velocity motion (not only this
    # backend's) drifts 1-1.5 mm sideways in the same second.
    with open_robot(sim.uri()) as robot:
        assert isinstance(robot, FrankaRobot)
        robot.settle(5.0)
        start = robot.pose()
        t0_s = robot.arm.state.time.to_sec()
        twist = np.array([0.01, 0.0, 0.0, 0.0, 0.0, 0.0])
        while robot.arm.state.time.to_sec() - t0_s < 1.0:
            robot.command_twist(twist)
            robot.wait_cycle()
        robot.stop()
        robot.settle(5.0)
        moved_mm = (robot.pose().p_base_tcp - start.p_base_tcp) * 1e3
        robot.move_pose(start.p_base_tcp, start.R_base_tcp, 2.0)
    assert moved_mm[0] == pytest.approx(10.0, abs=1.0), moved_mm
    assert np.all(np.abs(moved_mm[1:]) < 1.0), moved_mm


def test_a_reflex_is_one_line_naming_libfrankas_errors() -> None:
    # The line on franky's own exception type with the text libfranka gives a reflex
    # (robot_impl.cpp: the aborted motion and its errors); a reflex forced on franky-sim's arm:
    # test_a_forced_reflex_ends_run_with_its_stop_and_a_complete_log.
    exc = franky.ControlException(
        'libfranka: Move command aborted: motion aborted by reflex! ["cartesian_reflex"]\n'
        "control_command_success_rate: 0.99"
    )
    line = fault_line(exc, '["cartesian_reflex"]')
    assert line.startswith("the arm stopped: libfranka: Move command aborted: motion aborted by")
    assert "\n" not in line and line.count("cartesian_reflex") == 1
    late = fault_line(
        franky.ControlException("libfranka: ..."), '["communication_constraints_violation"]'
    )
    assert "real-time kernel" in late


def test_bad_uris_are_refused_naming_the_option() -> None:
    with pytest.raises(ParameterError, match="FCI address"):
        open_robot("franka://")
    with pytest.raises(ParameterError, match="dynamics must be in"):
        open_robot("franka://127.0.0.1?dynamics=2")
    with pytest.raises(ParameterError, match="realtime"):
        open_robot("franka://127.0.0.1?realtime=maybe")
    with pytest.raises(ParameterError, match="unknown option 'speed'"):
        open_robot("franka://127.0.0.1?speed=1")


def test_connecting_without_a_real_time_kernel_says_how(sim: Sim) -> None:
    if Path("/sys/kernel/realtime").exists():
        pytest.skip("this host runs a real-time kernel")
    with (
        pytest.raises(HardwareError, match="real-time kernel"),
        open_robot(f"franka://{sim.address}"),
    ):
        pass


#: Three designed poses near the FR3's home: the end effector moved a few centimetres and
#: tilted by up to 15 deg about three axes (orientations a calibration design asks for).
DESIGNED = [
    ([0.03, -0.05, 0.02], [15.0, 0.0, 0.0]),
    ([-0.04, 0.03, 0.05], [0.0, -12.0, 10.0]),
    ([0.02, 0.06, -0.03], [-8.0, 10.0, -20.0]),
]


@pytest.mark.parametrize("move", ["move_pose", "move_pose_joints"])
def test_moves_reach_three_designed_poses_within_1_mm_and_a_tenth_of_a_degree(
    sim: Sim, move: str
) -> None:
    """Both moves: franky's Cartesian motion, and (as record visits poses) a joint motion to
    ftcomp's inverse kinematics on libfranka's model of the arm."""
    with open_robot(sim.uri("dynamics=0.3")) as robot:
        assert isinstance(robot, ChecksReachability) and isinstance(robot, MovesInJointSpace)
        home = robot.pose()
        errors = []
        for dp, rpy_deg in DESIGNED:
            p = home.p_base_tcp + np.array(dp)
            R = Rotation.from_euler("xyz", rpy_deg, degrees=True).as_matrix() @ home.R_base_tcp
            assert robot.is_reachable(p, R)
            getattr(robot, move)(p, R, 2.0)
            robot.settle(5.0)
            at = robot.pose()
            errors.append((np.linalg.norm(at.p_base_tcp - p) * 1e3, _angle_deg(at.R_base_tcp, R)))
        robot.move_pose(home.p_base_tcp, home.R_base_tcp, 2.0)
    for off_mm, off_deg in errors:
        assert off_mm < 1.0 and off_deg < 0.1, errors


def test_payload_set_writes_the_calibrations_load_through_the_mount_and_the_hand(
    sim: Sim, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A 0.5 kg tool, its centre of gravity 40 mm along the sensor's z; the sensor 30 mm beyond
    # the end effector, turned 90 deg about z. franky-sim's end effector is the Franka Hand's
    # (F_T_EE: 103.4 mm along the flange's z, turned -45 deg about it), so on the flange the
    # centre of gravity is 103.4 + 30 + 40 mm along z. The inertia is about the centre of
    # gravity, turned from the sensor's axes into the flange's.
    cal = tmp_path / "cal.json"
    cal.write_text(
        json.dumps(
            {
                "format": FORMAT,
                "method": "paper",
                "tool_weight_N": 0.5 * STANDARD_GRAVITY_MPS2,
                "center_of_gravity_m": [0.0, 0.0, 0.04],
                "force_bias_N": [0.0, 0.0, 0.0],
                "torque_bias_Nm": [0.0, 0.0, 0.0],
                "base_tilt_deg": {"U": 0.0, "V": 0.0},
                "gravity_in_base_N": [0.0, 0.0, -0.5 * STANDARD_GRAVITY_MPS2],
            }
        )
    )
    inertia = tmp_path / "dynamic.json"
    inertia.write_text(
        json.dumps(
            {
                "format": DYNAMIC_FORMAT,
                "inertia_cog_kgm2": {
                    "Ixx": 1e-3,
                    "Iyy": 2e-3,
                    "Izz": 3e-3,
                    "Ixy": 0.0,
                    "Ixz": 0.0,
                    "Iyz": 0.0,
                },
            }
        )
    )
    argv = ["payload", "set", sim.uri(), "-c", str(cal), "--mount", "0,0,30,0,0,90"]
    assert main([*argv, "--inertia", str(inertia)]) == 0
    said = capsys.readouterr().out.splitlines()
    assert said[0].endswith(
        "load was 0.0000 kg at [0.00, 0.00, 0.00] mm from the flange, "
        "inertia diagonal [0.00e+00, 0.00e+00, 0.00e+00] kg m^2"
    ), said
    # The sensor's x is the end effector's y, the end effector's x is at -45 deg on the
    # flange: the inertia's diagonal comes out mixed in x and y, the same in z.
    assert said[1].endswith(
        "load now 0.5000 kg at [0.00, 0.00, 173.40] mm from the flange, "
        "inertia diagonal [1.50e-03, 1.50e-03, 3.00e-03] kg m^2"
    ), said


class _SteadyPush(NothingToClose):
    """A wrist sensor stand-in on the host's clock: a constant push of ``force_N`` along the
    sensor's z with a little noise (a repeated reading is a frozen sensor's), no tool."""

    def __init__(self, force_N: float, seed: int) -> None:
        self._rng = np.random.default_rng(seed)
        self._force_N = force_N

    def read(self) -> WrenchSample:
        wrench = self._rng.normal(0.0, 0.01, 6)
        wrench[2] += self._force_N
        return WrenchSample.owning(time.monotonic_ns(), wrench)

    def read_new(self) -> list[WrenchSample]:
        return [self.read()]


def _slow_run() -> tuple[RunConfig, GravityModel]:
    """A 20 s admittance run at 10 mm/s at most, 0.1 s stale limit, and no tool: for a run
    that a fault ends."""
    limits = SafetyLimits(
        max_twist=np.array([0.01] * 3 + [0.1] * 3),
        max_twist_rate=np.array([0.1] * 3 + [1.0] * 3),
        max_travel=np.array([0.05] * 3 + [0.2] * 3),
        max_force_N=40.0,
        max_torque_Nm=8.0,
        stale_after_s=0.1,
        max_repeated_samples=2,
    )
    no_tool = GravityModel(
        0.0, np.zeros(3), np.zeros(3), np.zeros(3), tilt_U_rad=0.0, tilt_V_rad=0.0
    )
    return RunConfig(AdmittanceConfig(limits), duration_s=20.0, max_late_cycles=10_000), no_tool


def test_the_controller_going_silent_ends_run_with_its_line_and_a_complete_log(
    sim: Sim, tmp_path: Path
) -> None:
    # The last test of the module: the simulator is paused for longer than libfranka's 1 s
    # receive time-out, then resumed.
    config, no_tool = _slow_run()
    log = tmp_path / "run.csv"
    paused_at: list[float] = []
    reads = [0]

    class _PausesTheSim(_SteadyPush):
        def read(self) -> WrenchSample:
            reads[0] += 1
            if reads[0] == 100:  # the loop is going: the arm moves at the push's twist
                sim.pause()
                paused_at.append(time.monotonic())
            elif paused_at and time.monotonic() - paused_at[0] > 1.5:
                sim.resume()
            return super().read()

    with open_robot(sim.uri("frequency_hz=100")) as robot:
        try:
            result = run_compliant(robot, _PausesTheSim(2.0, seed=37), no_tool, config, log)
        finally:
            sim.resume()
    assert result.outcome is Outcome.ERROR, (paused_at, result)
    assert "lost the connection to the arm (libfranka: UDP receive: Timeout)" in result.message
    assert time.monotonic() - paused_at[0] < 5.0
    rows = np.loadtxt(log, delimiter=",", skiprows=1, ndmin=2)
    assert len(rows) == result.cycles > 50
    assert np.all(np.isfinite(rows))


def test_a_silent_controller_is_seen_by_a_pose_read_while_nothing_moves(sim: Sim) -> None:
    # stream and a still run read poses and command nothing: the read itself must notice.
    with open_robot(sim.uri()) as robot:
        robot.pose()
        sim.pause()
        try:
            t0 = time.monotonic()
            with pytest.raises(HardwareError, match=r"lost the connection to the arm"):
                while time.monotonic() - t0 < 5.0:
                    robot.pose()
                    robot.wait_cycle()
            seen_after_s = time.monotonic() - t0
        finally:
            sim.resume()
    assert seen_after_s < 3.0  # libfranka's receive time-out is 1 s


def test_a_forced_reflex_ends_run_with_its_stop_and_a_complete_log(tmp_path: Path) -> None:
    """franky-sim's own MuJoCo FR3, its protocol server with the arm's error state
    (standins/franky_sim_faults.py: franky-sim simulates no reflex): a ``cartesian_reflex``
    raised while ``run`` moves the arm ends the run in the period libfranka reports it, with
    the reflex's line, and the log whole."""
    address = loopback_address("franky-sim-faults")
    command = [sys.executable, "-m", "standins.franky_sim_faults", address, str(SIM_MAX_S)]
    config, no_tool = _slow_run()
    log = tmp_path / "run.csv"
    reads = [0]
    with _launched(command, "ready", address) as faulty:

        class _ForcesAReflex(_SteadyPush):
            def read(self) -> WrenchSample:
                reads[0] += 1
                if reads[0] == 100:  # the loop is going: the arm moves at the push's twist
                    os.kill(faulty.proc.pid, signal.SIGUSR1)
                return super().read()

        with open_robot(faulty.uri("frequency_hz=100")) as robot:
            result = run_compliant(robot, _ForcesAReflex(2.0, seed=41), no_tool, config, log)
        said = "".join(faulty.drain.lines["stdout"])
    assert "reflex" in said.split(), said
    assert result.outcome is Outcome.ERROR, result
    reflex = 'the arm stopped: libfranka: Move command aborted: motion aborted by reflex! ["ca'
    assert reflex + 'rtesian_reflex"]' in result.message, result.message
    # raised at the 100th cycle's read: seen within 0.1 s (10 periods at 100 Hz)
    assert 100 <= result.cycles <= 110, result.cycles
    rows = np.loadtxt(log, delimiter=",", skiprows=1, ndmin=2)
    assert len(rows) == result.cycles
    assert np.all(np.isfinite(rows))
