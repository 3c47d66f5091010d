"""A virtual robot cell: the simulated cell served on loopback as a robot and a wrist sensor,
each through its device's face (:mod:`ftcomp.twin.faces`; by default a UR e-Series with RTDE,
dashboard and script ports, and an ATI Net F/T with HTTP and RDT over UDP), for the real
clients (``ur_rtde``, ``pynetft``) and every ftcomp command. See docs/twin.md.

Names are imported when first used (PEP 562): the Net F/T's process and the loopback stand-ins
import :mod:`ftcomp.twin.netft` without MuJoCo.
"""

from __future__ import annotations

from ftcomp.lazy import lazy_exports

__all__ = [
    "PROTECTIVE_STOP_FORCE_N",
    "NetFtFace",
    "RobotFace",
    "SafetyState",
    "SensorFace",
    "TwinConfig",
    "TwinResult",
    "UrController",
    "UrFace",
    "flange_wrenches",
    "pair_faults",
    "serve_twin",
]

_WHERE = {
    "NetFtFace": "ftcomp.twin.netft_face",
    "PROTECTIVE_STOP_FORCE_N": "ftcomp.twin.controller",
    "RobotFace": "ftcomp.twin.faces",
    "SafetyState": "ftcomp.twin.controller",
    "SensorFace": "ftcomp.twin.faces",
    "TwinConfig": "ftcomp.twin.serve",
    "TwinResult": "ftcomp.twin.serve",
    "UrController": "ftcomp.twin.controller",
    "UrFace": "ftcomp.twin.ur_face",
    "flange_wrenches": "ftcomp.twin.ur_face",
    "pair_faults": "ftcomp.twin.serve",
    "serve_twin": "ftcomp.twin.serve",
}


__getattr__ = lazy_exports(__name__, _WHERE)
