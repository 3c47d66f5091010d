"""Shared fixtures: the paper's data and synthetic readings from known parameters."""

from __future__ import annotations

import contextlib
import os
import zlib
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcomp.model import GravityModel
from ftcomp.samples import Samples

PAPER_CSV = Path(str(resources.files("ftcomp") / "data" / "huang2020_table1_2.csv"))
PUBLISHED_JSON = Path(str(resources.files("ftcomp") / "data" / "huang2020_published_results.json"))

#: A tool like the paper's gripper (its published values), on a noticeably tilted base.
TRUE_MODEL = GravityModel(
    3.153,
    np.array([0.0001, -0.0003, 0.047]),
    np.array([-0.8613, 1.1015, 0.1976]),
    np.array([-0.0002, -0.0605, 0.0255]),
    tilt_U_rad=np.radians(-0.204),
    tilt_V_rad=np.radians(-0.129),
)
#: Noise of one reading: about the paper's residual level per pose mean, times sqrt(20).
FORCE_NOISE_N = 0.08
TORQUE_NOISE_NM = 0.006


def synthetic_samples(
    rng: np.random.Generator,
    model: GravityModel = TRUE_MODEL,
    *,
    poses: int = 9,
    readings: int = 20,
    rotations: Rotation | None = None,
) -> Samples:
    """Readings at random orientations with seeded Gaussian noise, grouped by pose id."""
    R = (rotations if rotations is not None else Rotation.random(poses, rng=rng)).as_matrix()
    R = np.repeat(R.reshape(-1, 3, 3), readings, axis=0)
    clean = model.predict(R)
    noise = rng.normal(size=clean.shape) * np.repeat([FORCE_NOISE_N, TORQUE_NOISE_NM], 3)
    pose_ids = np.repeat(np.arange(1, len(R) // readings + 1), readings).astype(str)
    return Samples(
        wrench_sensor=clean + noise, R_base_sensor=R, encoding="quaternion", pose=pose_ids
    )


@pytest.fixture
def rng(request: pytest.FixtureRequest) -> np.random.Generator:
    """A generator seeded from the test's name, so every test has its own fixed stream."""
    return np.random.default_rng(zlib.crc32(request.node.name.encode()))


@pytest.fixture(scope="session")
def identified_tool() -> GravityModel:
    """The gripper identified on the simulated placement cell (tilted base, paper poses, joint
    method): what every placement test compensates with. The truth only scores the runs."""
    from ftcomp.sim.placement_cell import SimPlacementCell

    cell = SimPlacementCell("sponge", 0.5, seed=99, identify_samples_per_pose=200)
    assert cell.identified is not None
    return cell.identified.model


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist's own hook reads the groups
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """How pytest-xdist's workers (``-n``, ``--dist loadgroup``) share the tests.

    - The ``live`` tests that judge timing (a twin, a client's real-time loop, a ROS 2 graph)
      run one at a time, all on one worker: two at once on the two cores starved each other's
      streams (a Net F/T twin silent past pynetft's 100 ms time-out).
    - The tests that share a module-scoped fixture go to one worker, so that it is set up
      once, not once per worker that draws one of them.
    - Every other test, an ``untimed`` live one included, goes to whichever worker is free.
    """
    if not getattr(config.option, "loadgroup", False):
        return
    for item in items:
        if _timed_live(item):
            item.add_marker(pytest.mark.xdist_group("live"))
            continue
        # The fixtures' scopes are known only from pytest's own (private) fixture info.
        info = getattr(item, "_fixtureinfo", None)
        if info is None:
            continue
        shared = sorted(
            name
            for name, defs in info.name2fixturedefs.items()
            if defs and defs[-1].scope in ("module", "package", "class")
        )
        if not shared:
            continue
        callspec = getattr(item, "callspec", None)
        indices = callspec.indices if callspec is not None else {}
        key = item.nodeid.split("::")[0] + "".join(
            f"[{name}={indices[name]}]" for name in shared if name in indices
        )
        item.add_marker(pytest.mark.xdist_group(key))


@pytest.hookimpl(tryfirst=True)  # before any fixture of the test: its processes inherit it
def pytest_runtest_setup(item: pytest.Item) -> None:
    """Under ``-n 2 --dist loadgroup``, a test that is not ``live`` runs at nice 19, a live one
    at nice 0 (its twin and client raise their own loops to real-time priority).

    The live tests keep real time and use about one of the two cores (twin and client: 1077 s
    of CPU over a 1213 s run in one process, the rest of the tests included); at nice 0 the
    other worker's tests took a share of the core a live test's threads needed that do not run
    at real-time priority (the FR3 twin 18 % missed periods). ``SCHED_IDLE`` instead stalled
    a twin 3.2 s: a starved idle task holds what it holds (a kernel lock, a pipe's buffer) for
    as long as normal tasks want the cores; at nice 19 it still gets its 1.5 % share.
    """
    if os.environ.get("PYTEST_XDIST_WORKER") is None:
        return
    if not getattr(item.config.option, "loadgroup", False):
        return
    live = item.get_closest_marker("live") is not None
    with contextlib.suppress(PermissionError):
        os.setpriority(os.PRIO_PROCESS, 0, 0 if live else 19)


def _timed_live(item: pytest.Item) -> bool:
    """A live test whose checks judge timing: not marked ``untimed``."""
    live, untimed = (item.get_closest_marker(name) for name in ("live", "untimed"))
    return live is not None and untimed is None


@pytest.hookimpl(trylast=True)
def pytest_collection_finish(session: pytest.Session) -> None:
    """Stop a run whose groups pytest-xdist would ignore (a grouped test's node id carries its
    group once xdist's own hook has run): the live tests would run two at a time."""
    if not getattr(session.config.option, "loadgroup", False):
        return
    lost = [
        item.nodeid
        for item in session.items
        if item.get_closest_marker("xdist_group") is not None and "@" not in item.nodeid
    ]
    if lost:
        raise pytest.UsageError(
            f"pytest-xdist ignored the test groups ({lost[0]} has none): this pytest and "
            "pytest-xdist do not work together (pyproject.toml pins them)"
        )
