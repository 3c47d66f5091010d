"""``ftcomp demo --quick``: every section runs, the report shows every figure, metrics hold."""

from __future__ import annotations

import contextlib
import io
import json
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest

from ftcomp.cli import main
from ftcomp.huang2020.demo import MARKER_FILE
from ftcomp.session.verdicts import VERDICTS
from views.headless_chromium import chromium_binary, measure_page


class _Images(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.sources: list[str] = []
        self.external: list[str] = []
        self.links: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        if tag == "img" and values.get("src"):
            self.sources.append(str(values["src"]))
        if tag == "a" and values.get("href"):
            self.links.append(str(values["href"]))
        for key in ("src", "href"):
            link = values.get(key) or ""
            if link.startswith(("http:", "https:", "//")):
                self.external.append(link)


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """The quick demo's folder and what it printed."""
    out = tmp_path_factory.mktemp("demo") / "out"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert main(["demo", "--quick", "--seed", "3", "--out", str(out)]) == 0
    return out, printed.getvalue()


@pytest.fixture(scope="module")
def demo_dir(demo_run: tuple[Path, str]) -> Path:
    return demo_run[0]


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
        "beyond_online_load.png",
        "beyond_fast_move.png",
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


def test_every_link_of_the_report_points_at_a_file_or_a_section(demo_dir: Path) -> None:
    parser = _Images()
    html = (demo_dir / "report.html").read_text()
    parser.feed(html)
    runs = [link for link in parser.links if link.startswith("placement/")]
    assert len(runs) == len(list((demo_dir / "placement").iterdir()))
    for link in parser.links:
        if link.startswith("#"):
            assert f'id="{link[1:]}"' in html, link
        else:
            assert (demo_dir / link).is_file(), link


def test_the_uncompensated_run_is_reported_as_pressed_everywhere(
    demo_run: tuple[Path, str],
) -> None:
    """Its sensed force settles in the band, but the true contact says pressed (issue 13)."""
    demo_dir, printed = demo_run
    run = json.loads((demo_dir / "metrics.json").read_text())["placement"][
        "admittance_uncompensated_sponge"
    ]
    assert abs(run["final_force_N"]) <= 0.05  # what the controller sees: nothing wrong
    # Pressed by about the tool's weight and the bias along gravity (3.153 N + 0.2 N).
    assert run["verdict"] == "pressed"
    assert run["true_press_N"] == pytest.approx(3.3, abs=0.5)
    assert run["true_press_N"] == pytest.approx(
        run["final_true_contact_N"] - run["load_weight_N"], abs=1e-9
    )
    saved = json.loads(
        (demo_dir / "placement" / "admittance_uncompensated_sponge" / "metrics.json").read_text()
    )
    assert saved["verdict"] == "pressed"
    # The report's table row, and the terminal's verdict table.
    html = (demo_dir / "report.html").read_text()
    row = re.search(r"<tr><td[^>]*><a [^>]*>admittance, uncompensated, sponge</a>.*?</tr>", html)
    assert row is not None and ">pressed<" in row.group(0)
    assert f"{run['true_press_N']:.3f}" in row.group(0)
    line = next(x for x in printed.splitlines() if "admittance_uncompensated_sponge" in x)
    assert "pressed" in line and f"{run['true_press_N']:+.3f}" in line


def test_every_run_has_a_verdict_and_the_compensated_runs_are_gentle(demo_dir: Path) -> None:
    place = json.loads((demo_dir / "metrics.json").read_text())["placement"]
    runs = {k: v for k, v in place.items() if isinstance(v, dict) and "verdict" in v}
    assert len(runs) >= 9 and all(r["verdict"] in VERDICTS for r in runs.values())
    for name in ("admittance_sponge", "admittance_book"):
        assert runs[name]["verdict"] == "placed gently", runs[name]["verdict_reason"]
    # Position-only on the sponge presses it; on the book the force limit stops it.
    assert runs["position_sponge"]["verdict"] == "pressed"
    assert runs["position_book"]["verdict"] == "stopped"


def test_every_published_result_is_judged_and_a_miss_says_why(
    demo_run: tuple[Path, str],
) -> None:
    demo_dir, printed = demo_run
    rows = json.loads((demo_dir / "metrics.json").read_text())["comparisons"]
    assert len(rows) >= 12
    for row in rows:
        assert row["paper"] and row["ours"] and row["note"], row
    missed = {row["quantity"] for row in rows if not row["reproduced"]}
    # Our sensor has no gain error and our book is stiffer than the paper's (see the notes).
    assert "Table 4 weighing error δc per load [%]" in missed
    assert "position-only final force, book [N]" in missed
    html = (demo_dir / "report.html").read_text()
    assert html.count(">no<") >= len(missed)  # flagged in the summary and in its section
    assert printed.count("not reproduced") >= len(missed)


def test_the_report_renders_in_a_browser_without_overflow_at_1280_and_800_px(
    demo_dir: Path,
) -> None:
    if chromium_binary() is None:
        pytest.skip("chromium not installed (Debian: apt-get install chromium); CI installs it")
    pages = measure_page(demo_dir / "report.html", [1280, 800])
    for width, page in pages.items():
        assert len(page["images"]) == 9
        broken = [i["src"] for i in page["images"] if not i["loaded"] or i["naturalWidth"] <= 0]
        assert not broken, f"{width} px: images that did not load: {broken}"
        assert page["viewport"] == width
        assert page["scrollWidth"] <= width, f"{width} px: the page scrolls sideways"
        assert not page["overflowing"], f"{width} px: {page['overflowing'][:5]}"
