"""A virtual UR cell: the simulated cell served as a UR e-Series (RTDE, dashboard, script
ports) with a wrist ATI Net F/T (HTTP, RDT over UDP) on loopback, for the real clients
(``ur_rtde``, ``pynetft``) and every ftcomp command. See docs/twin.md."""

from ftcomp.twin.controller import PROTECTIVE_STOP_FORCE_N, SafetyState, UrController
from ftcomp.twin.serve import FAULTS, ROBOTS, TwinConfig, TwinResult, serve_twin

__all__ = [
    "FAULTS",
    "PROTECTIVE_STOP_FORCE_N",
    "ROBOTS",
    "SafetyState",
    "TwinConfig",
    "TwinResult",
    "UrController",
    "serve_twin",
]
