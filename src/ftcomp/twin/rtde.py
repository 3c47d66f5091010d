"""The controller's side of UR's RTDE protocol (version 2) on TCP port 30004.

Written from Universal Robots' published RTDE guide. Every package is ``uint16 size`` (header
included), ``uint8 type``, then its payload, big-endian:

- ``V`` request protocol version (uint16) -> ``V`` uint8 accepted (version 2 only);
- ``v`` get controller version -> ``v`` uint32 major, minor, bugfix, build;
- ``O`` output setup (double frequency, comma-separated names) -> ``O`` uint8 recipe id, the
  comma-separated types (``NOT_FOUND`` for a name the controller does not know);
- ``I`` input setup (comma-separated names) -> ``I`` uint8 recipe id, the types (``IN_USE``
  for a register another client already writes);
- ``S`` start / ``P`` pause -> uint8 accepted; while started the controller sends a ``U``
  data package (uint8 recipe id, the values in recipe order) every ``1/frequency`` s, and the
  client sends ``U`` packages (uint8 input recipe id, the values) to set inputs.

:class:`RtdeSession` serves one client: the handshake on its own thread, and one data package
per control cycle from :meth:`RtdeSession.publish` (the controller's loop), so the stream runs
at the controller's own rate (500 Hz on an e-Series) and every package holds one cycle's state.
"""

from __future__ import annotations

import contextlib
import socket
import struct
import threading
from collections.abc import Callable, Mapping
from typing import Final

__all__ = ["INPUT_TYPES", "OUTPUT_TYPES", "RtdeSession", "rtde_type"]

_V6: Final = "VECTOR6D"
#: Output variables the twin serves and their RTDE types (UR's RTDE guide, PolyScope 5.x).
OUTPUT_TYPES: Final[Mapping[str, str]] = {
    "timestamp": "DOUBLE",
    **{
        n: _V6
        for n in (
            "target_q",
            "target_qd",
            "target_qdd",
            "target_current",
            "target_moment",
            "actual_q",
            "actual_qd",
            "actual_current",
            "joint_control_output",
            "actual_TCP_pose",
            "actual_TCP_speed",
            "actual_TCP_force",
            "target_TCP_pose",
            "target_TCP_speed",
            "joint_temperatures",
            "actual_joint_voltage",
            "ft_raw_wrench",
            "actual_current_as_torque",
        )
    },
    **{
        n: "DOUBLE"
        for n in (
            "actual_execution_time",
            "speed_scaling",
            "target_speed_fraction",
            "actual_momentum",
            "actual_main_voltage",
            "actual_robot_voltage",
            "actual_robot_current",
            "standard_analog_input0",
            "standard_analog_input1",
            "standard_analog_output0",
            "standard_analog_output1",
            "io_current",
            "tool_analog_input0",
            "tool_analog_input1",
            "tool_output_current",
            "tool_temperature",
            "tcp_force_scalar",
            "payload",
        )
    },
    "robot_mode": "INT32",
    "safety_mode": "INT32",
    "safety_status": "INT32",
    "tool_output_voltage": "INT32",
    "joint_mode": "VECTOR6INT32",
    "actual_tool_accelerometer": "VECTOR3D",
    "elbow_position": "VECTOR3D",
    "elbow_velocity": "VECTOR3D",
    "payload_cog": "VECTOR3D",
    "payload_inertia": _V6,
    "actual_digital_input_bits": "UINT64",
    "actual_digital_output_bits": "UINT64",
    **{
        n: "UINT32"
        for n in (
            "runtime_state",
            "robot_status_bits",
            "safety_status_bits",
            "analog_io_types",
            "tool_mode",
            "tool_analog_input_types",
            "output_bit_registers0_to_31",
            "output_bit_registers32_to_63",
            "input_bit_registers0_to_31",
            "input_bit_registers32_to_63",
            "script_control_line",
        )
    },
    "tool_output_mode": "UINT8",
    "tool_digital_output0_mode": "UINT8",
    "tool_digital_output1_mode": "UINT8",
}
#: Input variables the twin accepts and their types (registers are matched by pattern).
INPUT_TYPES: Final[Mapping[str, str]] = {
    "speed_slider_mask": "UINT32",
    "speed_slider_fraction": "DOUBLE",
    "standard_digital_output_mask": "UINT8",
    "standard_digital_output": "UINT8",
    "configurable_digital_output_mask": "UINT8",
    "configurable_digital_output": "UINT8",
    "tool_digital_output_mask": "UINT8",
    "tool_digital_output": "UINT8",
    "standard_analog_output_mask": "UINT8",
    "standard_analog_output_type": "UINT8",
    "standard_analog_output_0": "DOUBLE",
    "standard_analog_output_1": "DOUBLE",
    "input_bit_registers0_to_31": "UINT32",
    "input_bit_registers32_to_63": "UINT32",
    "external_force_torque": _V6,
}
_FORMATS: Final = {
    "DOUBLE": "d",
    "VECTOR6D": "6d",
    "VECTOR3D": "3d",
    "INT32": "i",
    "UINT32": "I",
    "UINT64": "Q",
    "UINT8": "B",
    "BOOL": "?",
    "VECTOR6INT32": "6i",
    "VECTOR6UINT32": "6I",
}
_REGISTERS: Final = 48
_WIDTH: Final = {"VECTOR6D": 6, "VECTOR3D": 3, "VECTOR6INT32": 6, "VECTOR6UINT32": 6}


def rtde_type(name: str, *, output: bool) -> str:
    """The RTDE type of a variable, or ``"NOT_FOUND"``."""
    for prefix, kind in (("int_register_", "INT32"), ("double_register_", "DOUBLE")):
        for side in ("output_", "input_"):
            if name.startswith(side + prefix):
                index = name[len(side + prefix) :]
                if index.isdigit() and int(index) < _REGISTERS:
                    return kind
    if name.startswith("input_bit_register_"):
        return "BOOL"
    table = OUTPUT_TYPES if output else INPUT_TYPES
    return table.get(name, "NOT_FOUND")


def _recv_exact(conn: socket.socket, n: int) -> bytes:
    data = b""
    while len(data) < n:
        chunk = conn.recv(n - len(data))
        if not chunk:
            raise ConnectionError("the client closed the connection")
        data += chunk
    return data


def _flatten(value: object) -> list[float | int]:
    if isinstance(value, (list, tuple)):
        return list(value)
    return [value]  # type: ignore[list-item]


class RtdeSession:
    """One RTDE client connection.

    Args:
        conn: the accepted TCP connection.
        version: the controller version reported (major, minor, bugfix, build).
        write_inputs: called with one input package, whole (``{name: value}``): a UR controller
            applies a package in one cycle, so a cycle never sees half of one.
        cycle_hz: the controller's cycle rate [Hz]; output frequencies must divide it.
    """

    def __init__(
        self,
        conn: socket.socket,
        version: tuple[int, int, int, int],
        write_inputs: Callable[[dict[str, float | int | tuple[float, ...]]], None],
        cycle_hz: float = 500.0,
    ) -> None:
        self.conn = conn
        self.version = version
        self.write_inputs = write_inputs
        self.cycle_hz = cycle_hz
        self.send_lock = threading.Lock()
        self.outputs: list[str] = []
        self.defaults: list[object] = []
        self.out_format = struct.Struct(">B")
        self.every = 1
        self.inputs: dict[int, tuple[list[str], struct.Struct]] = {}
        self.started = False
        self.closed = False
        self.packets = 0
        self.cycles = 0

    def _send(self, kind: str, payload: bytes) -> None:
        with self.send_lock:
            self.conn.sendall(struct.pack(">HB", 3 + len(payload), ord(kind)) + payload)

    def serve(self) -> None:
        """Answer the client's requests until it disconnects (run on a thread)."""
        try:
            while True:
                size, kind = struct.unpack(">HB", _recv_exact(self.conn, 3))
                self._handle(chr(kind), _recv_exact(self.conn, size - 3))
        except (ConnectionError, OSError, struct.error):
            pass
        finally:
            self.close()

    def close(self) -> None:
        """Stop sending and close the connection."""
        self.started = False
        if not self.closed:
            self.closed = True
            with contextlib.suppress(OSError):
                self.conn.shutdown(socket.SHUT_RDWR)
            self.conn.close()

    def _handle(self, kind: str, payload: bytes) -> None:
        if kind == "U":
            recipe = self.inputs.get(payload[0]) if payload else None
            if recipe is not None:
                names, fmt = recipe
                values = fmt.unpack(payload[1 : 1 + fmt.size])
                package: dict[str, float | int | tuple[float, ...]] = {}
                k = 0
                for name in names:
                    n = _WIDTH.get(rtde_type(name, output=False), 1)
                    package[name] = values[k] if n == 1 else tuple(values[k : k + n])
                    k += n
                self.write_inputs(package)
        elif kind == "V":
            (requested,) = struct.unpack(">H", payload[:2])
            self._send("V", b"\x01" if requested == 2 else b"\x00")
        elif kind == "v":
            self._send("v", struct.pack(">IIII", *self.version))
        elif kind == "O":
            (frequency,) = struct.unpack(">d", payload[:8])
            names = [n for n in payload[8:].decode().split(",") if n]
            types = [rtde_type(n, output=True) for n in names]
            ok = 0.0 < frequency <= self.cycle_hz and "NOT_FOUND" not in types
            if ok:
                self.outputs = names
                self.defaults = [[0] * _WIDTH[t] if t in _WIDTH else 0 for t in types]
                self.out_format = struct.Struct(">B" + "".join(_FORMATS[t] for t in types))
                self.every = max(1, round(self.cycle_hz / frequency))
            self._send("O", (b"\x01" if ok else b"\x00") + ",".join(types).encode())
        elif kind == "I":
            names = [n for n in payload.decode().split(",") if n]
            types = [rtde_type(n, output=False) for n in names]
            recipe_id = len(self.inputs) + 1 if "NOT_FOUND" not in types else 0
            if recipe_id:
                fmt = struct.Struct(">" + "".join(_FORMATS[t] for t in types))
                self.inputs[recipe_id] = (names, fmt)
            self._send("I", bytes([recipe_id]) + ",".join(types).encode())
        elif kind == "S":
            self.started = bool(self.outputs)
            self._send("S", b"\x01" if self.started else b"\x00")
        elif kind == "P":
            self.started = False
            self._send("P", b"\x01")

    def publish(self, state: Mapping[str, object], registers: Mapping[str, float | int]) -> None:
        """Send one data package of the output recipe, if started and due this cycle.

        Args:
            state: the cycle's output variables by name.
            registers: the register values by name (``output_int_register_0``...); a register
                never written reads 0.
        """
        self.cycles += 1
        if not self.started or self.cycles % self.every:
            return
        values: list[float | int] = [1]
        for name, default in zip(self.outputs, self.defaults, strict=True):
            value = state.get(name)
            if value is None:
                value = registers.get(name, default)
            values += _flatten(value)
        try:
            self._send("U", self.out_format.pack(*values))
            self.packets += 1
        except (OSError, struct.error):
            self.close()
