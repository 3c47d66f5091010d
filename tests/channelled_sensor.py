"""A sensor with extra channels for session tests: any sensor's readings, each carrying
``temperature_C`` and ``accel_x_m_s2`` set to its own ``fx`` and ``fy``, so a log row whose
channels equal its raw ``fx`` and ``fy`` holds the values of the frame its wrench came from."""

from __future__ import annotations

from ftcomp.hardware.protocols import NothingToClose, WrenchSample, WrenchSensor

CHANNELS = ("temperature_C", "accel_x_m_s2")


def _with_channels(sample: WrenchSample) -> WrenchSample:
    w = sample.wrench_sensor
    return WrenchSample(sample.t_ns, w, (float(w[0]), float(w[1])))


class ChannelledSensor(NothingToClose):
    """``sensor`` (entered by the caller) whose readings carry :data:`CHANNELS`
    (a :class:`~ftcomp.hardware.protocols.ReportsExtraChannels` sensor)."""

    extra_channels = CHANNELS

    def __init__(self, sensor: WrenchSensor) -> None:
        self.sensor = sensor

    def read(self) -> WrenchSample:
        return _with_channels(self.sensor.read())

    def read_new(self) -> list[WrenchSample]:
        return [_with_channels(s) for s in self.sensor.read_new()]
