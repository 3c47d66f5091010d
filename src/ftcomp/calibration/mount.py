"""The sensor's mount rotation, when the recorded orientations are the flange's or the TCP's.

A recording from a robot gives the orientation of the flange (or TCP), ``R_base_rec``; the sensor
frame is ``R_base_sensor = R_base_rec @ R_rec_sensor``. A mounting yaw that is off by a few
degrees turns the tool's gravity the wrong way in the sensor frame after every posture change.
``ftcomp calibrate --identify-mount yaw`` identifies the yaw about the recorded frame's z axis
(the flange axis) jointly with the tool model (:mod:`.extended`,
:func:`~ftcomp.calibration.identify_extended.calibrate_extended`); ``full`` identifies all three
angles. The calibration then carries a :class:`~ftcomp.calibration_record.MountRotation`, and
compensation applies it: the orientations given to it are the recorded frame's. This module
reads the mount off a fit and says when the poses could not separate it.

Identifiability: a yaw about z only shows when gravity has a component across the flange axis in
the recorded frame, i.e. when the poses tilt the tool away from hanging straight down (or up);
the fit's standard error says how well, and :func:`mount_warnings` turns a poor one into words.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np

from ftcomp.calibration.extended import ExtendedFit
from ftcomp.calibration_record import MountRotation, mount_matrix

__all__ = ["MIN_POSES", "mount_from_fit", "mount_warnings"]

#: Fewest distinct poses for each mount model (yaw: one parameter more than the 12 of the
#: tool model; full: three, and the poses must tilt the tool in two directions).
MIN_POSES: Final[dict[str, int]] = {"yaw": 4, "full": 6}
#: A mount angle with a standard error above this [deg] is reported as not identified.
_WELL_IDENTIFIED_DEG: Final = 1.0


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
