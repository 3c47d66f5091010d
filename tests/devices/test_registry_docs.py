"""The device table of docs/hardware.md is the registry's (:func:`device_table`), and the
registry's declarations hold together: one backend per scheme and kind, unique face names, every
backend and face importable by its ``"module:attribute"``."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from ftcomp.hardware.devices import device_table, devices, load_target, twin_faces

DOCS = Path(__file__).resolve().parents[2] / "docs" / "hardware.md"


def test_the_docs_device_table_is_the_registrys() -> None:
    text = DOCS.read_text()
    begin, end = "<!-- devices: begin -->\n", "<!-- devices: end -->"
    assert begin in text and end in text
    shown = text[text.index(begin) + len(begin) : text.index(end)]
    assert shown == device_table(), "regenerate with ftcomp.hardware.devices.device_table()"


def test_every_declaration_names_a_module_that_has_it() -> None:
    for device in devices():
        module = device.backend.partition(":")[0]
        assert importlib.util.find_spec(module) is not None, device.backend
        if device.twin is not None:
            if importlib.util.find_spec("mujoco") is None:
                pytest.skip("the twin's faces need MuJoCo")
            assert callable(load_target(device.twin.factory)), device.twin.factory
            if device.twin.arm is not None:
                assert load_target(device.twin.arm)() is not None


def test_schemes_and_face_names_are_unique_per_kind() -> None:
    for kind in ("robot", "sensor"):
        # A scheme declared twice is one family reached two ways (robotiq://HOST and
        # robotiq:///dev/ttyUSB0), through one backend and one extra.
        backends = {(d.scheme, d.backend, d.extra) for d in devices(kind)}
        assert len(backends) == len({d.scheme for d in devices(kind)})
        uris = [d.uri for d in devices(kind)]
        assert len(uris) == len(set(uris))
        assert all(d.kind == kind for d in twin_faces(kind).values())
