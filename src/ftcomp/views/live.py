"""What a live command's ``--log FILE.mcap`` and ``--view HOST:PORT`` plug into its session.

:func:`session_observers` opens the observers a live session (``ftcomp stream``, ``record``,
``run``) hands its log rows and events to (:class:`~ftcomp.session.log.LogObserver`): an MCAP
log (:class:`~ftcomp.ros2.mcap_log.SessionMcapLog`) and a live Foxglove WebSocket view
(:class:`~ftcomp.views.foxglove_view.FoxgloveView`), and closes them when the block ends
(the session closes them too; closing twice is harmless). The session runs them on a worker
thread, so neither costs the control loop a period.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

from ftcomp.session.log import LogObserver

__all__ = ["session_observers"]


@contextlib.contextmanager
def session_observers(
    log: Path | None,
    view: str | None,
    *,
    overwrite: bool = False,
    base_frame: str = "base",
    sensor_frame: str = "ft_sensor",
    control_frame: str = "base",
) -> Iterator[list[LogObserver]]:
    """The observers asked for, closed when the block ends.

    Args:
        log: the MCAP file to write (None: none).
        view: ``HOST:PORT`` to serve the live view on (None: none).
        overwrite: replace an existing ``log``.
        base_frame, sensor_frame: frame ids of the robot's base and of the sensor.
        control_frame: frame id of the controller's wrench error.

    Raises:
        ParameterError: the log exists (without ``overwrite``), a bad address, or the port is
            taken.
    """
    observers: list[LogObserver] = []
    try:
        if log is not None:
            from ftcomp.ros2.mcap_log import SessionMcapLog

            observers.append(
                SessionMcapLog(
                    log,
                    base_frame=base_frame,
                    sensor_frame=sensor_frame,
                    control_frame=control_frame,
                    overwrite=overwrite,
                )
            )
        if view is not None:
            from ftcomp.views.foxglove_view import FoxgloveView

            observers.append(
                FoxgloveView(
                    view,
                    base_frame=base_frame,
                    sensor_frame=sensor_frame,
                    control_frame=control_frame,
                )
            )
        yield observers
    finally:
        for observer in observers:
            observer.close()
