"""A live session served over the Foxglove WebSocket protocol (``--view HOST:PORT``).

:class:`FoxgloveView` is a session's log observer (:class:`~ftcomp.session.log.LogObserver`): it
starts a WebSocket server with ``foxglove-sdk`` (extra ``view``) bound to the address given
(loopback unless asked otherwise), and publishes each log row as the same channels as the MCAP
log (:mod:`ftcomp.ros2.mcap_log`), so Foxglove and Lichtblick (``Open connection`` ->
``ws://HOST:PORT``) plot it live:

==============================  ===========================  ======================================
topic                           schema                       content
==============================  ===========================  ======================================
``/ftcomp/wrench_raw``          ``ftcomp.WrenchStamped``     ``timestamp``, ``frame_id``,
                                (JSON)                       ``force.{x,y,z}``, ``torque.{x,y,z}``
``/ftcomp/wrench_compensated``  ``ftcomp.WrenchStamped``     the contact wrench, same fields
``/ftcomp/wrench_error``        ``ftcomp.WrenchStamped``     the controller's error (its frame)
``/ftcomp/twist_command``       ``ftcomp.TwistStamped``      ``linear``, ``angular`` (base frame)
``/ftcomp/load``                ``ftcomp.LoadEstimate``      the online load's columns by name
``/tf``                         ``foxglove.FrameTransforms`` base -> sensor (the 3D panel)
``/ftcomp/events``              ``foxglove.Log``             pose recorded, grasp, release, end
==============================  ===========================  ======================================

``ftcomp twin --view HOST:PORT`` serves the twin's own state with :class:`TwinView` (the contact
log's columns, one row per controller cycle): ``/twin/contact_wrench`` (``ftcomp.WrenchStamped``,
frame ``base``: the wrench the surfaces exert on the load, torque about the TCP), ``/tf`` (base
-> ``tcp``), ``/twin/safety`` (``ftcomp.SafetyState``: ``timestamp``, ``protective_stop``) and
a ``foxglove.Log`` on ``/ftcomp/events`` when the safety state changes.

The wrenches are JSON with a JSON schema (the Plot panel plots any numeric field, e.g.
``/ftcomp/wrench_compensated.force.z``); the stamps are the log's, in integer nanoseconds as
``{sec, nsec}``. A channel with no client subscribed costs one check per row. The session calls
the view from its observer thread, never from the control loop.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ftcomp.errors import ParameterError
from ftcomp.frames import matrix_from_rotvec, quat_from_matrix
from ftcomp.ros2.mcap_log import RowLayout

__all__ = ["SCHEMAS", "TWIN_COLUMNS", "FoxgloveView", "TwinView", "parse_address"]

_NS = 1_000_000_000
_VECTOR = {
    "type": "object",
    "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}},
}
_TIME = {
    "type": "object",
    "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}},
}


def _stamped(title: str, first: str, second: str) -> dict[str, Any]:
    return {
        "title": title,
        "type": "object",
        "properties": {
            "timestamp": _TIME,
            "frame_id": {"type": "string"},
            first: _VECTOR,
            second: _VECTOR,
        },
    }


#: The JSON schemas of the row channels.
SCHEMAS: dict[str, dict[str, Any]] = {
    "ftcomp.WrenchStamped": _stamped("ftcomp.WrenchStamped", "force", "torque"),
    "ftcomp.TwistStamped": _stamped("ftcomp.TwistStamped", "linear", "angular"),
}
_TOPIC_SCHEMA = {
    "/ftcomp/wrench_raw": "ftcomp.WrenchStamped",
    "/ftcomp/wrench_compensated": "ftcomp.WrenchStamped",
    "/ftcomp/wrench_error": "ftcomp.WrenchStamped",
    "/ftcomp/twist_command": "ftcomp.TwistStamped",
}
_LEVELS = {"fault": "Error", "contact": "Warning"}
#: The columns :class:`TwinView` reads from the twin's rows (the contact log's; ``safety``
#: 1.0 in a protective stop, else 0.0).
TWIN_COLUMNS = (
    "t_s", "fx", "fy", "fz", "tx", "ty", "tz", "x", "y", "z", "rx", "ry", "rz", "safety",
)  # fmt: skip
_SAFETY_SCHEMA = {
    "title": "ftcomp.SafetyState",
    "type": "object",
    "properties": {"timestamp": _TIME, "protective_stop": {"type": "boolean"}},
}


def parse_address(address: str) -> tuple[str, int]:
    """``(host, port)`` from ``HOST:PORT``.

    Raises:
        ParameterError: not ``HOST:PORT`` with a port in 1..65535.
    """
    host, _, port = address.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ParameterError(
            f"address: expected HOST:PORT with a port 1..65535, got {address!r}", field="address"
        )
    return host.strip("[]"), int(port)


def _time(t_ns: int) -> dict[str, int]:
    t = max(0, int(t_ns))
    return {"sec": t // _NS, "nsec": t % _NS}


class FoxgloveView:
    """Serves a session live over the Foxglove WebSocket protocol (see the module docstring).

    Args:
        address: ``HOST:PORT`` to bind to.
        base_frame, sensor_frame: frame ids of the robot's base and the sensor.
        control_frame: the frame id of the controller's wrench error.
        name: the server's name (shown by the client).

    Raises:
        ParameterError: ``foxglove-sdk`` is not installed, a bad address, or the port is taken.
    """

    def __init__(
        self,
        address: str,
        *,
        base_frame: str = "base",
        sensor_frame: str = "ft_sensor",
        control_frame: str = "base",
        name: str = "ftcomp",
    ) -> None:
        try:
            import foxglove
        except ImportError:
            raise ParameterError(
                "a view at an address needs foxglove-sdk: pip install 'ftcomp[view]'",
                field="address",
            ) from None
        self._fox = foxglove
        self.host, self.port = parse_address(address)
        self.base_frame, self.sensor_frame = base_frame, sensor_frame
        self.control_frame = control_frame
        self._context = foxglove.Context()
        try:
            self._server: Any = foxglove.start_server(
                name=name, host=self.host, port=self.port, context=self._context
            )
        except Exception as exc:  # the SDK raises its own errors for a taken port, a bad host
            raise ParameterError(
                f"address {address}: cannot serve there: {exc}", field="address"
            ) from None
        self.layout = RowLayout(())
        self._channels: dict[str, Any] = {}
        self._load: Any = None
        self._tf: Any = None
        self._events = foxglove.channels.LogChannel("/ftcomp/events", context=self._context)

    @property
    def url(self) -> str:
        """Where a client connects."""
        return f"ws://{self.host}:{self._server.port}"

    def open(self, columns: Sequence[str]) -> None:
        """Advertise the channels the columns fill."""
        fox = self._fox
        self.layout = RowLayout(columns)
        for topic in self.layout.channels:
            if topic == "/tf":
                self._tf = fox.channels.FrameTransformsChannel("/tf", context=self._context)
                continue
            schema = SCHEMAS[_TOPIC_SCHEMA[topic]]
            self._channels[topic] = fox.Channel(topic, schema=schema, context=self._context)
        if self.layout.load:
            properties = {name: {"type": "number"} for name in self.layout.load_columns}
            schema = {"title": "ftcomp.LoadEstimate", "type": "object", "properties": properties}
            self._load = fox.Channel("/ftcomp/load", schema=schema, context=self._context)

    def row(self, t_ns: int, row: Sequence[float]) -> None:
        """Publish one row on every channel a client subscribed to."""
        layout = self.layout
        stamp = _time(t_ns)
        for topic, columns in layout.channels.items():
            if topic == "/tf":
                if self._tf.has_sinks():
                    self._tf.log(self._transforms(stamp, [row[k] for k in columns]), log_time=t_ns)
                continue
            channel = self._channels[topic]
            if not channel.has_sinks():
                continue
            v = [float(row[k]) for k in columns]
            if topic == "/ftcomp/twist_command":
                keys, frame, msg_stamp = ("linear", "angular"), self.base_frame, stamp
            elif topic == "/ftcomp/wrench_error":
                keys, frame, msg_stamp = ("force", "torque"), self.control_frame, stamp
            else:
                keys, frame = ("force", "torque"), self.sensor_frame
                msg_stamp = _time(layout.sample_ns(t_ns, row))
            message = {
                "timestamp": msg_stamp,
                "frame_id": frame,
                keys[0]: {"x": v[0], "y": v[1], "z": v[2]},
                keys[1]: {"x": v[3], "y": v[4], "z": v[5]},
            }
            channel.log(message, log_time=t_ns)
        if self._load is not None and self._load.has_sinks():
            values = {
                n: float(row[k]) for n, k in zip(layout.load_columns, layout.load, strict=True)
            }
            self._load.log(values, log_time=t_ns)

    def _transforms(self, stamp: dict[str, int], pose: list[float]) -> Any:
        m = self._fox.messages
        qx, qy, qz, qw, px, py, pz = (float(v) for v in pose)
        transform = m.FrameTransform(
            timestamp=m.Timestamp(stamp["sec"], stamp["nsec"]),
            parent_frame_id=self.base_frame,
            child_frame_id=self.sensor_frame,
            translation=m.Vector3(x=px, y=py, z=pz),
            rotation=m.Quaternion(x=qx, y=qy, z=qz, w=qw),
        )
        return m.FrameTransforms(transforms=[transform])

    def event(self, t_ns: int, kind: str, text: str) -> None:
        """Publish an event on ``/ftcomp/events`` (a ``foxglove.Log``)."""
        m = self._fox.messages
        stamp = _time(t_ns)
        level = getattr(m.LogLevel, _LEVELS.get(kind, "Info"))
        message = m.Log(
            timestamp=m.Timestamp(stamp["sec"], stamp["nsec"]),
            level=level,
            message=text,
            name=f"ftcomp.{kind}",
        )
        self._events.log(message, log_time=max(0, int(t_ns)))

    def close(self) -> None:
        """Stop serving (idempotent)."""
        server, self._server = self._server, None
        if server is not None:
            server.stop()


class TwinView(FoxgloveView):
    """Serves ``ftcomp twin``'s state live: its contact log's rows (:data:`TWIN_COLUMNS`) as
    the contact wrench, the TCP pose and the safety state (see the module docstring).

    Args:
        address: ``HOST:PORT`` to bind to.

    Raises:
        ParameterError: ``foxglove-sdk`` is not installed, a bad address, or the port is taken.
    """

    def __init__(self, address: str) -> None:
        super().__init__(address, sensor_frame="tcp", name="ftcomp twin")
        self._safety: float | None = None
        self._index = list(range(len(TWIN_COLUMNS)))

    def open(self, columns: Sequence[str]) -> None:
        """Advertise the twin's channels.

        Raises:
            ParameterError: the columns are not :data:`TWIN_COLUMNS`.
        """
        missing = [name for name in TWIN_COLUMNS if name not in columns]
        if missing:
            raise ParameterError(f"TwinView: the rows have no {', '.join(missing)}")
        self._index = [list(columns).index(name) for name in TWIN_COLUMNS]
        fox, context = self._fox, self._context
        schema = SCHEMAS["ftcomp.WrenchStamped"]
        self._channels["/twin/contact_wrench"] = fox.Channel(
            "/twin/contact_wrench", schema=schema, context=context
        )
        self._channels["/twin/safety"] = fox.Channel(
            "/twin/safety", schema=_SAFETY_SCHEMA, context=context
        )
        self._tf = fox.channels.FrameTransformsChannel("/tf", context=context)

    def row(self, t_ns: int, row: Sequence[float]) -> None:
        """Publish one of the twin's rows on every channel a client subscribed to."""
        row = [row[k] for k in self._index]
        stamp = _time(t_ns)
        contact, safety = self._channels["/twin/contact_wrench"], self._channels["/twin/safety"]
        if contact.has_sinks():
            f, m = row[1:4], row[4:7]
            message = {
                "timestamp": stamp,
                "frame_id": self.base_frame,
                "force": {"x": f[0], "y": f[1], "z": f[2]},
                "torque": {"x": m[0], "y": m[1], "z": m[2]},
            }
            contact.log(message, log_time=t_ns)
        if self._tf.has_sinks():
            pose = [*quat_from_matrix(matrix_from_rotvec(row[10:13])), *row[7:10]]
            self._tf.log(self._transforms(stamp, pose), log_time=t_ns)
        stopped = row[13] != 0.0
        if safety.has_sinks():
            safety.log({"timestamp": stamp, "protective_stop": stopped}, log_time=t_ns)
        if self._safety is not None and row[13] != self._safety:
            text = "protective stop" if stopped else "protective stop released"
            self.event(t_ns, "fault" if stopped else "contact", text)
        self._safety = row[13]
