"""Gravity compensation: remove what a calibration says the tool and the sensor add.

- :mod:`.bias_tracking`: :class:`~.bias_tracking.BiasTracker`, the bias followed live while
  the arm is still and nothing touches the tool.
- :mod:`.compensator`: :class:`~.compensator.GravityCompensator`, bias and tool gravity removed
  at run time (paper Eq. 20-22), with the calibration's mount and bias drift.
- :mod:`.load`: weighing a grasped load from compensated readings.
- :mod:`.online`: a grasped load estimated online (grasp and release detected) and removed too,
  its estimate and events followed for a log (:class:`~.online.LoadTracker`).
- :mod:`.pipeline`: :class:`~.pipeline.WrenchPipeline`, a live cycle's readings through the
  above once each (bias and gravity or an online load, then bias tracking).
- :mod:`.inertial`: the moving tool's inertial wrench removed as well.

The package imports none of its modules (``__all__`` names them), so a command loads only the
ones it uses.
"""

__all__ = ["bias_tracking", "compensator", "inertial", "load", "online", "pipeline"]
