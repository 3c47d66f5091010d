"""The one error hierarchy of ftcomp.

Every error a user can cause derives from :class:`FtcompError`; the CLI turns it into one line
``error: ...`` and exit code 2. Messages name the bad value, where it came from (file, row,
column, parameter) and what would be valid.
"""

from __future__ import annotations

__all__ = [
    "CalibrationFileError",
    "FtcompError",
    "HardwareError",
    "IdentificationError",
    "InputFileError",
    "MissingExtraError",
    "OrientationError",
    "ParameterError",
    "SimulationError",
    "UnreachablePoseError",
]


class FtcompError(Exception):
    """Base class of every error ftcomp raises on bad input or an impossible request.

    Attributes:
        fields: the config fields (or function arguments) at fault, as the message names them
            (``field="k1"`` or ``field=("track_bias", "online_load")``; empty: none). The CLI
            maps each back to the flag the user typed (:mod:`ftcomp.config_fields`): a library
            message names fields, never flags.
    """

    def __init__(self, message: str = "", *, field: str | tuple[str, ...] | None = None) -> None:
        super().__init__(message)
        self.fields: tuple[str, ...] = (field,) if isinstance(field, str) else tuple(field or ())


class ParameterError(FtcompError, ValueError):
    """A function or command-line parameter is out of its valid range or has the wrong shape."""


class InputFileError(FtcompError):
    """A sample file (CSV) cannot be used: missing columns, bad cells, wrong delimiter..."""


class CalibrationFileError(FtcompError):
    """A calibration file is unreadable, of an unknown format, incomplete or not finite."""


class OrientationError(FtcompError, ValueError):
    """An orientation cannot be interpreted (zero-norm quaternion, ambiguous encoding...)."""


class IdentificationError(FtcompError):
    """The calibration parameters cannot be identified from the given poses."""


class MissingExtraError(FtcompError, ImportError):
    """An optional dependency is not installed; the message names the extra that installs it
    (``pip install 'ftcomp[sim]'``)."""


class HardwareError(FtcompError):
    """A robot or sensor failed: unreachable, silent, disconnected, or reporting a fault."""


class SimulationError(FtcompError):
    """The simulated cell cannot do what was asked."""


class UnreachablePoseError(SimulationError):
    """Inverse kinematics found no joint configuration for a requested pose."""
