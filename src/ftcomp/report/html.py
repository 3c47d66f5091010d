"""A self-contained HTML report: sections of text, tables and PNG figures lying beside it.

The page has no scripts and no external resources, so it opens offline in any browser; figures
are referenced by relative path (``<img src="fig.png">``) from the report's folder.
"""

from __future__ import annotations

import html
import os
from collections.abc import Sequence
from dataclasses import dataclass, field

from ftcomp.io.atomic import atomic_write_text

__all__ = ["Figure", "Section", "Table", "render_report", "write_report"]


@dataclass(frozen=True)
class Table:
    """A table: a caption, column headers and rows of already formatted cells."""

    caption: str
    header: Sequence[str]
    rows: Sequence[Sequence[str]]


@dataclass(frozen=True)
class Figure:
    """A PNG beside the report (``path`` relative to the report's folder) and its caption."""

    path: str
    caption: str


@dataclass(frozen=True)
class Section:
    """One section: a heading, paragraphs, then tables and figures in order."""

    title: str
    paragraphs: Sequence[str] = ()
    tables: Sequence[Table] = ()
    figures: Sequence[Figure] = ()
    anchor: str = field(default="")


_STYLE = """
body { font-family: -apple-system, 'Segoe UI', Helvetica, Arial, sans-serif; margin: 2em auto;
       max-width: 1100px; color: #222; line-height: 1.45; padding: 0 1em; }
h1 { border-bottom: 2px solid #444; padding-bottom: .2em; }
h2 { margin-top: 2em; border-bottom: 1px solid #bbb; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.92em; }
caption { text-align: left; font-weight: 600; padding-bottom: .3em; }
th, td { border: 1px solid #ccc; padding: .25em .6em; text-align: right; }
th { background: #f0f0f0; }
td:first-child, th:first-child { text-align: left; }
figure { margin: 1.2em 0; }
figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.9em; color: #555; }
nav a { margin-right: 1em; }
.ok { color: #17702a; font-weight: 600; } .bad { color: #a4161a; font-weight: 600; }
"""


def _table(table: Table) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in table.header)
    body = "\n".join(
        "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>"
        for row in table.rows
    )
    return (
        f"<table><caption>{html.escape(table.caption)}</caption>"
        f"<thead><tr>{head}</tr></thead><tbody>\n{body}\n</tbody></table>"
    )


def _figure(figure: Figure) -> str:
    return (
        f'<figure><img src="{html.escape(figure.path)}" alt="{html.escape(figure.caption)}">'
        f"<figcaption>{html.escape(figure.caption)}</figcaption></figure>"
    )


def render_report(title: str, intro: Sequence[str], sections: Sequence[Section]) -> str:
    """The report as one HTML string."""
    nav = " ".join(
        f'<a href="#{html.escape(s.anchor or f"s{i}")}">{html.escape(s.title)}</a>'
        for i, s in enumerate(sections)
    )
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
        *(f"<p>{html.escape(p)}</p>" for p in intro),
        f"<nav>{nav}</nav>",
    ]
    for i, section in enumerate(sections):
        parts.append(f'<h2 id="{html.escape(section.anchor or f"s{i}")}">')
        parts.append(f"{html.escape(section.title)}</h2>")
        parts.extend(f"<p>{html.escape(p)}</p>" for p in section.paragraphs)
        parts.extend(_table(t) for t in section.tables)
        parts.extend(_figure(f) for f in section.figures)
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def write_report(
    path: str | os.PathLike[str], title: str, intro: Sequence[str], sections: Sequence[Section]
) -> None:
    """Render and write the report atomically."""
    atomic_write_text(path, render_report(title, intro, sections))
