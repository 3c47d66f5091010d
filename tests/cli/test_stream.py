"""``ftcomp stream`` against the fake Net F/T (and the fake UR controller for a pose)."""

from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np
import pytest

from ftcomp.calibration.identify import calibrate
from ftcomp.cli import main
from ftcomp.io.calibration_json import save_calibration

from conftest import synthetic_samples

pytest.importorskip("pynetft")

from standins.launch import loopback_address, running, running_all
from standins.scenario import TOOL_MODEL, Scenario, rotvecs

#: The stand-in's rate [Hz] and how far a 2 s log may stray from it: the stand-in paces its
#: packets with sleep on a shared 2-core machine, the log counts arrivals in a 2 s window.
RATE_HZ = 1000.0
RATE_TOLERANCE = 0.05


pytestmark = pytest.mark.live


def _scenario(**options: object) -> Scenario:
    return Scenario(
        t0=time.monotonic(),
        rotvecs_base_tcp=rotvecs([(30.0, 20.0, 170.0)]),
        model=Scenario.model_fields(TOOL_MODEL),
        noise=[0.05, 0.002],
        seed=11,
        rate_hz=RATE_HZ,
        max_s=12.0,
        **options,  # type: ignore[arg-type]
    )


def _served(s: Scenario, n: int) -> np.ndarray:
    """What the stand-in serves at its first ``n`` sensor ticks [N, N*m] (one pose: the values
    depend only on the seeded noise, drawn once per tick)."""
    rng = np.random.default_rng(s.seed)
    p, R_tcp, _ = s.tcp_pose(0.0)
    w = s.gravity_model().predict(s.mount().sensor_pose(p, R_tcp.as_matrix())[1])
    w = w + rng.normal(size=(n, 6)) * np.repeat(s.noise, 3)  # as the stand-in, tick by tick
    return s.wrench_from_counts(s.counts(w))


def _log(path: Path) -> np.ndarray:
    return np.genfromtxt(path, delimiter=",", skip_header=1, ndmin=2)


def test_stream_logs_every_reading_at_the_stand_in_rate_with_the_values_it_served(
    tmp_path: Path, request: pytest.FixtureRequest, capsys: pytest.CaptureFixture[str]
) -> None:
    s = _scenario()
    host, out = loopback_address(request.node.name), tmp_path / "log.csv"
    with running("fake_netft", host, "49152", "8080", s.to_json()):
        code = main(
            [
                "stream",
                "--sensor",
                f"netft://{host}?http_port=8080&timeout_s=1",
                "--seconds",
                "2",
                "-o",
                str(out),
            ]
        )
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "lost 0 packets" in captured.out, captured.out
    rows = _log(out)
    assert abs(len(rows) / 2.0 - RATE_HZ) < RATE_TOLERANCE * RATE_HZ, len(rows)
    # Each row is one served tick, in order, to the counts' resolution (0.5 count).
    table = _served(s, round(RATE_HZ * s.max_s))
    resolution = s.wrench_from_counts(np.full(6, 0.5))  # half a count, in N and N*m
    first = np.flatnonzero(np.all(np.abs(table - rows[0, 1:7]) <= resolution, axis=1))
    assert len(first) == 1
    ticks = first[0] + np.arange(len(rows))  # consecutive: no packet was lost
    assert np.all(np.abs(table[ticks] - rows[:, 1:7]) <= resolution)
    assert np.all(np.diff(rows[:, 0]) > 0.0)


def test_stream_counts_injected_packet_loss_exactly(
    tmp_path: Path, request: pytest.FixtureRequest, capsys: pytest.CaptureFixture[str]
) -> None:
    s = _scenario(lose_every=50)
    host, out = loopback_address(request.node.name), tmp_path / "log.csv"
    with running("fake_netft", host, "49152", "8080", s.to_json()):
        assert (
            main(
                [
                    "stream",
                    "--sensor",
                    f"netft://{host}?http_port=8080&timeout_s=1",  # room for a loaded runner
                    "--seconds",
                    "1.5",
                    "-o",
                    str(out),
                ]
            )
            == 0
        )
    printed = capsys.readouterr().out
    match = re.search(r"lost (\d+) packets of (\d+) \(last RDT sequence (\d+)\)", printed)
    assert match is not None, printed
    lost, total, last = map(int, match.groups())
    assert lost == last // 50  # every 50th sequence number was dropped, and only those
    assert total == last


@pytest.mark.parametrize(
    ("fault", "message"),
    [("fault_after_s", "sensor fault serious_status"), ("silent_after_s", "sensor fault timeout")],
)
def test_stream_stops_with_a_clear_error_on_a_fault_or_silence_and_keeps_the_log(
    fault: str,
    message: str,
    tmp_path: Path,
    request: pytest.FixtureRequest,
    capsys: pytest.CaptureFixture[str],
) -> None:
    s = _scenario(**{fault: 0.8})
    host, out = loopback_address(request.node.name), tmp_path / "log.csv"
    with running("fake_netft", host, "49152", "8080", s.to_json()):
        code = main(
            [
                "stream",
                "--sensor",
                f"netft://{host}?http_port=8080&timeout_s=1",
                "--seconds",
                "10",
                "-o",
                str(out),
            ]
        )
    err = capsys.readouterr().err
    # Stopped by the fault (exit 1 and its name), not by the end of --seconds (exit 0).
    assert code == 1 and message in err, err
    assert err.count("\n") == 1 and err.startswith("error: ")
    rows = _log(out)
    # What arrived before the fault is kept, every reading of it: consecutive served ticks,
    # as many as the command says it logged, none from after the fault (0.8 s of streaming
    # at the stand-in's rate at most; fewer when connecting took a while on a busy machine).
    logged = re.search(r"logged (\d+) readings", err)
    assert logged is not None and int(logged.group(1)) == len(rows) > 0, err
    table = _served(s, round(RATE_HZ * s.max_s))
    resolution = s.wrench_from_counts(np.full(6, 0.5))
    first = np.flatnonzero(np.all(np.abs(table - rows[0, 1:7]) <= resolution, axis=1))
    assert len(first) == 1
    ticks = first[0] + np.arange(len(rows))
    assert np.all(np.abs(table[ticks] - rows[:, 1:7]) <= resolution)
    assert len(rows) <= 0.8 * RATE_HZ + 1


def test_bad_sensor_configurations_are_one_line_and_exit_2_in_bounded_time(
    tmp_path: Path, request: pytest.FixtureRequest, capsys: pytest.CaptureFixture[str]
) -> None:
    good = loopback_address(request.node.name, 1)
    odd = loopback_address(request.node.name, 2)
    nobody = loopback_address(request.node.name, 3)
    s = _scenario()
    cases = [
        (f"netft://{nobody}?http_port=8080&connect_timeout_s=1", "cannot read the sensor's"),
        (f"netft://{good}?http_port=8081&connect_timeout_s=1", "cannot read the sensor's"),
        (f"netft://{good}:40000?http_port=8080&connect_timeout_s=1", "no data within 1 s"),
        (f"netft://{odd}?http_port=8080&connect_timeout_s=1", "unknown force unit"),
        (f"netft://{good}?http_port=8080&units=si", "unknown option 'units'"),
        ("netft://", "give the sensor's address"),
    ]
    furlongs = _scenario(force_unit="furlong")
    with running_all(
        [
            ("fake_netft", (good, "49152", "8080", s.to_json())),
            ("fake_netft", (odd, "49152", "8080", furlongs.to_json())),
        ]
    ):
        for i, (uri, message) in enumerate(cases):
            code = main(["stream", "--sensor", uri, "--seconds", "1", "-o", str(tmp_path / f"{i}")])
            err = capsys.readouterr().err
            # The message names the limit that ended the wait (1 s, connect_timeout_s), so the
            # bound is the URI's, whatever the load: no second count is asserted here.
            assert code == 2 and message in err, (uri, err)
            assert err.count("\n") == 1 and err.startswith("error: "), err
            assert not (tmp_path / f"{i}").exists()


def test_compensation_without_a_pose_source_is_refused(
    tmp_path: Path, rng: np.random.Generator, capsys: pytest.CaptureFixture[str]
) -> None:
    cal = tmp_path / "cal.json"
    save_calibration(cal, calibrate(synthetic_samples(rng, TOOL_MODEL)))
    args = ["stream", "--sensor", "netft://127.0.0.9", "-c", str(cal), "--seconds", "1"]
    assert main([*args, "-o", str(tmp_path / "log.csv")]) == 2
    assert "compensation (-c) needs the sensor's pose" in capsys.readouterr().err
    fixed = ["--robot", "fixed://"]
    assert main([*args, *fixed, "-o", str(tmp_path / "log.csv")]) == 2
    assert "gives no pose to compensate with" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["stream", "run"])
def test_a_net_ft_biased_at_start_is_refused_with_a_calibration(
    command: str, tmp_path: Path, rng: np.random.Generator, capsys: pytest.CaptureFixture[str]
) -> None:
    """bias=1 zeroes the tool's weight; -c would subtract it again (fz = -G, silently)."""
    cal = tmp_path / "cal.json"
    save_calibration(cal, calibrate(synthetic_samples(rng, TOOL_MODEL)))
    out = tmp_path / "log.csv"
    args = [command, "--robot", "fixed://?rpy_deg=0,0,0", "-c", str(cal), "-o", str(out)]
    args += ["--control", "admittance", "--dry-run"] if command == "run" else []
    # 127.0.0.9: nobody answers there; the refusal comes before anything is opened
    assert main([*args, "--sensor", "netft://127.0.0.9?bias=1", "--seconds", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1, err
    assert "bias=1" in err and "ftcomp rebias" in err
    assert not out.exists()


def test_stream_with_the_ur_pose_compensates_the_stand_ins_tool_to_zero(
    tmp_path: Path, request: pytest.FixtureRequest, rng: np.random.Generator
) -> None:
    pytest.importorskip("rtde_receive")
    cal = tmp_path / "cal.json"
    save_calibration(cal, calibrate(synthetic_samples(rng, TOOL_MODEL, readings=200)))
    s = _scenario()
    ur, ft = loopback_address(request.node.name, 1), loopback_address(request.node.name, 2)
    out = tmp_path / "log.csv"
    with running_all(
        [("fake_ur", (ur, s.to_json())), ("fake_netft", (ft, "49152", "8080", s.to_json()))]
    ):
        code = main(
            [
                "stream",
                "--robot",
                f"ur://{ur}?timeout_s=2",
                "--sensor",
                f"netft://{ft}?http_port=8080&timeout_s=1",
                "-c",
                str(cal),
                "--seconds",
                "1",
                "-o",
                str(out),
            ]
        )
    assert code == 0
    rows = _log(out)
    header = out.read_text().splitlines()[0].split(",")
    contact = rows[:, header.index("cfx") : header.index("cfx") + 3]
    # The calibration (noise 0.08 N, 1800 readings) is good to ~0.01 N; the mean of ~1000
    # readings of 0.05 N noise to ~0.002 N: 0.05 N is several times both.
    assert np.all(np.abs(contact.mean(axis=0)) < 0.05)
    raw = rows[:, header.index("fx") : header.index("fx") + 3].mean(axis=0)
    assert abs(np.linalg.norm(raw - TOOL_MODEL.force_bias_N) - TOOL_MODEL.weight_N) < 0.01


def test_stream_on_the_simulated_cell_logs_every_tick_of_the_sensor(tmp_path: Path) -> None:
    out = tmp_path / "log.csv"
    argv = ["stream", "--robot", "sim://", "--sensor", "sim://", "--seconds", "0.3", "-o", str(out)]
    assert main(argv) == 0
    t = np.genfromtxt(out, delimiter=",", skip_header=1, ndmin=2)[:, 0]
    assert len(t) >= 0.25 * 1200  # 0.3 s of 1.2 kHz, less the first cycles' start-up
    np.testing.assert_allclose(np.diff(t), 1 / 1200, rtol=0, atol=2e-9)  # no tick lost
