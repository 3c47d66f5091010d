"""A ROS 2 peer for the live tests, run in its own process: publishes a sensor, or listens.

``python dds_peer.py publish DOMAIN SECONDS``: ``/tf_static`` base -> ft_sensor (transient
local, as tf2's static broadcaster) and ``/ft_raw`` WrenchStamped at 200 Hz, reading k being
``MODEL.predict(R) + contact(k)`` stamped ``EPOCH_NS + k * 5 ms``.

``python dds_peer.py subscribe DOMAIN COUNT SECONDS OUT.json``: collects ``/ft_compensated``
until COUNT messages or SECONDS passed, writes ``[[stamp_ns, frame_id, fx, ..., tz], ...]``.

The DDS configuration comes from CYCLONEDDS_URI (the test restricts it to loopback).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from scipy.spatial.transform import Rotation

from ftcomp.model import GravityModel
from ftcomp.ros2.dds_types import (
    Header,
    Quaternion,
    TFMessage,
    Time,
    Transform,
    TransformStamped,
    Vector3,
    WrenchStamped,
    wrench_message,
    wrench_of,
)

EPOCH_NS = 1_700_000_000_000_000_000
PERIOD_NS = 5_000_000
MODEL = GravityModel(
    3.153,
    np.array([0.0001, -0.0003, 0.047]),
    np.array([-0.8613, 1.1015, 0.1976]),
    np.array([-0.0002, -0.0605, 0.0255]),
    tilt_U_rad=np.radians(-2.0),
    tilt_V_rad=np.radians(1.5),
)
R_BASE_SENSOR = Rotation.from_euler("ZYX", [30.0, 20.0, 170.0], degrees=True)


def contact(k: int) -> np.ndarray:
    """The contact wrench of reading k [N, N*m]: what compensation must give back."""
    return np.array([0.5, -1.0, 2.0, 0.01, -0.02, 0.03]) + 0.001 * k


def publish(domain: int, seconds: float) -> None:
    dp = DomainParticipant(domain)
    reliable = Policy.Reliability.Reliable(duration(milliseconds=100))
    static_qos = Qos(reliable, Policy.History.KeepLast(1), Policy.Durability.TransientLocal)
    tf_writer = DataWriter(dp, Topic(dp, "rt/tf_static", TFMessage), qos=static_qos)
    x, y, z, w = R_BASE_SENSOR.as_quat()
    tf_writer.write(
        TFMessage(
            [
                TransformStamped(
                    Header(Time(EPOCH_NS // 10**9, 0), "base"),
                    "ft_sensor",
                    Transform(Vector3(0.4, 0.0, 0.3), Quaternion(x, y, z, w)),
                )
            ]
        )
    )
    qos = Qos(reliable, Policy.History.KeepLast(10))
    writer = DataWriter(dp, Topic(dp, "rt/ft_raw", WrenchStamped), qos=qos)
    predicted = MODEL.predict(R_BASE_SENSOR.as_matrix())
    end = time.monotonic() + seconds
    k = 0
    while time.monotonic() < end:
        writer.write(wrench_message(EPOCH_NS + k * PERIOD_NS, "ft_sensor", predicted + contact(k)))
        k += 1
        time.sleep(PERIOD_NS / 1e9)


def subscribe(domain: int, count: int, seconds: float, out: str) -> None:
    dp = DomainParticipant(domain)
    qos = Qos(
        Policy.Reliability.Reliable(duration(milliseconds=100)), Policy.History.KeepLast(1000)
    )
    reader = DataReader(dp, Topic(dp, "rt/ft_compensated", WrenchStamped), qos=qos)
    got: list[list[object]] = []
    end = time.monotonic() + seconds
    while time.monotonic() < end and len(got) < count:
        for msg in reader.take(N=100):
            if isinstance(msg, WrenchStamped):
                stamp, wrench = wrench_of(msg)
                got.append([stamp, msg.header.frame_id, *wrench.tolist()])
        time.sleep(0.005)
    with open(out, "w", encoding="utf-8") as handle:
        json.dump(got, handle)


if __name__ == "__main__":
    mode, domain = sys.argv[1], int(sys.argv[2])
    if mode == "publish":
        publish(domain, float(sys.argv[3]))
    else:
        subscribe(domain, int(sys.argv[3]), float(sys.argv[4]), sys.argv[5])
