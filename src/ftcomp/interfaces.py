"""The hardware seams: a wrench sensor and a robot, as :class:`typing.Protocol` classes.

The MuJoCo cell (:mod:`ftcomp.sim`) implements them; drivers for real sensors and robots will
too, so calibration, compensation and control code runs unchanged on either.

Frames and units: positions [m] and rotations of the *sensor frame* in the *robot base frame*
(``p_base_sensor``, ``R_base_sensor``); wrenches [N, N*m] are what the tool exerts on the sensor,
in the sensor frame; twists ``[vx, vy, vz, wx, wy, wz]`` [m/s, rad/s] of the sensor frame's origin,
in the base frame; time [s].
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import ParameterError

__all__ = ["Robot", "WrenchSample", "WrenchSensor"]


@dataclass(frozen=True)
class WrenchSample:
    """One timestamped sensor reading.

    Attributes:
        t: time stamp [s] on the sensor's clock (the robot's clock in simulation).
        wrench_sensor: ``[fx, fy, fz, tx, ty, tz]`` [N, N*m], sensor frame, shape (6,); may hold
            NaN when the sensor reports garbage: consumers check (see ``ftcomp.control.safety``).
    """

    t: float
    wrench_sensor: NDArray[np.float64] = field(repr=False)

    def __post_init__(self) -> None:
        w = np.array(self.wrench_sensor, dtype=float)
        if w.shape != (6,):
            raise ParameterError(f"wrench_sensor must have shape (6,), got {w.shape}")
        w.setflags(write=False)
        object.__setattr__(self, "wrench_sensor", w)


@runtime_checkable
class WrenchSensor(Protocol):
    """A six-axis force/torque sensor."""

    def read(self) -> WrenchSample:
        """The newest reading (non-blocking)."""
        ...


@runtime_checkable
class Robot(Protocol):
    """A position-controlled arm with a Cartesian velocity interface, driven one cycle at a time."""

    @property
    def control_period_s(self) -> float:
        """Period of the control cycle [s] (1 ms in simulation)."""
        ...

    def time(self) -> float:
        """The robot's clock [s]."""
        ...

    def sensor_pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(p_base_sensor [m] (3,), R_base_sensor (3, 3))`` now."""
        ...

    def move_joints(self, q_rad: NDArray[np.float64], duration_s: float) -> None:
        """Blocking joint move to ``q_rad`` [rad] in ``duration_s`` [s]."""
        ...

    def move_pose(
        self,
        p_base_sensor: NDArray[np.float64],
        R_base_sensor: NDArray[np.float64],
        duration_s: float,
    ) -> None:
        """Blocking Cartesian move of the sensor frame (inverse kinematics)."""
        ...

    def command_twist(self, twist_base: NDArray[np.float64]) -> None:
        """Set the sensor frame's velocity for the coming cycles, shape (6,), base frame."""
        ...

    def wait_cycle(self) -> None:
        """Advance (simulation) or wait (hardware) one control period."""
        ...

    def stop(self) -> None:
        """Zero the commanded velocity at once."""
        ...
