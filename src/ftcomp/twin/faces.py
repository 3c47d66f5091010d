"""What a device's face in the twin implements: the seam between the cell's loop and a protocol.

The twin (:mod:`ftcomp.twin.serve`) is one loop over the simulated cell plus two faces: a robot
face and a sensor face, each the same device's protocol served on its own loopback address, as
the real device serves it, so the device's real client library drives it unchanged. A face is
declared once in the device registry (:class:`ftcomp.hardware.devices.TwinFace`: its name, its
class as ``"module:Class"``, its faults), and the twin pairs any robot face with any sensor
face.

Each period of the robot face (:attr:`RobotFace.period_s`) the loop:

1. fires a fault that is due (:meth:`RobotFace.inject` / :meth:`SensorFace.inject`, on the
   face that declares it; a fault both declare, such as ``network-loss``, on both);
2. lets the robot face command the cell's arm for the period (:meth:`RobotFace.cycle`: a
   twist or joint targets, given the contact force its safety system sees);
3. steps the cell's physics through the period, reading the wrist sensor's new samples (at the
   sensor face's rate) after each step;
4. hands the samples to the sensor face (:meth:`SensorFace.push`) and the newest wrench, with
   the cell's state, to the robot face (:meth:`RobotFace.publish`).

A face binds its sockets when it is made (a busy port is a
:class:`~ftcomp.errors.ParameterError`, nothing left bound), serves its clients on threads or a
process of its own, and stops in :meth:`close`. What a face gets for free: the cell (the arm,
the tool, the load and surfaces, the sensor's noise and drift), the loop's timing, the contact
log and the live view, the fault clock, the ready line and the conformance suite.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from ftcomp.hardware.protocols import WrenchSample
from ftcomp.sim.cell import SimCell

__all__ = ["RobotFace", "RobotFaceFactory", "SensorFace", "SensorFaceFactory"]


@runtime_checkable
class RobotFace(Protocol):
    """A robot's face: its controller's protocol over the cell's arm."""

    #: The controller's period [s]: the twin's loop runs at it (a UR e-Series: 2 ms).
    period_s: float

    def uri(self) -> str:
        """The URI that opens it live (``ur://127.0.0.2``)."""
        ...

    def commanded(self) -> bool:
        """Whether a client has commanded the arm to move (a joint or Cartesian move, a speed
        or a servo target): the fault clock starts then, in ``run`` with its loop's first
        cycle."""
        ...

    def cycle(self, contact_force_N: float) -> None:
        """One controller period: command the cell's arm for it, a twist of its sensor frame
        (:meth:`~ftcomp.sim.cell.SimCell.command_twist`, as a UR's Cartesian moves) or joint
        servo targets (:meth:`~ftcomp.sim.cell.SimCell.command_joints`, as a Franka's motion
        generators); ``contact_force_N`` is the contact force's magnitude, what a safety
        system sees [N]."""
        ...

    def publish(self, wrench_sensor: NDArray[np.float64]) -> None:
        """The period's state to the clients: the cell's state after its physics, and the
        wrist sensor's newest wrench (sensor frame [N, N*m]) for a robot that reports one."""
        ...

    def inject(self, fault: str) -> None:
        """A fault it declared, from now on."""
        ...

    def safety(self) -> str:
        """``normal``, or the safety stop it is in (``protective_stop``), for the contact log."""
        ...

    def served(self) -> str:
        """What it served, for the twin's last line (``60251 RTDE packages``)."""
        ...

    def close(self) -> None:
        """Stop serving: the program stopped, every socket closed."""
        ...


@runtime_checkable
class SensorFace(Protocol):
    """A sensor's face: its protocol, streaming the cell's wrist sensor."""

    def uri(self) -> str:
        """The URI that opens it live (``netft://127.0.0.3``)."""
        ...

    def push(self, samples: Sequence[WrenchSample]) -> None:
        """The wrist sensor's new samples of this period (sensor frame [N, N*m]), in order."""
        ...

    def inject(self, fault: str) -> None:
        """A fault it declared, from now on."""
        ...

    def served(self) -> str:
        """What it served, for the twin's last line (``50213 RDT records``); final after
        :meth:`close`."""
        ...

    def close(self) -> None:
        """Stop serving, every socket closed."""
        ...


class RobotFaceFactory(Protocol):
    """What a robot face's class is called with."""

    def __call__(self, host: str, cell: SimCell, *, realtime: bool, seed: int) -> RobotFace:
        """Bind ``host``'s ports and serve ``cell``'s arm; ``realtime`` asks for SCHED_FIFO
        for the face's threads where it has any, ``seed`` seeds its randomness."""
        ...


class SensorFaceFactory(Protocol):
    """What a sensor face's class is called with."""

    def __call__(self, host: str, *, rate_hz: float, realtime: bool) -> SensorFace:
        """Bind ``host``'s ports and stream at ``rate_hz`` [Hz]; ``realtime`` asks for
        SCHED_FIFO for its sender where it has one."""
        ...
