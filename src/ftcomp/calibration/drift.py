"""Bias drift: the sensor's zero offset as a function of time, identified with the tool model.

Real sensors' bias wanders (temperature): a calibration from poses recorded over minutes then
mixes that wander into the tool model.
:func:`~ftcomp.calibration.identify_extended.calibrate_extended` with ``bias_drift="linear"`` or
``"quadratic"`` fits the force and torque bias as a polynomial in the sample time ``t`` jointly
with the tool model (:mod:`.extended`), so the tool model is shared by all poses and the bias is
free to move; the result carries a :class:`~ftcomp.calibration_record.BiasDrift` (rates with
standard errors, the time range it was fitted over). The model's ``F0, M0`` are the bias at the
end of the recording (``t_ref``), the best constant for what comes next.

This module is the drift's side of that fit: each pose's time in the fit's scaled time
(:func:`drift_times`) and the drift, in seconds, that a fit found (:func:`drift_from_fit`).
The practical cure for drift is :func:`ftcomp.calibration.rebias.rebias`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ftcomp.arrays import freeze_field
from ftcomp.calibration.extended import ExtendedFit
from ftcomp.calibration.identify import pose_groups
from ftcomp.calibration_record import BiasDrift
from ftcomp.errors import IdentificationError, ParameterError
from ftcomp.samples import Samples

__all__ = ["DriftTimes", "drift_from_fit", "drift_times"]


@dataclass(frozen=True)
class DriftTimes:
    """Each pose's mean time, scaled for the fit: ``tau = (t - t_ref_s) / half_span_s``.

    Attributes:
        order: the drift polynomial's order, 1 (linear) or 2 (quadratic).
        tau: each pose's scaled time, (P,), in [-2, 0].
        t_ref_s: the reference time [s]: the end of the recording.
        t_min_s, t_max_s: the recording's time range [s].
        half_span_s: half that range [s] (at least 1 ns).
    """

    order: int
    tau: NDArray[np.float64]
    t_ref_s: float
    t_min_s: float
    t_max_s: float
    half_span_s: float

    def __post_init__(self) -> None:
        if self.order not in (1, 2):
            raise ParameterError(f"DriftTimes.order must be 1 or 2, got {self.order}")
        freeze_field(self, "tau", (len(self.tau),), finite=True)

    @property
    def t_s(self) -> NDArray[np.float64]:
        """Each pose's time [s], (P,)."""
        return self.t_ref_s + self.tau * self.half_span_s


def drift_times(samples: Samples, order: int) -> DriftTimes:
    """The poses' mean times (poses as :func:`~ftcomp.calibration.identify.pose_means` groups
    them) for a drift polynomial of ``order`` (1 or 2).

    Raises:
        IdentificationError: the samples have no times, or the poses' times take ``order``
            values or fewer (a drift needs poses recorded at ``order + 1`` or more times).
    """
    name = "linear" if order == 1 else "quadratic"
    if samples.t is None:
        raise IdentificationError(
            f"{samples.source}: bias_drift {name} needs each reading's time: the file "
            "has no 't' (or 't_ns') column",
            field="bias_drift",
        )
    group, first = pose_groups(samples)
    poses = len(first)
    t_pose = np.bincount(group, samples.t, poses) / np.bincount(group, minlength=poses)
    t_min, t_max = float(samples.t.min()), float(samples.t.max())
    half = max((t_max - t_min) / 2.0, 1e-9)
    if len(np.unique(np.round(t_pose, 9))) <= order:
        raise IdentificationError(
            f"{samples.source}: the poses' times take {order} value(s) or fewer: a "
            f"{name} drift needs poses recorded at {order + 1} or more times"
        )
    return DriftTimes(order, (t_pose - t_max) / half, t_max, t_min, t_max, half)


def drift_from_fit(fit: ExtendedFit, times: DriftTimes) -> BiasDrift:
    """The drift a fit with drift parameters found, per power of seconds, with standard
    errors (the fit's coefficients are per power of scaled time)."""
    order = fit.order
    if order != times.order:
        raise ParameterError(f"the fit's drift order {order} is not the times' {times.order}")
    scale = np.repeat(times.half_span_s ** -np.arange(1, order + 1, dtype=float), 6)
    se = np.sqrt(np.maximum(np.diag(fit.covariance)[12 : 12 + 6 * order], 0.0)) * scale
    return BiasDrift(
        order,
        times.t_ref_s,
        times.t_min_s,
        times.t_max_s,
        (fit.drift.ravel() * scale).reshape(order, 6),
        se.reshape(order, 6),
    )
