"""Live sessions as library calls: what ``ftcomp record``, ``stream``, ``run``, ``compensate``
and ``sim place`` do, each one function taking a typed config and returning a result record.

- :func:`~ftcomp.session.record.record`: calibration readings from a cell, robot-driven through
  poses (:class:`~ftcomp.session.record.RobotDriven`) or hand-guided
  (:class:`~ftcomp.session.record.HandGuided`), the file rewritten after every pose.
- :func:`~ftcomp.session.stream.stream`: log a sensor's readings live (raw, compensated, with an
  online load estimate).
- :func:`~ftcomp.session.run.run_compliant`: the compliant loop on a robot.
- :func:`~ftcomp.session.placement.run_placement`: set a grasped load down on a surface (the
  paper's experiment, on the simulated cell or a real one).
- :func:`~ftcomp.session.compensate_file.compensate_file`: compensate a recording of any length
  (CSV or Parquet), streamed.
- :class:`~ftcomp.session.compliant.CompliantStep`: the one compliant step run and placement
  share, with its settle rule (:class:`~ftcomp.session.compliant.SettleRule`).

Sessions take entered devices (``with ftcomp.open_robot(uri) as robot: ...``); on any exit the
loop stops the robot first.
"""

from ftcomp.session.compensate_file import CompensateConfig, CompensateResult, compensate_file
from ftcomp.session.compliant import CompliantStep, CycleRecord, SettleRule, Settling
from ftcomp.session.hand_guided import ManualRecorder, StillCriteria
from ftcomp.session.placement import PlacementConfig, PlacementResult, run_placement
from ftcomp.session.pose_record import PoseEvent, PoseRecord, WrenchTolerance
from ftcomp.session.record import HandGuided, RecordConfig, RecordResult, RobotDriven, record
from ftcomp.session.run import AdmittanceConfig, RunConfig, RunResult, run_compliant
from ftcomp.session.stream import StreamConfig, StreamProgress, StreamResult, stream

__all__ = [
    "AdmittanceConfig",
    "CompensateConfig",
    "CompensateResult",
    "CompliantStep",
    "CycleRecord",
    "HandGuided",
    "ManualRecorder",
    "PlacementConfig",
    "PlacementResult",
    "PoseEvent",
    "PoseRecord",
    "RecordConfig",
    "RecordResult",
    "RobotDriven",
    "RunConfig",
    "RunResult",
    "SettleRule",
    "Settling",
    "StillCriteria",
    "StreamConfig",
    "StreamProgress",
    "StreamResult",
    "WrenchTolerance",
    "compensate_file",
    "record",
    "run_compliant",
    "run_placement",
    "stream",
]
