"""Lazy exports for a package (PEP 562): a name is imported from its module when first used.

A package lists ``_WHERE = {name: "ftcomp.module", ...}`` and sets
``__getattr__ = lazy_exports(__name__, _WHERE)``, so importing one of its modules (a command
that only builds its options, the device registry) loads nothing else of the package.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["lazy_exports"]


def lazy_exports(package: str, where: Mapping[str, str]) -> Callable[[str], Any]:
    """The package's ``__getattr__``: ``name`` from the module ``where`` names for it."""

    def getattr_(name: str) -> Any:
        if name not in where:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(where[name]), name)

    return getattr_
