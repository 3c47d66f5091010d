"""Live bias tracking: the bias estimate follows the sensor while the arm is still and free.

A calibration is used for hours after its session while the sensor's bias keeps wandering.
:class:`BiasTracker` corrects the calibration's bias on line: each cycle it is given the
wrench a :class:`~ftcomp.compensation.compensator.GravityCompensator` computed (the tool model
and the calibration's bias removed) and the sensor's orientation; when nothing touches the tool
(the corrected wrench below the contact thresholds) and the pose is steady (the orientation
changing slower than ``still_rate_rad_s`` for ``still_hold_s``), what is left is the bias's
change, and a Kalman update per axis (the bias a random walk, the tool model held) moves the
correction toward it, at most ``max_rate`` per second. Never while in contact or moving.

Use::

    compensator = GravityCompensator(calibration)
    tracker = BiasTracker(BiasTrackingConfig(), initial_std=...)
    each cycle:
        contact = compensator.compensate(wrench_sensor, R_base_sensor)
        contact = tracker.correct(t_s, contact, R_base_sensor)  # update, then subtract
        tracker.updated                                         # bool: the log column

It costs about 10 us a cycle (Python floats; the one ``correction`` array updated in place).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.errors import ParameterError

__all__ = ["BiasTracker", "BiasTrackingConfig"]


@dataclass(frozen=True)
class BiasTrackingConfig:
    """When and how fast the bias estimate may follow the sensor.

    Attributes:
        contact_force_N: no contact while the corrected force's norm is below this [N].
        contact_torque_Nm: ... and the corrected torque's norm below this [N*m].
        still_rate_rad_s: still while the orientation turns slower than this [rad/s].
        still_hold_s: the arm must have been still and free this long before an update [s].
        noise_force_N: one reading's force noise (the Kalman measurement noise) [N].
        noise_torque_Nm: one reading's torque noise [N*m].
        walk_force_N_per_sqrt_s: how fast the bias may wander, a random walk [N/sqrt(s)].
        walk_torque_Nm_per_sqrt_s: the same for torque [N*m/sqrt(s)].
        max_rate_force_N_per_s: the correction moves at most this fast [N/s].
        max_rate_torque_Nm_per_s: ... and this for torque [N*m/s].
        max_correction_force_N: the correction never exceeds this from the calibration's
            bias per axis [N] (a larger change is not drift: re-calibrate).
        max_correction_torque_Nm: ... and this for torque [N*m].
    """

    contact_force_N: float = 1.0
    contact_torque_Nm: float = 0.05
    still_rate_rad_s: float = 0.005
    still_hold_s: float = 0.5
    noise_force_N: float = 0.125
    noise_torque_Nm: float = 0.003
    walk_force_N_per_sqrt_s: float = 0.01
    walk_torque_Nm_per_sqrt_s: float = 0.0002
    max_rate_force_N_per_s: float = 0.05
    max_rate_torque_Nm_per_s: float = 0.001
    max_correction_force_N: float = 2.0
    max_correction_torque_Nm: float = 0.05

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if not math.isfinite(value) or value <= 0.0:
                raise ParameterError(
                    f"BiasTrackingConfig.{name} must be finite and > 0, got {value}"
                )


class BiasTracker:
    """A Kalman filter on the bias's change since the calibration, updated only when still and
    free (see the module's docstring).

    Args:
        config: thresholds, noise and limits.
        initial_std: the calibration's bias standard error per axis ``[N]*3 + [N*m]*3`` at the
            first update (e.g. the calibration's ``F0, M0`` standard errors, or a stochastic
            drift's ``offset_std`` at that time); default: one reading's noise.

    Attributes:
        correction: the tracked bias minus the calibration's, (6,), updated in place: subtract
            it from the compensated wrench.
        updated: whether the last :meth:`update` moved the estimate.
        updates: how many updates moved it.
    """

    def __init__(self, config: BiasTrackingConfig, initial_std: ArrayLike | None = None) -> None:
        self.config = config
        c = config
        noise = [c.noise_force_N] * 3 + [c.noise_torque_Nm] * 3
        std = noise if initial_std is None else np.asarray(initial_std, dtype=float).tolist()
        if len(std) != 6 or not all(math.isfinite(s) and s >= 0.0 for s in std):
            raise ParameterError(f"initial_std must be 6 finite values >= 0, got {std}")
        self.correction: NDArray[np.float64] = np.zeros(6)
        self.updated = False
        self.updates = 0
        self._var = [s * s for s in std]
        self._r2 = [n * n for n in noise]
        self._q2 = [c.walk_force_N_per_sqrt_s**2] * 3 + [c.walk_torque_Nm_per_sqrt_s**2] * 3
        self._rate = [c.max_rate_force_N_per_s] * 3 + [c.max_rate_torque_Nm_per_s] * 3
        self._limit = [c.max_correction_force_N] * 3 + [c.max_correction_torque_Nm] * 3
        self._c = [0.0] * 6
        self._x = [0.0] * 6  # the Kalman estimate; _c follows it rate-limited
        self._t: float | None = None
        self._R: list[float] | None = None
        self._still_since: float | None = None

    @property
    def std(self) -> NDArray[np.float64]:
        """The correction's standard error per axis now, (6,)."""
        return np.sqrt(self._var)

    def free_and_still(self, contact: list[float], R: list[float], t_s: float) -> bool:
        """Whether the arm has been still and free for ``still_hold_s`` at ``t_s`` [s] (updates
        the still timer; ``contact`` corrected, ``R`` the orientation's 9 entries)."""
        c = self.config
        f = math.sqrt(contact[0] ** 2 + contact[1] ** 2 + contact[2] ** 2)
        m = math.sqrt(contact[3] ** 2 + contact[4] ** 2 + contact[5] ** 2)
        steady = False
        if self._R is not None and self._t is not None and t_s > self._t:
            # |R1 - R2|_F = 2 sqrt(2) sin(angle / 2) ~ sqrt(2) angle for small angles.
            d2 = sum((a - b) ** 2 for a, b in zip(R, self._R, strict=True))
            steady = math.sqrt(d2 / 2.0) <= c.still_rate_rad_s * (t_s - self._t)
        if f < c.contact_force_N and m < c.contact_torque_Nm and steady:
            if self._still_since is None:
                self._still_since = t_s
        else:
            self._still_since = None
        return self._still_since is not None and t_s - self._still_since >= c.still_hold_s

    def update(self, t_s: float, contact_sensor: ArrayLike, R_base_sensor: ArrayLike) -> bool:
        """One cycle: the uncertainty grows with the time since the last; when still and free,
        a Kalman step toward the compensated wrench, rate-limited.

        Args:
            t_s: the reading's time [s] (the same clock every cycle).
            contact_sensor: the calibration's compensated wrench (not yet corrected), (6,).
            R_base_sensor: the sensor's orientation, (3, 3).

        Returns:
            Whether the estimate moved (the log column).
        """
        w = np.asarray(contact_sensor, dtype=float).tolist()
        R = np.asarray(R_base_sensor, dtype=float).ravel().tolist()
        dt = 0.0 if self._t is None else max(t_s - self._t, 0.0)
        cor = self._c
        corrected = [w[j] - cor[j] for j in range(6)]
        go = self.free_and_still(corrected, R, t_s)
        self._t, self._R = t_s, R
        var = self._var
        for j in range(6):
            var[j] += self._q2[j] * dt
        self.updated = False
        if not go or dt <= 0.0:
            return False
        x = self._x
        for j in range(6):
            # The Kalman estimate of the bias's change, on the reading as it is (clipping each
            # noisy step would turn the rate limit into a far slower filter) ...
            gain = var[j] / (var[j] + self._r2[j])
            limit = self._limit[j]
            value = x[j] + gain * (w[j] - x[j])
            x[j] = limit if value > limit else (-limit if value < -limit else value)
            var[j] *= 1.0 - gain
            # ... and the correction applied follows it at most max_rate.
            most = self._rate[j] * dt
            step = x[j] - cor[j]
            cor[j] += most if step > most else (-most if step < -most else step)
        self.correction[:] = cor
        self.updated = True
        self.updates += 1
        return True

    def correct(
        self, t_s: float, contact_sensor: ArrayLike, R_base_sensor: ArrayLike
    ) -> NDArray[np.float64]:
        """:meth:`update`, then the contact wrench with the tracked change of the bias removed
        (a new (6,) array): what a live loop uses."""
        self.update(t_s, contact_sensor, R_base_sensor)
        return np.asarray(contact_sensor, dtype=float) - self.correction
