"""The report pages' HTML: one page frame, table, notes list and figure element.

Every page the package writes (a run's ``report/index.html``,
:mod:`eclipsebench.report.build`; a trust run's, :mod:`eclipsebench.trust.page`)
is made of these pieces, so they look and escape alike. A page is static:
no scripts, no external resources, every link relative to its folder so the
folder can be moved or opened offline. Every text given is escaped here;
``body`` parts are HTML already made with these functions.
"""

from __future__ import annotations

import html
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

__all__ = ["STYLE", "page_html", "html_table", "notes_html", "figure_html", "relative",
           "page_folder"]

#: The pages' one style sheet.
STYLE = ("body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}"
         "table{border-collapse:collapse;font-size:90%}td,th{border:1px solid #bbb;"
         "padding:2px 6px;text-align:right}td:first-child{text-align:left}"
         "figure{margin:1.5em 0}img{max-width:100%;border:1px solid #ddd}"
         "table.symbols td,table.symbols th{text-align:left}"
         "tr.chosen td{background:#fff3c4;font-weight:bold}"
         ".caution{border-left:4px solid #d62728;padding:0.2em 0.8em;background:#fdf0f0}")


def page_folder(dest: str | os.PathLike[str]) -> Path:
    """The folder a page and its figures go to, made if missing."""
    root = Path(dest)
    root.mkdir(parents=True, exist_ok=True)
    return root


def relative(path: Path, root: Path) -> str:
    """``path`` relative to the page's folder ``root``, with forward slashes."""
    return Path(path).relative_to(root).as_posix()


def page_html(title: str, body: Sequence[str]) -> str:
    """A whole page: ``<h1>title</h1>`` then the ``body`` parts, one per line."""
    esc = html.escape
    return "\n".join([
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
        f"<title>{esc(title)}</title>", f"<style>{STYLE}</style>", "</head>", "<body>",
        f"<h1>{esc(title)}</h1>", *body, "</body>", "</html>", ""])


def html_table(rows: Sequence[Sequence[object]], *, chosen: Sequence[int] = (),
               cls: str | None = None) -> str:
    """A table: ``rows[0]`` the headings, then the body rows (``chosen``: their indices,
    from 0, drawn highlighted).

    Examples
    --------
    >>> html_table([["method", "depth (ppm)"], ["a<b", 1.0]], chosen=[0])
    '<table><thead><tr><th>method</th><th>depth (ppm)</th></tr></thead><tbody>\\n<tr class="chosen"><td>a&lt;b</td><td>1.0</td></tr>\\n</tbody></table>'
    """
    esc = html.escape
    thead = "".join(f"<th>{esc(str(c))}</th>" for c in rows[0])
    tbody = "\n".join(("<tr class=\"chosen\">" if i in chosen else "<tr>")
                      + "".join(f"<td>{esc(str(c))}</td>" for c in r) + "</tr>"
                      for i, r in enumerate(rows[1:]))
    head = f'<table class="{esc(cls)}">' if cls else "<table>"
    return f"{head}<thead><tr>{thead}</tr></thead><tbody>\n{tbody}\n</tbody></table>"


def notes_html(notes: Mapping[str, object]) -> str:
    """``name: value`` lines as a list (the seed, the version, the command line...)."""
    esc = html.escape
    return "<ul>" + "".join(f"<li><b>{esc(str(k))}</b>: {esc(str(v))}</li>"
                            for k, v in notes.items()) + "</ul>"


def figure_html(name: str, caption: str, files: Sequence[Path], root: Path) -> str:
    """A figure's PNG with its caption and, where written, a link to its PDF."""
    esc = html.escape
    png = next(p for p in files if Path(p).suffix == ".png")
    pdf = [p for p in files if Path(p).suffix == ".pdf"]
    link = f' (<a href="{esc(relative(pdf[0], root))}">PDF</a>)' if pdf else ""
    return (f'<figure id="{esc(name)}"><img src="{esc(relative(png, root))}" '
            f'alt="{esc(name)}"><figcaption>{esc(caption)}{link}</figcaption></figure>')
