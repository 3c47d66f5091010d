"""Admittance control: laws (paper Eq. 24-27 and mass-damper-spring), filters, safety envelope.

See ``docs/control.md``. Every step function is pure (state and input in, state and command out),
so the same controller runs in the simulator, on a robot, and over a recorded log.
"""

from __future__ import annotations

from ftcomp.control.controller import AdmittanceController, ControlFrame, ControllerState
from ftcomp.control.filters import LowPassFilter
from ftcomp.control.laws import (
    AdmittanceLaw,
    CombinedLaw,
    LawState,
    MassDamperSpringLaw,
    PositionLaw,
    VelocityLaw,
    selection_matrix,
)
from ftcomp.control.safety import (
    SafetyLimits,
    StopReason,
    UniformLimits,
    WatchdogState,
    check_range,
    check_sample,
    check_travel,
    check_wrench,
    limit_twist,
)

__all__ = [
    "AdmittanceController",
    "AdmittanceLaw",
    "CombinedLaw",
    "ControlFrame",
    "ControllerState",
    "LawState",
    "LowPassFilter",
    "MassDamperSpringLaw",
    "PositionLaw",
    "SafetyLimits",
    "StopReason",
    "UniformLimits",
    "VelocityLaw",
    "WatchdogState",
    "check_range",
    "check_sample",
    "check_travel",
    "check_wrench",
    "limit_twist",
    "selection_matrix",
]
