"""The hardware seam: protocols a robot and a sensor implement, and the capabilities a backend
may add to them (:mod:`.protocols`), backends by URI (:mod:`.registry`), pacing on the host's
clock (:mod:`.pacing`) and fault injection (:mod:`.faults`)."""

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
