"""Fault injection: a sensor wrapper that breaks on cue, to test that every fault stops motion.

:class:`FaultySensor` wraps any :class:`~ftcomp.hardware.protocols.WrenchSensor` and, from a
given time on (the session's clock), returns one kind of fault instead of the real readings.
"""

from __future__ import annotations

import math
from types import TracebackType
from typing import Literal

import numpy as np

from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import WrenchSample, WrenchSensor

__all__ = ["FAULT_KINDS", "FaultKind", "FaultySensor"]

FaultKind = Literal["nan", "repeat", "spike", "stop", "freeze", "saturate"]
FAULT_KINDS: tuple[FaultKind, ...] = ("nan", "repeat", "spike", "stop", "freeze", "saturate")
_SPIKE = np.array([0.0, 0.0, 100.0, 0.0, 0.0, 0.0])


class FaultySensor:
    """Wraps a sensor and injects one fault from ``t_fault_s`` on.

    Kinds: ``"nan"`` (NaN readings), ``"repeat"`` (one sample repeated with its old stamp),
    ``"spike"`` (one 100 N spike along the sensor's z), ``"stop"`` (the stream stops: the last
    reading is returned forever, as a driver whose connection died), ``"freeze"`` (the last
    values forever under fresh stamps, as a driver repeating a dead value), ``"saturate"`` (the
    force x axis pinned at ``saturation_N``, the sensor's range, from then on).

    Args:
        sensor: the real sensor.
        kind: the fault.
        t_fault_s: when it starts [s] on the session's clock (``inf``: never, until changed).
    """

    def __init__(
        self,
        sensor: WrenchSensor,
        kind: FaultKind,
        t_fault_s: float,
        *,
        saturation_N: float = 250.0,
    ) -> None:
        if kind not in FAULT_KINDS:
            raise ParameterError(f"unknown fault {kind!r}; valid: {', '.join(FAULT_KINDS)}")
        self._sensor = sensor
        self.kind = kind
        self.t_fault_s = t_fault_s
        self.saturation_N = saturation_N
        self._last: WrenchSample | None = None
        self._fired = False

    def __enter__(self) -> FaultySensor:
        """Enter the wrapped sensor."""
        self._sensor.__enter__()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Leave the wrapped sensor."""
        self._sensor.__exit__(exc_type, exc, tb)

    def read(self) -> WrenchSample:
        """The underlying reading, or the fault."""
        sample = self._sensor.read()
        if sample.t_s < self.t_fault_s or (self._fired and self.kind in ("repeat", "spike")):
            # Before the fault, and after a one-off fault: the real reading.
            self._last = sample
            return sample
        self._fired = True
        if self.kind == "nan":
            return WrenchSample(sample.t_ns, np.full(6, math.nan))
        if self.kind == "spike":
            return WrenchSample(sample.t_ns, sample.wrench_sensor + _SPIKE)
        if self.kind == "saturate":
            pinned = sample.wrench_sensor.copy()
            pinned[0] = self.saturation_N
            return WrenchSample(sample.t_ns, pinned)
        if self.kind == "freeze":
            frozen = self._last if self._last is not None else sample
            self._last = frozen
            return WrenchSample(sample.t_ns, frozen.wrench_sensor)
        previous = self._last if self._last is not None else sample
        if self.kind == "stop":
            self._last = previous
        return previous

    def read_new(self) -> list[WrenchSample]:
        """The newest reading (or the fault) if it is new, as a list."""
        before = self._last
        sample = self.read()
        return [] if before is not None and sample.t_ns <= before.t_ns else [sample]
