"""Every name a module exports imports (mink once shipped names in __all__ that did not).

A package's ``__all__`` may name its submodules (the package imports none of them, so that a
command loads only what it uses): those must import as ``package.name``. A module whose optional
dependency is not installed is skipped, saying which. The order of ``__all__`` is ruff's
business (RUF022) and the layer test's (tests/test_architecture.py).
"""

from __future__ import annotations

import importlib
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "ftcomp"


def _module_names() -> list[str]:
    names = []
    for path in sorted(SRC.rglob("*.py")):
        parts = path.relative_to(SRC.parent).with_suffix("").parts
        if parts[-1] != "__main__":
            names.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return names


@pytest.mark.parametrize("module_name", _module_names())
def test_every_exported_name_imports(module_name: str) -> None:
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name is None or exc.name.split(".")[0] == "ftcomp":
            raise
        pytest.skip(f"{module_name} needs the optional dependency {exc.name!r}")
    missing = []
    for name in getattr(module, "__all__", ()):
        if hasattr(module, name):
            continue
        try:  # a package's __all__ naming one of its submodules
            importlib.import_module(f"{module_name}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{module_name}.{name}":
                raise
            missing.append(name)
    assert not missing, f"{module_name}.__all__ names missing {missing}"
