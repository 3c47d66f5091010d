"""The structure docs/architecture.md promises: no package cycle, short modules, a lazy CLI."""

from __future__ import annotations

import ast
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import ftcomp

SRC = Path(ftcomp.__file__).parent
MAX_LINES = 400


def _module_name(path: Path) -> str:
    parts = path.relative_to(SRC.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _package(module: str) -> str:
    """``ftcomp.sim.cell`` -> ``ftcomp.sim``; a top-level module stands for itself."""
    return ".".join(module.split(".")[:2])


def _runtime_imports(path: Path) -> set[str]:
    """ftcomp modules imported at module level (not under ``if TYPE_CHECKING``)."""
    found = set()
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("ftcomp"):
            if node.module == "ftcomp":
                found.update(f"ftcomp.{alias.name}" for alias in node.names)
            else:
                found.add(node.module)
    return found


def test_packages_import_each_other_without_a_cycle() -> None:
    graph: dict[str, set[str]] = defaultdict(set)
    for path in SRC.rglob("*.py"):
        source = _package(_module_name(path))
        for target in map(_package, _runtime_imports(path)):
            if target != source:
                graph[source].add(target)

    def reaches(start: str, goal: str) -> bool:
        seen, todo = set(), [start]
        while todo:
            for nxt in graph.get(todo.pop(), ()):
                if nxt == goal:
                    return True
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
        return False

    cyclic = sorted(p for p in graph if reaches(p, p))
    assert not cyclic, f"packages in an import cycle: {cyclic}"


def test_no_module_is_over_400_lines() -> None:
    long = {
        str(p.relative_to(SRC)): n
        for p in SRC.rglob("*.py")
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def test_importing_the_cli_loads_no_command_and_no_numpy() -> None:
    code = (
        "import sys, ftcomp.cli; "
        "print(sorted(m for m in sys.modules if m.startswith(('ftcomp.cli.', 'numpy', 'mujoco'))))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "[]", out
