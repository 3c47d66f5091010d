"""What a calibration identified, with its uncertainty: the records calibration produces.

:mod:`ftcomp.calibration` produces these records, :mod:`ftcomp.io` reads and writes them
(:mod:`ftcomp.io.calibration_json`, :mod:`ftcomp.io.dynamic_json`) and
:mod:`ftcomp.compensation` applies them; they sit below all three so that none of those needs
another. The physics of the tool and sensor is :class:`~ftcomp.model.GravityModel`; a record
here adds what was measured about it:

- :class:`Calibration`: the model plus the evidence for it (standard errors, per-pose
  residuals, the paper's Table 3, leave-one-pose-out), and optionally
- :class:`BiasDrift`: the bias as a polynomial in time (``ftcomp calibrate --bias-drift linear``
  or ``quadratic``), or :class:`StochasticBiasDrift`: the bias as a Matérn 3/2 process in time,
  its smoothed estimate (``--bias-drift stochastic``), or :class:`TemperatureBiasDrift`: the
  bias as a linear function of the sensor's temperature (``--bias-drift temperature``), and
- :class:`SensorMap`: a general linear map (gain, crosstalk, misalignment) on the tool's gravity
  wrench, regularised toward the physical model (``ftcomp calibrate --sensor-map linear``), and
- :class:`MountRotation`: the sensor frame in the frame the orientations were recorded in
  (``ftcomp calibrate --identify-mount``);
- :class:`DynamicCalibration`: the tool's inertia tensor (``ftcomp calibrate-dynamic``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import ClassVar, Final, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ftcomp.arrays import freeze_field
from ftcomp.errors import ParameterError
from ftcomp.model import GravityModel

__all__ = [
    "DRIFT_ORDERS",
    "SENSOR_MAP_SUPPORT",
    "AnyBiasDrift",
    "BiasDrift",
    "Calibration",
    "DriftModel",
    "DynamicCalibration",
    "Method",
    "MountAxes",
    "MountRotation",
    "SensorMap",
    "StandardErrors",
    "StochasticBiasDrift",
    "TemperatureBiasDrift",
    "TimeBiasDrift",
    "matern32_correlation",
    "mount_matrix",
]

#: The identification methods: the paper's two-stage linear fit, or the joint nonlinear fit.
Method = Literal["paper", "joint"]
#: The bias drift models: constant, linear or quadratic in time, a stochastic process in time,
#: or linear in the sensor's temperature.
DriftModel = Literal["none", "linear", "quadratic", "stochastic", "temperature"]
#: The polynomial order of each polynomial drift model (``stochastic`` is not a polynomial).
DRIFT_ORDERS: Final[dict[str, int]] = {"none": 0, "linear": 1, "quadratic": 2}
#: Rows of times evaluated at once by :meth:`StochasticBiasDrift.offset` (bounds its memory).
_OFFSET_BLOCK: Final = 8192
#: The mount models: a yaw about the recorded frame's z axis, or a full rotation.
MountAxes = Literal["yaw", "full"]


@dataclass(frozen=True)
class StandardErrors:
    """One standard error per identified quantity, in the quantity's own unit and frame."""

    weight_N: float
    center_of_gravity_m: NDArray[np.float64]
    force_bias_N: NDArray[np.float64]
    torque_bias_Nm: NDArray[np.float64]
    tilt_U_rad: float
    tilt_V_rad: float
    gravity_base_N: NDArray[np.float64]

    def __post_init__(self) -> None:
        for name in ("center_of_gravity_m", "force_bias_N", "torque_bias_Nm", "gravity_base_N"):
            freeze_field(self, name, (3,))


@dataclass(frozen=True)
class BiasDrift:
    """The bias as a polynomial in time: ``bias(t) = [F0, M0] + sum_k c_k (t - t_ref)^k``.

    Attributes:
        order: 1 (linear) or 2 (quadratic).
        t_ref_s: reference time [s] (the model's ``F0, M0`` are the bias then).
        t_min_s, t_max_s: the time range the drift was fitted over [s].
        coefficients: ``c_k`` per row k = 1..order, ``[N/s^k]*3 + [N*m/s^k]*3``, (order, 6).
        std_errors: their standard errors, (order, 6).
    """

    order: int
    t_ref_s: float
    t_min_s: float
    t_max_s: float
    coefficients: NDArray[np.float64]
    std_errors: NDArray[np.float64]

    def __post_init__(self) -> None:
        if self.order not in (1, 2):
            raise ParameterError(f"BiasDrift.order must be 1 or 2, got {self.order}")
        freeze_field(self, "coefficients", (self.order, 6), finite=True)
        freeze_field(self, "std_errors", (self.order, 6))

    @property
    def name(self) -> DriftModel:
        """``"linear"`` or ``"quadratic"``."""
        return "linear" if self.order == 1 else "quadratic"

    def outside(self, t_min_s: float, t_max_s: float) -> str | None:
        """What :meth:`offset` does for times in ``t_min_s .. t_max_s`` [s] beyond the fitted
        range, as a sentence, or None when they are all within it."""
        return _outside_sentence(self.name, self.t_min_s, self.t_max_s, t_min_s, t_max_s)

    def offset(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """Bias at ``t_s`` [s] minus the bias at ``t_ref``, shape (N, 6) (or (6,)).

        Outside the fitted range the polynomial is not extrapolated: the bias holds its value
        at the nearer end of the range (after the session: the bias at ``t_max_s``)."""
        t = np.clip(np.asarray(t_s, dtype=float), self.t_min_s, self.t_max_s)
        dt = t - self.t_ref_s
        out = np.multiply.outer(dt, self.coefficients[0])
        if self.order == 2:
            out += np.multiply.outer(dt * dt, self.coefficients[1])
        return out


def matern32_correlation(dt_s: ArrayLike, time_constant_s: float) -> NDArray[np.float64]:
    """The Matérn 3/2 correlation ``(1 + a) exp(-a)``, ``a = sqrt(3) |dt| / time_constant``.

    The covariance of a once-differentiable stationary process (the bias as a smooth wander):
    the state-space form is a pair (value, rate) driven by white noise, so a Kalman/RTS
    smoother and a Gaussian process with this covariance give the same estimates.
    """
    a = np.abs(np.asarray(dt_s, dtype=float)) * (math.sqrt(3.0) / time_constant_s)
    return np.asarray((1.0 + a) * np.exp(-a))


def _outside_sentence(
    name: str, fit_min: float, fit_max: float, t_min: float, t_max: float
) -> str | None:
    parts = []
    if t_min < fit_min:
        parts.append(f"before {fit_min:.6g} s the bias is held at its first estimate")
    if t_max > fit_max:
        parts.append(
            f"after {fit_max:.6g} s (the end of the calibration) the bias is held at its last "
            "estimate, not extrapolated (ftcomp rebias catches up with later drift)"
        )
    if not parts:
        return None
    return (
        f"times {t_min:.6g} .. {t_max:.6g} s reach beyond the {name} bias drift's range "
        f"{fit_min:.6g} .. {fit_max:.6g} s: " + "; ".join(parts)
    )


@dataclass(frozen=True)
class StochasticBiasDrift:
    """The bias as a stochastic process: a Matérn 3/2 wander per axis around the model's bias.

    Identified jointly with the tool model (``ftcomp calibrate --bias-drift stochastic``,
    :mod:`ftcomp.calibration.stochastic`): the bias at time ``t`` is the process's smoothed
    estimate given every pose, ``g(t) = sum_k weights[k] * scale^2 * rho(t - t_knots[k])``
    (the Gaussian-process form of the Kalman/RTS smoother's mean). Inside ``t_min_s ..
    t_max_s`` :meth:`offset` is that estimate; after it, the last estimate held (its
    uncertainty growing as :meth:`offset_std` says), before it the first; never a trend.

    Attributes:
        t_knots_s: each calibration pose's mean time [s], (P,).
        weights: ``V^-1 r`` per axis at the knots, (P, 6) [1/N, 1/(N*m)].
        scale: the wander's standard deviation per axis ``[N]*3 + [N*m]*3``, (6,).
        time_constant_s: its Matérn 3/2 length scale [s] (shared by the axes).
        white_noise: the per-pose scatter the fit found beyond the readings' noise, (6,).
        knot_std: the bias's standard error at each knot, model's tool parameters included,
            (P, 6).
        end_std: the same at ``t_max_s``, (6,) (the model's ``F0, M0`` standard errors).
        t_min_s, t_max_s: the calibration's time range [s]; ``t_ref_s`` is ``t_max_s``.
    """

    t_knots_s: NDArray[np.float64]
    weights: NDArray[np.float64]
    scale: NDArray[np.float64]
    time_constant_s: float
    white_noise: NDArray[np.float64]
    knot_std: NDArray[np.float64]
    end_std: NDArray[np.float64]
    t_min_s: float
    t_max_s: float

    def __post_init__(self) -> None:
        n = len(self.t_knots_s)
        if n < 2:
            raise ParameterError("StochasticBiasDrift needs 2 or more knots")
        freeze_field(self, "t_knots_s", (n,), finite=True)
        freeze_field(self, "weights", (n, 6), finite=True)
        freeze_field(self, "scale", (6,), finite=True)
        freeze_field(self, "white_noise", (6,), finite=True)
        freeze_field(self, "knot_std", (n, 6))
        freeze_field(self, "end_std", (6,))
        if not (math.isfinite(self.time_constant_s) and self.time_constant_s > 0.0):
            raise ParameterError(
                f"StochasticBiasDrift.time_constant_s must be > 0, got {self.time_constant_s}"
            )
        if np.any(self.scale < 0.0):
            raise ParameterError("StochasticBiasDrift.scale must be >= 0 per axis")
        if not (self.t_min_s <= self.t_max_s):
            raise ParameterError(
                f"StochasticBiasDrift: t_min_s {self.t_min_s} is after t_max_s {self.t_max_s}"
            )
        if np.any(np.diff(self.t_knots_s) <= 0.0):
            raise ParameterError("StochasticBiasDrift.t_knots_s must increase")

    #: Not a polynomial: no coefficients (a report listing polynomial terms lists none).
    order: ClassVar[int] = 0

    @cached_property
    def _end(self) -> NDArray[np.float64]:
        """The smoothed wander at ``t_max_s``, (6,)."""
        return self._smoothed(np.array([self.t_max_s]))[0]

    @property
    def coefficients(self) -> NDArray[np.float64]:
        """No polynomial coefficients: shape (0, 6)."""
        return np.zeros((0, 6))

    @property
    def std_errors(self) -> NDArray[np.float64]:
        """No polynomial coefficients' standard errors: shape (0, 6)."""
        return np.zeros((0, 6))

    @property
    def name(self) -> DriftModel:
        """``"stochastic"``."""
        return "stochastic"

    @property
    def t_ref_s(self) -> float:
        """The reference time [s]: the end of the calibration (the model's ``F0, M0``)."""
        return self.t_max_s

    def _smoothed(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        """The smoothed wander ``g(t)`` at times within the range, (N, 6)."""
        out = np.empty((len(t), 6))
        coef = self.weights * self.scale**2
        for start in range(0, len(t), _OFFSET_BLOCK):
            block = t[start : start + _OFFSET_BLOCK]
            rho = matern32_correlation(block[:, None] - self.t_knots_s, self.time_constant_s)
            np.dot(rho, coef, out=out[start : start + len(block)])
        return out

    def offset(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """Bias at ``t_s`` [s] minus the bias at ``t_ref_s``, shape (N, 6) (or (6,)): the
        smoothed estimate inside the range, held at its nearer end outside it."""
        t = np.asarray(t_s, dtype=float)
        flat = np.clip(t.reshape(-1), self.t_min_s, self.t_max_s)
        out = self._smoothed(flat) - self._end
        return out.reshape((*t.shape, 6))

    def offset_std(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """The bias estimate's standard error at ``t_s`` [s], (N, 6) (or (6,)): the knots'
        interpolated inside the range; after it, the end's grown by the wander the process
        allows since (``end_std^2 + 2 scale^2 (1 - rho(t - t_max))``); before it likewise."""
        t = np.asarray(t_s, dtype=float)
        flat = t.reshape(-1)
        inside = np.column_stack(
            [np.interp(flat, self.t_knots_s, self.knot_std[:, j]) for j in range(6)]
        )
        after = np.clip(flat - self.t_max_s, 0.0, None)
        before = np.clip(self.t_min_s - flat, 0.0, None)
        grow = 2.0 * (1.0 - matern32_correlation(after + before, self.time_constant_s))
        late, early = flat >= self.t_max_s, flat < self.t_min_s
        held = np.where(late[:, None], self.end_std, self.knot_std[0])
        out = np.where(
            (late | early)[:, None], np.sqrt(held**2 + grow[:, None] * self.scale**2), inside
        )
        return out.reshape((*t.shape, 6))

    def outside(self, t_min_s: float, t_max_s: float) -> str | None:
        """What :meth:`offset` does for times in ``t_min_s .. t_max_s`` [s] beyond the fitted
        range, as a sentence (with the uncertainty reached), or None when within it."""
        text = _outside_sentence(self.name, self.t_min_s, self.t_max_s, t_min_s, t_max_s)
        if text is None or t_max_s <= self.t_max_s:
            return text
        std = self.offset_std(np.array([t_max_s]))[0]
        return (
            f"{text}; its standard error grows to {np.max(std[:3]):.3g} N, "
            f"{np.max(std[3:]):.3g} N·m at {t_max_s:.6g} s"
        )


#: Either drift record in time: what compensation applies by each reading's time.
TimeBiasDrift = BiasDrift | StochasticBiasDrift


@dataclass(frozen=True)
class TemperatureBiasDrift:
    """The bias as a linear function of the sensor's temperature:
    ``bias(T) = [F0, M0] + slopes * (clip(T, T_min_C, T_max_C) - T_ref_C)``.

    Identified jointly with the tool model (``ftcomp calibrate --bias-drift temperature``,
    :func:`ftcomp.calibration.identify_extended.calibrate_extended`): each pose's mean
    temperature is the regressor, as each pose's mean time is a polynomial drift's. Applied
    from each reading's temperature (``temperature_C``), never from its time. Outside the
    temperatures it was fitted over the bias is held at the nearer end of that range, as a
    drift in time is held outside its time range (never extrapolated).

    Attributes:
        T_ref_C: the reference temperature [degC]: the poses' mean (the model's ``F0, M0`` are
            the bias at it).
        T_min_C, T_max_C: the temperatures the readings of the calibration spanned [degC].
        slopes: ``[N/degC]*3 + [N*m/degC]*3``, (6,).
        std_errors: their standard errors, (6,).
    """

    T_ref_C: float
    T_min_C: float
    T_max_C: float
    slopes: NDArray[np.float64]
    std_errors: NDArray[np.float64]

    def __post_init__(self) -> None:
        freeze_field(self, "slopes", (6,), finite=True)
        freeze_field(self, "std_errors", (6,))
        values = (self.T_min_C, self.T_ref_C, self.T_max_C)
        if not all(math.isfinite(v) for v in values) or not (
            self.T_min_C <= self.T_ref_C <= self.T_max_C
        ):
            raise ParameterError(
                "TemperatureBiasDrift needs finite T_min_C <= T_ref_C <= T_max_C, got "
                f"{self.T_min_C}, {self.T_ref_C}, {self.T_max_C}"
            )

    @property
    def name(self) -> DriftModel:
        """``"temperature"``."""
        return "temperature"

    def offset(self, temperature_C: ArrayLike) -> NDArray[np.float64]:
        """Bias at ``temperature_C`` [degC] minus the bias at ``T_ref_C``, shape (N, 6) (or
        (6,)); held at the range's nearer end outside ``T_min_C .. T_max_C``."""
        T = np.clip(np.asarray(temperature_C, dtype=float), self.T_min_C, self.T_max_C)
        return np.multiply.outer(T - self.T_ref_C, self.slopes)

    def outside(self, T_min_C: float, T_max_C: float) -> str | None:
        """What :meth:`offset` does for temperatures in ``T_min_C .. T_max_C`` [degC] beyond
        the fitted range, as a sentence, or None when they are all within it."""
        parts = []
        if T_min_C < self.T_min_C:
            parts.append(f"below {self.T_min_C:.4g} degC the bias is held at its value there")
        if T_max_C > self.T_max_C:
            parts.append(f"above {self.T_max_C:.4g} degC the bias is held at its value there")
        if not parts:
            return None
        return (
            f"temperatures {T_min_C:.4g} .. {T_max_C:.4g} degC reach beyond the temperature "
            f"bias model's range {self.T_min_C:.4g} .. {self.T_max_C:.4g} degC: "
            + "; ".join(parts)
            + " (not extrapolated)"
        )


#: Any drift record: in time (applied by each reading's time) or in temperature (by each
#: reading's temperature).
AnyBiasDrift = BiasDrift | StochasticBiasDrift | TemperatureBiasDrift


def mount_matrix(phi: NDArray[np.float64], axes: MountAxes | None) -> NDArray[np.float64]:
    """``R_rec_sensor`` for the mount parameters: yaw ``(psi,)`` [rad] about the recorded
    frame's z axis, or a rotation vector (3,) [rad]; the identity without a mount."""
    if axes is None:
        return np.eye(3)
    from scipy.spatial.transform import Rotation  # on first use: scipy.spatial costs ~0.4 s

    rotvec = np.array([0.0, 0.0, phi[0]]) if axes == "yaw" else np.asarray(phi, dtype=float)
    return np.asarray(Rotation.from_rotvec(rotvec).as_matrix(), dtype=float)


@dataclass(frozen=True)
class MountRotation:
    """``R_rec_sensor``: the sensor frame in the frame the orientations were recorded in.

    Attributes:
        axes: ``"yaw"`` (about the recorded frame's z axis) or ``"full"``.
        R_rec_sensor: shape (3, 3).
        angles_rad: yaw (1,) or rotation vector (3,) [rad].
        std_errors_rad: their standard errors [rad], same shape.
    """

    axes: MountAxes
    R_rec_sensor: NDArray[np.float64]
    angles_rad: NDArray[np.float64]
    std_errors_rad: NDArray[np.float64]

    def __post_init__(self) -> None:
        if self.axes not in ("yaw", "full"):
            raise ParameterError(f"MountRotation.axes must be 'yaw' or 'full', got {self.axes!r}")
        n = 1 if self.axes == "yaw" else 3
        freeze_field(self, "R_rec_sensor", (3, 3), finite=True)
        freeze_field(self, "angles_rad", (n,), finite=True)
        freeze_field(self, "std_errors_rad", (n,))


#: Log Bayes factor above which the data are said to support the sensor map (about 20:1).
SENSOR_MAP_SUPPORT: Final = 3.0


@dataclass(frozen=True)
class SensorMap:
    """A general linear map on the tool's gravity wrench: ``reading = bias + (A(P) + delta) g_s``
    with ``A(P) = [I; skew(P)]`` the physical model and ``g_s`` the tool's gravity in the sensor
    frame (:mod:`ftcomp.calibration.sensor_map`).

    Attributes:
        delta: (6, 3): force rows dimensionless (gain, crosstalk, misalignment), torque rows [m].
        std_errors: their standard errors, (6, 3).
        log_evidence_gain: log marginal likelihood with the map minus without it (a log Bayes
            factor; the map integrated out under its prior).
        applied: whether the calibration uses it: only when the data support it (the model,
            residuals and compensation are then the map's; otherwise the physical model's, and
            the map is kept for the record).
    """

    delta: NDArray[np.float64]
    std_errors: NDArray[np.float64]
    log_evidence_gain: float
    applied: bool = True

    def __post_init__(self) -> None:
        freeze_field(self, "delta", (6, 3), finite=True)
        freeze_field(self, "std_errors", (6, 3))

    @property
    def supported(self) -> bool:
        """Whether the data support the map: a log Bayes factor above ``SENSOR_MAP_SUPPORT``."""
        return self.log_evidence_gain > SENSOR_MAP_SUPPORT

    def verdict(self) -> str:
        """One sentence on whether the data support the map."""
        gain = self.log_evidence_gain
        if self.supported:
            return (
                f"the data support the linear sensor map (log Bayes factor {gain:+.1f} over the "
                "physical model)"
            )
        return (
            f"the data do not support the linear sensor map (log Bayes factor {gain:+.1f}, "
            f"needs > {SENSOR_MAP_SUPPORT:g}): the physical model is used"
        )


@dataclass(frozen=True)
class Calibration:
    """The result of an identification: the model plus the evidence for it.

    Attributes:
        model: the identified :class:`~ftcomp.model.GravityModel`.
        method: ``"paper"`` or ``"joint"``.
        std_errors: standard error of every parameter.
        pose_ids: the id of each pose, in the order of the per-pose arrays.
        R_base_sensor: orientation of each pose, shape (P, 3, 3).
        wrench_mean: mean reading at each pose [N, N*m], shape (P, 6).
        readings_per_pose: how many readings were averaged at each pose, shape (P,).
        residuals: ``wrench_mean - model.predict(R)`` per pose, shape (P, 6).
        relative_error_percent: the paper's Table 3, ``100 |residual| / |wrench_mean|``, (P, 6).
        loo_error: leave-one-pose-out prediction error per pose (NaN where the other poses
            could not identify the model), shape (P, 6).
        condition_number: of the force regressor (Eq. 7); large means poses too alike.
        warnings: human-readable warnings.
        bias_drift: the bias as a function of time (``--bias-drift``): a polynomial
            (:class:`BiasDrift`) or a smoothed process (:class:`StochasticBiasDrift`); or of the
            sensor's temperature (:class:`TemperatureBiasDrift`); or None: constant.
        mount: the sensor frame's rotation in the frame the orientations were recorded in
            (``--identify-mount``), or None: the orientations are the sensor's.
        sensor_map: the general linear map (``--sensor-map linear``), or None: the physical
            model's.
    """

    model: GravityModel
    method: Method
    std_errors: StandardErrors
    pose_ids: tuple[str, ...]
    R_base_sensor: NDArray[np.float64] = field(repr=False)
    wrench_mean: NDArray[np.float64] = field(repr=False)
    readings_per_pose: NDArray[np.float64] = field(repr=False)
    residuals: NDArray[np.float64] = field(repr=False)
    relative_error_percent: NDArray[np.float64] = field(repr=False)
    loo_error: NDArray[np.float64] = field(repr=False)
    condition_number: float = math.inf
    warnings: tuple[str, ...] = ()
    bias_drift: BiasDrift | StochasticBiasDrift | TemperatureBiasDrift | None = None
    mount: MountRotation | None = None
    sensor_map: SensorMap | None = None

    def __post_init__(self) -> None:
        n = len(self.pose_ids)
        for name, shape in (
            ("R_base_sensor", (n, 3, 3)),
            ("wrench_mean", (n, 6)),
            ("readings_per_pose", (n,)),
            ("residuals", (n, 6)),
            ("relative_error_percent", (n, 6)),
            ("loo_error", (n, 6)),
        ):
            freeze_field(self, name, shape)

    @property
    def residual_rms(self) -> tuple[float, float]:
        """RMS of the force [N] and torque [N*m] residuals over poses and axes."""
        r = self.residuals
        if not len(r):
            return math.nan, math.nan
        return float(np.sqrt(np.mean(r[:, :3] ** 2))), float(np.sqrt(np.mean(r[:, 3:] ** 2)))

    @property
    def relative_error_mean_percent(self) -> NDArray[np.float64]:
        """Mean of the Table-3 relative errors per axis, shape (6,) (the paper's delta row)."""
        relative = self.relative_error_percent
        seen = np.isfinite(relative).any(axis=0)  # an axis without any: NaN, and no warning
        out = np.full(6, np.nan)
        out[seen] = np.nanmean(relative[:, seen], axis=0)
        return out

    @property
    def loo_rms(self) -> tuple[float, float]:
        """RMS leave-one-pose-out prediction error: force [N], torque [N*m]."""
        e = self.loo_error
        if not np.any(np.isfinite(e)):
            return math.nan, math.nan
        with np.errstate(invalid="ignore"):
            return (
                float(np.sqrt(np.nanmean(e[:, :3] ** 2))),
                float(np.sqrt(np.nanmean(e[:, 3:] ** 2))),
            )


@dataclass(frozen=True)
class DynamicCalibration:
    """The tool's inertia, identified (the static parameters come from the static calibration).

    Attributes:
        inertia_cog_kgm2: inertia tensor about the centre of gravity, sensor axes, (3, 3).
        std_error_kgm2: standard errors of ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)``, (6,).
        residual_rms_Nm: RMS torque residual per axis after the fit, (3,).
        samples: readings used.
        duration_s: recorded time [s].
        peak_alpha_rad_s2: peak |angular acceleration| about each sensor axis, (3,).
        peak_omega_rad_s: peak |angular velocity| about each sensor axis, (3,).
        peak_accel_mps2: peak |linear acceleration| of the sensor origin [m/s^2].
    """

    inertia_cog_kgm2: NDArray[np.float64] = field(repr=False)
    std_error_kgm2: NDArray[np.float64] = field(repr=False)
    residual_rms_Nm: NDArray[np.float64] = field(repr=False)
    samples: int
    duration_s: float
    peak_alpha_rad_s2: NDArray[np.float64] = field(repr=False)
    peak_omega_rad_s: NDArray[np.float64] = field(repr=False)
    peak_accel_mps2: float

    def __post_init__(self) -> None:
        for name, shape in (
            ("inertia_cog_kgm2", (3, 3)),
            ("std_error_kgm2", (6,)),
            ("residual_rms_Nm", (3,)),
            ("peak_alpha_rad_s2", (3,)),
            ("peak_omega_rad_s", (3,)),
        ):
            freeze_field(self, name, shape)
