"""Every name a package exports exists (mink once shipped names in __all__ that did not).

The order of ``__all__`` is ruff's business (RUF022, isort-style).
"""

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
