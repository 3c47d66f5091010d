"""The ur:// backend through ur_rtde: the receive side against the fake controller; every call
of the control side checked against the installed ``RTDEControlInterface``."""

from __future__ import annotations

import contextlib
import os
import re
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.errors import HardwareError, ParameterError, UnreachablePoseError
from ftcomp.hardware.registry import open_robot, open_sensor
from ftcomp.hardware.ur import URRobot

rtde_control = pytest.importorskip("rtde_control")
pytest.importorskip("rtde_receive")

from standins.launch import loopback_address, running, running_all  # noqa: E402
from standins.scenario import TOOL_MODEL, Scenario, rotvecs  # noqa: E402

#: The installed class, kept before any test replaces it.
REAL_CONTROL = rtde_control.RTDEControlInterface

#: Doubles travel over RTDE exactly; the conversions (rotation vector <-> matrix) cost a few ulp.
EXACT = 1e-12


pytestmark = pytest.mark.live


def _scenario(**options: object) -> Scenario:
    settings: dict[str, object] = {"max_s": 10.0, **options}
    return Scenario(
        t0=time.monotonic(),
        rotvecs_base_tcp=rotvecs([(25.0, -35.0, 150.0)]),
        p_base_tcp_m=[0.45, -0.12, 0.33],
        model=Scenario.model_fields(TOOL_MODEL),
        **settings,  # type: ignore[arg-type]
    )


# ----------------------------------------------------------------- the control side
_SIGNATURE = re.compile(r"^(?:\d+\. )?(\w+)\(self: [\w.]+(?:, (.*))?\) -> (.+)$")


def _split(params: str) -> list[str]:
    """Top-level comma split (types hold brackets)."""
    out, depth, start = [], 0, 0
    for i, ch in enumerate(params):
        depth += ch == "["
        depth -= ch == "]"
        if ch == "," and depth == 0:
            out.append(params[start:i].strip())
            start = i + 1
    if params.strip():
        out.append(params[start:].strip())
    return out


def _signatures(name: str) -> list[tuple[list[tuple[str, str, bool]], str]]:
    """Every overload of a method of the installed RTDEControlInterface, from its pybind11
    docstring: ``([(parameter, type, has_default)], return type)``."""
    doc = getattr(REAL_CONTROL, name).__doc__ or ""
    found = []
    for line in doc.splitlines():
        match = _SIGNATURE.match(line.strip())
        if match and match.group(1) == name:
            params = []
            for item in _split(match.group(2) or ""):
                head, _, default = item.partition(" = ")
                pname, _, ptype = head.partition(": ")
                params.append((pname, ptype, bool(default)))
            found.append((params, match.group(3)))
    return found


def _fits(value: Any, ptype: str) -> bool:
    if ptype == "float":
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if ptype == "bool":
        return isinstance(value, bool)
    if ptype == "int":
        return isinstance(value, int) and not isinstance(value, bool)
    if ptype == "str":
        return isinstance(value, str)
    if ptype == "list[float]":
        return isinstance(value, list) and all(_fits(v, "float") for v in value)
    if ptype == "list[list[float]]":
        return isinstance(value, list) and all(_fits(v, "list[float]") for v in value)
    return True  # enums (flags) and other types: not used by the backend


def _accepts(params: list[tuple[str, str, bool]], args: tuple, kwargs: dict) -> bool:
    if len(args) > len(params) or any(k not in {p[0] for p in params} for k in kwargs):
        return False
    for i, (pname, ptype, has_default) in enumerate(params):
        if i < len(args):
            value = args[i]
        elif pname in kwargs:
            value = kwargs[pname]
        elif has_default:
            continue
        else:
            return False
        if not _fits(value, ptype):
            return False
    return True


class CheckedControl:
    """Stands in for RTDEControlInterface: every call must match one of the installed class's
    signatures; calls are recorded; each returns what a healthy controller would."""

    calls: ClassVar[list[str]] = []

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        doc = REAL_CONTROL.__init__.__doc__ or ""
        line = next(x for x in doc.splitlines() if x.startswith("__init__("))
        params = [
            (h.partition(": ")[0], h.partition(": ")[2], bool(d))
            for h, _, d in (
                p.partition(" = ") for p in _split(line[line.index(", ") + 2 : line.rindex(")")])
            )
        ]
        assert _accepts(params, args, kwargs), ("__init__", args, kwargs)
        CheckedControl.calls.append("__init__")

    def __getattr__(self, name: str) -> Any:
        overloads = _signatures(name)
        assert overloads, f"RTDEControlInterface has no method {name}"

        def call(*args: Any, **kwargs: Any) -> Any:
            fitting = [ret for params, ret in overloads if _accepts(params, args, kwargs)]
            assert fitting, f"{name}{args!r} {kwargs!r} matches no signature of the installed class"
            CheckedControl.calls.append(name)
            return True if fitting[0] == "bool" else None

        return call


def test_every_control_call_the_backend_makes_exists_with_that_signature(
    request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(rtde_control, "RTDEControlInterface", CheckedControl)
    CheckedControl.calls = []
    host = loopback_address(request.node.name)
    with running("fake_ur", host, _scenario().to_json()):
        for command in ("speedl", "servol"):
            with open_robot(f"ur://{host}?command={command}") as robot:
                here = robot.pose()  # the stand-in's arm does not move: moveL to where it is
                robot.move_pose(here.p_base_tcp, here.R_base_tcp, 1.0)
                robot.command_twist(np.array([0.0, 0.0, -0.005, 0.0, 0.0, 0.01]))
                robot.wait_cycle()
                robot.command_twist(np.array([0.0, 0.0, -0.005, 0.0, 0.0, 0.01]))
                robot.stop()
    expected = {
        "__init__",
        "getInverseKinematicsHasSolution",
        "isPoseWithinSafetyLimits",
        "moveL",
        "speedL",
        "servoL",
        "speedStop",
        "servoStop",
        "stopScript",
        "disconnect",
    }
    assert set(CheckedControl.calls) == expected
    # Each interface disconnected once, and kept: a destructor would disconnect again with
    # ur_rtde's 0.5 s sleep (URRobot.__exit__)
    assert CheckedControl.calls.count("disconnect") == 2


def test_an_unreachable_pose_is_refused_before_any_move(
    request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch
) -> None:
    class Unreachable(CheckedControl):
        def getInverseKinematicsHasSolution(self, *args: Any) -> bool:
            return False

    monkeypatch.setattr(rtde_control, "RTDEControlInterface", Unreachable)
    CheckedControl.calls = []
    host = loopback_address(request.node.name)
    with running("fake_ur", host, _scenario().to_json()), open_robot(f"ur://{host}") as robot:
        here = robot.pose()
        with pytest.raises(UnreachablePoseError, match="not reachable"):
            robot.move_pose(here.p_base_tcp, here.R_base_tcp, 1.0)
    assert "moveL" not in CheckedControl.calls


def test_a_move_that_ends_away_from_its_target_is_an_error(
    request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch
) -> None:
    """moveL reported done but the arm is not there (the twin's arm held by a joint limit, seen
    at designed poses 12 of 30): an error, not a recording at the wrong pose."""
    monkeypatch.setattr(rtde_control, "RTDEControlInterface", CheckedControl)
    host = loopback_address(request.node.name)
    with running("fake_ur", host, _scenario().to_json()), open_robot(f"ur://{host}") as robot:
        here = robot.pose()  # the stand-in's arm stays here whatever moveL says
        robot.move_pose(here.p_base_tcp + np.array([0.0, 0.0, 0.0005]), here.R_base_tcp, 1.0)
        with pytest.raises(HardwareError, match=r"moveL ended 10\.0 mm and 0\.0 deg from its"):
            robot.move_pose(here.p_base_tcp + np.array([0.0, 0.0, 0.01]), here.R_base_tcp, 1.0)


@pytest.mark.parametrize(
    ("options", "speed_rad_s", "accel_rad_s2"),
    [("", 1.05, 1.4), ("?max_joint_speed_deg_s=120&max_joint_accel_deg_s2=240", 2.094, 4.189)],
)
def test_joint_moves_keep_to_the_uri_s_joint_speed_and_acceleration(
    request: pytest.FixtureRequest,
    monkeypatch: pytest.MonkeyPatch,
    options: str,
    speed_rad_s: float,
    accel_rad_s2: float,
) -> None:
    """moveJ at most at ``max_joint_speed_deg_s`` (default ur_rtde's 1.05 rad/s), with
    ``max_joint_accel_deg_s2`` (1.4 rad/s^2), however short the move is asked to be."""
    sent: list[tuple[Any, ...]] = []

    class Recording(CheckedControl):
        def getInverseKinematics(self, pose: Any, qnear: Any, *args: Any) -> list[float]:
            return [qnear[0] + 1.0, *qnear[1:]]  # the leading joint 1 rad away

        def moveJ(self, *args: Any) -> bool:
            sent.append(args)
            return True

    monkeypatch.setattr(rtde_control, "RTDEControlInterface", Recording)
    host = loopback_address(request.node.name)
    with (
        running("fake_ur", host, _scenario().to_json()),
        open_robot(f"ur://{host}{options}") as robot,
    ):
        here = robot.pose()
        robot.move_pose_joints(here.p_base_tcp, here.R_base_tcp, 0.01)
    ((_q, speed, accel, asynchronous),) = sent
    assert speed == pytest.approx(speed_rad_s, abs=1e-3) and accel == pytest.approx(
        accel_rad_s2, abs=1e-3
    )
    assert not asynchronous


@pytest.mark.parametrize("command", ["speedl", "servol"])
def test_a_refused_motion_command_is_a_fault(
    request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch, command: str
) -> None:
    """ur_rtde's speedL/servoL return False once its script stopped (from the pendant)."""

    class ScriptStopped(CheckedControl):
        def speedL(self, *args: Any) -> bool:
            return False

        def servoL(self, *args: Any) -> bool:
            return False

    monkeypatch.setattr(rtde_control, "RTDEControlInterface", ScriptStopped)
    host = loopback_address(request.node.name)
    with (
        running("fake_ur", host, _scenario().to_json()),
        open_robot(f"ur://{host}?command={command}") as robot,
        pytest.raises(HardwareError, match=r"refused .*script is not running"),
    ):
        robot.command_twist(np.array([0.0, 0.0, -0.005, 0.0, 0.0, 0.0]))


# ----------------------------------------------------------------- the receive side
def test_pose_and_built_in_sensor_are_converted_to_our_frames(
    request: pytest.FixtureRequest,
) -> None:
    s = _scenario()
    host = loopback_address(request.node.name)
    p, R_tcp, _ = s.tcp_pose(0.0)
    truth = TOOL_MODEL.predict(R_tcp.as_matrix())  # identity mount: the sensor frame is the TCP's
    with running("fake_ur", host, s.to_json()), open_robot(f"ur://{host}") as robot:
        assert isinstance(robot, URRobot) and robot.version[:2] == (5, 11)
        assert robot.control_period_s == pytest.approx(0.002)  # e-Series: 500 Hz
        before_ns = time.monotonic_ns()
        pose = robot.pose()
        after_ns = time.monotonic_ns()
        assert np.allclose(pose.p_base_tcp, p, atol=EXACT, rtol=0)
        assert np.allclose(pose.R_base_tcp, R_tcp.as_matrix(), atol=EXACT, rtol=0)
        # Stamped on the host's monotonic clock as it is read: within the call, whatever the
        # load (ordered against the call, not a fixed number of milliseconds).
        assert before_ns <= pose.t_ns <= after_ns
        assert robot.settle(1.0) < 0.5  # the stand-in's joints are still
        no_offset = "&tcp_offset_mm=0,0,0&tcp_rotvec_rad=0,0,0"
        for options in ("", f"?wrench=tcp{no_offset}"):
            with open_sensor(f"ur://{host}{options}", robot) as sensor:
                first = sensor.read()
                assert np.allclose(first.wrench_sensor, truth, atol=EXACT, rtol=0)
                time.sleep(0.01)
                new = sensor.read_new()  # the newest only: the sensor is polled, not streamed
                again = sensor.read_new()  # nothing, unless a packet came in between
                assert len(new) == 1 and len(again) <= 1
                assert all(a.t_ns > new[0].t_ns for a in again)
                # Wait for the next packet (the event); the ceiling only guards a hang.
                deadline = time.monotonic() + 30.0
                while sensor.read().t_ns <= first.t_ns and time.monotonic() < deadline:
                    time.sleep(0.002)
                assert sensor.read().t_ns > first.t_ns
        flipped = open_sensor(f"ur://{host}?sign=-1", robot)
        with flipped:
            assert np.allclose(flipped.read().wrench_sensor, -truth, atol=EXACT, rtol=0)
        robot.command_twist(np.zeros(6))  # a zero twist at rest opens no control interface
        robot.stop()
        assert robot.control is None


def test_an_e_series_tcp_force_is_moved_from_the_flange_to_the_tcp(
    request: pytest.FixtureRequest,
) -> None:
    """e-Series ``actual_TCP_force``: the wrench at the flange in base orientation (as UR's ROS
    drivers read it). The stand-in serves it so: its sensor frame is the flange, placed on the
    TCP by the scenario's mount, so the controller's TCP offset is the mount's inverse."""
    s = _scenario(mount_xyz_m=[0.01, -0.02, 0.15], mount_rpy_deg=[10.0, -20.0, 35.0])
    host = loopback_address(request.node.name)
    _, R_tcp, _ = s.tcp_pose(0.0)
    mount = s.mount()  # the flange in the TCP frame
    R_base_flange = R_tcp.as_matrix() @ mount.R_tcp_sensor
    w_flange = TOOL_MODEL.predict(R_base_flange)
    f_tcp = mount.R_tcp_sensor @ w_flange[:3]
    m_tcp = mount.R_tcp_sensor @ w_flange[3:] + np.cross(mount.p_tcp_sensor_m, f_tcp)
    R_flange_tcp = mount.R_tcp_sensor.T
    p_flange_tcp_mm = -R_flange_tcp @ mount.p_tcp_sensor_m * 1e3
    offset = ",".join(repr(float(v)) for v in p_flange_tcp_mm)
    rotvec = ",".join(repr(float(v)) for v in Rotation.from_matrix(R_flange_tcp).as_rotvec())
    with running("fake_ur", host, s.to_json()), open_robot(f"ur://{host}") as robot:
        uri = f"ur://{host}?wrench=tcp&tcp_offset_mm={offset}&tcp_rotvec_rad={rotvec}"
        with open_sensor(uri, robot) as sensor:
            w = sensor.read().wrench_sensor
        assert np.allclose(w, np.concatenate([f_tcp, m_tcp]), atol=1e-9, rtol=0)
        with open_sensor(f"ur://{host}", robot) as raw:  # ft_raw_wrench: the flange frame
            assert np.allclose(raw.read().wrench_sensor, w_flange, atol=EXACT, rtol=0)
        with pytest.raises(ParameterError, match="actual_TCP_force is at the flange"):
            open_sensor(f"ur://{host}?wrench=tcp", robot).__enter__()
        with pytest.raises(ParameterError, match="give both"):
            open_sensor(f"ur://{host}?wrench=tcp&tcp_offset_mm=0,0,0", robot)


def test_a_controller_that_stops_sending_is_a_lost_connection(
    request: pytest.FixtureRequest,
) -> None:
    host = loopback_address(request.node.name)
    with (
        running("fake_ur", host, _scenario(silent_after_s=0.3).to_json()),
        open_robot(f"ur://{host}?timeout_s=0.2") as robot,
    ):
        robot.pose()
        time.sleep(0.8)
        with pytest.raises(HardwareError, match="no new data from the controller"):
            for _ in range(3):
                robot.pose()
                time.sleep(0.1)


@pytest.fixture(scope="module")
def controllers() -> Iterator[dict[str, str]]:
    """A working fake controller, one that answers the handshake but never sends data, and an
    address where nothing listens."""
    hosts = {name: loopback_address(f"{__name__}/{name}") for name in ("good", "silent", "nobody")}
    with running_all(
        [
            ("fake_ur", (hosts["good"], _scenario(max_s=60.0).to_json())),
            ("fake_ur", (hosts["silent"], _scenario(silent_after_s=0.0, max_s=60.0).to_json())),
        ]
    ):
        yield hosts


@pytest.mark.parametrize(
    ("robot", "sensor", "message"),
    [
        ("ur://{nobody}", None, "connection refused on port 30004"),
        ("ur://{silent}?connect_timeout_s=1", None, "no answer within 1 s while waiting"),
        ("ur://{good}:30003", None, "ur:// takes a host only"),
        ("ur://{good}?speed=1", None, "unknown option 'speed' for ur://"),
        ("ur://{good}?max_speed_mm_s=5000", None, "above 1000 mm/s"),
        ("ur://{good}?max_joint_speed_deg_s=400", None, "max_joint_speed_deg_s above 179"),
        ("ur://{good}?max_joint_accel_deg_s2=-1", None, "max_joint_accel_deg_s2"),
        ("ur://", None, "give the controller's address"),
        ("ur://{good}", "ur://{nobody}", "must be on the robot's controller"),
        ("ur://{good}", "ur://{good}?wrench=joint", "expected one of raw, tcp"),
        ("sim://", "ur://{good}", "needs a ur://HOST robot"),
    ],
)
def test_bad_configurations_are_one_clear_error_in_bounded_time(
    robot: str, sensor: str | None, message: str, controllers: dict[str, str]
) -> None:
    hosts = controllers
    t = time.monotonic()
    with (
        pytest.raises((ParameterError, HardwareError)) as info,
        open_robot(robot.format(**hosts)) as opened,
    ):
        if sensor is not None:
            with open_sensor(sensor.format(**hosts), opened):
                pass
    assert message in str(info.value) and "\n" not in str(info.value)
    assert time.monotonic() - t < 3.0  # the connection check gives up after 1 s


def _tcp_connections_to(host: str) -> int:
    """This process's established TCP connections to ``host`` (its sockets' inodes among the
    kernel's connection table, ``/proc/net/tcp``)."""
    inodes = set()
    for fd in Path("/proc/self/fd").iterdir():
        with contextlib.suppress(OSError):
            target = os.readlink(fd)
            if target.startswith("socket:["):
                inodes.add(target[8:-1])
    remote = "".join(f"{int(part):02X}" for part in reversed(host.split(".")))
    count = 0
    for line in Path("/proc/net/tcp").read_text().splitlines()[1:]:
        fields = line.split()
        established = fields[3] == "01"
        if established and fields[2].startswith(remote + ":") and fields[9] in inodes:
            count += 1
    return count


@pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="needs Linux's /proc/net/tcp")
def test_leaving_the_robot_closes_every_connection_to_the_controller(
    request: pytest.FixtureRequest,
) -> None:
    """The interfaces disconnect at once and are kept, not destroyed (a destructor disconnects
    again, with ur_rtde's 0.5 s sleep): no connection of theirs may outlive the block."""
    pytest.importorskip("mujoco")
    from standins.twin_process import running_twin

    with running_twin(request.node.name, seconds=120.0) as twin:  # it serves the control side
        with open_robot(twin.robot_uri) as robot:
            robot.connect_control()
            robot.command_twist(np.array([0.0, 0.0, 0.001, 0.0, 0.0, 0.0]))
            robot.wait_cycle()
            assert robot.control is not None
            during = _tcp_connections_to(twin.robot_host)
        after = _tcp_connections_to(twin.robot_host)
    assert during >= 3, during  # receive, control's RTDE, its script and dashboard clients
    assert after == 0, after
