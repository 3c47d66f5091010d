"""The ``fixed://`` robot: no arm, a sensor held still, on the host's clock.

For a sensor on a bench or a fixed fixture, and for streaming a sensor alone: the "robot"
reports one constant TCP pose, never moves, and paces loops on the host's monotonic clock (the
clock of ``netft://`` and ``ur://``). Without options the pose is unknown to ftcomp and only raw
readings make sense; give the pose to compensate::

    fixed://?rpy_deg=0,180,0      TCP orientation in the base frame, URDF-style roll, pitch, yaw
           &xyz_mm=0,0,0          TCP position in the base frame [mm]
           &rate_hz=1000          loop rate [Hz]
"""

from __future__ import annotations

import math
import time

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.pacing import LatenessOfPacer, RateLimiter
from ftcomp.hardware.protocols import ClockName, NothingToClose, PoseSample, Robot
from ftcomp.hardware.registry import Uri

__all__ = ["FixedRobot", "open_robot"]


class FixedRobot(LatenessOfPacer, NothingToClose):
    """A robot that does not move (see the module docstring). Capabilities:
    :class:`~ftcomp.hardware.protocols.ReportsLateness`.

    Args:
        p_base_tcp: the TCP position [m], base frame.
        R_base_tcp: the TCP orientation.
        rate_hz: the loop rate [Hz].
        pose_known: whether the pose was given (compensation needs it).
    """

    clock_name: ClockName = "monotonic"

    def __init__(
        self,
        p_base_tcp: NDArray[np.float64],
        R_base_tcp: NDArray[np.float64],
        rate_hz: float,
        *,
        pose_known: bool,
    ) -> None:
        self._p = np.array(p_base_tcp, dtype=float)
        self._R = np.array(R_base_tcp, dtype=float)
        self.pose_known = pose_known
        self.pacer = RateLimiter(1.0 / rate_hz, name=type(self).__name__, log_overruns=False)

    @property
    def control_period_s(self) -> float:
        """The loop period [s]."""
        return self.pacer.period_s

    def now_ns(self) -> int:
        """The host's monotonic clock [ns]."""
        return time.monotonic_ns()

    def pose(self) -> PoseSample:
        """The fixed pose, stamped now."""
        return PoseSample(time.monotonic_ns(), self._p, self._R)

    def move_pose(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64], duration_s: float
    ) -> None:
        """A fixed sensor cannot move.

        Raises:
            HardwareError: always.
        """
        raise HardwareError("fixed:// cannot move: visiting poses needs a robot arm")

    def settle(self, max_duration_s: float) -> float:
        """Already at rest."""
        return 0.0

    def command_twist(self, twist_base: NDArray[np.float64]) -> None:
        """Accept a zero twist; anything else is an error (there is nothing to move)."""
        if np.any(np.asarray(twist_base, dtype=float)):
            raise HardwareError("fixed:// cannot move: a non-zero twist was commanded")

    def wait_cycle(self) -> None:
        """Wait for the next period (host clock)."""
        self.pacer.sleep()

    def stop(self) -> None:
        """Nothing moves."""


def open_robot(uri: Uri) -> Robot:
    """A fixed "robot" from its URI."""
    if uri.host or uri.path not in ("", "/"):
        raise ParameterError(
            f"{uri.text!r}: fixed:// takes options only, e.g. fixed://?rpy_deg=0,0,0"
        )
    options = uri.reader()
    known = "rpy_deg" in uri.options or "xyz_mm" in uri.options
    rpy = options.floats("rpy_deg", (0.0, 0.0, 0.0))
    xyz = options.floats("xyz_mm", (0.0, 0.0, 0.0))
    rate = options.number("rate_hz", 1000.0)
    options.done()
    assert rate is not None
    if not (math.isfinite(rate) and 1.0 <= rate <= 10_000.0):
        raise ParameterError(f"{uri.text!r}: rate_hz must be in [1, 10000], got {rate:g}")
    R = Rotation.from_euler("xyz", rpy, degrees=True).as_matrix()
    return FixedRobot(np.array(xyz) * 1e-3, R, rate, pose_known=known)
