"""``ftcomp demo --quick``: every section runs, the report shows every figure, metrics hold."""

from __future__ import annotations

import json
from html.parser import HTMLParser
from pathlib import Path

import pytest

from ftcomp.cli import main
from ftcomp.experiments.demo import MARKER_FILE


class _Images(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.sources: list[str] = []
        self.external: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        if tag == "img" and values.get("src"):
            self.sources.append(str(values["src"]))
        for key in ("src", "href"):
            link = values.get(key) or ""
            if link.startswith(("http:", "https:", "//")):
                self.external.append(link)


@pytest.fixture(scope="module")
def demo_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("demo") / "out"
    assert main(["demo", "--quick", "--seed", "3", "--out", str(out)]) == 0
    return out


def test_report_references_only_existing_non_empty_local_images(demo_dir: Path) -> None:
    parser = _Images()
    parser.feed((demo_dir / "report.html").read_text())
    assert set(parser.sources) == {
        "fig5_continuous_pose.png",
        "table3_relative_error.png",
        "table4_load_weights.png",
        "fig6_position_only.png",
        "fig7_compensation.png",
        "fig7_k13_sweep.png",
        "fig7_k23_sweep.png",
    }
    assert not parser.external
    for src in parser.sources:
        image = demo_dir / src
        assert image.is_file(), src
        assert image.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", src
        assert image.stat().st_size > 5000, src


def test_metrics_have_every_section_and_the_published_numbers(demo_dir: Path) -> None:
    metrics = json.loads((demo_dir / "metrics.json").read_text())
    assert {"calibration", "continuous_pose", "table3", "table4", "placement"} <= set(metrics)
    assert metrics["table3"]["published"]["mean"] == [1.99, 2.98, 0.27, 3.89, 3.34, 0.69]
    assert metrics["table4"]["published"]["computed"][0] == 1.033
    assert metrics["placement"]["published"]["stop_band_N"] == 0.05
    # The paper's data, paper method: the published tool weight.
    assert round(metrics["calibration"]["paper_data"]["tool_weight_N"], 3) == 3.153
    # The simulated truth is found within 3 standard errors by both methods.
    for method in ("paper", "joint"):
        assert max(metrics["calibration"]["truth_error_in_standard_errors"][method].values()) < 3


def test_demo_meets_the_simulation_and_control_targets(demo_dir: Path) -> None:
    metrics = json.loads((demo_dir / "metrics.json").read_text())
    bare = metrics["calibration"]["no_gripper"]
    assert (
        abs(bare["identified_sensing_end_weight_N"] - bare["true_sensing_end_weight_N"])
        < 3 * bare["std_error_N"]
    )
    place = metrics["placement"]
    for surface in ("sponge", "book"):
        run = place[f"admittance_{surface}"]
        assert run["placed"], surface
        assert abs(run["final_force_N"]) <= 0.05
        assert run["peak_press_N"] <= 0.3
    assert place["position_book"]["peak_press_N"] >= 1.0
    assert (
        not place["admittance_uncompensated_sponge"]["placed"]
        or place["admittance_uncompensated_sponge"]["descent_mm"]
        > place["admittance_sponge"]["descent_mm"]
    )


def test_every_run_leaves_its_csv(demo_dir: Path) -> None:
    for name in (
        "calibration_samples.csv",
        "calibration_no_gripper_samples.csv",
        "continuous_pose.csv",
        "table4_load_weights.csv",
        "calibration.json",
    ):
        assert (demo_dir / name).stat().st_size > 0, name
    runs = list((demo_dir / "placement").iterdir())
    assert len(runs) >= 9
    for run in runs:
        assert (run / "timeseries.csv").stat().st_size > 0
        assert json.loads((run / "metrics.json").read_text())["placed"] in (True, False)


def test_demo_refuses_a_folder_it_did_not_write(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "thesis.tex").write_text("precious")
    assert main(["demo", "--quick", "--out", str(tmp_path)]) == 2
    assert "folder exists with files the demo did not write" in capsys.readouterr().err
    assert (tmp_path / "thesis.tex").read_text() == "precious"
    assert not (tmp_path / MARKER_FILE).exists()
