"""The UR's built-in F/T sensor (``--sensor ur://HOST``), read from the ``ur://`` robot's RTDE
stream; frames, units and signs are described in :mod:`ftcomp.hardware.ur`.

``wrench=tcp`` reads ``actual_TCP_force``. On an e-Series controller (major version 5 or later)
that is the wrench at the *flange* origin, in *base* orientation, as UR's own ROS drivers read
it; a CB3 (major 3) gives it at the TCP. This backend converts it, once, to the TCP frame about
the TCP origin (:func:`tcp_wrench_from_flange`), for which it needs the controller's TCP offset
(the TCP in the flange frame, as PolyScope's Installation > TCP shows it): the URI options
``tcp_offset_mm=X,Y,Z`` and ``tcp_rotvec_rad=RX,RY,RZ``, required on an e-Series (a convention
is never guessed). The sensor frame is then the TCP frame: ``--mount`` stays the identity.
"""

from __future__ import annotations

import math
import time

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import ParameterError
from ftcomp.frames import cross3, matrix_from_rotvec
from ftcomp.hardware.protocols import NothingToClose, Robot, WrenchSample, WrenchSensor
from ftcomp.hardware.registry import Uri
from ftcomp.hardware.ur import URRobot

__all__ = ["URWrenchSensor", "open_sensor", "tcp_wrench_from_flange"]

#: The first controller major version (e-Series) whose ``actual_TCP_force`` is at the flange.
FLANGE_FORCE_MAJOR = 5


def tcp_wrench_from_flange(
    wrench_flange_base: NDArray[np.float64],
    R_base_tcp: NDArray[np.float64],
    R_flange_tcp: NDArray[np.float64],
    p_flange_tcp_m: NDArray[np.float64],
) -> NDArray[np.float64]:
    """An e-Series ``actual_TCP_force`` in the TCP frame, about the TCP origin.

    Args:
        wrench_flange_base: ``[f, m]`` [N, N*m], base orientation, torque about the flange
            origin (what the controller reports), shape (6,).
        R_base_tcp: the TCP's orientation in the base frame, shape (3, 3).
        R_flange_tcp: the TCP offset's rotation (TCP axes in the flange frame), shape (3, 3).
        p_flange_tcp_m: the TCP offset (TCP origin in the flange frame) [m], shape (3,).

    Returns:
        ``[f_tcp, m_tcp]``: ``f_tcp = R_base_tcp^T f``, ``m_tcp = R_base_tcp^T (m - r x f)``
        with ``r = R_base_flange p_flange_tcp`` the lever from the flange to the TCP in base
        orientation (``R_base_flange = R_base_tcp R_flange_tcp^T``).
    """
    f, m = wrench_flange_base[:3], wrench_flange_base[3:]
    lever_base = R_base_tcp @ (R_flange_tcp.T @ p_flange_tcp_m)
    return np.concatenate([R_base_tcp.T @ f, R_base_tcp.T @ (m - cross3(lever_base, f))])


class URWrenchSensor(NothingToClose):
    """The UR's built-in F/T sensor, read from the robot's RTDE stream.

    Args:
        robot: the session's ``ur://`` robot (same controller).
        wrench: ``"raw"`` (ft_raw_wrench, flange frame) or ``"tcp"`` (actual_TCP_force,
            converted to the TCP frame about the TCP origin).
        sign: +1 or -1 (see :mod:`ftcomp.hardware.ur`).
        tcp_offset: ``(R_flange_tcp, p_flange_tcp_m)``, the controller's TCP offset; needed
            for ``"tcp"`` on an e-Series (checked when the robot has connected).
    """

    def __init__(
        self,
        robot: URRobot,
        wrench: str,
        sign: float,
        tcp_offset: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
    ) -> None:
        self.robot = robot
        self.wrench = wrench
        self.sign = sign
        self.tcp_offset = tcp_offset
        self._stamp = math.nan
        self._last: WrenchSample | None = None
        self._fresh = False

    def __enter__(self) -> URWrenchSensor:
        """The robot connects; check the controller has the chosen output."""
        if self.wrench == "raw" and "ft_raw_wrench" not in self.robot.variables:
            version = ".".join(map(str, self.robot.version))
            raise ParameterError(
                f"{self.robot.uri.text!r}: this controller ({version}) has no ft_raw_wrench "
                "(PolyScope 5.9 or later); use the sensor 'ur://HOST?wrench=tcp'"
            )
        at_flange = self.robot.version[0] >= FLANGE_FORCE_MAJOR
        if self.wrench == "tcp" and at_flange and self.tcp_offset is None:
            version = ".".join(map(str, self.robot.version))
            raise ParameterError(
                f"{self.robot.uri.text!r}: on this e-Series controller ({version}) "
                "actual_TCP_force is at the flange; give the TCP offset PolyScope shows "
                "(Installation > TCP): ?wrench=tcp&tcp_offset_mm=X,Y,Z&tcp_rotvec_rad=RX,RY,RZ"
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
            if robot.version[0] >= FLANGE_FORCE_MAJOR:
                assert self.tcp_offset is not None  # checked on entering
                w = tcp_wrench_from_flange(w_base, R_base_tcp, *self.tcp_offset)
            else:  # CB3: at the TCP, base orientation
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
        raise ParameterError(f"{uri.text!r}: the UR's built-in sensor needs a ur://HOST robot")
    if uri.host != robot.host:
        raise ParameterError(
            f"{uri.text!r}: the built-in sensor must be on the robot's controller "
            f"({robot.host}), got {uri.host or 'no host'}"
        )
    options = uri.reader()
    wrench = options.text("wrench", "raw", ("raw", "tcp"))
    sign = options.number("sign", 1.0)
    unset = (math.nan,) * 3
    offset_mm = options.floats("tcp_offset_mm", unset)
    rotvec = options.floats("tcp_rotvec_rad", unset)
    options.done()
    if sign not in (1.0, -1.0):
        raise ParameterError(f"{uri.text!r}: sign must be 1 or -1, got {sign:g}")
    tcp_offset = None
    given_offset, given_rotvec = offset_mm is not unset, rotvec is not unset
    if given_offset or given_rotvec:
        if wrench != "tcp":
            raise ParameterError(
                f"{uri.text!r}: tcp_offset_mm and tcp_rotvec_rad are for wrench=tcp (ft_raw_wrench "
                "is in the flange frame: give it as the mount instead)",
                field="mount",
            )
        if not (given_offset and given_rotvec):
            raise ParameterError(
                f"{uri.text!r}: give both tcp_offset_mm=X,Y,Z and tcp_rotvec_rad=RX,RY,RZ "
                "(PolyScope's Installation > TCP; 0,0,0 for none)"
            )
        tcp_offset = (matrix_from_rotvec(rotvec), np.array(offset_mm, dtype=float) * 1e-3)
    return URWrenchSensor(robot, wrench, float(sign), tcp_offset)
