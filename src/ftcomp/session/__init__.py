"""Sessions: what a user does with ftcomp, each one library call with a config and a result.

- :func:`~ftcomp.session.record.record`: record calibration readings on a live cell.
- :func:`~ftcomp.session.compensate_file.compensate_file`: compensate a whole sample file.
"""

from ftcomp.session.compensate_file import (
    CompensateConfig,
    CompensateResult,
    compensate_file,
)
from ftcomp.session.hand_guided import ManualRecorder, StillCriteria
from ftcomp.session.pose_record import PoseEvent, PoseRecord, WrenchTolerance
from ftcomp.session.record import HandGuided, RecordConfig, RecordResult, RobotDriven, record

__all__ = [
    "CompensateConfig",
    "CompensateResult",
    "HandGuided",
    "ManualRecorder",
    "PoseEvent",
    "PoseRecord",
    "RecordConfig",
    "RecordResult",
    "RobotDriven",
    "StillCriteria",
    "WrenchTolerance",
    "compensate_file",
    "record",
]
