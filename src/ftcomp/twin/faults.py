"""The twin's faults on demand (``ftcomp twin --fault NAME --fault-at-s T``): their names and
what each does. Apart from the cell, so that the command line lists them without loading
MuJoCo. What ``ftcomp run`` does on each is in docs/twin.md."""

from __future__ import annotations

from typing import Final

__all__ = ["FAULTS"]

#: Faults on demand: name -> what the twin does from the fault's time on.
FAULTS: Final = {
    "sensor-frozen": "the Net F/T repeats its last reading (status healthy)",
    "sensor-fault": "the Net F/T reports a serious status and goes on sending",
    "rdt-loss": "the next 200 RDT records are lost on the way",
    "rtde-stop": "the controller stops sending RTDE data (connections stay open)",
    "network-loss": "the cell's network goes silent: no RTDE data, no RDT records (a cable "
    "pulled between the host and the cell's switch; connections stay open)",
    "protective-stop": "a protective stop: the arm stops, the program ends",
    "script-stop": "the program is stopped from the pendant",
    "latency": "every RTDE package is sent 8-14 ms late (8 ms, up to 4 ms of jitter, in the "
    "cell's 2 ms cycles)",
}
