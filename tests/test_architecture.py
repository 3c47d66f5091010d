"""The layers docs/architecture.md promises, counting every import.

Every module under src/ftcomp is parsed with :mod:`ast` and every import counted: at module
level, inside functions, under ``if TYPE_CHECKING``, relative ones resolved, and
``importlib.import_module("ftcomp...")`` with a literal name. The checker is a set of functions
of a source tree (the ``ftcomp`` package folder), so a test can run it on a copy with deliberate
violations and see each one reported. Findings are strings:

- ``upward: A imports B (layer i -> j)``: nothing imports a layer above its own (:data:`LAYERS`;
  ``from ftcomp import __version__``, the package's metadata, is not an import of the facade:
  every ftcomp module runs ``ftcomp/__init__.py`` first anyway);
- ``unplaced: A``: a module in no layer (a new package must be placed in :data:`LAYERS`);
- ``private: A imports B._x``: no module imports another module's private name or module;
- ``cycle: A, B, ...``: no import cycle among modules (the modules of one strongly connected
  component);
- ``all: P ...``: every package ``__init__.py`` has a literal ``__all__`` of strings, sorted as
  ruff sorts it (RUF022: constants, then classes, then the rest, each in natural order).
"""

from __future__ import annotations

import ast
import re
import shutil
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "ftcomp"

#: Module prefix -> layer, bottom (1) to top. A module is in the layer of its longest prefix;
#: the facade ``ftcomp`` (the package's ``__init__``) is matched by its own name only.
LAYERS: dict[str, int] = {
    # 1. base: errors, constants, arrays, frames, the model, samples, kinematics, records, extras
    "ftcomp.arrays": 1,
    "ftcomp.calibration_record": 1,
    "ftcomp.config_fields": 1,
    "ftcomp.constants": 1,
    "ftcomp.errors": 1,
    "ftcomp.extras": 1,
    "ftcomp.frames": 1,
    "ftcomp.chain_ik": 1,
    "ftcomp.kinematics": 1,
    "ftcomp.lazy": 1,
    "ftcomp.model": 1,
    "ftcomp.samples": 1,
    # 2. file formats, device protocols and backends
    "ftcomp.hardware": 2,
    "ftcomp.io": 2,
    # 3. identification, compensation, control, the paper's numbers
    "ftcomp.calibration": 3,
    "ftcomp.compensation": 3,
    "ftcomp.control": 3,
    "ftcomp.paper": 3,
    # 4. the simulated cell (extra [sim]) and ROS 2
    "ftcomp.ros2": 4,
    "ftcomp.sim": 4,
    # 5. live sessions as library calls
    "ftcomp.session": 5,
    # the twin serves devices from the simulated cell (a session of its own)
    "ftcomp.twin": 5,
    # 6. plots and html pages (extra [report])
    "ftcomp.views": 6,
    # 7. the facade: lazy exports of library names
    "ftcomp": 7,
    # 8. applications; the library never imports them
    "ftcomp.__main__": 8,
    "ftcomp.cli": 8,
    "ftcomp.huang2020": 8,
}


@dataclass(frozen=True)
class Import:
    """One import: ``importer`` imports the module ``target`` (and from it ``name``, if any)."""

    importer: str
    target: str
    name: str | None
    line: int


def module_files(package_dir: Path) -> dict[str, Path]:
    """Every module of the package in ``package_dir``, by dotted name (a package by its own)."""
    out = {}
    for path in sorted(package_dir.rglob("*.py")):
        parts = path.relative_to(package_dir.parent).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def _ours(module: str, root: str) -> bool:
    return module == root or module.startswith(root + ".")


def _resolve(node: ast.ImportFrom, module: str, is_package: bool) -> str:
    """The absolute module a ``from ... import`` names (relative ones resolved)."""
    if not node.level:
        return node.module or ""
    package = module.split(".") if is_package else module.split(".")[:-1]
    base = package[: len(package) - (node.level - 1)]
    return ".".join([*base, *([node.module] if node.module else [])])


def _is_import_module(node: ast.Call) -> bool:
    func = node.func
    name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", None)
    return name == "import_module"


def imports(package_dir: Path) -> Iterator[Import]:
    """Every import of the package's own modules, wherever it stands in a module."""
    modules = module_files(package_dir)
    root = package_dir.name
    for module, path in modules.items():
        is_package = path.name == "__init__.py"
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if _ours(alias.name, root):
                        yield Import(module, alias.name, None, node.lineno)
            elif isinstance(node, ast.ImportFrom):
                target = _resolve(node, module, is_package)
                if not _ours(target, root):
                    continue
                for alias in node.names:
                    submodule = f"{target}.{alias.name}"
                    if submodule in modules:  # ``from package import module``
                        yield Import(module, submodule, None, node.lineno)
                    else:
                        yield Import(module, target, alias.name, node.lineno)
            elif isinstance(node, ast.Call) and _is_import_module(node) and node.args:
                arg = node.args[0]
                if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                    name = arg.value
                    if _ours(name, root):
                        yield Import(module, name, None, node.lineno)


def layer_of(module: str) -> int | None:
    """The layer of ``module`` by the longest prefix in :data:`LAYERS`, or None."""
    if module in LAYERS:
        return LAYERS[module]
    root = module.split(".")[0]
    prefixes = [p for p in LAYERS if p != root and module.startswith(p + ".")]
    return LAYERS[max(prefixes, key=len)] if prefixes else None


def _dunder(name: str) -> bool:
    return name.startswith("__") and name.endswith("__")


def _private(part: str) -> bool:
    return part.startswith("_") and not _dunder(part)


def layer_findings(package_dir: Path) -> set[str]:
    """``upward``, ``unplaced`` and ``private`` findings."""
    found = {f"unplaced: {m}" for m in module_files(package_dir) if layer_of(m) is None}
    root = package_dir.name
    for imp in imports(package_dir):
        if imp.target == root and imp.name is not None and _dunder(imp.name):
            continue  # the package's metadata (``__version__``): not the facade's exports
        low, high = layer_of(imp.importer), layer_of(imp.target)
        if high is None:
            found.add(f"unplaced: {imp.target}")
        elif low is not None and high > low:
            found.add(f"upward: {imp.importer} imports {imp.target} (layer {low} -> {high})")
        if any(_private(part) for part in imp.target.split(".")):
            found.add(f"private: {imp.importer} imports {imp.target}")
        if imp.name is not None and _private(imp.name):
            found.add(f"private: {imp.importer} imports {imp.target}.{imp.name}")
    return found


def cycle_findings(package_dir: Path) -> set[str]:
    """One ``cycle`` finding per set of modules that import each other, directly or not
    (a strongly connected component of the import graph, Tarjan's algorithm)."""
    graph: dict[str, set[str]] = {m: set() for m in module_files(package_dir)}
    for imp in imports(package_dir):
        if imp.target in graph and imp.target != imp.importer:
            graph[imp.importer].add(imp.target)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found = set()

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.add(f"cycle: {', '.join(sorted(component))}")

    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 10 * len(graph) + 100))
    try:
        for v in sorted(graph):
            if v not in index:
                visit(v)
    finally:
        sys.setrecursionlimit(limit)
    return found


def ruff_sort_key(name: str) -> tuple[int, list[int | str]]:
    """RUF022's isort-style order: SCREAMING_CASE, then CamelCase, then the rest; natural
    order within each (``x2`` before ``x10``)."""
    kind = 0 if len(name) > 1 and name.isupper() else 1 if name[:1].isupper() else 2
    return kind, [int(p) if p.isdigit() else p for p in re.split(r"(\d+)", name)]


def _literal_all(tree: ast.Module) -> list[str] | None:
    """The strings of a module-level ``__all__ = [...]`` (or annotated), None if not literal."""
    for node in tree.body:
        if isinstance(node, ast.Assign):
            targets, value = node.targets, node.value
        elif isinstance(node, ast.AnnAssign) and node.value is not None:
            targets, value = [node.target], node.value
        else:
            continue
        if not any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
            continue
        if not isinstance(value, (ast.List, ast.Tuple)):
            return None
        names = [
            e.value for e in value.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)
        ]
        return names if len(names) == len(value.elts) else None
    return None


def all_findings(package_dir: Path) -> set[str]:
    """``all`` findings: a package ``__init__`` without a literal or a sorted ``__all__``."""
    found = set()
    for module, path in module_files(package_dir).items():
        if path.name != "__init__.py":
            continue
        names = _literal_all(ast.parse(path.read_text(encoding="utf-8")))
        if names is None:
            found.add(f"all: {module} has no literal __all__")
        elif names != sorted(names, key=ruff_sort_key):
            found.add(f"all: {module} has an unsorted __all__")
    return found


def findings(package_dir: Path) -> set[str]:
    """Everything the layer rules find in the package at ``package_dir``."""
    return layer_findings(package_dir) | cycle_findings(package_dir) | all_findings(package_dir)


@pytest.fixture(scope="module")
def real_findings() -> set[str]:
    return findings(SRC)


@pytest.mark.parametrize("kind", ["upward", "unplaced", "private", "cycle", "all"])
def test_the_library_keeps_its_layers(kind: str, real_findings: set[str]) -> None:
    found = sorted(f for f in real_findings if f.startswith(kind + ":"))
    assert not found, "\n".join(found)


def test_io_and_compensation_use_calibration_records_without_importing_calibration() -> None:
    """Calibration produces the records (ftcomp.calibration_record); io reads and writes them,
    compensation applies them: neither imports calibration, though compensation shares its
    layer."""
    found = {
        f"{imp.importer} imports {imp.target}"
        for imp in imports(SRC)
        if imp.importer.startswith(("ftcomp.io.", "ftcomp.compensation."))
        and _ours(imp.target, "ftcomp.calibration")
    }
    assert not found, sorted(found)


#: Deliberate violations: file (relative to the package) -> source, and what each must cause.
SCRATCH = {
    "io/scratch_upward.py": "def main():\n    from ftcomp.cli import main\n\n    return main\n",
    "io/scratch_typing.py": (
        "from typing import TYPE_CHECKING\n\nif TYPE_CHECKING:\n    import ftcomp.session\n"
    ),
    "io/scratch_relative.py": "from ..calibration import identify\n",
    "calibration/scratch_private.py": "from ftcomp.calibration.methods import _linear_lstsq\n",
    "compensation/scratch_private_module.py": "import ftcomp.compensation._hidden\n",
    "io/scratch_a.py": "def f():\n    from ftcomp.io import scratch_b\n",
    "io/scratch_b.py": (
        "from typing import TYPE_CHECKING\n\nif TYPE_CHECKING:\n    from .scratch_a import f\n"
    ),
    "scratch_top.py": "X = 1\n",
    "sim/scratch_facade.py": "from ftcomp import Calibration, __version__\n",
    "io/scratch_package/__init__.py": '"""No __all__."""\n',
    "io/scratch_unsorted/__init__.py": '__all__ = ["b", "a"]\n',
    "hardware/scratch_dynamic.py": (
        "import importlib\n\nimportlib.import_module('ftcomp.control.controller')\n"
    ),
}
EXPECTED = {
    "upward: ftcomp.io.scratch_upward imports ftcomp.cli (layer 2 -> 8)",
    "upward: ftcomp.io.scratch_typing imports ftcomp.session (layer 2 -> 5)",
    "upward: ftcomp.io.scratch_relative imports ftcomp.calibration.identify (layer 2 -> 3)",
    "upward: ftcomp.hardware.scratch_dynamic imports ftcomp.control.controller (layer 2 -> 3)",
    "private: ftcomp.calibration.scratch_private imports ftcomp.calibration.methods._linear_lstsq",
    "private: ftcomp.compensation.scratch_private_module imports ftcomp.compensation._hidden",
    "cycle: ftcomp.io.scratch_a, ftcomp.io.scratch_b",
    "unplaced: ftcomp.scratch_top",
    "upward: ftcomp.sim.scratch_facade imports ftcomp (layer 4 -> 7)",
    "all: ftcomp.io.scratch_package has no literal __all__",
    "all: ftcomp.io.scratch_unsorted has an unsorted __all__",
}


def test_the_checker_reports_each_deliberate_violation(tmp_path: Path) -> None:
    tree = tmp_path / "ftcomp"
    shutil.copytree(SRC, tree, ignore=shutil.ignore_patterns("__pycache__", "*.csv", "*.json"))
    before = findings(tree)
    assert before == findings(SRC)  # the copy is the tree
    for name, text in SCRATCH.items():
        path = tree / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    assert findings(tree) - before == EXPECTED


def test_a_package_reexporting_its_modules_public_names_is_fine(tmp_path: Path) -> None:
    tree = tmp_path / "ftcomp"
    (tree / "io").mkdir(parents=True)
    (tree / "__init__.py").write_text("__all__ = []\n", encoding="utf-8")
    (tree / "io" / "__init__.py").write_text(
        "from ftcomp.io.reader import read\nfrom .writer import write\n\n"
        '__all__ = ["read", "write"]\n',
        encoding="utf-8",
    )
    (tree / "io" / "reader.py").write_text("def read(): ...\ndef _parse(): ...\n")
    (tree / "io" / "writer.py").write_text("from ftcomp.errors import Error\ndef write(): ...\n")
    (tree / "errors.py").write_text("class Error(Exception): ...\n")
    assert findings(tree) == set()


def test_ruff_sort_key_orders_constants_classes_then_the_rest() -> None:
    names = [
        "paper_poses",
        "PUBLISHED",
        "Samples",
        "R_base_sensor_from",
        "x10",
        "x2",
        "__version__",
    ]
    assert sorted(names, key=ruff_sort_key) == [
        "PUBLISHED",
        "R_base_sensor_from",
        "Samples",
        "__version__",
        "paper_poses",
        "x2",
        "x10",
    ]


def test_importing_the_cli_loads_no_command_and_no_numpy() -> None:
    code = (
        "import sys, ftcomp.cli; "
        "print(sorted(m for m in sys.modules if m.startswith(('ftcomp.cli.', 'numpy', 'mujoco'))))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "[]", out
