"""``ftcomp record``: robot-driven on sim://, by hand against the UR and Net F/T stand-ins."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.calibration.identify import calibrate, max_deviations_in_standard_errors
from ftcomp.cli import main
from ftcomp.hardware.registry import open_robot
from ftcomp.io.calibration_json import load_calibration
from ftcomp.io.samples_csv import read_samples
from ftcomp.session.hand_guided import ManualRecorder

pytest.importorskip("pynetft")
pytest.importorskip("rtde_receive")

from standins.launch import loopback_address, running_all
from standins.scenario import HAND_GUIDED_DEG, TOOL_MODEL, Scenario, rotvecs

#: A standard error bound with a reason: the identified numbers are estimates from noisy
#: readings, and each test bounds the largest deviation of all ten (weight, bias, centre of
#: gravity): 4 standard errors hold for all ten with 99.94 % probability (3 hold for one number
#: with 99.7 %, for all ten only with 97 %: a test failing one run in 35 by chance, as the
#: stand-ins' random noise made it under load: 3.11 on the centre of gravity).
SE_BOUND = 4.0


pytestmark = pytest.mark.live


def test_record_on_sim_drives_the_paper_poses_and_calibrate_recovers_the_truth(
    tmp_path: Path,
) -> None:
    samples, cal = tmp_path / "s.csv", tmp_path / "cal.json"
    robot = "sim://?seed=5"
    code = main(
        [
            *("record", "--robot", robot, "--sensor", "sim://", "--poses", "paper"),
            *("--samples-per-pose", "200", "--move-s", "1", "-o", str(samples)),
        ]
    )
    assert code == 0
    assert main(["calibrate", str(samples), "-o", str(cal), "--json"]) == 0
    with open_robot(robot) as cell:
        truth = cell.true_gravity_model()  # type: ignore[attr-defined]  # the empty gripper
    deviations = max_deviations_in_standard_errors(load_calibration(cal), truth)
    assert max(deviations.values()) < SE_BOUND, deviations
    assert len(set(read_samples(samples).pose)) == 9  # type: ignore[arg-type]


def test_record_refuses_to_overwrite_and_a_pose_count_without_manual(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "s.csv"
    out.write_text("keep me")
    assert main(["record", "--robot", "sim://", "--sensor", "sim://", "-o", str(out)]) == 2
    assert "exists; pass --force" in capsys.readouterr().err
    assert out.read_text() == "keep me"
    args = ["record", "--robot", "sim://", "--sensor", "sim://", "--poses", "12"]
    assert main([*args, "-o", str(tmp_path / "t.csv")]) == 2
    assert "--poses N needs --manual" in capsys.readouterr().err


def _hand_guided(t0_file: Path, *, max_s: float) -> Scenario:
    """12 poses and, after the fifth, a repeat 2 deg from the third (to be ignored); the
    timeline starts when the command starts streaming from the fake Net F/T."""
    angles = list(HAND_GUIDED_DEG)
    near_third = (angles[2][0] + 2.0, angles[2][1], angles[2][2])
    angles.insert(5, near_third)
    return Scenario(
        t0=0.0,
        t0_file=str(t0_file),
        rotvecs_base_tcp=rotvecs(angles),
        first_hold_s=1.0,
        hold_s=0.6,
        move_s=0.25,
        mount_rpy_deg=[0.0, 0.0, 30.0],
        model=Scenario.model_fields(TOOL_MODEL),
        noise=[0.05, 0.002],
        seed=3,
        max_s=max_s,
    )


def _stand_ins(ur: str, ft: str, scenario: Scenario) -> Any:
    """The fake UR controller and the fake Net F/T, both serving ``scenario``."""
    return running_all(
        [
            ("fake_ur", (ur, scenario.to_json())),
            ("fake_netft", (ft, "49152", "8080", scenario.to_json())),
        ]
    )


def _manual_args(ur: str, ft: str, out: Path) -> list[str]:
    return [
        "record",
        "--manual",
        "--robot",
        # Fault limits with room for a loaded 2-core runner (a stand-in may be starved for a
        # few hundred ms); the faults themselves are tested with their own limits elsewhere.
        f"ur://{ur}?timeout_s=2",
        "--sensor",
        f"netft://{ft}?http_port=8080&timeout_s=1",
        "--mount",
        "0,0,0,0,0,30",
        "--poses",
        "12",
        "--still-s",
        "0.3",
        "-o",
        str(out),
    ]


def test_manual_recording_against_the_stand_ins_records_12_poses_and_recovers_the_tool(
    tmp_path: Path, request: pytest.FixtureRequest, capsys: pytest.CaptureFixture[str]
) -> None:
    ur, ft = loopback_address(request.node.name, 1), loopback_address(request.node.name, 2)
    scenario = _hand_guided(tmp_path / "t0", max_s=40.0)
    out, cal = tmp_path / "s.csv", tmp_path / "cal.json"
    with _stand_ins(ur, ft, scenario):
        code = main(_manual_args(ur, ft, out))
    captured = capsys.readouterr()
    printed = captured.out
    assert code == 0, printed + captured.err
    assert "ignored: " in printed and "from pose 3" in printed  # the repeat of pose 3
    samples = read_samples(out)
    assert samples.pose is not None and len(set(samples.pose)) == 12
    # Each recorded orientation is one the stand-in held (through the 30 deg mount).
    held = (
        Rotation.from_rotvec(scenario.rotvecs_base_tcp).as_matrix() @ scenario.mount().R_tcp_sensor
    )
    for R in samples.R_base_sensor[:: len(samples) // 12]:
        assert np.min(np.linalg.norm(held - R, axis=(1, 2))) < 1e-6
    assert main(["calibrate", str(out), "-o", str(cal), "--json"]) == 0
    deviations = max_deviations_in_standard_errors(calibrate(samples), TOOL_MODEL)
    assert max(deviations.values()) < SE_BOUND, deviations


def test_killing_the_ur_stand_in_mid_recording_keeps_the_poses_so_far(
    tmp_path: Path,
    request: pytest.FixtureRequest,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    ur, ft = loopback_address(request.node.name, 1), loopback_address(request.node.name, 2)
    scenario = _hand_guided(tmp_path / "t0", max_s=20.0)
    out = tmp_path / "s.csv"
    with _stand_ins(ur, ft, scenario) as (controller, netft):
        # Killed on an event, not after a time: the moment the third pose is recorded (in the
        # recorder's own cycle, so no later pose can be held long enough to be recorded).
        step = ManualRecorder.__call__

        def kill_after_the_third_pose(recorder: ManualRecorder, reading: Any) -> Any:
            result = step(recorder, reading)
            if len(recorder.records) == 3 and controller.poll() is None:
                controller.kill()
                controller.wait()
            return result

        monkeypatch.setattr(ManualRecorder, "__call__", kill_after_the_third_pose)
        code = main(_manual_args(ur, ft, out))
        # Ended by the lost controller while the Net F/T still streams (not by its end).
        assert netft.poll() is None
    err = capsys.readouterr().err
    assert code == 1
    assert "lost the connection" in err or "no new data" in err, err
    kept = read_samples(out)
    assert kept.pose is not None
    n = len(set(kept.pose))
    assert n == 3 and f": {n} poses" in err


def test_an_unreachable_controller_is_one_line_and_exit_2_at_once(
    tmp_path: Path, request: pytest.FixtureRequest, capsys: pytest.CaptureFixture[str]
) -> None:
    nobody = loopback_address(request.node.name)
    out = tmp_path / "s.csv"
    code = main(_manual_args(nobody, nobody, out))
    err = capsys.readouterr().err
    # Refused (the event the probe reports), not timed out: no second count needed.
    assert code == 2 and "connection refused on port 30004" in err, err
    assert err.count("\n") == 1
    assert not out.exists()
