"""Live sessions as library calls: what ``ftcomp record``, ``stream``, ``run``, ``compensate``
and ``sim place`` do, each one function taking a typed config and returning a result record.

- :func:`~ftcomp.session.stream.stream`: log a sensor's readings live (raw, compensated, with an
  online load estimate).
- :func:`~ftcomp.session.run.run_compliant`: the compliant loop on a robot.
- :func:`~ftcomp.session.placement.run_placement`: set a grasped load down on a surface (the
  paper's experiment, on the simulated cell or a real one).
- :class:`~ftcomp.session.compliant.CompliantStep`: the one compliant step both run, with its
  settle rule (:class:`~ftcomp.session.compliant.SettleRule`).

Sessions take entered devices (``with ftcomp.open_robot(uri) as robot: ...``); on any exit the
loop stops the robot first.
"""

from ftcomp.session.compliant import CompliantStep, CycleRecord, SettleRule, Settling
from ftcomp.session.placement import PlacementConfig, PlacementResult, run_placement
from ftcomp.session.run import AdmittanceConfig, RunConfig, RunResult, run_compliant
from ftcomp.session.stream import StreamConfig, StreamProgress, StreamResult, stream

__all__ = [
    "AdmittanceConfig",
    "CompliantStep",
    "CycleRecord",
    "PlacementConfig",
    "PlacementResult",
    "RunConfig",
    "RunResult",
    "SettleRule",
    "Settling",
    "StreamConfig",
    "StreamProgress",
    "StreamResult",
    "run_compliant",
    "run_placement",
    "stream",
]
