"""URRobot.check on a stand-in receive interface: new data is a timestamp that changes (a
controller clock running slow is not a stall), and one safety getter names both stops."""

from __future__ import annotations

import time

import pytest

from ftcomp.errors import HardwareError
from ftcomp.hardware.registry import parse_uri
from ftcomp.hardware.ur import URRobot


class _Receive:
    def __init__(self) -> None:
        self.timestamp_s = 100.0
        self.bits = 1  # normal mode

    def isConnected(self) -> bool:
        return True

    def getTimestamp(self) -> float:
        return self.timestamp_s

    def getSafetyStatusBits(self) -> int:
        return self.bits


def _robot(receive: _Receive) -> URRobot:
    robot = URRobot(
        parse_uri("ur://127.0.0.1"),
        frequency_hz=500.0,
        max_speed_m_s=0.1,
        max_accel_m_s2=0.5,
        command="speedl",
        timeout_s=0.02,
        connect_timeout_s=1.0,
    )
    robot.receive = receive
    robot.check()  # the first data seen
    return robot


def test_a_controller_clock_running_slow_is_not_a_stall_but_a_frozen_one_is() -> None:
    receive = _Receive()
    robot = _robot(receive)
    start = time.monotonic()
    while time.monotonic() - start < 0.1:  # five stale limits, the clock at a tenth of the rate
        receive.timestamp_s += 0.0002
        robot.check()
        time.sleep(0.002)
    deadline = time.monotonic() + 0.03  # then no new timestamp for longer than timeout_s
    while time.monotonic() < deadline:
        time.sleep(0.005)
    with pytest.raises(HardwareError, match="no new data from the controller"):
        robot.check()


@pytest.mark.parametrize(("bits", "kind"), [(1 << 2, "protective"), (1 << 7, "emergency")])
def test_check_names_the_stop_from_the_safety_status_bits(bits: int, kind: str) -> None:
    receive = _Receive()
    robot = _robot(receive)
    receive.bits = bits
    receive.timestamp_s += 0.002
    with pytest.raises(HardwareError, match=f"the arm is in a {kind} stop"):
        robot.check()
