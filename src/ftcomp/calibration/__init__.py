"""Calibration: identify sensor bias, tool weight and centre of gravity, and base tilt.

- :mod:`.identify`: :func:`calibrate` and the :class:`Calibration` it returns (standard errors,
  residuals, Table 3, leave-one-pose-out).
- :mod:`.methods`: the paper's two-stage linear least squares and the joint weighted fit.
- :mod:`.collect`: static readings at a list of poses from any robot and sensor.
"""
