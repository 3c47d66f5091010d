"""Calibration: identify sensor bias, tool weight and centre of gravity, and base tilt.

It produces the records of :mod:`ftcomp.calibration_record`
(:class:`~ftcomp.calibration_record.Calibration` and what it carries); :mod:`ftcomp.io` writes
them, :mod:`ftcomp.compensation` applies them.

- :mod:`.identify`: :func:`~.identify.calibrate` (the paper's method or the joint fit, with
  standard errors, residuals, Table 3, leave-one-pose-out) and the grouping of readings by pose.
- :mod:`.methods`: the paper's two-stage linear least squares and the joint weighted fit;
  :mod:`.loo`: leave-one-pose-out; :mod:`.outliers`: absurd readings and fits, outlier poses.
- :mod:`.identify_extended`: :func:`~.identify_extended.calibrate_extended`, the joint fit with a
  drifting bias (:mod:`.drift`) and/or an unknown mount rotation (:mod:`.mount`), on the fit of
  :mod:`.extended`; :mod:`.rebias`: the bias alone from still readings.
- :mod:`.dynamic`: the tool's inertia tensor from a fast excitation trajectory.
- :mod:`.stochastic`: the bias as a stochastic process in time (``--bias-drift stochastic``);
  :mod:`.sensor_map`: a general linear force/torque map regularised toward the paper's model;
  :mod:`.temperature`: a bias that follows the sensor's temperature (its regressor for
  ``--bias-drift temperature``, and the two-stage reference fits of the bench).
- :mod:`.design`: D-optimal calibration poses, :mod:`.reachable_design` on an arm that does not
  reach every orientation; :mod:`.collect`: static readings at a list of poses from any robot
  and sensor; :mod:`.still`: the still segments of a recording in motion.

The package imports none of its modules (``__all__`` names them), so a command loads only the
ones it uses.
"""

__all__ = [
    "collect",
    "design",
    "drift",
    "dynamic",
    "extended",
    "identify",
    "identify_extended",
    "loo",
    "methods",
    "mount",
    "outliers",
    "reachable_design",
    "rebias",
    "sensor_map",
    "still",
    "stochastic",
    "temperature",
]
