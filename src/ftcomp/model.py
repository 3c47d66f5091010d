"""The static model of an F/T sensor carrying a tool: bias plus tool gravity (paper Eq. 4, 12).

``GravityModel`` is the set of physical parameters that calibration identifies, compensation
removes and the simulator's ground truth reports. The reading it predicts at an orientation
``R_base_sensor`` is::

    g_s = R_base_sensor.T @ gravity_base                 # tool gravity in the sensor frame [N]
    force  = force_bias_N  + g_s                          # Eq. 4
    torque = torque_bias_Nm + center_of_gravity_m x g_s   # Eq. 12

with ``gravity_base = R_world_base.T @ [0, 0, -G]`` and ``R_world_base = Rx(U) @ Ry(V)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.arrays import freeze_field
from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import ParameterError
from ftcomp.frames import gravity_in_base, gravity_in_sensor, tilt_from_gravity_in_base

__all__ = ["GravityModel", "skew"]


def skew(v: ArrayLike) -> NDArray[np.float64]:
    """The cross-product matrix of ``v``: ``skew(v) @ x == np.cross(v, x)``, shape (3, 3)."""
    x, y, z = np.asarray(v, dtype=float)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


@dataclass(frozen=True)
class GravityModel:
    """Sensor bias, tool weight and centre of gravity, base tilt.

    Attributes:
        weight_N: tool weight G [N], including the sensor's sensing end; >= 0.
        center_of_gravity_m: tool centre of gravity P in the sensor frame [m], shape (3,).
        force_bias_N: force reading with no load, F0 [N], sensor frame, shape (3,).
        torque_bias_Nm: torque reading with no load, M0 [N*m], sensor frame, shape (3,).
        tilt_U_rad: base tilt about the world x axis, U [rad] (paper Eq. 1).
        tilt_V_rad: base tilt about the tilted y axis, V [rad] (paper Eq. 1).
    """

    weight_N: float
    center_of_gravity_m: NDArray[np.float64] = field(repr=True)
    force_bias_N: NDArray[np.float64] = field(repr=True)
    torque_bias_Nm: NDArray[np.float64] = field(repr=True)
    tilt_U_rad: float = field(kw_only=True)
    tilt_V_rad: float = field(kw_only=True)

    def __post_init__(self) -> None:
        if not math.isfinite(self.weight_N) or self.weight_N < 0.0:
            raise ParameterError(f"weight_N must be finite and >= 0, got {self.weight_N}")
        for name in ("tilt_U_rad", "tilt_V_rad"):
            value = getattr(self, name)
            if not math.isfinite(value) or abs(value) >= math.pi / 2:
                raise ParameterError(f"{name} must be finite and within +-pi/2, got {value}")
        for name in ("center_of_gravity_m", "force_bias_N", "torque_bias_Nm"):
            freeze_field(self, name, (3,), finite=True)

    @classmethod
    def from_gravity_in_base(
        cls,
        gravity_base_N: ArrayLike,
        center_of_gravity_m: ArrayLike,
        force_bias_N: ArrayLike,
        torque_bias_Nm: ArrayLike,
    ) -> GravityModel:
        """Build the model from the tool's gravity vector in the base frame (a in Eq. 5)."""
        weight, U, V = tilt_from_gravity_in_base(gravity_base_N)
        return cls(
            weight,
            np.asarray(center_of_gravity_m, dtype=float),
            np.asarray(force_bias_N, dtype=float),
            np.asarray(torque_bias_Nm, dtype=float),
            tilt_U_rad=U,
            tilt_V_rad=V,
        )

    @property
    def gravity_base_N(self) -> NDArray[np.float64]:
        """Tool gravity in the base frame [N], shape (3,) (a = [ax, ay, az] of Eq. 5)."""
        return gravity_in_base(self.weight_N, self.tilt_U_rad, self.tilt_V_rad)

    @property
    def mass_kg(self) -> float:
        """Tool mass [kg] at standard gravity."""
        return self.weight_N / STANDARD_GRAVITY_MPS2

    def gravity_wrench(self, R_base_sensor: ArrayLike) -> NDArray[np.float64]:
        """Wrench of the tool's gravity alone, sensor frame, shape (6,) or (N, 6)."""
        g_s = gravity_in_sensor(self.gravity_base_N, R_base_sensor)
        return np.concatenate([g_s, np.cross(self.center_of_gravity_m, g_s)], axis=-1)

    def predict(self, R_base_sensor: ArrayLike) -> NDArray[np.float64]:
        """The reading with no contact: bias plus tool gravity, shape (6,) or (N, 6) (Eq. 21)."""
        bias = np.concatenate([self.force_bias_N, self.torque_bias_Nm])
        return bias + self.gravity_wrench(R_base_sensor)
