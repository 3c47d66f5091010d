"""A bounded check that a UR controller answers RTDE, before ``ur_rtde`` connects to it.

``ur_rtde``'s interfaces connect inside their constructors, holding Python's interpreter lock,
and wait without a time limit for the controller's first data package: a host that accepts the
connection but never answers would hang the whole program. :func:`probe_rtde` walks through the
same handshake first (Universal Robots' published RTDE protocol, version 2: request the
protocol version, the controller version, an output recipe, start, one data package, pause),
every step under a timeout, and reports what went wrong in one line. Only then does the backend
hand the connection to ``ur_rtde``.

Wire format: a package is ``uint16 size`` (header included), ``uint8 type``, then its payload,
big-endian.
"""

from __future__ import annotations

import socket
import struct
import time
from collections.abc import Sequence

from ftcomp.errors import HardwareError, ParameterError

__all__ = ["RTDE_PORT", "probe_rtde"]

#: The controller's RTDE port.
RTDE_PORT = 30004
_V, _VERSION, _TEXT, _OUTPUTS, _START, _PAUSE, _DATA = (
    ord("V"),
    ord("v"),
    ord("M"),
    ord("O"),
    ord("S"),
    ord("P"),
    ord("U"),
)


def _send(sock: socket.socket, kind: int, payload: bytes = b"") -> None:
    sock.sendall(struct.pack(">HB", 3 + len(payload), kind) + payload)


def _recv_exact(sock: socket.socket, n: int, deadline: float, what: str) -> bytes:
    data = b""
    while len(data) < n:
        left = deadline - time.monotonic()
        if left <= 0.0:
            raise TimeoutError(what)
        sock.settimeout(left)
        chunk = sock.recv(n - len(data))
        if not chunk:
            raise ConnectionError(f"the controller closed the connection while {what}")
        data += chunk
    return data


def _expect(sock: socket.socket, kind: int, deadline: float, what: str) -> bytes:
    """The payload of the next package of ``kind`` (text messages and stray data skipped)."""
    while True:
        size, got = struct.unpack(">HB", _recv_exact(sock, 3, deadline, what))
        if size < 3:
            raise ConnectionError(f"a malformed RTDE package (size {size}) while {what}")
        payload = _recv_exact(sock, size - 3, deadline, what)
        if got == kind:
            return payload
        if got not in (_TEXT, _DATA):
            raise ConnectionError(f"an unexpected RTDE package {chr(got)!r} while {what}")


def probe_rtde(
    host: str,
    variables: Sequence[str],
    *,
    port: int = RTDE_PORT,
    frequency_hz: float = 125.0,
    timeout_s: float = 2.0,
    label: str = "",
) -> tuple[int, int, int, int]:
    """Check that ``host`` serves RTDE with these output variables; return its version.

    Args:
        host: the controller's address.
        variables: output variable names the backend will ask for.
        port: the RTDE port.
        frequency_hz: the output frequency asked for [Hz].
        timeout_s: the whole check's time limit [s].
        label: names the device in messages (its URI).

    Returns:
        The controller version ``(major, minor, bugfix, build)``.

    Raises:
        HardwareError: nothing listens, no answer in time, or the protocol is refused.
        ParameterError: the controller does not know one of the variables.
    """
    name = label or f"{host}:{port}"
    deadline = time.monotonic() + timeout_s
    step = "connecting"
    try:
        with socket.create_connection((host, port), timeout=timeout_s) as sock:
            step = "negotiating the protocol version"
            _send(sock, _V, struct.pack(">H", 2))
            if _expect(sock, _V, deadline, step)[:1] != b"\x01":
                raise HardwareError(f"{name}: the controller refused RTDE protocol version 2")
            step = "reading the controller version"
            _send(sock, _VERSION)
            version = struct.unpack(">IIII", _expect(sock, _VERSION, deadline, step)[:16])
            step = "setting up the output recipe"
            names = ",".join(variables).encode()
            _send(sock, _OUTPUTS, struct.pack(">d", frequency_hz) + names)
            reply = _expect(sock, _OUTPUTS, deadline, step)
            types = reply[1:].decode(errors="replace").split(",")
            missing = [v for v, t in zip(variables, types, strict=False) if t == "NOT_FOUND"]
            if missing or len(types) < len(variables):
                unknown = missing[0] if missing else variables[len(types)]
                raise ParameterError(
                    f"{name}: the controller (version {'.'.join(map(str, version))}) has no "
                    f"RTDE output {unknown!r}"
                )
            step = "starting the data stream"
            _send(sock, _START)
            if _expect(sock, _START, deadline, step)[:1] != b"\x01":
                raise HardwareError(f"{name}: the controller refused to start RTDE output")
            step = "waiting for the first data package"
            _expect(sock, _DATA, deadline, step)
            _send(sock, _PAUSE)
    except TimeoutError:
        raise HardwareError(f"{name}: no answer within {timeout_s:g} s while {step}") from None
    except ConnectionRefusedError:
        raise HardwareError(
            f"{name}: connection refused on port {port} (is this a UR controller, and is it on?)"
        ) from None
    except OSError as exc:
        raise HardwareError(f"{name}: {step}: {exc.strerror or exc}") from None
    return version
