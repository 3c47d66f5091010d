"""Backends by URI: ``--robot URI`` and ``--sensor URI`` pick the hardware.

A URI names a backend by its scheme, a host where it has one, and options as query parameters::

    sim://?tilt_deg=-0.204,-0.129&load_kg=0.5&grasp=1     the MuJoCo cell (robot and sensor)
    sim://                                                 the sensor of the sim:// robot

Each scheme is a device of :mod:`ftcomp.hardware.devices` (the registry), whose backend is a
module path and a factory, imported only when a URI asks for it (the CLI starts fast and a
backend's client library is needed only by those who use it). A robot's
factory takes the parsed :class:`Uri`; a sensor's also gets the already opened robot, so a
sensor that lives in the robot (the simulated cell, a UR's built-in sensor) attaches to it and
shares its clock.

Every option a backend does not know is an error naming the URI and the valid options.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any
from urllib.parse import parse_qsl, urlsplit

from ftcomp.errors import ParameterError
from ftcomp.hardware.devices import Kind, devices, load_target

if TYPE_CHECKING:
    from ftcomp.hardware.protocols import Robot, WrenchSensor

__all__ = [
    "Options",
    "Uri",
    "open_robot",
    "open_sensor",
    "parse_uri",
]


@dataclass(frozen=True)
class Uri:
    """A parsed backend URI.

    Attributes:
        text: the URI as given (for messages).
        scheme: the backend (``sim``, ...).
        host: the device's address, or ``""``.
        port: the port, or None.
        path: the path (a topic or a file), or ``""``.
        options: the query parameters, each once.
    """

    text: str
    scheme: str
    host: str = ""
    port: int | None = None
    path: str = ""
    options: Mapping[str, str] = field(default_factory=dict)

    def reader(self) -> Options:
        """The options, to be taken one by one (see :class:`Options`)."""
        return Options(self)


def parse_uri(text: str) -> Uri:
    """Split ``scheme://host:port/path?key=value&...``.

    Raises:
        ParameterError: no scheme, a bad port, or an option given twice.
    """
    if "://" not in text:
        raise ParameterError(f"{text!r}: not a backend URI; expected SCHEME://..., e.g. sim://")
    parts = urlsplit(text)
    try:
        port = parts.port
    except ValueError:
        raise ParameterError(f"{text!r}: the port is not a number in 0..65535") from None
    options: dict[str, str] = {}
    for key, value in parse_qsl(parts.query, keep_blank_values=True):
        if key in options:
            raise ParameterError(f"{text!r}: option {key!r} given twice")
        options[key] = value
    return Uri(text, parts.scheme.lower(), parts.hostname or "", port, parts.path, options)


class Options:
    """Takes a URI's options one at a time, typed; :meth:`done` rejects any left over."""

    def __init__(self, uri: Uri) -> None:
        self._uri = uri
        self._left = dict(uri.options)
        self._known: list[str] = []

    def _take(self, key: str) -> str | None:
        self._known.append(key)
        return self._left.pop(key, None)

    def _bad(self, key: str, value: str, expected: str) -> ParameterError:
        return ParameterError(f"{self._uri.text!r}: option {key}={value!r}: expected {expected}")

    def text(self, key: str, default: str, choices: tuple[str, ...] = ()) -> str:
        """A text option (one of ``choices`` if given)."""
        value = self._take(key)
        if value is None:
            return default
        if choices and value not in choices:
            raise self._bad(key, value, "one of " + ", ".join(choices))
        return value

    def floats(self, key: str, default: tuple[float, ...]) -> tuple[float, ...]:
        """Comma-separated finite numbers, as many as ``default`` has."""
        value = self._take(key)
        if value is None:
            return default
        try:
            numbers = tuple(float(v) for v in value.split(","))
        except ValueError:
            numbers = ()
        if len(numbers) != len(default) or not all(math.isfinite(v) for v in numbers):
            raise self._bad(key, value, f"{len(default)} comma-separated finite numbers")
        return numbers

    def number(self, key: str, default: float | None) -> float | None:
        """One finite number."""
        value = self._take(key)
        if value is None:
            return default
        try:
            number = float(value)
        except ValueError:
            raise self._bad(key, value, "a number") from None
        if not math.isfinite(number):
            raise self._bad(key, value, "a finite number")
        return number

    def positive(self, key: str, default: float) -> float:
        """One finite number > 0."""
        number = self.number(key, default)
        assert number is not None  # a default is given
        if not number > 0.0:
            raise ParameterError(f"{self._uri.text!r}: {key} must be > 0, got {number:g}")
        return number

    def integer(self, key: str, default: int) -> int:
        """A whole number."""
        value = self._take(key)
        if value is None:
            return default
        try:
            return int(value)
        except ValueError:
            raise self._bad(key, value, "a whole number") from None

    def flag(self, key: str, default: bool) -> bool:
        """``1/true/yes`` or ``0/false/no``."""
        value = self._take(key)
        if value is None:
            return default
        lowered = value.lower()
        if lowered in ("1", "true", "yes"):
            return True
        if lowered in ("0", "false", "no"):
            return False
        raise self._bad(key, value, "1 or 0")

    def done(self) -> None:
        """Raise on any option nobody asked for."""
        if self._left:
            key = sorted(self._left)[0]
            valid = ", ".join(self._known) or "none"
            raise ParameterError(
                f"{self._uri.text!r}: unknown option {key!r} for {self._uri.scheme}://; "
                f"valid: {valid}"
            )


def _factory(uri: Uri, kind: Kind) -> Any:
    known = {d.scheme: d for d in devices(kind)}
    device = known.get(uri.scheme)
    if device is None:
        valid = ", ".join(f"{scheme}://" for scheme in known)
        raise ParameterError(f"{uri.text!r}: no {kind} backend {uri.scheme}://; valid: {valid}")
    return load_target(device.backend)


def open_robot(text: str) -> Robot:
    """The robot a URI names (not yet entered: use it in a ``with`` block)."""
    uri = parse_uri(text)
    robot: Robot = _factory(uri, "robot")(uri)
    return robot


def open_sensor(text: str, robot: Robot | None = None) -> WrenchSensor:
    """The sensor a URI names; ``robot`` is the session's robot, if any (see the module doc)."""
    uri = parse_uri(text)
    sensor: WrenchSensor = _factory(uri, "sensor")(uri, robot)
    return sensor
