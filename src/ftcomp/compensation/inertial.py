"""Inertial compensation: the wrench a moving tool exerts on the sensor beyond its weight.

Newton-Euler for the rigid body below the sensing element (tool, sensing end, and a held load),
all in the sensor frame (docs/calibration.md derives it): with ``m`` its mass, ``c`` its centre
of gravity, ``I`` its inertia tensor about ``c``, and the sensor frame's linear acceleration
``a``, angular velocity ``w`` and angular acceleration ``alpha``,

```
a_c   = a + alpha x c + w x (w x c)                 (acceleration of the centre of gravity)
force = F0 + m g_s - m a_c
torque= M0 + c x (m g_s - m a_c) - (I alpha + w x I w)
```

The static part ``F0 + m g_s`` and ``M0 + c x m g_s`` is the paper's gravity model
(:class:`~ftcomp.compensation.compensator.GravityCompensator`); the rest is
:func:`ftcomp.kinematics.inertial_wrench`, which :class:`InertialCompensator` also removes.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.calibration_record import Calibration
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import ParameterError
from ftcomp.kinematics import SensorMotion, inertial_wrench
from ftcomp.model import GravityModel

__all__ = ["InertialCompensator"]


class InertialCompensator:
    """Static gravity compensation plus the tool's inertial wrench (batch, recorded motion).

    Args:
        calibration: the tool's static calibration (weight, centre of gravity, bias, tilt).
        inertia_cog_kgm2: the tool's inertia tensor about its centre of gravity, sensor axes
            (:func:`ftcomp.calibration.dynamic.identify_inertia`), (3, 3).
    """

    def __init__(
        self, calibration: Calibration | GravityModel, inertia_cog_kgm2: ArrayLike
    ) -> None:
        self.static = GravityCompensator(calibration)
        inertia = np.asarray(inertia_cog_kgm2, dtype=float)
        if inertia.shape != (3, 3) or not np.isfinite(inertia).all():
            raise ParameterError(f"inertia_cog_kgm2 must be a finite (3, 3), got {inertia.shape}")
        self.inertia_cog_kgm2 = 0.5 * (inertia + inertia.T)
        model = self.static.model
        self.mass_kg = model.weight_N / STANDARD_GRAVITY_MPS2
        self.cog_m = model.center_of_gravity_m

    def compensate(
        self, wrench_sensor: ArrayLike, R_base_sensor: ArrayLike, motion: SensorMotion
    ) -> NDArray[np.float64]:
        """Contact wrench [N, N*m], sensor frame, (N, 6): the reading without bias, tool
        gravity and the tool's inertial wrench."""
        static = self.static.compensate(
            np.asarray(wrench_sensor, dtype=float).reshape(-1, 6),
            np.asarray(R_base_sensor, dtype=float).reshape(-1, 3, 3),
        )
        return static - inertial_wrench(self.mass_kg, self.cog_m, self.inertia_cog_kgm2, motion)
