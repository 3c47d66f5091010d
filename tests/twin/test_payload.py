"""``ftcomp payload set`` on the UR twin: the controller holds the calibration's payload, and
``actual_TCP_force`` with it reads only the contact.

The twin has a TCP offset (the sensor 25 mm out along the flange's z, turned 0.5 rad about it),
so the centre of gravity goes from the sensor frame to the flange through it. The calibration is
the twin's truth (``--truth``), so what is checked is the payload's path to the controller, not
an identification.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np
import pytest

rtde_control = pytest.importorskip("rtde_control")
rtde_receive = pytest.importorskip("rtde_receive")
pytest.importorskip("mujoco")

from ftcomp.cli import main  # noqa: E402
from ftcomp.constants import STANDARD_GRAVITY_MPS2  # noqa: E402
from ftcomp.frames import matrix_from_rotvec  # noqa: E402
from standins.twin_process import calibration_from_truth, running_twin  # noqa: E402

OFFSET_M = np.array([0.0, 0.0, 0.025])
ROTVEC = np.array([0.0, 0.0, 0.5])


#: Untimed: the controller's answers and a stream's values (no stop, rate or lateness).
pytestmark = [pytest.mark.live, pytest.mark.untimed]


def _at_rest(receive: object, timeout_s: float = 5.0) -> None:
    """Wait until the arm is still: every joint slower than 1 mrad/s in 25 packages running."""
    still, deadline = 0, time.monotonic() + timeout_s
    while still < 25:
        assert time.monotonic() < deadline, "the arm did not come to rest"
        speed = np.abs(receive.getActualQd()).max()  # type: ignore[attr-defined]
        still = still + 1 if speed < 1e-3 else 0
        time.sleep(0.002)


def _mean_force(receive: object, seconds: float = 0.3) -> np.ndarray:
    """The mean of ``actual_TCP_force`` over ``seconds`` (one value per 2 ms package)."""
    values, t0 = [], time.monotonic()
    while time.monotonic() - t0 < seconds:
        values.append(receive.getActualTCPForce())  # type: ignore[attr-defined]
        time.sleep(0.002)
    return np.mean(values, axis=0)


def test_payload_set_writes_the_calibration_and_actual_TCP_force_then_reads_no_contact(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    truth, cal = tmp_path / "truth.json", tmp_path / "cal.json"
    with running_twin(
        "test_payload",
        "--truth",
        str(truth),
        "--tcp-offset-mm=0,0,25",
        "--tcp-rotvec-rad=0,0,0.5",
        seconds=90.0,
    ) as twin:
        calibration_from_truth(truth, cal)
        assert main(["payload", "set", twin.robot_uri, "-c", str(cal)]) == 0
        said = capsys.readouterr().out
        assert "payload was 0.0000 kg" in said and "payload now" in said
        true = json.loads(truth.read_text())
        mass = true["tool_weight_N"] / STANDARD_GRAVITY_MPS2
        cog_flange = OFFSET_M + matrix_from_rotvec(ROTVEC) @ np.array(true["center_of_gravity_m"])
        receive = rtde_receive.RTDEReceiveInterface(twin.robot_host)
        control = rtde_control.RTDEControlInterface(twin.robot_host)
        try:
            assert receive.getPayload() == pytest.approx(mass, abs=1e-6)
            assert np.allclose(receive.getPayloadCog(), cog_flange, atol=1e-6)
            assert control.zeroFtSensor()
            time.sleep(0.2)  # the zeroing's 0.1 s of readings
            q0 = np.array(receive.getActualQ())
            rng = np.random.default_rng(34)
            worst_N, worst_Nm = 0.0, 0.0
            for _ in range(9):  # the wrist turned every way: the payload's weight moves around
                dq = np.radians([*rng.uniform(-15, 15, 3), *rng.uniform(-70, 70, 3)])
                assert control.moveJ((q0 + dq).tolist(), 3.0, 6.0)
                _at_rest(receive)
                w = _mean_force(receive)
                worst_N = max(worst_N, float(np.max(np.abs(w[:3]))))
                worst_Nm = max(worst_Nm, float(np.max(np.abs(w[3:]))))
        finally:
            control.stopScript()
            control.disconnect()
            receive.disconnect()
    # The noise: the sensor's 0.13 N / 0.0032 N*m per reading, over the zeroing's 50 and this
    # mean's ~150 readings, 0.02 N / 0.0005 N*m. Alone on this host the worst of nine poses read
    # 0.022-0.043 N and 0.0006-0.0013 N*m; within a whole suite's run two clean clones read
    # 0.105 N and 0.0033 N*m (cause not found), so the bounds are 10 of those standard errors.
    # The tool's 3.15 N weight at a wrong mass or centre of gravity would leave up to 3 N.
    assert worst_N < 0.2, worst_N
    assert worst_Nm < 0.005, worst_Nm
    assert math.isfinite(worst_N)
