"""Admittance control: laws (paper Eq. 24-27 and mass-damper-spring), filters, safety envelope.

See ``docs/control.md``. Every step function is pure (state and input in, state and command out),
so the same controller runs in the simulator, on a robot, and over a recorded log.

Names are imported when first used (PEP 562), so a module of the package imports only what it
needs (``--help`` and the device registry load no numpy or scipy through here).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ftcomp.lazy import lazy_exports

if TYPE_CHECKING:
    from ftcomp.control.controller import (
        AdmittanceController,
        ControlFrame,
        ControllerState,
    )
    from ftcomp.control.filters import (
        LowPassFilter,
    )
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

_WHERE = {
    "AdmittanceController": "ftcomp.control.controller",
    "AdmittanceLaw": "ftcomp.control.laws",
    "CombinedLaw": "ftcomp.control.laws",
    "ControlFrame": "ftcomp.control.controller",
    "ControllerState": "ftcomp.control.controller",
    "LawState": "ftcomp.control.laws",
    "LowPassFilter": "ftcomp.control.filters",
    "MassDamperSpringLaw": "ftcomp.control.laws",
    "PositionLaw": "ftcomp.control.laws",
    "SafetyLimits": "ftcomp.control.safety",
    "StopReason": "ftcomp.control.safety",
    "UniformLimits": "ftcomp.control.safety",
    "VelocityLaw": "ftcomp.control.laws",
    "WatchdogState": "ftcomp.control.safety",
    "check_range": "ftcomp.control.safety",
    "check_sample": "ftcomp.control.safety",
    "check_travel": "ftcomp.control.safety",
    "check_wrench": "ftcomp.control.safety",
    "limit_twist": "ftcomp.control.safety",
    "selection_matrix": "ftcomp.control.laws",
}


__getattr__ = lazy_exports(__name__, _WHERE)
