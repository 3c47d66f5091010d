"""The wrench pipeline of a live cycle: each reading compensated once, in time order.

A live loop turns a raw reading into the contact wrench in one place,
:class:`WrenchPipeline`, which :class:`ftcomp.control.loop.ControlCycle` owns: ``ftcomp run``,
``stream`` and ``record`` read what it computed and compensate nothing themselves. In order:

1. bias and tool gravity of the calibration (:class:`~ftcomp.compensation.compensator.
   GravityCompensator`; a bias that follows the sensor's temperature from each reading's
   ``temperature_C`` channel; with ``accelerometer``, the tool's weight and linear inertial
   force under the apparent gravity the sensor's IMU reads, ``accel_x_m_s2``...), or with a
   grasped load weighed online that load's too
   (:class:`~ftcomp.compensation.online.OnlineLoadCompensator`, stateful: one call per reading,
   in time order; its load columns and events followed by a
   :class:`~ftcomp.compensation.online.LoadTracker`);
2. the bias followed while the arm is still and free
   (:class:`~ftcomp.compensation.bias_tracking.BiasTracker`), on the compensated wrench.

Without a compensator the raw reading passes on. The online load estimate needs the readings'
rate: given, it is used as is; otherwise it is measured from the stamps of the first readings
(:data:`MEASURE_RATE_S`), which are held back until then and compensated in order once the rate
is known, so none is lost (:meth:`WrenchPipeline.weighing`).

A pipeline is used one of two ways by its cycle: :meth:`~WrenchPipeline.contact` for the
newest reading of each cycle (a control loop, one call per cycle), or :meth:`~WrenchPipeline.
push` for every reading the sensor delivered (a stream at the sensor's rate), whose results come
out as :class:`Compensated` records in :attr:`~WrenchPipeline.ready`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ftcomp.calibration_record import Calibration
from ftcomp.compensation.bias_tracking import BiasTracker
from ftcomp.compensation.compensator import GravityCompensator
from ftcomp.compensation.online import LoadTracker, OnlineLoadCompensator, OnlineSettings
from ftcomp.errors import ParameterError
from ftcomp.hardware.protocols import IMU_CHANNELS, TEMPERATURE_CHANNEL
from ftcomp.model import GravityModel

__all__ = ["MEASURE_RATE_S", "MIN_RATE_READINGS", "Compensated", "WrenchPipeline"]

#: How long the readings' stamps are watched to measure their rate when none is given [s].
MEASURE_RATE_S = 0.5
#: ... and at least this many readings.
MIN_RATE_READINGS = 20


@dataclass(frozen=True, slots=True)
class Compensated:
    """One reading through the pipeline (:meth:`WrenchPipeline.push`).

    Attributes:
        t_ns: the reading's stamp [ns] (session clock).
        wrench_raw_sensor: the reading [N, N*m], sensor frame, (6,).
        wrench_contact_sensor: the contact wrench (the raw reading without a compensator)
            [N, N*m], sensor frame, (6,).
        R_base_sensor: the sensor's orientation the cycle that read it saw, (3, 3).
        p_base_sensor: the sensor's origin then [m], base frame, (3,).
        bias_updated: whether this reading moved the tracked bias (False without tracking).
        load: the online load's columns after this reading
            (:data:`~ftcomp.compensation.online.LOAD_COLUMNS`; empty without it).
        extras: the sensor's extra channels in the reading's frame
            (:attr:`~ftcomp.hardware.protocols.WrenchSample.extras`; empty without them).
    """

    t_ns: int
    wrench_raw_sensor: NDArray[np.float64]
    wrench_contact_sensor: NDArray[np.float64]
    R_base_sensor: NDArray[np.float64]
    p_base_sensor: NDArray[np.float64]
    bias_updated: bool = False
    load: tuple[float, ...] = ()
    extras: tuple[float, ...] = ()


class WrenchPipeline:
    """Raw reading -> contact wrench, once per reading (see the module docstring).

    Args:
        compensator: bias and tool gravity (an
            :class:`~ftcomp.compensation.online.OnlineLoadCompensator`: a grasped load weighed
            online too); None passes the raw reading on (the paper's uncompensated comparison).
        bias_tracker: follows the bias while the arm is still and free, after the compensator.
        extra_channels: the sensor's extra channels, in the order of each reading's
            ``extras`` (:attr:`~ftcomp.hardware.protocols.ReportsExtraChannels.extra_channels`):
            a calibration whose bias follows the temperature takes ``temperature_C`` from them.
        accelerometer: take the tool's (and a weighed load's) acceleration from the sensor's
            accelerometer channels (``accel_x_m_s2``, ``accel_y_m_s2``, ``accel_z_m_s2``:
            :meth:`~ftcomp.compensation.compensator.GravityCompensator.compensate`'s
            ``specific_force_mps2``) rather than hold it still at the pose's gravity.

    Raises:
        ParameterError: a bias tracker without a compensator; a calibration whose bias follows
            the sensor's temperature with a sensor that reports none; ``accelerometer`` without
            a compensator, or with a sensor that reports no acceleration.

    Attributes:
        load: follows the online compensator's estimate and events (None without one).
        ready: the readings :meth:`push` has compensated and not yet handed on (the caller
            clears it).
    """

    def __init__(
        self,
        compensator: GravityCompensator | None = None,
        *,
        bias_tracker: BiasTracker | None = None,
        extra_channels: tuple[str, ...] = (),
        accelerometer: bool = False,
    ) -> None:
        if bias_tracker is not None and compensator is None:
            raise ParameterError("tracking the bias needs the tool's calibration")
        if accelerometer and compensator is None:
            raise ParameterError(
                "accelerometer: compensating with it needs the tool's calibration",
                field="accelerometer",
            )
        self.extra_channels = extra_channels
        #: Where each reading's acceleration is in its extras (None: not used).
        self._accel_at = _accelerometer_indices(extra_channels) if accelerometer else None
        #: Where each reading's temperature is in its extras (None: not used).
        self._temperature_at = _temperature_index(compensator, extra_channels)
        #: The lowest and highest temperature compensated with [degC] (inf, -inf: none).
        self._T_low, self._T_high = math.inf, -math.inf
        self.compensator = compensator
        self.bias_tracker = bias_tracker
        self.load = (
            LoadTracker(compensator) if isinstance(compensator, OnlineLoadCompensator) else None
        )
        self.ready: list[Compensated] = []
        #: How the online estimate's rate was found ("given", "measured from ...", "" without).
        self.rate_source = "given" if self.load is not None else ""
        self._weigh: tuple[Calibration | GravityModel, OnlineSettings, int] | None = None
        self._held: list[
            tuple[int, NDArray[np.float64], NDArray[np.float64], NDArray, tuple[float, ...]]
        ] = []

    @classmethod
    def weighing(
        cls,
        calibration: Calibration | GravityModel,
        rate_Hz: float | None = None,
        *,
        settings: OnlineSettings | None = None,
        measure_s: float = MEASURE_RATE_S,
        extra_channels: tuple[str, ...] = (),
        accelerometer: bool = False,
    ) -> WrenchPipeline:
        """A pipeline weighing a grasped load online (no bias tracking).

        Args:
            calibration: the tool's calibration (with its weight).
            rate_Hz: the readings' rate [Hz]; None: measured from the stamps of the first
                ``measure_s`` of readings (at least :data:`MIN_RATE_READINGS`), which
                :meth:`push` holds back until then.
            settings: the compensator's tuning; its ``rate_Hz`` is replaced by the rate
                (default :class:`~ftcomp.compensation.online.OnlineSettings`).
            measure_s: how long to measure the rate [s].
            extra_channels, accelerometer: as :class:`WrenchPipeline`'s.

        Raises:
            ParameterError: a weightless tool, a rate that is not > 0, a calibration whose
                bias follows the temperature with a sensor that reports none, or
                ``accelerometer`` with a sensor that reports no acceleration.
        """
        if rate_Hz is not None and not (math.isfinite(rate_Hz) and rate_Hz > 0.0):
            raise ParameterError(f"the readings' rate must be > 0 Hz, got {rate_Hz:g}")
        settings = settings if settings is not None else OnlineSettings()
        if rate_Hz is not None:
            return cls(
                OnlineLoadCompensator(calibration, replace(settings, rate_Hz=rate_Hz)),
                extra_channels=extra_channels,
                accelerometer=accelerometer,
            )
        # refuses a weightless tool, or a temperature model without a temperature, now
        _temperature_index(OnlineLoadCompensator(calibration, settings), extra_channels)
        pipeline = cls(extra_channels=extra_channels)  # its compensator once the rate is known
        pipeline._accel_at = _accelerometer_indices(extra_channels) if accelerometer else None
        pipeline._weigh = (calibration, settings, round(measure_s * 1e9))
        return pipeline

    @property
    def rate_Hz(self) -> float:
        """The online estimate's rate in use [Hz] (NaN without it or while it is measured)."""
        c = self.compensator
        return c.settings.rate_Hz if isinstance(c, OnlineLoadCompensator) else math.nan

    @property
    def measuring(self) -> bool:
        """Whether readings are held back while the online estimate's rate is measured."""
        return self._weigh is not None

    def contact(
        self,
        t_ns: int,
        wrench_sensor: NDArray[np.float64],
        R_base_sensor: NDArray[np.float64],
        extras: tuple[float, ...] = (),
    ) -> NDArray[np.float64]:
        """One reading's contact wrench [N, N*m], sensor frame, (6,): the reading (stamp [ns],
        raw wrench, the sensor's orientation, its extra channels) through the compensator, then
        the bias tracker. Call it once per reading, in time order (the online estimate and the
        tracker keep state); a pipeline still measuring its rate has no compensator yet."""
        if self._weigh is not None:
            raise ParameterError("the online load estimate's rate is still being measured")
        c, at, acc = self.compensator, self._temperature_at, self._accel_at
        if c is None:
            contact = wrench_sensor
        elif at is None and acc is None:
            contact = c.compensate(wrench_sensor, R_base_sensor)
        else:
            temperature = None
            if at is not None:  # the bias at this reading's temperature
                temperature = extras[at]
                if temperature < self._T_low:
                    self._T_low = temperature
                if temperature > self._T_high:
                    self._T_high = temperature
            contact = c.compensate(
                wrench_sensor,
                R_base_sensor,
                temperature_C=temperature,
                specific_force_mps2=None if acc is None else [extras[i] for i in acc],
            )
        tracker = self.bias_tracker
        if tracker is not None:  # the bias followed while still and free
            contact = tracker.correct(t_ns * 1e-9, contact, R_base_sensor)
        return contact

    def temperature_outside(self) -> str:
        """What the calibration's temperature bias model did with the readings' temperatures
        beyond its calibrated range, one sentence ("" when there were none, or no model)."""
        c = self.compensator
        heat = c.temperature_drift if c is not None else None
        if heat is None or self._T_low > self._T_high:
            return ""
        return heat.outside(self._T_low, self._T_high) or ""

    def push(
        self,
        t_ns: int,
        wrench_sensor: NDArray[np.float64],
        R_base_sensor: NDArray[np.float64],
        p_base_sensor: NDArray[np.float64],
        extras: tuple[float, ...] = (),
    ) -> None:
        """One reading (stamp [ns], raw wrench, the sensor's orientation and origin when it was
        read, its extra channels): compensated into :attr:`ready`, or held back while the rate
        is measured."""
        if self._weigh is not None:
            self._held.append((t_ns, wrench_sensor, R_base_sensor, p_base_sensor, extras))
            span_ns = t_ns - self._held[0][0]
            if span_ns >= self._weigh[2] and len(self._held) >= MIN_RATE_READINGS:
                self._start_measured()
            return
        self._push(t_ns, wrench_sensor, R_base_sensor, p_base_sensor, extras)

    def finish(self, until_ns: int | None = None) -> None:
        """At the end: the readings still held back into :attr:`ready`, the rate measured from
        them (``until_ns``: only those stamped before it [ns], the ones a session logs)."""
        if until_ns is not None:
            self._held = [h for h in self._held if h[0] < until_ns]
        if self._weigh is not None and self._held:
            self._start_measured()

    def _push(
        self,
        t_ns: int,
        wrench_sensor: NDArray[np.float64],
        R_base_sensor: NDArray[np.float64],
        p_base_sensor: NDArray[np.float64],
        extras: tuple[float, ...],
    ) -> None:
        contact = self.contact(t_ns, wrench_sensor, R_base_sensor, extras)
        tracker, load = self.bias_tracker, self.load
        self.ready.append(
            Compensated(
                t_ns,
                wrench_sensor,
                contact,
                R_base_sensor,
                p_base_sensor,
                tracker is not None and tracker.updated,
                tuple(load.update(t_ns * 1e-9)) if load is not None else (),
                extras,
            )
        )

    def _start_measured(self) -> None:
        assert self._weigh is not None
        calibration, settings, _ = self._weigh
        stamps = [h[0] for h in self._held]
        span_s = (stamps[-1] - stamps[0]) * 1e-9
        if len(stamps) >= 2 and span_s > 0.0:
            rate = (len(stamps) - 1) / span_s
            source = f"measured from {len(stamps)} readings over {span_s:.2f} s"
        else:  # one stamp: no step can be confirmed (two calls at least), the rate is moot
            rate, source = settings.rate_Hz, "too few readings to measure: the default"
        compensator = OnlineLoadCompensator(calibration, replace(settings, rate_Hz=rate))
        self.compensator, self.load = compensator, LoadTracker(compensator)
        self._temperature_at = _temperature_index(compensator, self.extra_channels)
        self.rate_source = source
        self._weigh = None
        held, self._held = self._held, []
        for reading in held:
            self._push(*reading)


def _accelerometer_indices(extra_channels: tuple[str, ...]) -> tuple[int, int, int]:
    """Where a reading's acceleration (x, y, z) is among its extras; a sensor that reports
    none is a ParameterError."""
    wanted = IMU_CHANNELS[:3]
    if not all(name in extra_channels for name in wanted):
        reported = ", ".join(extra_channels) if extra_channels else "none"
        raise ParameterError(
            f"accelerometer: the sensor reports no acceleration ({', '.join(wanted)}; its extra "
            f"channels: {reported})",
            field="accelerometer",
        )
    x, y, z = (extra_channels.index(name) for name in wanted)
    return x, y, z


def _temperature_index(
    compensator: GravityCompensator | None, extra_channels: tuple[str, ...]
) -> int | None:
    """Where a reading's temperature is among its extras when the compensator needs it, else
    None; a compensator that needs it with a sensor that reports none is a ParameterError."""
    if compensator is None or not compensator.needs_temperature:
        return None
    if TEMPERATURE_CHANNEL not in extra_channels:
        reported = ", ".join(extra_channels) if extra_channels else "none"
        raise ParameterError(
            "the calibration's bias follows the sensor's temperature (bias_drift temperature), "
            f"but the sensor reports no {TEMPERATURE_CHANNEL} (its extra channels: "
            f"{reported}); use a sensor that reports its temperature, or a calibration "
            "without the temperature model"
        )
    return extra_channels.index(TEMPERATURE_CHANNEL)
