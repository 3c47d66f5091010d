"""``ftcomp ros2 node`` at 1 kHz beside an rclpy relay node, in one run, on loopback.

Run by hand (not a test)::

    .venv/bin/python bench/bench_ros2_node.py [--seconds 60] [--rate-hz 1000]

Five processes, every participant pinned to 127.0.0.1 (``loopback_environment``) on a domain of
the run's own:

- ``sensor``: an rclpy node publishing ``/ft_raw`` (WrenchStamped, reliable, keep last 100) at
  ``--rate-hz`` for ``--seconds``, each stamped with the wall clock (ROS time) when sent, and
  ``/joint_states`` at 100 Hz;
- ``node``: :class:`~ftcomp.ros2.node.CompensationNode` (``ftcomp ros2 node``, raw topic QoS
  ``reliable``) publishing ``/ftcomp/wrench_compensated``;
- ``relay``: an rclpy node that subscribes to ``/ft_raw`` and republishes each message as it
  came on ``/relay/wrench`` (no work: the baseline);
- ``meter``: one rclpy node subscribed to both outputs (reliable, keep last 10000), its executor
  spun on a thread, each callback taking the messages queued behind its own (``take_queued``):
  for each message the latency ``received - header.stamp`` (raw stamp to compensated message
  received: the wall clock when the meter's middleware received it, its
  ``MessageInfo.received_timestamp``, so the meter's own executor delays neither path), the
  stamps seen, and the node's ``/diagnostics`` (published, dropped, why);
- this process, which starts them, waits and reports.

Reported: messages sent, lost on each path (sent stamps never received), latency p50/p99/max
of each path and the node's p99 over the relay's (the target: at most 1.5), CPU of the node,
the relay, the meter and the sensor (user + system time over the run, from
``/proc/PID/stat``), the load average at the end, and what the node said on ``/diagnostics``.
The non-loopback interfaces' packet counters are checked unchanged.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "tests" / "ros2"))


def _cpu_s(pid: int) -> float:
    """User + system CPU time of a process so far [s]."""
    with open(f"/proc/{pid}/stat", encoding="ascii") as handle:
        fields = handle.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def sensor(seconds: float, rate_hz: float, out: str, go: str) -> None:
    import rclpy
    from geometry_msgs.msg import WrenchStamped
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rclpy_peer import MODEL, R_BASE_SENSOR, Q, contact
    from sensor_msgs.msg import JointState

    rclpy.init()
    node = Node("sensor_driver")
    qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
    wrenches = node.create_publisher(WrenchStamped, "/ft_raw", qos)
    joints = node.create_publisher(JointState, "/joint_states", qos)
    predicted = MODEL.predict(R_BASE_SENSOR.as_matrix())
    # Joint states until every subscription is matched (the node starts on them) and the meter
    # has matched both outputs (``go``): messages before that would be lost unmeasured.
    while wrenches.get_subscription_count() < 2 or not Path(go).exists():
        js = JointState(name=["yaw", "pitch"], position=list(Q))
        js.header.stamp.sec, js.header.stamp.nanosec = divmod(time.time_ns(), 10**9)
        joints.publish(js)
        time.sleep(0.01)
    period = 1.0 / rate_hz
    stamps = []
    start = time.monotonic()
    k = 0
    while True:
        due = start + k * period
        now = time.monotonic()
        if now - start >= seconds:
            break
        if due > now:
            time.sleep(due - now)
        msg = WrenchStamped()
        msg.header.frame_id = "ft_sensor"
        f, m = msg.wrench.force, msg.wrench.torque
        f.x, f.y, f.z, m.x, m.y, m.z = (predicted + contact(k % 1000)).tolist()
        t = time.time_ns()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(t, 10**9)
        wrenches.publish(msg)
        stamps.append(t)
        if k % round(rate_hz / 100) == 0:
            js = JointState(name=["yaw", "pitch"], position=list(Q))
            js.header.stamp = msg.header.stamp
            joints.publish(js)
        k += 1
    time.sleep(1.0)
    Path(out).write_text(json.dumps({"stamps": stamps, "seconds": time.monotonic() - start}))
    node.destroy_node()
    rclpy.try_shutdown()


def relay() -> None:
    import rclpy
    from geometry_msgs.msg import WrenchStamped
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    rclpy.init()
    node = Node("relay")
    qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
    pub = node.create_publisher(WrenchStamped, "/relay/wrench", qos)
    node.create_subscription(WrenchStamped, "/ft_raw", pub.publish, qos)
    rclpy.spin(node)  # until killed


def compensation_node(urdf: str, cal: str) -> None:
    from ftcomp.ros2.node import CompensationNode

    settings = {
        "calibration_file": cal,
        "urdf": urdf,
        "base_frame": "base",
        "sensor_frame": "ft_sensor",
        "wrench_topic": "/ft_raw",
        "wrench_qos": "reliable",
        "timeout_s": 120.0,
    }
    with CompensationNode(settings):
        while True:  # until killed
            time.sleep(1.0)


def meter(out: str, ready: str, stop: str) -> None:
    import threading

    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import WrenchStamped
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    rclpy.init()
    node = Node("meter")
    qos = QoSProfile(depth=10000, reliability=ReliabilityPolicy.RELIABLE)
    got: dict[str, list[tuple[int, int]]] = {"node": [], "relay": []}

    from ftcomp.ros2.rclpy_runtime import take_queued

    subscriptions = {}

    def on(path: str):
        def record(msg: WrenchStamped, info: dict[str, int]) -> None:
            # When the meter's middleware received it: the meter's own executor (behind at
            # 2 kHz in on a loaded host) delays neither path.
            now = info.get("received_timestamp") or time.time_ns()
            got[path].append((msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec, now))

        def callback(msg: WrenchStamped, info: dict[str, int]) -> None:
            record(msg, info)
            # What is queued behind it too, as the node does: one wait set for many, so the
            # meter takes less of the two cores the paths it measures share.
            for queued in take_queued(subscriptions[path], 1000):
                record(*queued)

        return callback

    for path, topic in (("node", "/ftcomp/wrench_compensated"), ("relay", "/relay/wrench")):
        subscriptions[path] = node.create_subscription(WrenchStamped, topic, on(path), qos)
    said: dict[str, object] = {"errors": []}  # the node's /diagnostics: why it dropped any

    def on_diagnostics(msg: DiagnosticArray) -> None:
        for status in msg.status:
            said.update({kv.key: kv.value for kv in status.values})
            if status.level != b"\x00" and status.message not in said["errors"]:
                said["errors"].append(status.message)  # type: ignore[attr-defined]

    node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, qos)
    # Spun on a thread of its own: a spin_once(timeout) loop costs a timer and a wait set per
    # message, which at 2 kHz in starves the meter and delays both paths it measures alike.
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    threading.Thread(target=executor.spin, daemon=True).start()
    while node.count_publishers("/ftcomp/wrench_compensated") < 1 or (
        node.count_publishers("/relay/wrench") < 1
    ):
        time.sleep(0.05)
    time.sleep(0.5)  # the publishers' side of the match, too
    Path(ready).write_text("ready")
    while not Path(stop).exists():
        time.sleep(0.1)
    executor.shutdown()
    Path(out).write_text(json.dumps({**got, "diagnostics": said}))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--rate-hz", type=float, default=1000.0)
    parser.add_argument("--role", default="main", help=argparse.SUPPRESS)
    parser.add_argument("args", nargs="*", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.role == "sensor":
        sensor(args.seconds, args.rate_hz, *args.args)
        return 0
    if args.role == "relay":
        relay()
        return 0
    if args.role == "node":
        compensation_node(*args.args)
        return 0
    if args.role == "meter":
        meter(*args.args)
        return 0

    from rclpy_peer import MODEL, URDF

    from ftcomp.io.calibration_json import FORMAT, model_to_dict
    from ftcomp.ros2.rclpy_runtime import loopback_environment, transmitted_packets

    tmp = Path(tempfile.mkdtemp(prefix="bench_ros2_"))
    env = {
        **os.environ,
        **loopback_environment(tmp),
        "ROS_DOMAIN_ID": str(200 + os.getpid() % 30),
        "PYTHONPATH": os.pathsep.join([str(ROOT / "tests" / "ros2"), *sys.path]),
    }
    (tmp / "cal.json").write_text(
        json.dumps({"format": FORMAT, "method": "joint", **model_to_dict(MODEL)})
    )
    (tmp / "robot.urdf").write_text(URDF)

    def spawn(role: str, *extra: object) -> subprocess.Popen[bytes]:
        cmd = [sys.executable, __file__, "--role", role, "--seconds", str(args.seconds)]
        cmd += ["--rate-hz", str(args.rate_hz), *map(str, extra)]
        return subprocess.Popen(cmd, env=env)

    before = transmitted_packets()
    ready = tmp / "meter.ready"
    meter_proc = spawn("meter", tmp / "meter.json", ready, tmp / "stop")
    node_proc = spawn("node", tmp / "robot.urdf", tmp / "cal.json")
    relay_proc = spawn("relay")
    sensor_proc = spawn("sensor", tmp / "sensor.json", ready)
    while not ready.exists():
        time.sleep(0.1)
    # CPU from the moment the sensor starts sending to its end, of each process (the sensor's
    # as last sampled, at most 0.2 s before it ended).
    procs = {"node": node_proc, "relay": relay_proc, "meter": meter_proc, "sensor": sensor_proc}
    cpu0 = {k: _cpu_s(p.pid) for k, p in procs.items()}
    t0 = time.monotonic()
    sensor_cpu = cpu0["sensor"]
    while sensor_proc.poll() is None:
        try:
            sensor_cpu = _cpu_s(sensor_proc.pid)
        except FileNotFoundError:
            break
        time.sleep(0.2)
    wall = time.monotonic() - t0
    cpu = {k: _cpu_s(p.pid) - cpu0[k] for k, p in procs.items() if k != "sensor"}
    cpu["sensor"] = sensor_cpu - cpu0["sensor"]
    loadavg = Path("/proc/loadavg").read_text().split()[:3]
    time.sleep(2.0)  # the last messages arrive
    (tmp / "stop").write_text("stop")
    meter_proc.wait(timeout=120)
    for proc in (node_proc, relay_proc):
        proc.kill()
        proc.wait(timeout=30)
    after = transmitted_packets()
    sent = json.loads((tmp / "sensor.json").read_text())["stamps"]
    got = json.loads((tmp / "meter.json").read_text())
    sent_set = set(sent)
    rows = {}
    for path in ("node", "relay"):
        pairs = [(s, r) for s, r in got[path] if s in sent_set]
        lat_ms = np.array([(r - s) / 1e6 for s, r in pairs])
        lost = len(sent_set - {s for s, _ in pairs})
        rows[path] = {
            "received": len(pairs),
            "lost": lost,
            "p50_ms": float(np.percentile(lat_ms, 50)) if len(lat_ms) else float("nan"),
            "p99_ms": float(np.percentile(lat_ms, 99)) if len(lat_ms) else float("nan"),
            "max_ms": float(lat_ms.max()) if len(lat_ms) else float("nan"),
            "cpu_percent": 100.0 * cpu[path] / wall,
        }
    moved = {k: after[k] - before.get(k, 0) for k in after if after[k] != before.get(k, 0)}
    print(f"sent {len(sent)} raw wrenches at {args.rate_hz:g} Hz over {args.seconds:g} s")
    print(
        f"{'path':<8}{'received':>10}{'lost':>7}{'p50 ms':>9}{'p99 ms':>9}{'max ms':>9}{'CPU %':>8}"
    )
    for path, r in rows.items():
        print(
            f"{path:<8}{r['received']:>10}{r['lost']:>7}{r['p50_ms']:>9.3f}{r['p99_ms']:>9.3f}"
            f"{r['max_ms']:>9.2f}{r['cpu_percent']:>8.1f}"
        )
    ratio = rows["node"]["p99_ms"] / rows["relay"]["p99_ms"]
    print(
        f"node p99 / relay p99 = {ratio:.2f} (target <= 1.5); lost by the node: "
        f"{rows['node']['lost']} (target 0)"
    )
    others = {k: round(100.0 * cpu[k] / wall, 1) for k in ("meter", "sensor")}
    print(
        f"CPU % of one core: meter {others['meter']}, sensor {others['sensor']}; load average "
        f"at the end {' '.join(loadavg)}"
    )
    said = got["diagnostics"]
    print(
        f"the node's /diagnostics: published {said.get('published')}, dropped "
        f"{said.get('dropped')}{''.join(chr(10) + '  ' + e for e in said['errors'])}"
    )
    print(f"non-loopback packets sent during the run: {moved or 'none'}")
    summary = {"sent": len(sent), **rows, "p99_ratio": ratio, "cpu_percent": others}
    print(json.dumps({**summary, "loadavg": loadavg, "non_loopback": moved}))
    return 0 if rows["node"]["lost"] == 0 and ratio <= 1.5 and not moved else 1


if __name__ == "__main__":
    sys.exit(main())
