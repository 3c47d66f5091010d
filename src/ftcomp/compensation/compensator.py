"""Run-time gravity compensation (paper Eq. 20-22); weighing a load is in :mod:`.load`.

``GravityCompensator(calibration).compensate(wrench_sensor, R_base_sensor)`` removes the sensor
bias and the tool's gravity wrench from a reading, leaving the wrench of everything else: contact
forces and a grasped load. It is written for the control loop: the constant parts are computed
once, and one sample costs two small matrix products.
"""

from __future__ import annotations

from typing import cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.calibration_record import (
    Calibration,
    MountRotation,
    TemperatureBiasDrift,
    TimeBiasDrift,
)
from ftcomp.constants import STANDARD_GRAVITY_MPS2
from ftcomp.errors import ParameterError
from ftcomp.model import GravityModel, skew

__all__ = ["GravityCompensator"]


class GravityCompensator:
    """Removes bias and tool gravity from F/T readings.

    Args:
        calibration: a :class:`~ftcomp.calibration_record.Calibration` (e.g. from
            :func:`ftcomp.load_calibration`) or a bare :class:`~ftcomp.model.GravityModel`.

    A calibration with a mount (``--identify-mount``) takes the orientations of the frame it
    was recorded in (flange, TCP) and turns them into the sensor's at no extra cost (folded
    into the constant matrices, as is a general linear sensor map, ``--sensor-map``). One
    with a bias drift applies it when given each sample's time (``t_s``, on the recording's
    clock): a polynomial or the smoothed stochastic bias inside the calibration's time
    range, the bias at its nearer end outside it (never extrapolated); without times the
    bias is the model's, the bias at the end of the calibration. One whose bias follows the
    sensor's temperature (``--bias-drift temperature``) applies it from each reading's
    temperature (``temperature_C``), held at the calibrated range's nearer end outside it;
    it needs that temperature for every reading (:attr:`needs_temperature`): without it
    :meth:`compensate` raises rather than silently use a constant bias.

    With a sensor's accelerometer (an IMU in the sensor: ``specific_force_mps2``, what it reads,
    the sensor's acceleration less gravity, sensor frame) the tool's wrench is that of its mass
    under the *apparent* gravity ``-f`` rather than under gravity at the sensor's orientation:
    ``m (g_s - a) = -m f``, so its linear inertial force is removed too (not the rotational
    terms, which need the angular acceleration and the inertia: :mod:`.inertial`). The mass is
    the calibrated weight over standard gravity (local gravity differs by up to 0.3 %).
    """

    def __init__(self, calibration: Calibration | GravityModel) -> None:
        sensor_map = None
        if isinstance(calibration, Calibration):
            model, mount, drift = calibration.model, calibration.mount, calibration.bias_drift
            sensor_map = calibration.sensor_map
        else:
            model, mount, drift = calibration, None, None
        self.model = model
        #: The calibration's mount (None: the orientations given are the sensor's).
        self.mount: MountRotation | None = mount
        #: The calibration's bias drift applied by each reading's time (None: none in time).
        self.time_drift: TimeBiasDrift | None = (
            None if isinstance(drift, TemperatureBiasDrift) else drift
        )
        #: The bias's dependence on the sensor's temperature (None: none).
        self.temperature_drift: TemperatureBiasDrift | None = (
            drift if isinstance(drift, TemperatureBiasDrift) else None
        )
        self._gravity_base = model.gravity_base_N.copy()
        self._bias = np.concatenate([model.force_bias_N, model.torque_bias_Nm])
        # [F; M] of the tool gravity = A @ g_s with A = [I; skew(P)] (Eq. 12, 20); with a mount,
        # g_s = R_rec_sensor.T @ g_rec, so A @ R_rec_sensor.T acts on the recorded frame's.
        self._A = np.vstack([np.eye(3), skew(model.center_of_gravity_m)])
        if sensor_map is not None and sensor_map.applied:  # folded in as the mount is
            self._A = self._A + sensor_map.delta
        if self.mount is not None:
            self._A = self._A @ self.mount.R_rec_sensor.T
        # For a batch, fold R.T @ g and A into one (9, 6) matrix acting on R flattened row-major:
        # g_s[j] = sum_i g[i] R[i, j], so R.reshape(N, 9) @ K gives every g_s, K[3i+j, j] = g[i].
        K = np.zeros((9, 3))
        for i in range(3):
            K[3 * i : 3 * i + 3, :] = self._gravity_base[i] * np.eye(3)
        self._batch_matrix = K @ self._A.T
        # The single-sample path on floats (a control loop's one call per cycle): g, and
        # bias + A as rows of floats.
        self._g = tuple(self._gravity_base.tolist())
        self._rows = tuple(
            (b, *a) for b, a in zip(self._bias.tolist(), self._A.tolist(), strict=True)
        )
        heat = self.temperature_drift
        # The temperature model on floats: slopes, reference and range.
        self._slopes = tuple(heat.slopes.tolist()) if heat is not None else (0.0,) * 6
        self._T = (heat.T_ref_C, heat.T_min_C, heat.T_max_C) if heat is not None else None
        #: The tool's mass [kg] (its calibrated weight over standard gravity), which an
        #: accelerometer's specific force turns into its apparent weight.
        self.mass_kg = float(model.weight_N) / STANDARD_GRAVITY_MPS2
        # The apparent weight -m f (sensor frame) into the frame A acts on (the recorded one).
        self._f_to_s = -self.mass_kg * (
            self.mount.R_rec_sensor if self.mount is not None else np.eye(3)
        )
        self._imu_matrix = (self._A @ self._f_to_s).T  # (3, 6): f -> the tool's wrench
        #: Unit vector along gravity, base frame (None for a weightless tool).
        self.gravity_dir_base = (
            self._gravity_base / np.linalg.norm(self._gravity_base) if model.weight_N else None
        )

    @property
    def needs_temperature(self) -> bool:
        """Whether :meth:`compensate` needs each reading's sensor temperature: the
        calibration's bias follows it."""
        return self.temperature_drift is not None

    def compensate(
        self,
        wrench_sensor: ArrayLike,
        R_base_sensor: ArrayLike,
        *,
        out: NDArray[np.float64] | None = None,
        t_s: ArrayLike | None = None,
        temperature_C: ArrayLike | None = None,
        specific_force_mps2: ArrayLike | None = None,
    ) -> NDArray[np.float64]:
        """Contact wrench ``[F'; M']`` (Eq. 22) [N, N*m], sensor frame.

        Args:
            wrench_sensor: raw reading(s), shape (6,) or (N, 6), sensor frame.
            R_base_sensor: the sensor's orientation(s) in the base frame, (3, 3) or (N, 3, 3).
            out: for a batch, an optional C-contiguous float64 (N, 6) array to write into
                (saves allocating a fresh result when streaming blocks of readings).
            t_s: each sample's time [s], scalar or (N,): applies the calibration's bias drift
                in time (ignored without one).
            temperature_C: each sample's sensor temperature [degC], scalar or (N,): applies a
                bias that follows it (needed with one; ignored without). A NaN temperature
                gives a NaN wrench.
            specific_force_mps2: each sample's accelerometer reading [m/s^2], sensor frame,
                (3,) or (N, 3): the tool's weight and linear inertial force from it (class
                docstring) instead of from ``R_base_sensor``.

        Returns:
            Shape (6,) or (N, 6).

        Raises:
            ParameterError: shapes that do not fit (``specific_force_mps2``'s too); no
                ``temperature_C`` for a calibration whose bias follows the temperature.
        """
        w = np.asarray(wrench_sensor, dtype=float)
        R = np.asarray(R_base_sensor, dtype=float)
        T = self._T
        if T is not None and temperature_C is None:
            raise ParameterError(
                "the calibration's bias follows the sensor's temperature (bias_drift "
                "temperature): compensate needs each reading's temperature_C"
            )
        f = None if specific_force_mps2 is None else np.asarray(specific_force_mps2, float)
        if w.shape == (6,) and R.shape == (3, 3):
            if t_s is not None and self.time_drift is not None:
                w = w - self.time_drift.offset(t_s)
            if f is None:
                g0, g1, g2 = self._g
                (a0, a1, a2), (b0, b1, b2), (c0, c1, c2) = R.tolist()
                s = (
                    g0 * a0 + g1 * b0 + g2 * c0,
                    g0 * a1 + g1 * b1 + g2 * c1,
                    g0 * a2 + g1 * b2 + g2 * c2,
                )
            elif f.shape == (3,):
                s = tuple((self._f_to_s @ f).tolist())
            else:
                raise ParameterError(
                    f"specific_force_mps2 must be (3,) with one reading, got {f.shape}",
                    field="specific_force_mps2",
                )
            if T is None:
                return self._one(w, s, 0.0)
            ref, low, high = T
            now = float(cast(float, temperature_C))
            return self._one(w, s, min(max(now, low), high) - ref)
        if w.ndim == 2 and w.shape[1] == 6 and R.shape == (len(w), 3, 3):
            if out is None:
                out = np.empty((len(w), 6))
            elif out.shape != w.shape or out.dtype != np.float64 or not out.flags.c_contiguous:
                raise ParameterError("out must be a C-contiguous float64 array of shape (N, 6)")
            if f is None:  # every sample's tool gravity in one (N, 9) @ (9, 6) product
                np.dot(np.ascontiguousarray(R).reshape(len(R), 9), self._batch_matrix, out=out)
            elif f.shape == (len(w), 3):
                np.dot(f, self._imu_matrix, out=out)
            else:
                raise ParameterError(
                    f"specific_force_mps2 must be ({len(w)}, 3) with {len(w)} readings, got "
                    f"{f.shape}",
                    field="specific_force_mps2",
                )
            np.subtract(w, out, out=out)
            out -= self._bias
            if t_s is not None and self.time_drift is not None:
                out -= self.time_drift.offset(np.broadcast_to(np.asarray(t_s, float), len(w)))
            if self.temperature_drift is not None:
                heat = np.broadcast_to(np.asarray(temperature_C, float), len(w))
                out -= self.temperature_drift.offset(heat)
            return out
        raise ParameterError(
            "compensate needs wrench_sensor (6,) with R_base_sensor (3, 3), or (N, 6) with "
            f"(N, 3, 3); got {w.shape} and {R.shape}"
        )

    def _one(self, w: NDArray[np.float64], s: tuple[float, ...], dT: float) -> NDArray[np.float64]:
        """``w - bias - slopes dT - A @ s`` for one sample, on floats (``s``: the tool's
        weight in the frame ``A`` acts on, ``g @ R`` or the accelerometer's; ``dT``: the
        temperature held to the calibrated range less the reference [degC], 0 without one)."""
        s0, s1, s2 = s
        return np.array(
            [
                x - b - k * dT - (k0 * s0 + k1 * s1 + k2 * s2)
                for x, k, (b, k0, k1, k2) in zip(w.tolist(), self._slopes, self._rows, strict=True)
            ]
        )
