"""A robot and a sensor added from a module of their own, with no other file changed: the
command line, the twin and the conformance suite pick them up (``FTCOMP_DEVICES``).

The module (``toy_devices.py`` beside this file, copied to a temporary folder under another
name so that nothing imports it by accident) declares a toy arm and a toy F/T sensor, each a
live backend and a twin face. The conformance suite pairs each with the first face of the
other kind; asked for the grid of every pair (``FTCOMP_CONFORMANCE_PAIRS=grid``), it is run on
the toy pair: record at designed poses, calibrate, stream, the faces' faults (its placements
are left to the real pairs: the same ``run`` through the same faces as the faults).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("mujoco")

HERE = Path(__file__).resolve().parent
MODULE = "ftcomp_toy_devices_under_test"


pytestmark = pytest.mark.live


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    folder = tmp_path_factory.mktemp("toy")
    shutil.copy(HERE / "toy_devices.py", folder / f"{MODULE}.py")
    env = dict(os.environ)
    env["FTCOMP_DEVICES"] = MODULE
    env["PYTHONPATH"] = os.pathsep.join(
        filter(None, [str(folder), str(HERE.parent), env.get("PYTHONPATH", "")])
    )
    return env


def _ftcomp(env: dict[str, str], *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "ftcomp", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
        check=False,
    )


def test_the_command_line_offers_the_new_devices(env: dict[str, str]) -> None:
    twin = _ftcomp(env, "twin", "--help")
    assert twin.returncode == 0, twin.stderr
    help_text = " ".join(twin.stdout.split())
    assert "toybot, a toy arm" in help_text and "toyft, a toy F/T sensor" in help_text
    assert "toybot-silent (toybot: no more state lines)" in help_text
    record = _ftcomp(env, "record", "--help")
    assert "toybot://HOST" in record.stdout and "toyft://HOST" in record.stdout
    # without the module named, nothing of it is there
    plain = {k: v for k, v in env.items() if k != "FTCOMP_DEVICES"}
    assert "toybot" not in _ftcomp(plain, "twin", "--help").stdout
    # a fault of a face not served is refused in one line
    refused = _ftcomp(
        env, "twin", "--robot-host", "127.0.0.5", "--sensor-host", "127.0.0.6",
        "--fault", "toybot-silent", "--seconds", "1",
    )  # fmt: skip
    assert refused.returncode == 2 and refused.stderr.count("\n") == 1, refused.stderr
    assert "--fault: 'toybot-silent' is declared by neither ur5e nor netft" in refused.stderr


SUITE = str(HERE / "test_conformance.py")


def _collected(env: dict[str, str]) -> set[str]:
    """The conformance suite's test ids (what is in brackets) with ``env``."""
    collected = subprocess.run(
        [sys.executable, "-m", "pytest", SUITE, "--collect-only", "-q", "-p", "no:cacheprovider",
         "-n", "0"],
        capture_output=True, text=True, env=env, timeout=120, check=False, cwd=HERE.parent.parent,
    )  # fmt: skip
    return set(re.findall(r"\[([^\]]+)\]", collected.stdout))


def test_the_conformance_suite_runs_every_pair_and_the_toy_pair_passes(
    env: dict[str, str],
) -> None:
    # By default each new face with the first face of the other kind ...
    star = {i.split("-")[0] + "-" + i.split("-")[1] for i in _collected(env)}
    assert {"ur5e-toyft", "toybot-netft"} <= star and "toybot-toyft" not in star, star
    # ... and with the grid asked for, every robot face with every sensor face.
    env = {**env, "FTCOMP_CONFORMANCE_PAIRS": "grid"}
    ids = _collected(env)
    for pair in ("ur5e-netft", "ur5e-toyft", "toybot-netft", "toybot-toyft"):
        assert any(i.startswith(pair) for i in ids), (pair, sorted(ids))
    # each face's faults once: the toy sensor's with the first robot face, the toy arm's with
    # the first sensor face
    assert "ur5e-toyft-toyft-silent" in ids and "toybot-netft-toybot-silent" in ids
    assert "toybot-toyft-toyft-silent" not in ids
    run = subprocess.run(
        # in one process (-n 0): this test's worker is the live tests' one (conftest.py)
        [sys.executable, "-m", "pytest", SUITE, "-q", "-p", "no:cacheprovider", "-n", "0", "-k",
         "(toybot-toyft and not sponge) or ur5e-toyft-toyft-silent or toybot-netft-toybot-silent"],
        capture_output=True, text=True, env=env, timeout=600, check=False, cwd=HERE.parent.parent,
    )  # fmt: skip
    assert run.returncode == 0, run.stdout[-6000:] + run.stderr[-2000:]
    # record and calibrate, stream, the two faces' faults (each with its partner above); not
    # the placements, which ``run`` carries through the same faces as the faults (the sponge's
    # is every real pair's, the book's the first sensor face's), so the toy pair's would add
    # 8 s and prove nothing more
    assert re.search(r"\b4 passed, 1 skipped\b", run.stdout), run.stdout[-2000:]
