"""Faults on demand behave as the device does, seen through the devices' own protocols."""

from __future__ import annotations

import socket
import struct
import time
from typing import Any

import pytest

rtde_control = pytest.importorskip("rtde_control")
rtde_receive = pytest.importorskip("rtde_receive")
pytest.importorskip("mujoco")

from standins.twin_process import running_twin  # noqa: E402

pytestmark = pytest.mark.live


def _wait_for(condition, timeout_s: float = 10.0) -> bool:  # type: ignore[no-untyped-def]
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.01)
    return False


def _command_a_hold(host: str) -> Any:
    """A client that commands the arm (a zero speedL): the twin's fault clock starts then."""
    control = rtde_control.RTDEControlInterface(host)
    control.speedL([0.0] * 6, 0.5, 0.0)
    return control


def test_a_protective_stop_on_demand_shows_in_the_safety_mode() -> None:
    with running_twin("twin_fault_pstop", "--fault", "protective-stop", "--fault-at-s", "0.2") as t:
        receive = rtde_receive.RTDEReceiveInterface(t.robot_host)
        control = _command_a_hold(t.robot_host)
        assert _wait_for(lambda: receive.getSafetyMode() == 3)
        assert receive.getSafetyStatusBits() & 0b100
        receive.disconnect()
        control.disconnect()


def test_a_sensor_fault_on_demand_sets_the_serious_status_bit_of_every_record() -> None:
    with running_twin("twin_fault_sensor", "--fault", "sensor-fault", "--fault-at-s", "0.2") as t:
        receive = rtde_receive.RTDEReceiveInterface(t.robot_host)
        control = _command_a_hold(t.robot_host)  # starts the fault's clock
        rdt = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        rdt.settimeout(2.0)
        rdt.sendto(struct.pack(">HHI", 0x1234, 2, 0), (t.sensor_host, 49152))

        def serious() -> bool:
            status = struct.unpack(">III6i", rdt.recvfrom(64)[0])[2]
            return bool(status & 0x80000000)

        assert _wait_for(serious)
        rdt.close()
        receive.disconnect()
        control.disconnect()
