"""The ``netft://`` backend: an ATI Net F/T (or Ethernet Axia) through ``pynetft``.

URI::

    netft://HOST[:RDT_PORT]       RDT over UDP (port 49152 by default)
          ?http_port=80           the sensor's web server (its configuration, netftapi2.xml)
          &timeout_s=0.1          silence longer than this is a fault [s]
          &connect_timeout_s=2    longest wait for the configuration and the first sample [s]
          &bias=0|1               zero the sensor (RDT software bias) after connecting;
                                  refused with a calibration (see below)

``pynetft`` reads the sensor's calibration over HTTP (counts per force and torque unit and the
units themselves) and streams RDT records over UDP. This backend converts every reading, once,
at the boundary, from the sensor's units (N, lbf, kgf, kN, klbf; N-m, N-mm, lbf-in, lbf-ft,
kgf-cm, kN-m) to N and N*m. The frame is the sensor's own measuring frame, and the reading is
what the tool exerts on the sensor, as ATI reports it (a tool hanging below the sensor along
its +z reads +fz): ftcomp's convention, so no sign changes.

Each sample is stamped with pynetft's arrival stamp, ``received_at_ns``, on the host's
monotonic clock (the same clock as :func:`time.monotonic_ns`), so the sensor shares the clock of
the hardware robots (``ur://``) and of the stand-alone host clock. The stream runs fail-stop:
a device status other than healthy or a monitor warning, silence beyond ``timeout_s``, a stalled
or backward sequence, or a storm of malformed packets ends it, and the next :meth:`read` raises
:class:`~ftcomp.errors.HardwareError` with the fault's name. Packets lost on the way are
counted from the RDT sequence numbers (:attr:`NetFTSensor.lost_packets`).

``bias=1`` zeroes the reading at the pose the tool is in when the stream starts, gravity
included; a calibration (``-c calibration.json``) then subtracts the tool's weight a second time
(with nothing touching, a 0.34 kg tool reads fz = -3.35 N). The sensor says so
(:class:`~ftcomp.hardware.protocols.TaresInHardware`) and a session with a calibration refuses
it: use the calibration's own bias (drop ``bias=1``), or re-bias the calibration
gravity-aware at any still pose with ``ftcomp rebias``.
"""

from __future__ import annotations

import collections
import math
import time
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np

from ftcomp.errors import HardwareError, ParameterError
from ftcomp.hardware.arrival_stream import mean_rate_hz
from ftcomp.hardware.pacing import on_host_clock
from ftcomp.hardware.protocols import Robot, StreamHealth, WrenchSample, WrenchSensor
from ftcomp.hardware.registry import Uri

if TYPE_CHECKING:
    import pynetft

__all__ = [
    "FORCE_UNITS_N",
    "TORQUE_UNITS_NM",
    "NetFTSensor",
    "open_sensor",
]

#: Newtons per force unit, by the unit's label in the sensor's configuration.
FORCE_UNITS_N: dict[str, float] = {
    "N": 1.0,
    "kN": 1e3,
    "lbf": 4.4482216152605,
    "klbf": 4448.2216152605,
    "kgf": 9.80665,
}
#: Newton-metres per torque unit.
TORQUE_UNITS_NM: dict[str, float] = {
    "N-m": 1.0,
    "N-mm": 1e-3,
    "kN-m": 1e3,
    "lbf-in": 0.112984829027617,
    "lbf-ft": 1.3558179483314,
    "kgf-cm": 0.0980665,
}
#: Readings kept for :meth:`NetFTSensor.read_new` between two calls (about 10 s at 7 kHz).
_BACKLOG = 70_000
_DEFAULT_RDT_PORT = 49152
#: One record as kept until read: its arrival stamp [ns] and the six values in sensor units.
_Record = tuple[int, float, float, float, float, float, float]


def _import_pynetft() -> Any:
    try:
        import pynetft
    except ImportError:
        raise ParameterError(
            "netft:// needs the pynetft package: pip install 'ftcomp[ati]'"
        ) from None
    return pynetft


class NetFTSensor:
    """An ATI Net F/T sensor streaming over RDT (see the module docstring). Capabilities:
    :class:`~ftcomp.hardware.protocols.CountsLostPackets`,
    :class:`~ftcomp.hardware.protocols.ReportsStreamHealth`,
    :class:`~ftcomp.hardware.protocols.TaresInHardware`.

    Args:
        uri: the parsed ``netft://`` URI (for messages).
        host: the sensor's address.
        rdt_port: its RDT (UDP) port.
        http_port: its web server's port.
        timeout_s: silence longer than this ends the stream with a fault [s].
        connect_timeout_s: longest wait for the first sample when connecting [s].
        bias: send the software-bias command after connecting.
    """

    def __init__(
        self,
        uri: Uri,
        host: str,
        *,
        rdt_port: int = _DEFAULT_RDT_PORT,
        http_port: int = 80,
        timeout_s: float = 0.1,
        connect_timeout_s: float = 2.0,
        bias: bool = False,
    ) -> None:
        self.uri = uri
        self._pynetft = _import_pynetft()
        pn = self._pynetft
        config = pn.Config(
            sensor_host=host,
            rdt_port=rdt_port,
            http_port=http_port,
            receive_timeout=timeout_s,
            configuration_connect_timeout=min(connect_timeout_s, 1.0),
            configuration_timeout=connect_timeout_s,
            recovery_policy=pn.RecoveryPolicy.FAIL_STOP,
        )
        try:
            self._client = pn.Client(config, queue_size=_BACKLOG)
        except pn.ConfigurationError as exc:
            raise ParameterError(f"{uri.text!r}: {exc}") from None
        self._connect_timeout_s = connect_timeout_s
        self._timeout_ns = round(timeout_s * 1e9)
        self._bias = bias
        #: :class:`~ftcomp.hardware.protocols.TaresInHardware`: ``bias=1`` zeroes the sensor.
        self.tares_in_hardware = bias
        # The records as numbers (_Record): each is converted once, when it is read (the
        # loop's read() converts only the newest; read_new() every one).
        self._backlog: collections.deque[_Record] = collections.deque(maxlen=_BACKLOG)
        self._newest: _Record | None = None
        self._drained = 0
        self._first_ns: int | None = None
        self._last: WrenchSample | None = None
        self._scale: tuple[float, float] | None = None
        self._units = ("", "")
        self._running = False

    # ----------------------------------------------------------------- lifecycle
    def __enter__(self) -> NetFTSensor:
        """Read the configuration, start the stream and wait for its first sample."""
        pn = self._pynetft
        try:
            self._client.start()
        except (pn.DiscoveryError, pn.NotConnectedError) as exc:
            raise HardwareError(f"{self.uri.text!r}: cannot connect: {exc}") from None
        self._running = True
        try:
            if not self._client.wait_for_first_sample(self._connect_timeout_s):
                raise HardwareError(self._no_data_message())
            self._drain()
            if self._bias:
                self._client.bias()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Stop streaming (the client sends Stop Streaming) and close."""
        self.close()

    def close(self) -> None:
        """Stop the stream (idempotent)."""
        if self._running:
            self._running = False
            self._client.stop()

    def _no_data_message(self) -> str:
        health = self._client.health()
        detail = health.last_error or "no RDT record arrived"
        text = self.uri.text
        if health.fault_code.value == "sensor_configuration":
            return (
                f"{text!r}: cannot read the sensor's configuration ({detail}); check the address "
                "and http_port"
            )
        return (
            f"{text!r}: no data within {self._connect_timeout_s:g} s ({detail}); check the RDT "
            "port, a firewall, or another program streaming from the sensor"
        )

    # ----------------------------------------------------------------- reading
    def _set_units(self, sample: pynetft.Sample) -> tuple[float, float]:
        """N per force unit and N*m per torque unit, from the first record's units."""
        force_unit, torque_unit = sample.force_unit.value, sample.torque_unit.value
        if force_unit not in FORCE_UNITS_N or torque_unit not in TORQUE_UNITS_NM:
            raise HardwareError(
                f"{self.uri.text!r}: the sensor reports force in {force_unit!r} and torque "
                f"in {torque_unit!r}; known: {', '.join(FORCE_UNITS_N)} and "
                f"{', '.join(TORQUE_UNITS_NM)}"
            )
        self._scale = (FORCE_UNITS_N[force_unit], TORQUE_UNITS_NM[torque_unit])
        self._units = (force_unit, torque_unit)
        return self._scale

    def _convert(self, record: _Record) -> WrenchSample:
        """One kept record as a reading in N and N*m."""
        assert self._scale is not None  # set by the first record drained
        f, t = self._scale
        stamp, fx, fy, fz, tx, ty, tz = record
        return WrenchSample.owning(
            stamp, np.array([fx * f, fy * f, fz * f, tx * t, ty * t, tz * t])
        )

    def _drain(self) -> None:
        """Move every delivered sample into the backlog; raise on a fault of the stream."""
        pn = self._pynetft
        if not self._running:
            raise HardwareError(f"{self.uri.text!r}: the stream is closed")
        try:
            for sample in self._client.samples(timeout=0.0):
                if self._scale is None:
                    self._set_units(sample)
                # A tuple of numbers: the collector soon stops tracking it, so a long backlog
                # (a loop that only calls read()) adds nothing to its collections.
                record = (sample.received_at_ns, *sample.force, *sample.torque)
                self._backlog.append(record)
                self._newest = record
                if self._first_ns is None:
                    self._first_ns = sample.received_at_ns
                self._drained += 1
        except TimeoutError:
            return  # nothing more for now
        except pn.SensorFaultError as exc:
            raise self._fault(exc.fault_code, exc.health) from None
        # The iterator ended without a fault: the client was stopped.
        self._running = False
        raise HardwareError(f"{self.uri.text!r}: the stream stopped")

    def _check_health(self) -> None:
        """Raise if the stream has faulted or stopped (the client's health, without draining)."""
        pn = self._pynetft
        health = self._client.health()
        if health.fault_code is not pn.FaultCode.NONE:
            raise self._fault(health.fault_code, health)
        if health.state is pn.ClientState.STOPPED:
            self._running = False
            raise HardwareError(f"{self.uri.text!r}: the stream stopped")

    def _fault(self, code: pynetft.FaultCode, health: pynetft.Health) -> HardwareError:
        """The error of a stream that faulted (fail-stop: it is over)."""
        self._running = False
        status = f" (device status 0x{health.last_status:08x})" if health.last_status else ""
        return HardwareError(
            f"{self.uri.text!r}: sensor fault {code.value}{status}: "
            f"{health.last_error or 'the stream stopped'}"
        )

    def _newest_reading(self) -> WrenchSample:
        """The newest record, converted once."""
        newest = self._newest
        if newest is None:
            raise HardwareError(f"{self.uri.text!r}: no reading yet")
        if self._last is None or self._last.t_ns != newest[0]:
            self._last = self._convert(newest)
        return self._last

    def read(self) -> WrenchSample:
        """The newest reading (the same again until a newer one arrives).

        The loop's path: the client's newest sample alone (one conversion), not its queue:
        draining the queue costs a conversion per record and a wait on the empty queue, about
        0.2 ms a cycle. Only when nothing newer arrived (or the newest is older than the
        silence limit ``timeout_s``) is the stream's health asked, so a fault of the stream is
        raised in the cycle that finds no new sample. The records stay
        queued for :meth:`read_new`.
        """
        if not self._running:
            raise HardwareError(f"{self.uri.text!r}: the stream is closed")
        sample = self._client.latest_sample()
        newest = self._newest
        fresh = sample is not None and (newest is None or sample.received_at_ns > newest[0])
        if not fresh or time.monotonic_ns() - sample.received_at_ns > self._timeout_ns:
            self._check_health()
        if fresh:
            if self._scale is None:
                self._set_units(sample)
            self._newest = (sample.received_at_ns, *sample.force, *sample.torque)
        return self._newest_reading()

    def read_new(self) -> list[WrenchSample]:
        """Every reading since the previous call, oldest first."""
        self._drain()
        if not self._backlog:
            return []
        *older, _ = self._backlog
        out = [self._convert(sample) for sample in older]
        out.append(self._newest_reading())
        self._backlog.clear()
        return out

    # ----------------------------------------------------------------- health
    @property
    def lost_packets(self) -> int:
        """RDT packets lost since the stream started (gaps in the RDT sequence)."""
        return int(self._client.health().lost_count)

    @property
    def sample_rate_hz(self) -> float:
        """The mean rate of the records taken from the client since the first [Hz] (those
        :meth:`read_new` handed out or keeps; :meth:`read` takes none); NaN until
        :func:`~ftcomp.hardware.arrival_stream.mean_rate_hz` can tell
        (:class:`~ftcomp.hardware.protocols.ReportsRate`)."""
        if self._first_ns is None or self._newest is None:
            return math.nan
        return mean_rate_hz(self._drained, self._first_ns, self._newest[0])

    @property
    def rate_hz(self) -> float:
        """The rate samples arrive at [Hz], as pynetft measures it."""
        return float(self._client.health().receive_rate_hz)

    def stream_health(self) -> StreamHealth:
        """One consistent snapshot: received, lost, the last RDT sequence, rate and the units."""
        health = self._client.health()
        return StreamHealth(
            received=int(health.received_count),
            lost_packets=int(health.lost_count),
            last_sequence=health.last_rdt_sequence,
            rate_hz=float(health.receive_rate_hz),
            force_unit=self._units[0],
            torque_unit=self._units[1],
        )


def open_sensor(uri: Uri, robot: Robot | None) -> WrenchSensor:
    """A Net F/T sensor from its URI (not connected until entered).

    Raises:
        ParameterError: no host, a bad option, or a robot on another clock (simulation).
    """
    if not uri.host:
        raise ParameterError(f"{uri.text!r}: give the sensor's address, e.g. netft://192.168.1.1")
    if uri.path not in ("", "/"):
        raise ParameterError(f"{uri.text!r}: netft:// takes no path, got {uri.path!r}")
    if robot is not None and not on_host_clock(robot):
        raise ParameterError(
            f"{uri.text!r}: a Net F/T is stamped on the host's monotonic clock and cannot share "
            "a session with this robot (simulated time); use it with ur:// or alone"
        )
    options = uri.reader()
    http_port = options.integer("http_port", 80)
    timeout_s = options.positive("timeout_s", 0.1)
    connect_s = options.positive("connect_timeout_s", 2.0)
    bias = options.flag("bias", False)
    options.done()
    rdt_port = uri.port if uri.port is not None else _DEFAULT_RDT_PORT
    for name, port in (("RDT port", rdt_port), ("http_port", http_port)):
        if not 1 <= port <= 65535:
            raise ParameterError(f"{uri.text!r}: {name} must be in 1..65535, got {port}")
    return NetFTSensor(
        uri,
        uri.host,
        rdt_port=rdt_port,
        http_port=http_port,
        timeout_s=timeout_s,
        connect_timeout_s=connect_s,
        bias=bias,
    )
