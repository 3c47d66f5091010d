"""Every name a package exports exists (mink once shipped names in __all__ that did not)."""

from __future__ import annotations

import importlib
import pkgutil

import ftcomp


def test_every_exported_name_exists_in_every_module() -> None:
    for info in pkgutil.walk_packages(ftcomp.__path__, prefix="ftcomp."):
        if info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        for name in getattr(module, "__all__", []):
            assert hasattr(module, name), f"{info.name}.__all__ names missing {name!r}"


def test_all_lists_are_sorted() -> None:
    for info in pkgutil.walk_packages(ftcomp.__path__, prefix="ftcomp."):
        if info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        exported = list(getattr(module, "__all__", []))
        assert exported == sorted(exported), f"{info.name}.__all__ is not sorted"
