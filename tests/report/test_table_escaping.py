"""Issue 28: the Markdown and AASTeX tables escape method names and the run's name.

Before, a method named ``a|b`` (a plugin's) split its Markdown row into one
more column, and ``_``, ``&``, ``%`` in a method's or run's name broke the
AASTeX table; the HTML page already escaped them.
"""

from __future__ import annotations

import re

import numpy as np
from astropy.table import Table

from eclipsebench.report.paper_tables import TABLE4, comparison_markdown
from eclipsebench.report.tables import format_markdown, write_tables
from eclipsebench.stats.summary import summarize

NAMES = ("a|b", "x_y*", "50%&#")


def _summary() -> dict:
    rng = np.random.default_rng(1)
    rows = [(name, epoch, 1875.0 + 60 * rng.standard_normal(), 50.0)
            for name in NAMES for epoch in range(1, 5)]
    table = Table(rows=rows, names=("method", "epoch", "depth_ppm", "error_ppm"))
    return summarize(table, sigma_phot_ppm=53.0, truth_ppm=1875.0, n_bootstrap=0)


def _cells(line: str) -> list[str]:
    """The cells of a Markdown table row (a ``|`` escaped with a backslash is no border)."""
    return [c.strip() for c in re.split(r"(?<!\\)\|", line.strip())[1:-1]]


def test_markdown_rows_keep_their_columns_and_show_the_names():
    summary = _summary()
    lines = format_markdown(summary).splitlines()
    width = len(_cells(lines[0]))
    assert all(len(_cells(line)) == width for line in lines), lines
    methods = [_cells(line)[0] for line in lines[2:-1]]
    assert methods == ["a\\|b", "x\\_y\\*", "50%\\&\\#"]
    comparison = comparison_markdown(summary, TABLE4).splitlines()
    assert all(len(_cells(line)) == len(_cells(comparison[0])) for line in comparison)


def test_aastex_escapes_method_names_and_the_caption(tmp_path):
    write_tables(_summary(), tmp_path, caption="run_1 & 100% {test}")
    tex = (tmp_path / "eclipse_depth_stats.tex").read_text()
    assert r"a\textbar{}b" in tex and r"x\_y*" in tex and r"50\%\&\#" in tex
    assert r"run\_1 \& 100\% \{test\}" in tex
    body = tex.split(r"\startdata")[1].split(r"\enddata")[0]
    assert "&" not in body.replace(r"\&", "").replace(" & ", "")  # only the column separators
    assert not re.search(r"(?<!\\)[_%#]", body.replace("$", ""))
