"""The hardware seam: protocols a robot and a sensor implement, and the capabilities a backend
may add to them (:mod:`.protocols`), backends by URI (:mod:`.registry`), pacing on the host's
clock (:mod:`.pacing`) and fault injection (:mod:`.faults`).

Names are imported when first used (PEP 562), so a module of the package imports only what it
needs (``--help`` and the device registry load no numpy or scipy through here).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ftcomp.lazy import lazy_exports

if TYPE_CHECKING:
    from ftcomp.hardware.protocols import (
        ChecksReachability,
        CountsLostPackets,
        Mount,
        PoseSample,
        ReportsLateness,
        ReportsStreamHealth,
        Robot,
        StreamHealth,
        TakesControl,
        WrenchSample,
        WrenchSensor,
    )

__all__ = [
    "ChecksReachability",
    "CountsLostPackets",
    "Mount",
    "PoseSample",
    "ReportsLateness",
    "ReportsStreamHealth",
    "Robot",
    "StreamHealth",
    "TakesControl",
    "WrenchSample",
    "WrenchSensor",
]

_WHERE = {
    "ChecksReachability": "ftcomp.hardware.protocols",
    "CountsLostPackets": "ftcomp.hardware.protocols",
    "Mount": "ftcomp.hardware.protocols",
    "PoseSample": "ftcomp.hardware.protocols",
    "ReportsLateness": "ftcomp.hardware.protocols",
    "ReportsStreamHealth": "ftcomp.hardware.protocols",
    "Robot": "ftcomp.hardware.protocols",
    "StreamHealth": "ftcomp.hardware.protocols",
    "TakesControl": "ftcomp.hardware.protocols",
    "WrenchSample": "ftcomp.hardware.protocols",
    "WrenchSensor": "ftcomp.hardware.protocols",
}


__getattr__ = lazy_exports(__name__, _WHERE)
