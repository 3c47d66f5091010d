"""Physical constants and physical bounds used across ftcomp (SI units)."""

from __future__ import annotations

__all__ = ["PLAUSIBLE_FORCE_N", "PLAUSIBLE_TORQUE_NM", "STANDARD_GRAVITY_MPS2"]

#: Standard acceleration of gravity [m/s^2] (ISO 80000-3), used to turn weights into masses.
STANDARD_GRAVITY_MPS2 = 9.80665

#: A force reading beyond +-this [N] is not from any F/T sensor (a hundred tonnes; the largest
#: six-axis sensors made stop near 1e5 N): a corrupt cell or a unit mistake. The sample readers
#: (:mod:`ftcomp.io.sample_format`) and the calibration (:mod:`ftcomp.calibration.outliers`)
#: reject such readings.
PLAUSIBLE_FORCE_N = 1e6
#: A torque reading beyond +-this [N*m] is not from any F/T sensor (the largest stop near
#: 1e4 N*m).
PLAUSIBLE_TORQUE_NM = 1e5
