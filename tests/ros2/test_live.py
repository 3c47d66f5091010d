"""Live ROS 2 topics over Cyclone DDS, on loopback only (experimental backend).

Three processes: a peer publishing a sensor's WrenchStamped and /tf_static, this test running the
``ros2://`` sensor and pose source through the control loop with compensation and republishing,
and a peer subscribing to the compensated topic. DDS is restricted to 127.0.0.1 (no multicast,
unicast discovery to 127.0.0.1 only) through CYCLONEDDS_URI, on a domain of its own.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.control.loop import ControlCycle, run_loop
from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.registry import open_robot, open_sensor
from ftcomp.ros2.dds_types import Header, TFMessage, Time, TransformStamped, wrench_message
from ftcomp.ros2.live import WrenchPublisher

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))
from dds_peer import EPOCH_NS, MODEL, PERIOD_NS, contact  # noqa: E402

LOOPBACK = (
    "<CycloneDDS><Domain id='any'><General><Interfaces>"
    "<NetworkInterface address='127.0.0.1'/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
    "<MaxAutoParticipantIndex>16</MaxAutoParticipantIndex>"
    "<Peers><Peer address='127.0.0.1'/></Peers></Discovery></Domain></CycloneDDS>"
)


@pytest.fixture
def domain(monkeypatch: pytest.MonkeyPatch) -> int:
    """A DDS domain of this test's own, restricted to loopback in this and child processes."""
    monkeypatch.setenv("CYCLONEDDS_URI", LOOPBACK)
    return 100 + os.getpid() % 100


def _opts(domain: int) -> str:
    """URI options: the test's domain; a generous first-message wait (the peer process needs a
    few seconds to start on a loaded machine)."""
    return f"&domain={domain}&timeout_s=20"


def _peer(*args: object) -> subprocess.Popen[bytes]:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE), *sys.path])}
    return subprocess.Popen(
        [sys.executable, str(HERE / "dds_peer.py"), *map(str, args)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )


def test_the_cdr_bytes_are_what_rosbags_serialises() -> None:
    store = get_typestore(Stores.ROS2_HUMBLE)
    msg = wrench_message(EPOCH_NS + 123, "ft_sensor", np.array([1.5, -2, 3, 0.1, -0.2, 0.3]))
    from_rosbags = store.deserialize_cdr(msg.serialize(), "geometry_msgs/msg/WrenchStamped")
    assert bytes(store.serialize_cdr(from_rosbags, "geometry_msgs/msg/WrenchStamped")) == (
        msg.serialize()
    )
    assert from_rosbags.header.stamp.nanosec == 123 and from_rosbags.wrench.torque.z == 0.3
    tf = TFMessage([TransformStamped(Header(Time(5, 6), "base"), "tool0")] * 2)
    decoded = store.deserialize_cdr(tf.serialize(), "tf2_msgs/msg/TFMessage")
    assert bytes(store.serialize_cdr(decoded, "tf2_msgs/msg/TFMessage")) == tf.serialize()
    assert WrenchPublisher("/ft", "s")._dds_topic == "rt/ft"  # ROS 2's topic prefix


def test_publisher_to_compensating_loop_to_subscriber_on_loopback(
    domain: int, tmp_path: Path
) -> None:
    out = tmp_path / "received.json"
    subscriber = _peer("subscribe", domain, 150, 20, out)
    publisher = _peer("publish", domain, 20)
    try:
        robot = open_robot(
            f"ros2:///?base_frame=base&tcp_frame=ft_sensor&domain={domain}&timeout_s=20"
        )
        sensor = open_sensor(f"ros2:///ft_raw?domain={domain}&frame=ft_sensor&timeout_s=20")
        with (
            robot,
            sensor,
            WrenchPublisher("/ft_compensated", "ft_sensor", domain_id=domain) as pub,
        ):
            cycle = ControlCycle(robot, sensor, compensator=GravityCompensator(MODEL))
            sink = pub.sink(sensor.source_stamp_ns)  # type: ignore[attr-defined]
            run_loop(cycle, lambda _r: np.zeros(6), sinks=[sink], max_cycles=1500)
        assert pub.count >= 150
        subscriber.wait(timeout=25)
    finally:
        for proc in (publisher, subscriber):
            proc.kill()
            proc.wait(timeout=10)
    received = json.loads(out.read_text())
    assert len(received) >= 150
    for stamp, frame, *wrench in received:
        k, rest = divmod(stamp - EPOCH_NS, PERIOD_NS)
        assert rest == 0 and frame == "ft_sensor"  # the raw reading's own stamp, republished
        np.testing.assert_allclose(wrench, contact(k), atol=1e-9)


def test_a_silent_topic_is_a_hardware_error_within_its_timeout(domain: int) -> None:
    sensor = open_sensor(f"ros2:///nobody_publishes?domain={domain}&timeout_s=0.3")
    message = r"no geometry_msgs/msg/WrenchStamped within 0\.3 s"
    with pytest.raises(HardwareError, match=message), sensor:
        pass


@pytest.mark.parametrize(
    ("uri", "message"),
    [
        ("ros2://host/ft", "no host in ros2:// URIs"),
        ("ros2:///", "name the WrenchStamped topic"),
        ("ros2:///ft?domain=300", "domain must be a ROS_DOMAIN_ID"),
        ("ros2:///ft?rate=1", "unknown option 'rate'"),
        ("ros2:///ft-bad", "not an absolute ROS 2 topic name"),
    ],
)
def test_bad_sensor_uris_name_the_problem(uri: str, message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        open_sensor(uri)


def test_ftcomp_stream_logs_the_contact_wrench_from_ros2_topics(
    domain: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The ``ros2://`` sensor and pose source through ``ftcomp stream`` (issue 9's command)."""
    from ftcomp.cli import main
    from ftcomp.io.calibration_json import FORMAT, model_to_dict

    cal, log = tmp_path / "cal.json", tmp_path / "log.csv"
    cal.write_text(json.dumps({"format": FORMAT, "method": "joint", **model_to_dict(MODEL)}))
    publisher = _peer("publish", domain, 20)
    try:
        code = main(
            [
                "stream",
                "--sensor",
                f"ros2:///ft_raw?frame=ft_sensor{_opts(domain)}",
                "--robot",
                f"ros2:///?base_frame=base&tcp_frame=ft_sensor{_opts(domain)}",
                "-c",
                str(cal),
                "--seconds",
                "1.5",
                "-o",
                str(log),
            ]
        )
    finally:
        publisher.kill()
        publisher.wait(timeout=10)
    assert code == 0, capsys.readouterr().err
    rows = list(csv.DictReader(log.open()))
    assert len(rows) >= 100
    contact_logged = np.array(
        [[float(r[c]) for c in ("cfx", "cfy", "cfz", "ctx", "cty", "ctz")] for r in rows]
    )
    # Each row is some reading k: the contact it carries is contact(k) for one k.
    k = np.round((contact_logged[:, 0] - contact(0)[0]) / 0.001)
    np.testing.assert_allclose(contact_logged, np.array([contact(int(i)) for i in k]), atol=1e-6)
