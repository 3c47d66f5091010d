"""The ``replay://FILE`` backend: a recorded CSV played back at its own time stamps.

The file is a sample CSV with a ``t`` column [s] (``ftcomp record``, ``ftcomp sim collect``) or
a log of ``ftcomp stream``: columns ``t``, ``fx..tz`` (the raw reading, sensor frame), and, for
a pose, one orientation encoding of ``R_base_sensor`` (``qx,qy,qz,qw`` | ``rx,ry,rz`` |
``alpha_deg,beta_deg,gamma_deg``) with optional ``px,py,pz`` [m]. Rows must be in time order.

- ``--sensor replay://FILE`` replays the readings: each becomes readable when the session's
  clock passes its time stamp.
- ``--robot replay://FILE`` replays the poses (the recorded sensor frame as its TCP: use the
  identity mount) and is the session's clock; it cannot move. With ``--sensor`` the same file,
  both run on one clock.

Options: ``speed=1`` plays at the recorded pace (2: twice as fast). The clock starts at the
file's first stamp when the backend opens; once it passes the last stamp, reading raises
:class:`EndOfReplayError`.
"""

from __future__ import annotations

import csv
import math
import time
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ftcomp.errors import HardwareError, InputFileError, ParameterError
from ftcomp.frames import ENCODING_COLUMNS, rotation_from_encoding
from ftcomp.hardware.pacing import RateLimiter, on_host_clock
from ftcomp.hardware.protocols import (
    ClockName,
    NothingToClose,
    PoseSample,
    Robot,
    WrenchSample,
    WrenchSensor,
)
from ftcomp.hardware.registry import Uri

__all__ = [
    "EndOfReplayError",
    "ReplayLog",
    "ReplayRobot",
    "ReplaySensor",
    "open_robot",
    "open_sensor",
]

_WRENCH = ("fx", "fy", "fz", "tx", "ty", "tz")


class EndOfReplayError(HardwareError):
    """The replayed recording has no more readings."""


class ReplayLog:
    """A recording in memory: stamps [ns], readings, and poses when the file has them.

    Raises:
        InputFileError: no such file, missing columns, a bad cell, or stamps out of order.
    """

    def __init__(self, path: str) -> None:
        self.path = path
        try:
            with Path(path).open(encoding="utf-8-sig", newline="") as handle:
                rows = list(csv.reader(handle))
        except OSError as exc:
            raise InputFileError(f"{path}: cannot read ({exc.strerror or exc})") from None
        if len(rows) < 2:
            raise InputFileError(f"{path}: needs a header and at least one row")
        header = [h.strip() for h in rows[0]]
        index = {name: i for i, name in enumerate(header)}
        for name in ("t", *_WRENCH):
            if name not in index:
                raise InputFileError(f"{path}, header: missing column {name!r} (replay needs t)")
        encoding = next(
            (e for e, cols in ENCODING_COLUMNS.items() if all(c in index for c in cols)), None
        )
        cols = ["t", *_WRENCH, *(ENCODING_COLUMNS[encoding] if encoding else ())]
        has_p = all(c in index for c in ("px", "py", "pz"))
        cols += ["px", "py", "pz"] if has_p else []
        data = np.empty((len(rows) - 1, len(cols)))
        for r, cells in enumerate(rows[1:]):
            for c, name in enumerate(cols):
                try:
                    data[r, c] = float(cells[index[name]])
                except (ValueError, IndexError):
                    raise InputFileError(
                        f"{path}, row {r + 1}, column {name!r}: not a number"
                    ) from None
        if not np.all(np.isfinite(data)):
            raise InputFileError(f"{path}: a cell is not finite")
        self.t_ns = np.round(data[:, 0] * 1e9).astype(np.int64)
        if np.any(np.diff(self.t_ns) <= 0):
            raise InputFileError(f"{path}: column 't' must increase from row to row")
        self.wrench = data[:, 1:7]
        self.R: NDArray[np.float64] | None = None
        if encoding is not None:
            k = len(ENCODING_COLUMNS[encoding])
            self.R = (
                rotation_from_encoding(encoding, data[:, 7 : 7 + k]).as_matrix().reshape(-1, 3, 3)
            )
        self.p = data[:, -3:] if has_p else np.zeros((len(data), 3))
        self.period_s = float(np.median(np.diff(self.t_ns))) * 1e-9 if len(data) > 1 else 1e-3

    def index_at(self, t_ns: int) -> int:
        """The last row stamped at or before ``t_ns`` (-1 before the first)."""
        return int(np.searchsorted(self.t_ns, t_ns, side="right")) - 1


class _Clock:
    """File time running at ``speed`` times the host's monotonic clock from its first reading
    (not from when it was made: setting up a loop must not skip the recording's first rows)."""

    def __init__(self, start_ns: int, speed: float) -> None:
        self.start_ns, self.speed = start_ns, speed
        self._host0_ns: int | None = None

    @property
    def host0_ns(self) -> int:
        """The host's monotonic time [ns] at the recording's first stamp."""
        if self._host0_ns is None:
            self._host0_ns = time.monotonic_ns()
        return self._host0_ns

    def now_ns(self) -> int:
        host0 = self.host0_ns
        return self.start_ns + round((time.monotonic_ns() - host0) * self.speed)


class ReplayRobot(NothingToClose):
    """Replays the recorded poses; the session's clock is the recording's."""

    clock_name: ClockName = "replay"
    pose_known = True

    def __init__(self, log: ReplayLog, speed: float) -> None:
        if log.R is None:
            raise InputFileError(
                f"{log.path}: no orientation columns: replay:// as a robot needs the poses"
            )
        self.log, self.speed = log, speed
        self.clock = _Clock(int(log.t_ns[0]), speed)
        self.pacer = RateLimiter(log.period_s / speed, name=type(self).__name__, log_overruns=False)
        #: The sensor replaying the same file on this clock, if any: the replay ends when it
        #: has handed out every row, not when the clock passes the end (a loop that stalled
        #: near the end would otherwise lose the last rows).
        self.linked_sensor: ReplaySensor | None = None

    @property
    def control_period_s(self) -> float:
        """The recording's median sample interval [s]."""
        return self.log.period_s

    def __enter__(self) -> ReplayRobot:
        """Start the clock at the first stamp."""
        self.clock = _Clock(int(self.log.t_ns[0]), self.speed)
        return self

    def now_ns(self) -> int:
        """The recording's time now [ns]."""
        return self.clock.now_ns()

    def pose(self) -> PoseSample:
        """The recorded pose at the clock's time."""
        now = self.now_ns()
        i = max(self.log.index_at(now), 0)
        linked = self.linked_sensor
        past_end = now > self.log.t_ns[-1] + round(self.log.period_s * 1e9)
        if past_end and not (linked is not None and linked.pending):
            raise EndOfReplayError(f"{self.log.path}: end of the recording")
        assert self.log.R is not None
        return PoseSample(now, self.log.p[i], self.log.R[i])

    def move_pose(
        self, p_base_tcp: NDArray[np.float64], R_base_tcp: NDArray[np.float64], duration_s: float
    ) -> None:
        """A recording cannot move.

        Raises:
            HardwareError: always.
        """
        raise HardwareError(f"replay://{self.log.path} cannot move")

    def settle(self, max_duration_s: float) -> float:
        """Nothing to wait for."""
        return 0.0

    def command_twist(self, twist_base: NDArray[np.float64]) -> None:
        """Commands are ignored (a dry run over a recording)."""

    def wait_cycle(self) -> None:
        """Wait for the next recorded period."""
        self.pacer.sleep()

    def stop(self) -> None:
        """Nothing moves."""


class ReplaySensor(NothingToClose):
    """Replays the recorded readings on the session's clock."""

    def __init__(self, log: ReplayLog, clock: _Clock, *, host_stamps: bool) -> None:
        self.log, self.clock, self.host_stamps = log, clock, host_stamps
        self._next = 0
        self._streaming = False  # read_new was called: hand out every row before the end

    def _sample(self, i: int) -> WrenchSample:
        t_ns = int(self.log.t_ns[i])
        if self.host_stamps:  # when the host's clock passes it: host0 + (t - t0) / speed
            clock = self.clock
            t_ns = clock.host0_ns + round((t_ns - clock.start_ns) / clock.speed)
        return WrenchSample(t_ns, self.log.wrench[i])

    @property
    def pending(self) -> bool:
        """Whether a caller of :meth:`read_new` has rows still to receive."""
        return self._streaming and self._next < len(self.log.t_ns)

    def _index(self) -> int:
        now = self.clock.now_ns()
        if now > self.log.t_ns[-1] + round(self.log.period_s * 1e9) and not self.pending:
            raise EndOfReplayError(f"{self.log.path}: end of the recording")
        return max(self.log.index_at(now), 0)

    def read(self) -> WrenchSample:
        """The last reading stamped at or before now."""
        return self._sample(self._index())

    def read_new(self) -> list[WrenchSample]:
        """Every reading that became due since the previous call (after the end of the
        recording: the rows not yet handed out, then :class:`EndOfReplayError`)."""
        self._streaming = True
        i = self._index()
        out = [self._sample(k) for k in range(self._next, i + 1)]
        self._next = i + 1
        return out


def _path_and_speed(uri: Uri) -> tuple[str, float]:
    path = uri.text[len(uri.scheme) + 3 :].split("?", 1)[0]
    if not path:
        raise ParameterError(f"{uri.text!r}: give the file, e.g. replay://log.csv")
    options = uri.reader()
    speed = options.number("speed", 1.0)
    options.done()
    assert speed is not None
    if not (math.isfinite(speed) and 0.01 <= speed <= 100.0):
        raise ParameterError(f"{uri.text!r}: speed must be in [0.01, 100], got {speed:g}")
    return path, speed


def open_robot(uri: Uri) -> Robot:
    """The recorded poses as a robot."""
    path, speed = _path_and_speed(uri)
    return ReplayRobot(ReplayLog(path), speed)


def open_sensor(uri: Uri, robot: Robot | None) -> WrenchSensor:
    """The recorded readings, on the replay robot's clock when it replays the same file, else
    mapped onto the host's monotonic clock from now."""
    path, speed = _path_and_speed(uri)
    if isinstance(robot, ReplayRobot) and Path(robot.log.path).resolve() == Path(path).resolve():
        robot.linked_sensor = ReplaySensor(robot.log, robot.clock, host_stamps=False)
        return robot.linked_sensor
    if robot is not None and not on_host_clock(robot):
        raise ParameterError(f"{uri.text!r}: replay with this robot's clock is not possible")
    log = ReplayLog(path)
    return ReplaySensor(log, _Clock(int(log.t_ns[0]), speed), host_stamps=True)
