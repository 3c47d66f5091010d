"""``ftcomp run``: the compliant loop on sim:// with a recorded calibration; dry runs; faults."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ftcomp.cli import main
from ftcomp.constants import STANDARD_GRAVITY_MPS2

LOAD_KG = 0.5
#: The placement's acceptance band [N] (the issue's): the final force error along z.
BAND_N = 0.05
PLACE = "sim://?seed=4&surface=sponge&load_kg=0.5&grasp=1&clearance_mm=2"


@pytest.fixture(scope="module")
def recorded_calibration(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The empty gripper recorded on sim:// at the paper's poses and calibrated, by the CLI."""
    folder = tmp_path_factory.mktemp("calibration")
    samples, cal = folder / "s.csv", folder / "cal.json"
    record = ["record", "--robot", "sim://?seed=4", "--sensor", "sim://", "--poses", "paper"]
    assert main([*record, "--samples-per-pose", "200", "--move-s", "1", "-o", str(samples)]) == 0
    assert main(["calibrate", str(samples), "-o", str(cal), "--json"]) == 0
    return cal


def _log(path: Path) -> dict[str, np.ndarray]:
    header = path.read_text().splitlines()[0].split(",")
    data = np.genfromtxt(path, delimiter=",", skip_header=1, ndmin=2)
    return {name: data[:, i] for i, name in enumerate(header)}


def test_run_places_the_load_on_the_sponge_with_the_recorded_calibration(
    tmp_path: Path, recorded_calibration: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run.csv"
    code = main(
        [
            *("run", "--robot", PLACE, "--sensor", "sim://", "-c", str(recorded_calibration)),
            *("--control", "admittance", "--axes", "z", "--frame", "base"),
            *("--k1", "0.1", "--k2", "1", "--settle-band-N", str(BAND_N), "-o", str(out)),
        ]
    )
    printed = capsys.readouterr().out
    assert code == 0 and printed.splitlines()[-1].startswith("settled"), printed
    log = _log(out)
    weight = LOAD_KG * STANDARD_GRAVITY_MPS2
    # At the start the gripper carries the load (contact force along base z = -its weight; the
    # first 0.1 s: 0.125 N counts, and the load still sways from the move there) ...
    assert abs(log["ez"][:100].mean() + weight) < 0.3
    # ... at the end the sponge does: the force error over the last 0.3 s is within the band.
    last = log["t_s"] >= log["t_s"][-1] - 0.3
    assert abs(log["ez"][last].mean()) <= BAND_N
    # It got there by lowering the load (2 mm gap plus the sponge's give), nothing sideways.
    descent_mm = (log["pz"][0] - log["pz"][-1]) * 1e3
    assert 2.0 < descent_mm < 10.0
    assert np.all(log["sent"] == 1.0)


def test_dry_run_computes_commands_but_moves_nothing(
    tmp_path: Path, recorded_calibration: Path
) -> None:
    out = tmp_path / "run.csv"
    code = main(
        [
            *("run", "--robot", PLACE, "--sensor", "sim://", "-c", str(recorded_calibration)),
            *("--control", "admittance", "--dry-run", "--seconds", "0.3", "-o", str(out)),
        ]
    )
    assert code == 0
    log = _log(out)
    assert np.all(log["sent"] == 0.0)
    assert np.mean(log["vz"]) < -1e-4  # it would lower the hanging load ...
    # ... but the arm stayed (it settles by ~0.1 mm after the grasp; sent, the law would have
    # lowered it about a millimetre in 0.3 s).
    assert np.ptp(log["pz"]) < 2e-4


def test_a_protective_stop_stops_the_robot_and_exits_1_with_the_reason(
    tmp_path: Path, recorded_calibration: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run.csv"
    code = main(
        [
            *("run", "--robot", PLACE, "--sensor", "sim://", "-c", str(recorded_calibration)),
            *("--control", "admittance", "--max-force-N", "2", "-o", str(out)),
        ]
    )
    err = capsys.readouterr().err
    assert code == 1 and "protective stop: force_limit" in err, err
    assert len(_log(out)["t_s"]) <= 2  # at once: the hanging load is 4.9 N


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--sensor", "netft://127.0.0.9"], "cannot share a session with this robot"),
        (["--sensor", "sim://", "--k2", "-1"], "--k2 must be >= 0"),
        (["--sensor", "sim://", "--axes", "q"], "unknown selection axis 'q'"),
        (["--sensor", "sim://", "--rebias-s", "-1"], "--rebias-s must be in (0, 60] s"),
    ],
)
def test_bad_run_configurations_are_one_line_and_exit_2(
    extra: list[str],
    message: str,
    tmp_path: Path,
    recorded_calibration: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = ["run", "--robot", "sim://", "-c", str(recorded_calibration), "--control", "admittance"]
    assert main([*args, *extra, "-o", str(tmp_path / "run.csv")]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1, err


def test_run_needs_an_existing_calibration(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["run", "--robot", "sim://", "--sensor", "sim://", "--control", "admittance"]
    assert main([*args, "-c", str(tmp_path / "none.json"), "-o", str(tmp_path / "r.csv")]) == 2
    assert "none.json" in capsys.readouterr().err


def test_the_cli_offers_every_law_of_the_library() -> None:
    from ftcomp.cli import build_parser
    from ftcomp.session.run import LAWS

    commands = next(a for a in build_parser(["run"])._actions if a.dest == "command")
    run_parser = commands.choices["run"]
    law = next(a for a in run_parser._actions if a.dest == "law")
    assert tuple(law.choices) == LAWS  # read from AdmittanceConfig's field, never copied


def test_two_ctrl_c_end_run_with_the_robot_stopped_and_the_summary(
    tmp_path: Path,
    recorded_calibration: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The first Ctrl-C in the loop, the second while the robot is being stopped and
    disconnected (the cell's exit): once that second one cut the exit short and run said only
    ``error: interrupted``."""
    import signal

    from ftcomp.sim.cell import SimCell

    cycles = {"n": 0}
    wait_cycle, leave = SimCell.wait_cycle, SimCell.__exit__

    def pressed_in_the_loop(self: SimCell) -> None:
        cycles["n"] += 1
        if cycles["n"] == 200:
            signal.raise_signal(signal.SIGINT)
        wait_cycle(self)

    def pressed_while_closing(self: SimCell, *exc: object) -> None:
        signal.raise_signal(signal.SIGINT)
        leave(self, *exc)  # type: ignore[arg-type]

    monkeypatch.setattr(SimCell, "wait_cycle", pressed_in_the_loop)
    monkeypatch.setattr(SimCell, "__exit__", pressed_while_closing)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal
    try:
        code = main(
            [
                *("run", "--robot", PLACE, "--sensor", "sim://", "-c", str(recorded_calibration)),
                *("--control", "admittance", "--axes", "z", "--seconds", "5"),
                *("-o", str(tmp_path / "run.csv")),
            ]
        )
    finally:
        signal.signal(signal.SIGINT, before)
    err = capsys.readouterr().err
    assert code == 130, err
    assert "Ctrl-C again to abandon it" in err
    assert "the robot was stopped" in err and "cycles in" in err, err
