"""Every robot and sensor ftcomp knows, declared once: the device registry.

A :class:`Device` is one family of robots or of sensors. Its declaration says everything the
rest of ftcomp needs to know about it, so a new device is one declaration and its modules:

- the URI scheme that opens it live (``--robot ur://HOST``, ``--sensor netft://HOST``), the
  live backend behind it (``"module:factory"``, imported only when a URI asks for it, so a
  client library is needed only by those who use it), and the extra that installs that client;
- its face in the twin (:class:`TwinFace`): the same device's protocol served from the
  simulated cell (``ftcomp twin --robot NAME --sensor NAME``), with the faults it can inject
  on demand (:class:`Fault`) and what ``ftcomp run`` says on each;
- a one-line summary, the URI as a user writes it, and what it was tested against (the device
  table of docs/hardware.md is made from these; a test holds the page to it).

From the registry come the URI schemes (:mod:`ftcomp.hardware.registry`), the command line's
help for ``--robot`` and ``--sensor``, the twin's ``--robot``/``--sensor``/``--fault``
choices, the device conformance suite's pairs and the docs' device table.

Devices from elsewhere: a module named in the environment variable ``FTCOMP_DEVICES``
(comma-separated module names), or in the ``ftcomp.devices`` entry-point group of an installed
distribution, that defines ``DEVICES`` (a sequence of :class:`Device`) adds them, as the
built-in ones are added (:func:`devices`). Capabilities beyond the protocols (a sensor that
tares itself in hardware, a robot that checks reachability) are not declared here: they are
protocols the backend's objects implement (:mod:`ftcomp.hardware.protocols`).
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from importlib.metadata import entry_points
from typing import Any, Final, Literal

from ftcomp.errors import ParameterError

__all__ = [
    "DEVICES_ENV",
    "ENTRY_POINT_GROUP",
    "Device",
    "Fault",
    "Kind",
    "TwinFace",
    "device_table",
    "devices",
    "fault",
    "load_target",
    "twin_faces",
    "uri_help",
]

#: The environment variable naming modules of more devices (comma-separated).
DEVICES_ENV: Final = "FTCOMP_DEVICES"
#: The entry-point group of installed distributions' device modules.
ENTRY_POINT_GROUP: Final = "ftcomp.devices"

#: A device is a robot or a sensor.
Kind = Literal["robot", "sensor"]


@dataclass(frozen=True)
class Fault:
    """A fault a twin face injects on demand (``ftcomp twin --fault NAME``).

    Attributes:
        name: the fault's name (``rdt-loss``), unique among the faces of a twin.
        does: what the face does from the fault's time on.
        run_says: what ``ftcomp run`` prints when it stops on it (a part of its error line),
            or None where the fault is within the limits and ``run`` goes on to its end.
        seen_within_s: the longest time from the fault to ``run``'s last logged cycle [s]: the
            period that sees it, after the time the fault takes to show (a silent controller
            is seen after its time-out, a frozen sensor after the watchdog's count of
            identical readings), with the margin a shared test host needs.
    """

    name: str
    does: str
    run_says: str | None
    seen_within_s: float = 0.0


@dataclass(frozen=True)
class TwinFace:
    """A device's face in the twin: its protocol served from the simulated cell.

    Attributes:
        name: the twin's ``--robot``/``--sensor`` choice (``ur5e``, ``netft``).
        factory: ``"module:Class"`` of the face (:mod:`ftcomp.twin.faces` says what it
            implements), imported when a twin serves it.
        faults: the faults it injects on demand.
        arm: a robot face's arm, ``"module:function"`` returning the simulated cell's arm
            (:mod:`ftcomp.sim.arm`; a seven-joint arm is data), or None: the cell's default.
        rate_hz: a sensor face's default output rate [Hz] (None: the simulated sensor's).
        max_rate_hz: a sensor face's fastest output rate [Hz] (None: no other limit).
        requires: modules the live backend needs to drive this face (the conformance suite
            skips a pair whose client is not installed, saying which).
        record_options: URI options that make ``record`` against the face quick (a test's
            business: faster moves than a first session's defaults), appended to its URI.
    """

    name: str
    factory: str
    faults: tuple[Fault, ...] = ()
    arm: str | None = None
    rate_hz: float | None = None
    max_rate_hz: float | None = None
    requires: tuple[str, ...] = ()
    record_options: str = ""


@dataclass(frozen=True)
class Device:
    """One family of robots or sensors (module docstring).

    Attributes:
        kind: ``robot`` or ``sensor``.
        scheme: the URI scheme that opens it (``ur``), unique per kind.
        backend: ``"module:factory"`` of the live backend: a robot's ``factory(uri) -> Robot``,
            a sensor's ``factory(uri, robot | None) -> WrenchSensor``
            (:mod:`ftcomp.hardware.registry`).
        uri: the URI as a user writes it (``ur://HOST``), for help and docs.
        summary: what it is, in a few words.
        extra: the pyproject extra that installs its client library (None: none needed).
        tested: what the live backend was tested against.
        twin: its face in the twin, or None.
    """

    kind: Kind
    scheme: str
    backend: str
    uri: str
    summary: str
    extra: str | None = None
    tested: str = ""
    twin: TwinFace | None = None


_NOT_ON_A_TWIN: Final = "no twin face: a file, a fixed pose or the simulated cell itself"

#: The cell's network going silent: declared by the robot face and by each sensor face on the
#: cell's network (a fault both faces of a pair declare fires on both).
_NETWORK_LOSS: Final = Fault(
    "network-loss",
    "the cell's network goes silent: no data from robot or sensor (a cable pulled between the "
    "host and the cell's switch; connections stay open)",
    "stale_sample",
    0.1,
)
_FT300_FROZEN: Final = Fault(
    "ft300-frozen", "the FT 300 repeats its last reading", "frozen_sample", 1.0
)
_FT300_OVERRANGE: Final = Fault(
    "ft300-overrange",
    "the FT 300 reads Fz = 310 N, beyond its rated 300 N",
    "sensor fault: overrange",
    0.1,
)

#: The devices ftcomp ships: robots, then sensors.
BUILT_IN: Final[tuple[Device, ...]] = (
    Device(
        "robot",
        "sim",
        "ftcomp.sim.backend:open_robot",
        "sim://?OPTIONS",
        "the simulated MuJoCo cell (docs/sim.md)",
        extra="sim",
        tested=_NOT_ON_A_TWIN,
    ),
    Device(
        "robot",
        "ur",
        "ftcomp.hardware.ur:open_robot",
        "ur://HOST",
        "Universal Robots e-Series through RTDE (ur-rtde)",
        extra="ur",
        tested="the twin's UR5e through ur_rtde 1.6; URSim and a real arm by users "
        "(docs/hardware.md)",
        twin=TwinFace(
            "ur5e",
            "ftcomp.twin.ur_face:UrFace",
            faults=(
                Fault(
                    "rtde-stop",
                    "the controller stops sending RTDE data (connections stay open)",
                    "no new data from the controller within 0.50 s",
                    1.0,
                ),
                _NETWORK_LOSS,
                Fault(
                    "protective-stop",
                    "a protective stop: the arm stops, the program ends",
                    "the arm is in a protective stop",
                    0.5,
                ),
                Fault(
                    "script-stop",
                    "the program is stopped from the pendant",
                    "the controller refused speedL",
                    0.5,
                ),
                Fault(
                    "latency",
                    "every RTDE package is sent 8-14 ms late (8 ms, up to 4 ms of jitter, in "
                    "the cell's 2 ms cycles)",
                    None,
                ),
            ),
            arm="ftcomp.sim.arm:ur5e_arm",
            requires=("rtde_control", "rtde_receive"),
            record_options=(
                # the UR5e's joints near their top speed (ur_rtde's 179 deg/s), at 800 deg/s^2
                "max_speed_mm_s=250&max_accel_mm_s2=1500"
                "&max_joint_speed_deg_s=170&max_joint_accel_deg_s2=800"
            ),
        ),
    ),
    Device(
        "robot",
        "franka",
        "ftcomp.hardware.franka:open_robot",
        "franka://HOST",
        "Franka Research 3 and Panda through the FCI (franky-control)",
        extra="franka",
        tested="franky-control 2.0.0 against the twin's FR3 (the whole session, reflexes) "
        "and franky-sim 1.0.4's MuJoCo FR3 (motions); not timing; no real arm "
        "(docs/hardware.md)",
        twin=TwinFace(
            "fr3",
            "ftcomp.twin.franka_face:FrankaFace",
            faults=(
                Fault(
                    "reflex",
                    "a Cartesian collision reflex: the motion aborts, the arm stays in reflex "
                    "mode until recovered",
                    "cartesian_reflex",
                    0.5,
                ),
                Fault(
                    "communication-violation",
                    "the arm's communication_constraints_violation reflex (it saw the host "
                    "miss its 1 kHz deadline)",
                    "communication_constraints_violation",
                    0.5,
                ),
                Fault(
                    "user-stop",
                    "the user stop is pressed: the motion aborts",
                    "User Stop pressed",
                    0.5,
                ),
                _NETWORK_LOSS,
            ),
            arm="ftcomp.sim.arm:fr3_arm",
            requires=("franky", "franky_sim"),
            record_options="dynamics=0.3",
        ),
    ),
    Device(
        "robot",
        "fixed",
        "ftcomp.hardware.fixed:open_robot",
        "fixed://?rpy_deg=R,P,Y",
        "no robot: a fixed pose on the host's clock",
        tested=_NOT_ON_A_TWIN,
    ),
    Device(
        "robot",
        "replay",
        "ftcomp.hardware.replay:open_robot",
        "replay://FILE",
        "the poses of a recorded log",
        tested=_NOT_ON_A_TWIN,
    ),
    Device(
        "robot",
        "ros2",
        "ftcomp.ros2.live:open_robot",
        "ros2:///?base_frame=B&tcp_frame=S&twist_topic=TOPIC",
        "an arm in a ROS 2 graph: its pose from JointState and the URDF, driven by "
        "TwistStamped on a servo topic (rclpy; docs/ros2.md)",
        extra="ros2",
        tested="rclpy nodes on loopback: joint states, a latched /robot_description, a robot "
        "node integrating the twists (not yet a compliant placement); no real arm's driver",
    ),
    Device(
        "sensor",
        "sim",
        "ftcomp.sim.backend:open_sensor",
        "sim://",
        "the wrist sensor of the sim:// robot",
        extra="sim",
        tested=_NOT_ON_A_TWIN,
    ),
    Device(
        "sensor",
        "netft",
        "ftcomp.hardware.netft:open_sensor",
        "netft://HOST",
        "ATI Net F/T and Ethernet Axia through RDT (pynetft)",
        extra="ati",
        tested="the twin's Net F/T through pynetft 2.1; a real Net F/T by users",
        twin=TwinFace(
            "netft",
            "ftcomp.twin.netft_face:NetFtFace",
            faults=(
                Fault(
                    "sensor-frozen",
                    "the Net F/T repeats its last reading (status healthy)",
                    "frozen_sample",
                    1.0,
                ),
                Fault(
                    "sensor-fault",
                    "the Net F/T reports a serious status and goes on sending",
                    "sensor fault serious_status",
                    0.1,
                ),
                Fault(
                    "rdt-loss",
                    "the next 200 RDT records are lost on the way",
                    "stale_sample",
                    0.1,
                ),
                _NETWORK_LOSS,
            ),
            max_rate_hz=7000.0,
            requires=("pynetft",),
        ),
    ),
    Device(
        "sensor",
        "ur",
        "ftcomp.hardware.ur_sensor:open_sensor",
        "ur://HOST",
        "a UR e-Series' built-in F/T sensor (ur-rtde)",
        extra="ur",
        tested="the twin's UR5e through ur_rtde 1.6",
    ),
    Device(
        "sensor",
        "robotiq",
        "ftcomp.hardware.robotiq:open_sensor",
        "robotiq://HOST",
        "Robotiq FT 300 through the URCap's stream on a UR controller (TCP 63351)",
        extra="robotiq",
        tested="the twin's URCap stream (the line format as users' drivers read it); no "
        "real controller",
        twin=TwinFace(
            "ft300-urcap",
            "ftcomp.twin.robotiq_face:RobotiqUrcapFace",
            faults=(
                _FT300_FROZEN,
                _FT300_OVERRANGE,
                Fault(
                    "urcap-garbled",
                    "one line of the URCap's stream is cut short",
                    "sensor fault: a line that is not six numbers",
                    0.1,
                ),
                Fault(
                    "urcap-disconnect",
                    "the controller closes the URCap's stream",
                    "sensor fault: the URCap stream ended",
                    0.1,
                ),
                _NETWORK_LOSS,
            ),
            rate_hz=100.0,
            max_rate_hz=100.0,
        ),
    ),
    Device(
        "sensor",
        "robotiq",
        "ftcomp.hardware.robotiq:open_sensor",
        "robotiq:///dev/ttyUSB0",
        "Robotiq FT 300 on its serial line, Modbus RTU stream mode (pyserial)",
        extra="robotiq",
        tested="the twin's FT 300 on a pty through pyserial 3.5 (frames and CRC as Robotiq's "
        "manual gives them); no real sensor",
        twin=TwinFace(
            "ft300-rtu",
            "ftcomp.twin.robotiq_face:RobotiqRtuFace",
            faults=(
                _FT300_FROZEN,
                _FT300_OVERRANGE,
                Fault(
                    "rtu-crc",
                    "one stream frame arrives with a wrong CRC",
                    "sensor fault: corrupted frame (bad CRC)",
                    0.1,
                ),
                Fault(
                    "rtu-disconnect",
                    "the sensor's USB adapter is unplugged",
                    "sensor fault: the serial device is gone",
                    0.1,
                ),
            ),
            rate_hz=100.0,
            max_rate_hz=100.0,
            requires=("serial",),
        ),
    ),
    Device(
        "sensor",
        "bota",
        "ftcomp.hardware.bota:open_sensor",
        "bota:///dev/ttyUSB0",
        "Bota Gen0 sensor (Rokubi) on its serial line, frames read by ftcomp (pyserial)",
        extra="bota",
        tested="the twin's Gen0 face on a pty through pyserial 3.5 (frames and CRC as Bota's "
        "open serial drivers declare them); no real sensor",
        twin=TwinFace(
            "bota-gen0",
            "ftcomp.twin.bota_face:BotaGen0Face",
            faults=(
                Fault(
                    "bota-frozen",
                    "the Bota sensor repeats its last reading (status clean)",
                    "frozen_sample",
                    1.0,
                ),
                Fault(
                    "bota-crc",
                    "one Gen0 frame arrives with a wrong CRC",
                    "sensor fault: corrupted frame (bad CRC)",
                    0.1,
                ),
                Fault(
                    "bota-overrange",
                    "the Bota sensor sets its status word's overrange bit",
                    "sensor fault: status 0x0002 (overrange)",
                    0.1,
                ),
                Fault(
                    "bota-disconnect",
                    "the Bota sensor's USB adapter is unplugged",
                    "sensor fault: the serial device is gone",
                    0.1,
                ),
            ),
            rate_hz=800.0,
            max_rate_hz=1245.0,
            requires=("serial",),
        ),
    ),
    Device(
        "sensor",
        "bota",
        "ftcomp.hardware.bota:open_sensor",
        "bota://dummy",
        "Bota sensors through Bota's bota-driver: its simulated sensor (bota://dummy) or a "
        "Gen A sensor over Ethernet (bota://HOST)",
        extra="bota",
        tested="bota-driver 1.1.16's simulated sensor (Bota_Dummy); no real sensor",
    ),
    Device(
        "sensor",
        "replay",
        "ftcomp.hardware.replay:open_sensor",
        "replay://FILE",
        "the readings of a recorded log",
        tested=_NOT_ON_A_TWIN,
    ),
    Device(
        "sensor",
        "ros2",
        "ftcomp.ros2.live:open_sensor",
        "ros2:///TOPIC",
        "a geometry_msgs/WrenchStamped topic (rclpy; docs/ros2.md)",
        extra="ros2",
        tested="rclpy publishers on loopback (ROS 2 Kilted wheels); no vendor driver",
    ),
)


def _modules_named() -> list[Any]:
    """The device modules the environment and installed distributions name, imported."""
    modules = []
    names = [n.strip() for n in os.environ.get(DEVICES_ENV, "").split(",") if n.strip()]
    for name in names:
        try:
            modules.append(importlib.import_module(name))
        except ImportError as exc:
            raise ParameterError(
                f"{DEVICES_ENV}: cannot import device module {name!r}: {exc}"
            ) from None
    for point in entry_points(group=ENTRY_POINT_GROUP):
        modules.append(point.load())
    return modules


@cache
def _registry() -> tuple[Device, ...]:
    found = list(BUILT_IN)
    for module in _modules_named():
        declared = getattr(module, "DEVICES", None)
        if not isinstance(declared, Sequence) or not all(isinstance(d, Device) for d in declared):
            raise ParameterError(
                f"device module {module.__name__!r}: DEVICES must be a sequence of "
                "ftcomp.hardware.devices.Device"
            )
        found.extend(declared)
    seen: dict[tuple[str, str], Device] = {}
    faces: dict[tuple[str, str], Device] = {}
    for device in found:
        key = (device.kind, device.scheme)
        # One family may be declared once per way of reaching it (robotiq://HOST and
        # robotiq:///dev/ttyUSB0, each with its twin face), through one backend.
        if key in seen and (seen[key].backend, seen[key].extra) != (device.backend, device.extra):
            raise ParameterError(f"two {device.kind} devices declare the scheme {device.scheme}://")
        seen[key] = device
        if device.twin is not None:
            face_key = (device.kind, device.twin.name)
            if face_key in faces:
                raise ParameterError(
                    f"two {device.kind} faces of the twin named {device.twin.name}"
                )
            faces[face_key] = device
    return tuple(found)


def devices(kind: Kind | None = None) -> tuple[Device, ...]:
    """Every registered device (of one kind), built-in first, in declaration order."""
    return tuple(d for d in _registry() if kind is None or d.kind == kind)


def twin_faces(kind: Kind) -> Mapping[str, Device]:
    """The twin's faces of one kind: face name -> its device."""
    return {d.twin.name: d for d in devices(kind) if d.twin is not None}


def fault(name: str) -> Fault:
    """The fault of that name, whichever face declares it.

    Raises:
        ParameterError: no face declares it.
    """
    for device in devices():
        for declared in device.twin.faults if device.twin is not None else ():
            if declared.name == name:
                return declared
    known = sorted({f.name for d in devices() if d.twin for f in d.twin.faults})
    raise ParameterError(f"fault: unknown {name!r}; known: {', '.join(known)}")


def load_target(target: str) -> Any:
    """The object ``"module:attribute"`` names, its module imported now."""
    module_name, _, attribute = target.partition(":")
    return getattr(importlib.import_module(module_name), attribute)


def uri_help(kind: Kind) -> str:
    """The URIs of one kind as a user writes them, for ``--robot``/``--sensor`` help."""
    return ", ".join(dict.fromkeys(d.uri for d in devices(kind)))


def device_table() -> str:
    """The device table of docs/hardware.md (Markdown), made from the registry."""
    rows = [
        "| kind | URI | what | extra | twin face (faults) | tested against |",
        "|---|---|---|---|---|---|",
    ]
    for d in devices():
        face = (
            f"`{d.twin.name}` ({', '.join(f.name for f in d.twin.faults) or 'none'})"
            if d.twin is not None
            else "-"
        )
        extra = f"`[{d.extra}]`" if d.extra else "-"
        rows.append(f"| {d.kind} | `{d.uri}` | {d.summary} | {extra} | {face} | {d.tested} |")
    return "\n".join(rows) + "\n"
