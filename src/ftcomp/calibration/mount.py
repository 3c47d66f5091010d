"""The sensor's mount rotation, when the recorded orientations are the flange's or the TCP's.

A recording from a robot gives the orientation of the flange (or TCP), ``R_base_rec``; the sensor
frame is ``R_base_sensor = R_base_rec @ R_rec_sensor``. A mounting yaw that is off by a few
degrees turns the tool's gravity the wrong way in the sensor frame after every posture change.
``ftcomp calibrate --identify-mount yaw`` identifies the yaw about the recorded frame's z axis
(the flange axis) jointly with the tool model (:mod:`.extended`); ``full`` identifies all three
angles. The calibration then carries :class:`MountRotation`, and compensation applies it: the
orientations given to it are the recorded frame's.

Identifiability: a yaw about z only shows when gravity has a component across the flange axis in
the recorded frame, i.e. when the poses tilt the tool away from hanging straight down (or up);
the fit's standard error says how well, and :func:`mount_warnings` turns a poor one into words.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ftcomp.arrays import freeze_field
from ftcomp.calibration.extended import ExtendedFit, MountAxes, mount_matrix
from ftcomp.errors import CalibrationFileError

__all__ = ["MIN_POSES", "MountRotation", "mount_from_fit", "mount_warnings"]

#: Fewest distinct poses for each mount model (yaw: one parameter more than the 12 of the
#: tool model; full: three, and the poses must tilt the tool in two directions).
MIN_POSES: Final[dict[str, int]] = {"yaw": 4, "full": 6}
#: A mount angle with a standard error above this [deg] is reported as not identified.
_WELL_IDENTIFIED_DEG: Final = 1.0


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
        n = 1 if self.axes == "yaw" else 3
        freeze_field(self, "R_rec_sensor", (3, 3), finite=True)
        freeze_field(self, "angles_rad", (n,), finite=True)
        freeze_field(self, "std_errors_rad", (n,))

    def to_dict(self) -> dict[str, object]:
        """Calibration-file form (degrees at the edge)."""
        return {
            "axes": self.axes,
            "angles_deg": np.degrees(self.angles_rad).tolist(),
            "std_errors_deg": [
                math.degrees(v) if math.isfinite(v) else None for v in self.std_errors_rad
            ],
        }

    @classmethod
    def from_dict(cls, data: object, source: str) -> MountRotation:
        """Read back :meth:`to_dict` (checked)."""
        if not isinstance(data, dict) or data.get("axes") not in ("yaw", "full"):
            raise CalibrationFileError(f"{source}: 'mount' must be {{axes: yaw|full, angles_deg}}")
        axes = data["axes"]
        n = 1 if axes == "yaw" else 3
        angles = data.get("angles_deg")
        try:
            values = np.array(angles, dtype=float)
        except (TypeError, ValueError):
            values = np.array([])
        if values.shape != (n,) or not np.all(np.isfinite(values)):
            raise CalibrationFileError(
                f"{source}: 'mount.angles_deg' must be {n} finite number(s), got {angles!r}"
            )
        se = data.get("std_errors_deg")
        se_values = np.array(
            [float(v) if isinstance(v, (int, float)) else math.nan for v in se]
            if isinstance(se, list) and len(se) == n
            else [math.nan] * n
        )
        phi = np.radians(values)
        return cls(axes, mount_matrix(phi, axes), phi, np.radians(se_values))


def mount_from_fit(fit: ExtendedFit) -> MountRotation:
    """The mount a fit with mount parameters found, with standard errors."""
    if fit.mount_axes is None:
        raise ValueError("the fit has no mount parameters")
    k = len(fit.phi)
    n = len(fit.x)
    se = np.sqrt(np.maximum(np.diag(fit.covariance)[-k:], 0.0))
    for j in range(k):
        if fit.unidentified(n - k + j):
            se[j] = math.inf
    return MountRotation(fit.mount_axes, mount_matrix(fit.phi, fit.mount_axes), fit.phi, se)


def mount_warnings(mount: MountRotation) -> list[str]:
    """A sentence when an angle's standard error is above 1 deg: the poses cannot separate it."""
    se_deg = np.degrees(mount.std_errors_rad)
    if np.all(se_deg <= _WELL_IDENTIFIED_DEG):
        return []
    worst = float(np.nanmax(se_deg)) if np.any(np.isfinite(se_deg)) else math.inf
    return [
        f"mount {mount.axes} not identified: standard error {worst:.2g} deg "
        f"(> {_WELL_IDENTIFIED_DEG:g} deg); these poses cannot separate the sensor's mount "
        "rotation from the tool model: tilt the tool away from hanging straight down, in "
        "several directions"
    ]


def rotvec_deg(mount: MountRotation) -> NDArray[np.float64]:
    """The mount as a rotation vector [deg], shape (3,) (for display)."""
    return np.asarray(np.degrees(Rotation.from_matrix(mount.R_rec_sensor).as_rotvec()))
