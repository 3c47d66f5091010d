"""The HTML report: escaping, links, judgements, and a page that fits 800 px in a real browser."""

from __future__ import annotations

from pathlib import Path

import pytest

from ftcomp.views.html import Figure, Link, Mark, Section, Table, render_report, write_report
from views.headless_chromium import chromium_binary, measure_page


def test_text_is_escaped_and_cells_keep_their_kind() -> None:
    table = Table(
        "a <caption>",
        ["run", "verdict", "value"],
        [[Link("run <1>", "placement/a&b/plot.png"), Mark("pressed", "bad"), "1 < 2"]],
        groups=[("", 1), ("both", 2)],
        text_columns=2,
    )
    page = render_report("t & t", ["intro <b>"], [Section("s", tables=[table], anchor="s")])
    assert "<b>" not in page.replace("<b>t", "")  # the intro's markup is escaped
    assert "intro &lt;b&gt;" in page and "1 &lt; 2" in page
    assert '<a href="placement/a&amp;b/plot.png">run &lt;1&gt;</a>' in page
    assert '<td class="bad text">pressed</td>' in page
    assert '<th class="group" colspan="2">both</th>' in page


def test_a_figure_shows_its_title_as_the_caption() -> None:
    page = render_report(
        "t", [], [Section("s", figures=[Figure("f.png", "Fig. 7: the title", "What to see.")])]
    )
    assert '<img src="f.png" alt="Fig. 7: the title">' in page
    assert "<b>Fig. 7: the title.</b> What to see." in page


def _browser() -> None:
    if chromium_binary() is None:
        pytest.skip("chromium not installed (Debian: apt-get install chromium); CI installs it")


def test_the_browser_check_sees_a_broken_image_and_an_overflow(tmp_path: Path) -> None:
    """The check the demo's report passes would fail a page that does not fit."""
    _browser()
    wide = Table("wide", ["x"], [["9" * 400]])  # one word, too long to wrap
    write_report(
        tmp_path / "bad.html",
        "bad",
        [],
        [Section("s", tables=[wide], figures=[Figure("no.png", "missing")])],
    )
    page = measure_page(tmp_path / "bad.html", [800])[800]
    assert page["images"] == [
        {
            "src": "no.png",
            "loaded": False,
            "naturalWidth": 0,
            "shownWidth": page["images"][0]["shownWidth"],
        }
    ]
    assert page["scrollWidth"] > 800 and page["overflowing"]


def test_long_text_and_wide_tables_wrap_to_fit_800_px(tmp_path: Path) -> None:
    _browser()
    words = " ".join(["compensation"] * 40)
    table = Table(  # as wide as the report's widest: seven columns of value ± standard error
        "many columns",
        [f"a long column header number {i}" for i in range(7)],
        [[words, *(f"{-12.5678 * i:+.4f} ± 0.0123 (not identified)" for i in range(6))]] * 3,
    )
    write_report(
        tmp_path / "r.html", "title " * 30, [words], [Section("s " * 20, [words], [table])]
    )
    for width, page in measure_page(tmp_path / "r.html", [1280, 800]).items():
        assert page["scrollWidth"] <= width and not page["overflowing"], (
            width,
            page["overflowing"][:3],
        )
