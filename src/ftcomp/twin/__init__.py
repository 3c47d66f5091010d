"""A virtual UR cell: the simulated cell served as a UR e-Series (RTDE, dashboard, script
ports) with a wrist ATI Net F/T (HTTP, RDT over UDP) on loopback, for the real clients
(``ur_rtde``, ``pynetft``) and every ftcomp command. See docs/twin.md.

Names are imported when first used (PEP 562): the Net F/T's process and the loopback stand-ins
import :mod:`ftcomp.twin.netft` without MuJoCo.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = [
    "FAULTS",
    "PROTECTIVE_STOP_FORCE_N",
    "ROBOTS",
    "SafetyState",
    "TwinConfig",
    "TwinResult",
    "UrController",
    "flange_wrenches",
    "serve_twin",
]

_WHERE = {
    "FAULTS": "ftcomp.twin.faults",
    "PROTECTIVE_STOP_FORCE_N": "ftcomp.twin.controller",
    "ROBOTS": "ftcomp.twin.serve",
    "SafetyState": "ftcomp.twin.controller",
    "TwinConfig": "ftcomp.twin.serve",
    "TwinResult": "ftcomp.twin.serve",
    "UrController": "ftcomp.twin.controller",
    "flange_wrenches": "ftcomp.twin.serve",
    "serve_twin": "ftcomp.twin.serve",
}


def __getattr__(name: str) -> Any:
    if name not in _WHERE:
        raise AttributeError(f"module 'ftcomp.twin' has no attribute {name!r}")
    return getattr(importlib.import_module(_WHERE[name]), name)
