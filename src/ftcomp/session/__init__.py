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

Names are imported when first used (PEP 562): a command that needs one session's config (to
build its options) does not load every session's dependencies.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ftcomp.lazy import lazy_exports

if TYPE_CHECKING:
    from ftcomp.session.compensate_file import (
        CompensateConfig,
        CompensateResult,
        compensate_file,
    )
    from ftcomp.session.compliant import (
        CompliantStep,
        CycleRecord,
        SettleRule,
        Settling,
    )
    from ftcomp.session.hand_guided import (
        ManualRecorder,
        StillCriteria,
    )
    from ftcomp.session.placement import (
        PlacementConfig,
        PlacementResult,
        run_placement,
    )
    from ftcomp.session.pose_record import (
        PoseEvent,
        PoseRecord,
        WrenchTolerance,
    )
    from ftcomp.session.record import (
        HandGuided,
        RecordConfig,
        RecordResult,
        RobotDriven,
        record,
    )
    from ftcomp.session.run import (
        AdmittanceConfig,
        RunConfig,
        RunResult,
        run_compliant,
    )
    from ftcomp.session.stream import (
        StreamConfig,
        StreamProgress,
        StreamResult,
        stream,
    )

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

_WHERE = {
    "AdmittanceConfig": "ftcomp.session.run",
    "CompensateConfig": "ftcomp.session.compensate_file",
    "CompensateResult": "ftcomp.session.compensate_file",
    "CompliantStep": "ftcomp.session.compliant",
    "CycleRecord": "ftcomp.session.compliant",
    "HandGuided": "ftcomp.session.record",
    "ManualRecorder": "ftcomp.session.hand_guided",
    "PlacementConfig": "ftcomp.session.placement",
    "PlacementResult": "ftcomp.session.placement",
    "PoseEvent": "ftcomp.session.pose_record",
    "PoseRecord": "ftcomp.session.pose_record",
    "RecordConfig": "ftcomp.session.record",
    "RecordResult": "ftcomp.session.record",
    "RobotDriven": "ftcomp.session.record",
    "RunConfig": "ftcomp.session.run",
    "RunResult": "ftcomp.session.run",
    "SettleRule": "ftcomp.session.compliant",
    "Settling": "ftcomp.session.compliant",
    "StillCriteria": "ftcomp.session.hand_guided",
    "StreamConfig": "ftcomp.session.stream",
    "StreamProgress": "ftcomp.session.stream",
    "StreamResult": "ftcomp.session.stream",
    "WrenchTolerance": "ftcomp.session.pose_record",
    "compensate_file": "ftcomp.session.compensate_file",
    "record": "ftcomp.session.record",
    "run_compliant": "ftcomp.session.run",
    "run_placement": "ftcomp.session.placement",
    "stream": "ftcomp.session.stream",
}


__getattr__ = lazy_exports(__name__, _WHERE)
