"""``ftcomp ros2 node`` against rclpy nodes in other processes, on loopback (``ros2_graph``).

A peer publishes a sensor's raw WrenchStamped and the arm's JointState; the node (in this
process, or ``ftcomp ros2 node`` in its own) compensates; an rclpy subscriber peer collects
``/ftcomp/wrench_compensated``, an rclpy client peer calls ``/ftcomp/rebias``.
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rclpy")
from rclpy.qos import QoSProfile

sys.path.insert(0, str(Path(__file__).parent))

from rclpy_peer import (
    EPOCH_NS,
    LOAD_COG_M,
    MODEL,
    PERIOD_NS,
    R_BASE_SENSOR,
    SHIFT,
    URDF,
    contact,
)
from ros2_graph import peer, ros2_graph_fixture, stop  # noqa: F401  (the fixture ros2_graph)

from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.errors import InputFileError, ParameterError
from ftcomp.io.calibration_json import FORMAT, load_calibration, model_to_dict
from ftcomp.ros2.node import CompensationNode
from ftcomp.ros2.rclpy_runtime import (
    DESCRIPTION_QOS,
    DiagnosticArray,
    InertiaStamped,
    Ros2Runtime,
    String,
    WrenchStamped,
    qos_profile,
    stamp_ns,
    wrench_of,
)

pytestmark = pytest.mark.live


@pytest.fixture
def files(tmp_path: Path) -> dict[str, str]:
    cal, urdf = tmp_path / "cal.json", tmp_path / "two_joint.urdf"
    cal.write_text(json.dumps({"format": FORMAT, "method": "joint", **model_to_dict(MODEL)}))
    urdf.write_text(URDF, encoding="utf-8")
    return {
        "calibration_file": str(cal),
        "urdf": str(urdf),
        "base_frame": "base",
        "sensor_frame": "ft_sensor",
        "wrench_topic": "/ft_raw",
        "timeout_s": 120.0,
    }


def test_the_node_publishes_the_compensated_wrench_with_the_raw_stamps(
    ros2_graph: int, tmp_path: Path, files: dict[str, str]
) -> None:
    out, out_base = tmp_path / "sensor.json", tmp_path / "base.json"
    subscribers = [
        peer("subscribe", "/ftcomp/wrench_compensated", 200, 150, out),
        peer("subscribe", "/ftcomp/wrench_contact_base", 200, 150, out_base),
    ]
    publisher = peer("publish", 150)
    try:
        with CompensationNode(files) as node, Ros2Runtime("observer") as observer:
            deadline = time.monotonic() + 120
            while "ftcomp" not in observer.node.get_node_names() and time.monotonic() < deadline:
                time.sleep(0.05)
            assert "ftcomp" in observer.node.get_node_names()  # rclpy's graph lists it
            for proc in subscribers:
                proc.wait(timeout=160)
            assert node.config is not None and node.config.rebias_s == 2.0
    finally:
        stop(publisher, *subscribers)
    compensator = GravityCompensator(MODEL)
    R = R_BASE_SENSOR.as_matrix()
    raw_of = MODEL.predict(R)
    for path, frame, rotate in ((out, "ft_sensor", False), (out_base, "base", True)):
        received = json.loads(path.read_text())
        assert len(received) >= 200
        for stamp, frame_id, *wrench in received:
            k, rest = divmod(stamp - EPOCH_NS, PERIOD_NS)
            assert rest == 0 and frame_id == frame  # the raw reading's own stamp
            expected = compensator.compensate(raw_of + contact(k), R)
            if rotate:
                expected = np.concatenate([R @ expected[:3], R @ expected[3:]])
            # Exact algebra on the same doubles as GravityCompensator's: its rounding only.
            np.testing.assert_allclose(wrench, expected, atol=1e-9)


def test_readings_queued_while_the_node_was_busy_all_come_out_in_order(
    ros2_graph: int, files: dict[str, str]
) -> None:
    """The node's executor held for 0.3 s (about 60 readings at 200 Hz queue up, taken in
    one wake-up afterwards): every reading from the first received to the last comes out once,
    in order, compensated, and none is stale (each took the joint states that arrived)."""
    stamps: list[int] = []
    said: list[str] = []
    held, release = threading.Event(), threading.Event()

    def on_wrench(msg: WrenchStamped) -> None:
        stamps.append(stamp_ns(msg.header.stamp))

    def on_diag(msg: DiagnosticArray) -> None:
        said.extend(f"{status.level[0]} {status.message}" for status in msg.status)

    publisher = peer("publish", 150)
    try:
        with (
            CompensationNode({**files, "wrench_qos": "reliable"}) as node,
            Ros2Runtime("watcher") as watcher,
        ):
            qos = qos_profile("reliable", 1000)
            watcher.node.create_subscription(DiagnosticArray, "/diagnostics", on_diag, qos)
            watcher.node.create_subscription(
                WrenchStamped, "/ftcomp/wrench_compensated", on_wrench, qos
            )
            deadline = time.monotonic() + 120  # discovery: seconds on a loaded host
            while len(stamps) < 20:
                assert time.monotonic() < deadline, "the compensated stream never came"
                time.sleep(0.02)

            def hold() -> None:  # on the node's one executor thread: nothing else runs
                timer.cancel()
                held.set()
                release.wait(10)

            timer = node.runtime.node.create_timer(0.001, hold)
            assert held.wait(10)
            time.sleep(0.3)
            before = len(stamps)
            release.set()
            while len(stamps) < before + 200:
                assert time.monotonic() < deadline, f"{len(stamps) - before} after the hold"
                time.sleep(0.02)
    finally:
        stop(publisher)
    k = (np.array(stamps) - EPOCH_NS) // PERIOD_NS
    assert (np.diff(k) == 1).all(), k  # none lost, none twice, in order
    assert not any(line.startswith("2 ") for line in said), said


def test_rebias_through_the_trigger_service_takes_the_moved_bias(
    ros2_graph: int, tmp_path: Path, files: dict[str, str]
) -> None:
    out = tmp_path / "rebias.json"
    publisher = peer("publish", 150, "--still")
    try:
        with CompensationNode({**files, "rebias_s": 0.5}) as node:
            client = peer("rebias", out)
            client.wait(timeout=160)
            calibration = node.calibration
    finally:
        stop(publisher)
    success, message = json.loads(out.read_text())
    assert success, message
    assert message.startswith("re-biased from") and "[+0.300 -0.200 +0.500] N" in message
    assert calibration is not None
    # Still readings of the tool at rest with the bias moved: the new bias is the old plus
    # the shift, to the rounding of a mean of identical doubles.
    np.testing.assert_allclose(
        calibration.model.force_bias_N, MODEL.force_bias_N + SHIFT[:3], atol=1e-9
    )
    np.testing.assert_allclose(
        calibration.model.torque_bias_Nm, MODEL.torque_bias_Nm + SHIFT[3:], atol=1e-9
    )


def test_online_load_publishes_the_mass_of_a_grasped_load(
    ros2_graph: int, tmp_path: Path, files: dict[str, str]
) -> None:
    """The peer's tool at rest grasps 0.5 kg once the subscribers are matched: an rclpy
    subscriber sees ``~/load_state`` go empty -> estimating -> holding and ``~/load`` carry the
    mass and centre of gravity, and the compensated wrench falls back to zero."""
    states: list[str] = []
    loads: list[tuple[int, float, list[float]]] = []  # stamp, mass, centre, after holding
    wrenches: dict[int, list[float]] = {}  # by stamp
    done = threading.Event()

    def check() -> None:  # 0.2 s of readings held (past the 0.1 s ramp), both topics
        if len(loads) >= 3 and loads[2][0] in wrenches:
            done.set()

    def on_state(msg: String) -> None:
        states.append(msg.data)

    def on_load(msg: InertiaStamped) -> None:
        if states and states[-1] == "holding":
            com = msg.inertia.com
            loads.append((stamp_ns(msg.header.stamp), msg.inertia.m, [com.x, com.y, com.z]))
            check()

    def on_wrench(msg: WrenchStamped) -> None:  # the topics arrive each at its own pace
        wrenches[stamp_ns(msg.header.stamp)] = wrench_of(msg).tolist()
        check()

    grasp = tmp_path / "grasp"
    publisher = peer("publish", 150, "--load=0.5", f"--grasp-when={grasp}")
    try:
        with (
            CompensationNode({**files, "online_load": True, "wrench_qos": "reliable"}) as node,
            Ros2Runtime("watcher") as watcher,
        ):
            assert node.config is not None and node.config.online_load
            qos = qos_profile("reliable", 1000)
            # Latched like the publisher's, but every change kept: a fast node publishes
            # `empty` and `estimating` back to back when its first readings are released.
            states_qos = QoSProfile(
                depth=10,
                reliability=DESCRIPTION_QOS.reliability,
                durability=DESCRIPTION_QOS.durability,
            )
            subscriptions = [
                watcher.node.create_subscription(
                    String, "/ftcomp/load_state", on_state, states_qos
                ),
                watcher.node.create_subscription(InertiaStamped, "/ftcomp/load", on_load, qos),
                watcher.node.create_subscription(
                    WrenchStamped, "/ftcomp/wrench_compensated", on_wrench, qos
                ),
            ]
            deadline = time.monotonic() + 120  # discovery: seconds on a loaded host
            while any(s.get_publisher_count() == 0 for s in subscriptions):
                assert time.monotonic() < deadline, "the node's topics were never matched"
                time.sleep(0.02)
            # Matched is not delivered: the latched "empty" reaches this subscriber a moment
            # later, and a state published before that replaces it (the writer keeps the last).
            while not states:
                assert time.monotonic() < deadline, "no load state was ever received"
                time.sleep(0.02)
            grasp.write_text("")  # the peer grasps from its next reading
            assert done.wait(120), (states, loads)
    finally:
        stop(publisher)
    assert states[:3] == ["empty", "estimating", "holding"], states
    stamp, mass_kg, com = loads[2]
    assert (stamp - EPOCH_NS) % PERIOD_NS == 0  # a raw reading's stamp
    # Noise-free readings: the estimate departs from the truth only by its weak prior (1 kg),
    # outweighed by each reading's information (g^2 / 0.125^2 ~ 6000 /kg^2) over the >= 157
    # readings convergence takes: < 1e-6 kg, here held to 1e-5.
    assert abs(mass_kg - 0.5) < 1e-5
    # The centre of gravity along gravity is unobservable at one orientation (the estimate
    # keeps it at 0): the part across gravity is the load's, to the same relative error.
    d = R_BASE_SENSOR.as_matrix().T @ GravityCompensator(MODEL).gravity_dir_base
    across = LOAD_COG_M - (LOAD_COG_M @ d) * d
    np.testing.assert_allclose(com, across, atol=1e-6)
    # Held and ramped in: the load is compensated too (its 4.9 N times that relative error).
    np.testing.assert_allclose(wrenches[stamp], np.zeros(6), atol=1e-4)


def _watch(seconds: float, until: str, published: int) -> tuple[list[str], list[list[float]]]:
    """ftcomp's diagnostics and compensated wrenches, until a status says ``until`` and
    ``published`` wrenches came (or ``seconds`` passed)."""
    said: list[str] = []
    wrenches: list[list[float]] = []
    done = threading.Event()

    def check() -> None:
        if any(until in line for line in said) and len(wrenches) >= published:
            done.set()

    def on_diag(msg: DiagnosticArray) -> None:
        said.extend(f"{status.level[0]} {status.message}" for status in msg.status)
        check()

    def on_wrench(msg: WrenchStamped) -> None:
        wrenches.append(wrench_of(msg).tolist())
        check()

    with Ros2Runtime("watcher") as watcher:
        qos = qos_profile("reliable", 1000)
        watcher.node.create_subscription(DiagnosticArray, "/diagnostics", on_diag, qos)
        watcher.node.create_subscription(
            WrenchStamped, "/ftcomp/wrench_compensated", on_wrench, qos
        )
        done.wait(seconds)
        time.sleep(0.5)  # what the node published meanwhile arrives too
    return said, wrenches


@pytest.mark.parametrize(
    ("flags", "says", "published"),
    [
        (("tool0",), "a wrench in frame 'tool0', the calibration's is 'ft_sensor'", 0),
        (("--nan",), "a non-finite wrench on /ft_raw", 20),
        (("--joints-s=3",), "joint states on /joint_states", 0),
    ],
)
def test_bad_readings_publish_nothing_and_say_why_on_diagnostics(
    ros2_graph: int, files: dict[str, str], flags: tuple[str, ...], says: str, published: int
) -> None:
    publisher = peer("publish", 150, *flags)
    try:
        with CompensationNode(files):
            said, wrenches = _watch(120, says, published)
    finally:
        stop(publisher)
    # Level 2: ERROR, and the reason in one line.
    assert any(x.startswith(f"2 {says}") and x.endswith(": nothing published") for x in said), said
    if published:  # every other reading is NaN: the finite ones go on
        assert len(wrenches) >= published and np.isfinite(wrenches).all()
    elif flags == ("tool0",):
        assert wrenches == []
    else:  # the joint states stopped: the readings after stale_s are not published
        assert any("s older than the reading (stale after 0.1 s)" in line for line in said)


def test_a_urdf_without_the_frames_stops_the_node_at_start(
    ros2_graph: int, files: dict[str, str]
) -> None:
    with pytest.raises(InputFileError, match=r"link 'tool0' is not in the URDF"):
        CompensationNode({**files, "sensor_frame": "tool0"}).__enter__()


def test_a_calibration_whose_bias_follows_temperature_stops_the_node_at_start(
    ros2_graph: int, files: dict[str, str]
) -> None:
    """A wrench topic carries no temperature: the node refuses the model, never applies its
    bias at some temperature of its own."""
    path = Path(files["calibration_file"])
    data = json.loads(path.read_text())
    data["bias_drift"] = {
        "model": "temperature",
        "T_ref_C": 25.0,
        "T_range_C": [22.0, 28.0],
        "slopes_per_C": [0.01, 0.0, 0.02, 0.0, 0.0, 0.001],
        "std_errors": [0.001] * 6,
    }
    path.write_text(json.dumps(data))
    assert load_calibration(path).bias_drift is not None  # a valid file
    with pytest.raises(ParameterError, match="bias follows the sensor's temperature"):
        CompensationNode(files).__enter__()


def test_a_ros_parameter_of_the_wrong_type_names_the_parameter(
    ros2_graph: int, files: dict[str, str]
) -> None:
    node = CompensationNode(files, arguments=["--ros-args", "-p", "rebias_s:=fast"])
    with pytest.raises(ParameterError, match="ROS parameter rebias_s must be a number"):
        node.__enter__()


def test_the_command_takes_ros_parameters_and_says_bad_input_in_one_line(
    ros2_graph: int, files: dict[str, str]
) -> None:
    """``ftcomp ros2 node`` in its own process: ``-p`` sets what the options did not; a URDF
    without the sensor frame is one line, exit 2."""
    main = "import sys; from ftcomp.cli import main; sys.exit(main(sys.argv[1:]))"
    cmd = [sys.executable, "-c", main, "ros2", "node", "--calibration"]
    cmd += [files["calibration_file"], "--base-frame", "base", "--urdf", files["urdf"]]
    cmd += ["--timeout-s", "120", "--seconds", "0.1", "--ros-args", "-p"]
    bad = subprocess.run([*cmd, "sensor_frame:=tool0"], capture_output=True, text=True, timeout=200)
    assert bad.returncode == 2
    assert bad.stderr.count("\n") == 1 and "link 'tool0' is not in the URDF" in bad.stderr
    publisher = peer("publish", 150)
    try:
        good = subprocess.run(
            [*cmd, "sensor_frame:=ft_sensor", "-p", "wrench_topic:=/ft_raw"],
            capture_output=True,
            text=True,
            timeout=200,
        )
    finally:
        stop(publisher)
    assert good.returncode == 0, good.stderr
    assert "node ftcomp: /ft_raw compensated with" in good.stdout
