"""The lean install: without MuJoCo and matplotlib the core commands run, and a command that
needs an extra says in one line which one to install (exit code 2).

Each command runs in its own interpreter where ``import mujoco``, ``import matplotlib`` and
``import pytransform3d`` (the extra ``urdf``, which requires matplotlib) fail (a
``sys.meta_path`` finder raises ``ModuleNotFoundError`` for them, as after a fresh
``pip install ftcomp``), so nothing can have imported them before.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from conftest import PAPER_CSV

sys.path.insert(0, str(Path(__file__).parent / "ros2"))
from simbag import WRENCH_TOPIC, recording, write_bag

#: Runs ``ftcomp ARGS`` (or, with ``--python CODE``, the code) with MuJoCo, matplotlib and
#: pytransform3d impossible to import.
LEAN = """
import sys


class NotInstalled:
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in ("mujoco", "matplotlib", "pytransform3d"):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None


sys.meta_path.insert(0, NotInstalled())
if sys.argv[1] == "--python":
    exec(sys.argv[2])
    sys.exit(0)
from ftcomp.cli import main

sys.exit(main(sys.argv[1:]))
"""


def lean(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """Run ``ftcomp *args`` in a fresh interpreter without MuJoCo and matplotlib."""
    return subprocess.run(
        [sys.executable, "-c", LEAN, *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


def test_mujoco_and_matplotlib_cannot_be_imported_there() -> None:
    for module in ("mujoco", "matplotlib.figure", "pytransform3d.urdf"):
        done = lean("--python", f"import {module}")
        assert done.returncode == 1 and "ModuleNotFoundError" in done.stderr, done.stderr


@pytest.fixture(scope="module")
def bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small MCAP bag of the simulated cell (written here, where MuJoCo is installed)."""
    return write_bag(recording(), tmp_path_factory.mktemp("bag") / "rosbag2", storage="mcap")


def test_calibrate_compensate_export_and_import_bag_run_without_the_extras(
    tmp_path: Path, bag: Path
) -> None:
    cal, out = tmp_path / "cal.json", tmp_path / "compensated.csv"
    params, samples = tmp_path / "params.yaml", tmp_path / "from_bag.csv"
    frames = ["--base-frame", "base", "--sensor-frame", "ft_sensor"]
    commands = [
        ["calibrate", PAPER_CSV, "--method", "paper", "-o", cal],
        ["compensate", PAPER_CSV, "-c", cal, "-o", out],
        ["export", "ros2", cal, "-o", params, "--world-frame", "base", "--sensor-frame", "ft"],
        ["import-bag", bag, "--wrench-topic", WRENCH_TOPIC, *frames, "-o", samples],
        ["calibrate", samples, "-o", tmp_path / "cal_from_bag.json"],
    ]
    for args in commands:
        done = lean(*args)
        assert done.returncode == 0, f"ftcomp {args[0]}: {done.stderr}"
    for path in (cal, out, params, samples, tmp_path / "cal_from_bag.json"):
        assert path.stat().st_size > 0, path


def test_import_bag_with_a_urdf_names_the_urdf_extra(tmp_path: Path, bag: Path) -> None:
    urdf = tmp_path / "robot.urdf"
    urdf.write_text(recording().urdf)
    args = ["import-bag", bag, "--wrench-topic", WRENCH_TOPIC, "--base-frame", "base"]
    route = ["--urdf", urdf, "--joint-states", "/joint_states"]
    done = lean(*args, "--sensor-frame", "ft_sensor", *route, "-o", tmp_path / "s.csv")
    assert done.returncode == 2, done.stderr
    assert done.stderr == (
        "error: reading a URDF needs pytransform3d: pip install -e '.[urdf]' (in the ftcomp "
        "clone)\n"
    )


@pytest.mark.parametrize(
    ("args", "line"),
    [
        (
            ["demo", "--quick"],
            "error: ftcomp demo needs MuJoCo and matplotlib: pip install -e '.[demo]' "
            "(in the ftcomp clone)",
        ),
        (
            ["sim", "collect", "-o", "x.csv"],
            "error: ftcomp sim collect needs MuJoCo: pip install -e '.[sim]' (in the ftcomp clone)",
        ),
        (
            ["sim", "place", "--surface", "sponge", "--control", "admittance", "--out", "run"],
            "error: ftcomp sim place needs MuJoCo and matplotlib: pip install -e '.[demo]' "
            "(in the ftcomp clone)",
        ),
        (
            ["poses", "design", "--count", "3", "--robot", "sim://", "-o", "poses.csv"],
            "error: the simulated cell (ftcomp sim, sim://) needs MuJoCo: "
            "pip install -e '.[sim]' (in the ftcomp clone)",
        ),
    ],
)
def test_a_command_that_needs_an_extra_names_it_in_one_line(
    args: list[str], line: str, tmp_path: Path
) -> None:
    done = subprocess.run(
        [sys.executable, "-c", LEAN, *args],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
        cwd=tmp_path,
    )
    assert done.returncode == 2, done.stderr
    assert done.stderr == line + "\n"
    assert not list(tmp_path.iterdir())  # nothing written


def test_the_library_says_which_extra_it_needs() -> None:
    code = """
from ftcomp.errors import MissingExtraError
from ftcomp.hardware.registry import open_robot
import ftcomp.views, ftcomp.views.html, ftcomp.views.figures  # importable without matplotlib
for call, extra in ((lambda: open_robot("sim://"), "sim"),
                    (lambda: ftcomp.views.figures.new_figure(1.0, 1.0), "report")):
    try:
        call()
    except MissingExtraError as exc:
        assert f"pip install -e '.[{extra}]' (in the ftcomp clone)" in str(exc), exc
    else:
        raise AssertionError("no MissingExtraError")
"""
    done = lean("--python", code)
    assert done.returncode == 0, done.stderr
