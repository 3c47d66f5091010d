"""Bad input to ``ftcomp twin`` is one line and exit 2, before anything is bound."""

from __future__ import annotations

import pytest

pytest.importorskip("mujoco")

from ftcomp.cli import main

BASE = ("twin", "--robot-host", "127.0.0.5", "--sensor-host", "127.0.0.6", "--seconds", "1")


pytestmark = pytest.mark.live


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("--robot-host", "10.0.0.1"), "outside 127.0.0.0/8"),
        (("--robot", "ur10"), "--robot: unknown 'ur10'"),
        (("--surface", "glass"), "--surface must be one of none, sponge, book, got 'glass'"),
        (("--load-kg", "100"), "--load-kg must be"),
        (("--tcp-offset-mm", "1,2"), "--tcp-offset-mm"),
        (("--tcp-offset-mm", "0,0,nan"), "--tcp-offset-mm must be"),
        (("--tcp-rotvec-rad", "4,0,0"), "--tcp-rotvec-rad must be"),
    ],
)
def test_twin_refuses_bad_input_in_one_line_with_exit_2(
    args: tuple[str, ...], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([*BASE, *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and message in err and err.count("\n") == 1, err
