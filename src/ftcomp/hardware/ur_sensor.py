"""The UR's built-in F/T sensor (``--sensor ur://HOST``), read from the ``ur://`` robot's RTDE
stream; frames, units and signs are described in :mod:`ftcomp.hardware.ur`."""

from __future__ import annotations

import math
import time

import numpy as np

from ftcomp.errors import ParameterError
from ftcomp.frames import matrix_from_rotvec
from ftcomp.hardware.protocols import NothingToClose, Robot, WrenchSample, WrenchSensor
from ftcomp.hardware.registry import Uri
from ftcomp.hardware.ur import URRobot

__all__ = ["URWrenchSensor", "open_sensor"]


class URWrenchSensor(NothingToClose):
    """The UR's built-in F/T sensor, read from the robot's RTDE stream.

    Args:
        robot: the session's ``ur://`` robot (same controller).
        wrench: ``"raw"`` (ft_raw_wrench, flange frame) or ``"tcp"`` (actual_TCP_force,
            rotated into the TCP frame).
        sign: +1 or -1 (see the module docstring).
    """

    def __init__(self, robot: URRobot, wrench: str, sign: float) -> None:
        self.robot = robot
        self.wrench = wrench
        self.sign = sign
        self._stamp = math.nan
        self._last: WrenchSample | None = None
        self._fresh = False

    def __enter__(self) -> URWrenchSensor:
        """The robot connects; check the controller has the chosen output."""
        if self.wrench == "raw" and "ft_raw_wrench" not in self.robot.variables:
            version = ".".join(map(str, self.robot.version))
            raise ParameterError(
                f"{self.robot.uri.text!r}: this controller ({version}) has no ft_raw_wrench "
                "(PolyScope 5.9 or later); use --sensor 'ur://HOST?wrench=tcp'"
            )
        self._update()
        return self

    def _update(self) -> None:
        robot = self.robot
        robot.check()
        r = robot.receive
        stamp = r.getTimestamp()
        if stamp == self._stamp and self._last is not None:
            return
        self._stamp = stamp
        if self.wrench == "raw":
            w = np.array(r.getFtRawWrench(), dtype=float)
        else:
            x = r.getActualTCPPose()
            R_base_tcp = matrix_from_rotvec(x[3:6])
            w_base = np.array(r.getActualTCPForce(), dtype=float)
            w = np.concatenate([R_base_tcp.T @ w_base[:3], R_base_tcp.T @ w_base[3:]])
        self._last = WrenchSample(time.monotonic_ns(), self.sign * w)
        self._fresh = True

    def read(self) -> WrenchSample:
        """The newest reading."""
        self._update()
        assert self._last is not None
        return self._last

    def read_new(self) -> list[WrenchSample]:
        """The newest reading if it is new since the previous call."""
        self._update()
        if not self._fresh or self._last is None:
            return []
        self._fresh = False
        return [self._last]


def open_sensor(uri: Uri, robot: Robot | None) -> WrenchSensor:
    """The built-in sensor of the session's ``ur://`` robot (same host)."""
    if not isinstance(robot, URRobot):
        raise ParameterError(f"{uri.text!r}: the UR's built-in sensor needs --robot ur://HOST")
    if uri.host != robot.host:
        raise ParameterError(
            f"{uri.text!r}: the built-in sensor must be on the robot's controller "
            f"({robot.host}), got {uri.host or 'no host'}"
        )
    options = uri.reader()
    wrench = options.text("wrench", "raw", ("raw", "tcp"))
    sign = options.number("sign", 1.0)
    options.done()
    if sign not in (1.0, -1.0):
        raise ParameterError(f"{uri.text!r}: sign must be 1 or -1, got {sign:g}")
    return URWrenchSensor(robot, wrench, float(sign))
