"""The twin's ATI Net F/T face: HTTP ``netftapi2.xml`` and RDT over UDP 49152.

The protocol is served by :class:`~ftcomp.twin.netft.NetFtProcess`, a process of its own (a
device with its own clock); this face turns the wrist sensor's samples into the Net F/T's
counts (:data:`~ftcomp.twin.netft.COUNTS_PER_FORCE`, :data:`~ftcomp.twin.netft.COUNTS_PER_TORQUE`
per N and N*m, as its configuration page reports) and hands them over once a period.

Faults (declared in :mod:`ftcomp.hardware.devices`): ``sensor-frozen`` (the last reading
repeated, status healthy), ``sensor-fault`` (a serious status word, still sending),
``rdt-loss`` (200 records lost), ``network-loss`` (no records at all).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

import numpy as np

from ftcomp.hardware.protocols import WrenchSample
from ftcomp.twin.netft import COUNTS_PER_FORCE, COUNTS_PER_TORQUE, SERIOUS_STATUS, NetFtProcess

__all__ = ["NetFtFace"]

#: Net F/T counts per N (forces) and per N*m (torques), by axis.
_COUNTS_PER_UNIT: Final = np.repeat([COUNTS_PER_FORCE, COUNTS_PER_TORQUE], 3)


class NetFtFace:
    """An ATI Net F/T streaming the cell's wrist sensor (module docstring; a
    :class:`~ftcomp.twin.faces.SensorFace`).

    Args:
        host: the sensor's loopback address (UDP 49152, TCP 80).
        rate_hz: its RDT output rate [Hz]: records sent evenly at it.
        realtime: ask for SCHED_FIFO for its sender.

    Raises:
        ParameterError: a port cannot be bound (nothing is left bound).
    """

    def __init__(self, host: str, *, rate_hz: float, realtime: bool) -> None:
        self.host = host
        self.status = 0
        self.process = NetFtProcess(host, rate_hz, realtime)

    def uri(self) -> str:
        return f"netft://{self.host}"

    def push(self, samples: Sequence[WrenchSample]) -> None:
        if not samples:
            return
        # In counts, all samples in one numpy call (rint halves to even).
        wrenches = np.reshape([s.wrench_sensor for s in samples], (-1, 6))
        counts = np.rint(wrenches * _COUNTS_PER_UNIT).astype(np.int64).tolist()
        self.process.push(counts, self.status)

    def inject(self, fault: str) -> None:
        if fault == "sensor-fault":
            self.status = SERIOUS_STATUS
        else:  # sensor-frozen, rdt-loss, network-loss: in the sender's process
            self.process.inject(fault)

    def served(self) -> str:
        return f"{self.process.sent} RDT records"

    def close(self) -> None:
        if self.process.proc.is_alive():
            self.process.close()
