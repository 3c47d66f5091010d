"""A self-contained HTML page: sections of text, tables and PNG figures lying beside it.

The page has no scripts and no external resources, so it opens offline in any browser; figures
are referenced by relative path (``<img src="fig.png">``) from the report's folder. Tables and
figures fit the page from 800 px wide up (cells wrap, images scale down), so nothing needs
sideways scrolling.
"""

from __future__ import annotations

import html
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

from ftcomp.io.atomic import atomic_write_text

__all__ = [
    "Cell",
    "Figure",
    "Link",
    "Mark",
    "Section",
    "Table",
    "render_report",
    "write_report",
]


@dataclass(frozen=True)
class Link:
    """A table cell or list item that links to a file beside the report (relative path)."""

    text: str
    href: str


@dataclass(frozen=True)
class Mark:
    """A table cell with a judgement: ``good`` in green, ``bad`` in red, ``note`` plain."""

    text: str
    kind: Literal["good", "bad", "note"]


#: What a table cell holds: plain text, a link or a judgement.
Cell = str | Link | Mark


@dataclass(frozen=True)
class Table:
    """A table: a caption, column headers and rows of already formatted cells.

    ``groups`` optionally puts a header row above ``header``: ``(label, span)`` pairs whose
    spans add up to the number of columns. ``note`` is a line under the table. The first
    ``text_columns`` columns hold text and are aligned left; the others right (numbers).
    """

    caption: str
    header: Sequence[str]
    rows: Sequence[Sequence[Cell]]
    groups: Sequence[tuple[str, int]] = ()
    note: str = ""
    text_columns: int = 1


@dataclass(frozen=True)
class Figure:
    """A PNG beside the report (``path`` relative to the report's folder) and its caption.

    ``title`` is also the figure's own title (drawn into the PNG), so the two always agree;
    ``caption`` explains what to read in it.
    """

    path: str
    title: str
    caption: str = ""


@dataclass(frozen=True)
class Section:
    """One section: a heading, paragraphs, then tables and figures in order."""

    title: str
    paragraphs: Sequence[str] = ()
    tables: Sequence[Table] = ()
    figures: Sequence[Figure] = ()
    anchor: str = field(default="")
    links: Sequence[Link] = ()


_STYLE = """
body { font-family: -apple-system, 'Segoe UI', Helvetica, Arial, sans-serif; margin: 2em auto;
       max-width: 1100px; color: #222; line-height: 1.45; padding: 0 1em; }
h1 { border-bottom: 2px solid #444; padding-bottom: .2em; font-size: 1.7em; }
h2 { margin-top: 2em; border-bottom: 1px solid #bbb; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.86em; max-width: 100%; }
caption { text-align: left; font-weight: 600; padding-bottom: .3em; }
th, td { border: 1px solid #ccc; padding: .25em .5em; text-align: right;
         overflow-wrap: break-word; vertical-align: top; }
th { background: #f0f0f0; }
td.text, th.text { text-align: left; }
th.group { text-align: center; }
p.note { font-size: 0.86em; color: #555; margin-top: -.6em; }
figure { margin: 1.2em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: 0.9em; color: #444; }
figcaption b { color: #222; }
nav a { margin-right: 1em; }
ul.links { columns: 2 16em; font-size: 0.9em; }
.good { color: #17702a; font-weight: 600; } .bad { color: #a4161a; font-weight: 600; }
"""


def _cell(cell: Cell, text: bool) -> str:
    if isinstance(cell, Link):
        link = f'<a href="{html.escape(cell.href)}">{html.escape(cell.text)}</a>'
        return f'<td class="text">{link}</td>'
    if isinstance(cell, Mark):
        kind = "text" if cell.kind == "note" else f"{cell.kind} text"
        return f'<td class="{kind}">{html.escape(cell.text)}</td>'
    if text:
        return f'<td class="text">{html.escape(cell)}</td>'
    return f"<td>{html.escape(cell)}</td>"


def _table(table: Table) -> str:
    groups = ""
    if table.groups:
        groups = (
            "<tr>"
            + "".join(
                f'<th class="group" colspan="{span}">{html.escape(label)}</th>'
                for label, span in table.groups
            )
            + "</tr>"
        )
    left = table.text_columns
    head = "".join(
        f'<th class="text">{html.escape(h)}</th>' if i < left else f"<th>{html.escape(h)}</th>"
        for i, h in enumerate(table.header)
    )
    body = "\n".join(
        "<tr>" + "".join(_cell(c, i < left) for i, c in enumerate(row)) + "</tr>"
        for row in table.rows
    )
    note = f'<p class="note">{html.escape(table.note)}</p>' if table.note else ""
    return (
        f"<table><caption>{html.escape(table.caption)}</caption>"
        f"<thead>{groups}<tr>{head}</tr></thead><tbody>\n{body}\n</tbody></table>{note}"
    )


def _figure(figure: Figure) -> str:
    caption = f"<b>{html.escape(figure.title)}.</b>"
    if figure.caption:
        caption += " " + html.escape(figure.caption)
    return (
        f'<figure><img src="{html.escape(figure.path)}" alt="{html.escape(figure.title)}">'
        f"<figcaption>{caption}</figcaption></figure>"
    )


def _links(links: Sequence[Link]) -> str:
    items = "".join(
        f'<li><a href="{html.escape(link.href)}">{html.escape(link.text)}</a></li>'
        for link in links
    )
    return f'<ul class="links">{items}</ul>'


def render_report(title: str, intro: Sequence[str], sections: Sequence[Section]) -> str:
    """The report as one HTML string."""
    nav = " ".join(
        f'<a href="#{html.escape(s.anchor or f"s{i}")}">{html.escape(s.title)}</a>'
        for i, s in enumerate(sections)
    )
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
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
        if section.links:
            parts.append(_links(section.links))
        parts.extend(_figure(f) for f in section.figures)
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def write_report(
    path: str | os.PathLike[str], title: str, intro: Sequence[str], sections: Sequence[Section]
) -> None:
    """Render and write the report atomically."""
    atomic_write_text(path, render_report(title, intro, sections))
