"""``ftcomp import-bag`` -> ``ftcomp calibrate`` on bags recorded from the simulated cell.

The bags (written with rosbags, see ``tests/ros2/simbag.py``) hold a 500 Hz wrench topic with
the simulated sensor's noise, a tf chain base -> flange -> ft_sensor whose mount is not the
identity, joint states, and the paper's nine orientations held still with moves between.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np
import pytest

from ftcomp.calibration.identify import deviations_in_standard_errors
from ftcomp.cli import main
from ftcomp.io.calibration_json import load_calibration

sys.path.insert(0, str(Path(__file__).parents[1] / "ros2"))
from simbag import WRENCH_TOPIC, recording, write_bag

FRAMES = ["--base-frame", "base", "--sensor-frame", "ft_sensor"]


@pytest.fixture(scope="module")
def bags(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("bags")
    rec = recording()
    (folder / "robot.urdf").write_text(rec.urdf)
    return {
        "mcap": write_bag(rec, folder / "rosbag2_mcap", storage="mcap"),
        "sqlite3": write_bag(rec, folder / "rosbag2_sqlite3", storage="sqlite3"),
        "ros1": write_bag(rec, folder / "recording.bag", storage="ros1"),
        "urdf": folder / "robot.urdf",
    }


def _import_and_calibrate(
    bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], *extra: str
) -> tuple[str, Path]:
    samples, cal = tmp_path / "samples.csv", tmp_path / "cal.json"
    args = ["import-bag", str(bag), "--wrench-topic", WRENCH_TOPIC, *FRAMES, *extra]
    assert main([*args, "-o", str(samples)]) == 0
    printed = capsys.readouterr().out
    assert main(["calibrate", str(samples), "-o", str(cal)]) == 0
    return printed, cal


def _assert_truth_within_3_standard_errors(cal: Path) -> None:
    deviations = deviations_in_standard_errors(load_calibration(cal), recording().truth)
    worst = max(deviations, key=deviations.__getitem__)
    assert deviations[worst] <= 3.0, f"{worst}: {deviations[worst]:.2f} standard errors"


@pytest.mark.parametrize("storage", ["mcap", "sqlite3", "ros1"])
def test_import_bag_then_calibrate_recovers_the_truth_from_tf(
    storage: str, bags: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    printed, cal = _import_and_calibrate(bags[storage], tmp_path, capsys)
    assert "tf base -> flange -> ft_sensor" in printed
    assert "in 9 still segments" in printed
    _assert_truth_within_3_standard_errors(cal)


def test_import_bag_then_calibrate_recovers_the_truth_from_joint_states_and_urdf(
    bags: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    route = ["--urdf", str(bags["urdf"]), "--joint-states", "/joint_states"]
    printed, cal = _import_and_calibrate(bags["mcap"], tmp_path, capsys, *route)
    assert "joints j1, j2, j3, j4, j5, j6" in printed and "in 9 still segments" in printed
    _assert_truth_within_3_standard_errors(cal)


def test_the_sample_csv_keeps_the_bag_stamps_as_integer_nanoseconds(
    bags: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    samples = tmp_path / "s.csv"
    args = ["import-bag", str(bags["mcap"]), "--wrench-topic", WRENCH_TOPIC, *FRAMES]
    assert main([*args, "-o", str(samples)]) == 0
    rows = list(csv.DictReader(samples.open()))
    stamps = np.array([int(r["t_ns"]) for r in rows])
    rec = recording()
    assert np.isin(stamps, rec.wrench_t_ns).all()
    t = np.array([float(r["t"]) for r in rows])
    np.testing.assert_allclose(t, (stamps - rec.wrench_t_ns[0]) * 1e-9, atol=1e-9)
    assert rows[0]["pose"] == "1" and rows[-1]["pose"] == "9"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (["--wrench-topic", "/ft/wrenchh"], "no topic '/ft/wrenchh' in the bag"),
        (["--wrench-topic", "/tf"], "topic '/tf' has type tf2_msgs/msg/TFMessage"),
        (["--sensor-frame", "tool0"], "frame 'tool0' is not in the tf tree; frames: base, camera"),
        (["--joint-states", "/joint_states"], "--urdf and --joint-states go together"),
    ],
)
def test_a_bad_request_is_one_line_naming_it(
    change: list[str],
    message: str,
    bags: dict[str, Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = ["import-bag", str(bags["mcap"]), "--wrench-topic", WRENCH_TOPIC, *FRAMES]
    for i in range(0, len(change), 2):
        if change[i] in args:
            args[args.index(change[i]) + 1] = change[i + 1]
        else:
            args += change[i : i + 2]
    out = tmp_path / "s.csv"
    assert main([*args, "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1
    assert message in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("bag_kind", "message"),
    [
        ("no_still", "no still period on /ft_sensor/wrench"),
        ("frame", "readings on /ft_sensor/wrench are in frame 'ft_link', not the sensor frame"),
        ("no_tf", "no /tf or /tf_static topic"),
        ("not_a_bag", "not a readable ROS bag"),
    ],
)
def test_a_bad_bag_is_one_line_naming_the_problem(
    bag_kind: str, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rec = recording()
    bag = tmp_path / "bag"
    if bag_kind == "no_still":
        write_bag(rec, bag, still=False, until_s=5.0)
    elif bag_kind == "frame":
        topics = (WRENCH_TOPIC, "/tf", "/tf_static")
        write_bag(rec, bag, wrench_frame="ft_link", topics=topics, until_s=1.0)
    elif bag_kind == "no_tf":
        write_bag(rec, bag, topics=(WRENCH_TOPIC, "/joint_states"), until_s=1.0)
    else:
        bag = tmp_path / "bag.mcap"
        bag.write_bytes(b"not an mcap file at all")
    out = tmp_path / "s.csv"
    args = ["import-bag", str(bag), "--wrench-topic", WRENCH_TOPIC, *FRAMES, "-o", str(out)]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1
    assert message in err
    assert not out.exists()


def test_a_bag_with_a_service_event_channel_and_an_unknown_type_imports_and_names_them(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = write_bag(recording(), tmp_path / "bag", foreign=True)
    samples = tmp_path / "s.csv"
    args = ["import-bag", str(bag), "--wrench-topic", WRENCH_TOPIC, *FRAMES]
    assert main([*args, "-o", str(samples)]) == 0
    captured = capsys.readouterr()
    assert "in 9 still segments" in captured.out
    assert "example_interfaces/srv/AddTwoInts_Event" in captured.err
    assert "acme_msgs/msg/GripperState" in captured.err
    assert "acme_msgs/msg/Finger" in captured.err  # why: the type it names is unknown


def test_a_needed_definition_that_cannot_be_parsed_is_shown_with_its_whole_reason(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = "std_msgs/Header header\n---\ngeometry_msgs/Wrench wrench\n"
    bag = write_bag(recording(), tmp_path / "bag", until_s=0.5, wrench_msgdef=bad)
    out = tmp_path / "s.csv"
    args = ["import-bag", str(bag), "--wrench-topic", WRENCH_TOPIC, *FRAMES, "-o", str(out)]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1
    assert "definition of geometry_msgs/msg/WrenchStamped on topic '/ft_sensor/wrench'" in err
    assert "---" in err  # the part of the definition rosbags stopped at, not an empty reason
    assert not out.exists()


@pytest.mark.parametrize("header_frame", ["base_link", ""])
def test_wrench_frame_states_the_frame_a_driver_did_not_put_in_the_header(
    header_frame: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = write_bag(recording(), tmp_path / "bag", wrench_frame=header_frame)
    samples = tmp_path / "s.csv"
    args = ["import-bag", str(bag), "--wrench-topic", WRENCH_TOPIC, *FRAMES, "-o", str(samples)]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "--wrench-frame" in err and not samples.exists()
    assert main([*args, "--wrench-frame", "ft_sensor"]) == 0
    captured = capsys.readouterr()
    assert "in 9 still segments" in captured.out
    assert f"header.frame_id {header_frame!r}" in captured.err
    assert "taken as in 'ft_sensor'" in captured.err
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(samples), "-o", str(cal)]) == 0
    _assert_truth_within_3_standard_errors(cal)


@pytest.mark.parametrize("route", ["tf", "urdf"])
def test_import_bag_reports_its_progress_up_to_every_message_it_reads(
    route: str, bags: dict[str, Path]
) -> None:
    from ftcomp.ros2.importer import import_bag

    calls: list[tuple[int, int]] = []
    urdf = {"urdf": bags["urdf"], "joint_states_topic": "/joint_states"} if route == "urdf" else {}
    import_bag(
        bags["mcap"], wrench_topic=WRENCH_TOPIC, base_frame="base", sensor_frame="ft_sensor",
        progress=lambda done, total: calls.append((done, total)), **urdf,  # type: ignore[arg-type]
    )  # fmt: skip
    done = [d for d, _ in calls]
    assert len(calls) > 2 and done == sorted(done)
    assert len({t for _, t in calls}) == 1 and calls[-1][0] == calls[-1][1]  # all of it read
