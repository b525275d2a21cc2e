"""The paper's Tables 3 and 4 from a statistics summary: text, ECSV, AASTeX, Markdown.

Input is the dict of :func:`eclipsebench.stats.summary.summarize` (the
``summary.json`` / ``eclipsebench stats --json`` content). Names that come
from outside (methods, plugins' included; a run's title) are escaped for the
format they are written in (:func:`escape_markdown`, :func:`escape_latex`),
as the HTML page escapes them.
"""

from __future__ import annotations

import io
import math
import re
from collections.abc import Callable
from pathlib import Path

from astropy.table import Table

from ..io.atomic import atomic_path, write_text

__all__ = ["stats_table", "anova_lines", "display_rows", "format_text_table", "format_markdown",
           "write_tables", "TABLE_COLUMNS", "escape_markdown", "escape_latex"]

_MARKDOWN_SPECIAL = re.compile(r"([\\`*_{}\[\]<>()#+!|~&])")
_LATEX_SPECIAL = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#",
                  "_": r"\_", "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}",
                  "^": r"\textasciicircum{}", "|": r"\textbar{}", "<": r"\textless{}",
                  ">": r"\textgreater{}"}


def escape_markdown(text: str) -> str:
    r"""``text`` with every character Markdown (or a table's ``|``) would read escaped.

    Examples
    --------
    >>> print(escape_markdown("a|b *c* <x>"))
    a\|b \*c\* \<x\>
    """
    return _MARKDOWN_SPECIAL.sub(r"\\\1", " ".join(str(text).split()))


def escape_latex(text: str) -> str:
    r"""``text`` as LaTeX prints it literally (``\ & % $ # _ { } ~ ^ | < >`` escaped).

    Examples
    --------
    >>> print(escape_latex("kr_pmap & 50%"))
    kr\_pmap \& 50\%
    """
    return "".join(_LATEX_SPECIAL.get(c, c) for c in " ".join(str(text).split()))


#: (key, heading, unit) of the displayed columns, in the order of Table 4.
TABLE_COLUMNS = (
    ("method", "Method", ""),
    ("D_mean", "D_mean", "ppm"),
    ("sigma_mean", "sigma_mean", "ppm"),
    ("SD", "SD", "ppm"),
    ("sigma_orig", "sigma_orig", "ppm"),
    ("f_dis", "f_dis", ""),
    ("sigma_tot", "sigma_tot", "ppm"),
    ("R", "R", "ppm"),
    ("r", "r", ""),
    ("closest", "Closest match", "ppm"),
    ("RMSE", "RMSE", "ppm"),
    ("bias", "bias", "ppm"),
    ("a", "a", ""),
)

_NUMERIC = ("N", "D_mean", "sigma_mean", "SD", "sigma_orig", "f_dis", "f_dis_raw", "f_dis_lo",
            "f_dis_hi", "sigma_tot", "R", "R_lo", "R_hi", "r", "r_lo", "r_hi", "RMSE", "bias",
            "a", "a_lo", "a_hi", "coverage", "coverage_lo", "coverage_hi", "coverage_2sigma",
            "coverage_2sigma_lo", "coverage_2sigma_hi", "z_rms", "closest_match_mean_ppm",
            "closest_match_sd_ppm")


def _num(v) -> float:
    return float("nan") if v is None else float(v)


def _has_truth(summary: dict) -> bool:
    return any(s.get("RMSE") is not None for s in summary["methods"].values())


def stats_table(summary: dict) -> Table:
    """A machine-readable table (one row per method, plus ``Average``).

    Missing values (no truth, no photon limit) are NaN.
    """
    rows = []
    for name, s in summary["methods"].items():
        row = {"method": name, "closest_match": s.get("closest_match") or ""}
        row.update({k: _num(s.get(k)) for k in _NUMERIC})
        rows.append(row)
    avg: dict[str, str | float] = {"method": "Average", "closest_match": ""}
    avg.update({k: _num(summary.get("average", {}).get(k)) for k in _NUMERIC})
    rows.append(avg)
    cols = ["method", *_NUMERIC[:20], "closest_match", *_NUMERIC[20:]]
    table = Table(rows=[[r[c] for c in cols] for r in rows], names=cols)
    for c in cols:
        if c in ("D_mean", "sigma_mean", "SD", "sigma_orig", "sigma_tot", "R", "R_lo", "R_hi",
                 "RMSE", "bias", "closest_match_mean_ppm", "closest_match_sd_ppm"):
            table[c].unit = "ppm"
    table.meta["sigma_phot_ppm"] = summary.get("sigma_phot_ppm")
    table.meta["truth_ppm"] = summary.get("truth_ppm")
    return table


def _fmt(v, digits: int = 0) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "..."
    return f"{v:.{digits}f}"


def _signed(v: float, minus: str) -> str:
    text = f"{v:.0f}"
    return text.replace("-", minus) if text.startswith("-") else text


def display_rows(summary: dict, *, minus: str = "-", pm: str = "+/-",
                 interval: str = "{f} +{up}/-{down}",
                 escape: Callable[[str], str] = str) -> list[list[str]]:
    """Rows of formatted cells like the paper's table (method rows, then Average).

    ``f_dis`` shows its 68% interval only when the raw value exceeds 1 (the
    paper prints a floored 1.0 without one); the closest match reads
    ``NAME: (mean +/- SD)``. ``escape`` is applied to every method name (the
    format's escaping: :func:`escape_markdown`, :func:`escape_latex`).
    """
    truth = _has_truth(summary)
    keys = [c for c in TABLE_COLUMNS if truth or c[0] not in ("RMSE", "bias", "a")]
    rows = []
    for name, s in [*summary["methods"].items(), ("Average", summary.get("average", {}))]:
        cells = []
        for key, _, _ in keys:
            if key == "method":
                cells.append(escape(name))
            elif key == "f_dis":
                f = s.get("f_dis")
                if name != "Average" and s.get("f_dis_raw", 0) > 1.0:
                    cells.append(interval.format(f=_fmt(f, 1), up=_fmt(s["f_dis_hi"] - f, 1),
                                                 down=_fmt(f - s["f_dis_lo"], 1)))
                else:
                    cells.append(_fmt(f, 1))
            elif key == "closest":
                m = s.get("closest_match")
                cells.append("..." if not m else
                             f"{escape(m)}: ({_signed(s['closest_match_mean_ppm'], minus)}{pm}"
                             f"{s['closest_match_sd_ppm']:.0f})")
            elif key in ("r", "a"):
                cells.append(_fmt(s.get(key), 2))
            else:
                cells.append(_fmt(s.get(key), 0))
        rows.append(cells)
    return [[h for _, h, _ in keys], *rows]


def format_text_table(summary: dict) -> str:
    """A fixed-width text table with the columns of Table 4 (Table 3 without truth)."""
    rows = display_rows(summary)
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = ["  ".join(c.ljust(w) if i in (0, len(widths) - 1) and not c[:1].isdigit()
                       else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True)))
             for r in rows]
    lines.insert(1, "-" * len(lines[0]))
    lines.insert(len(lines) - 1, "-" * len(lines[0]))
    head = []
    if summary.get("sigma_phot_ppm") is not None:
        head.append(f"sigma_phot = {summary['sigma_phot_ppm']:.1f} ppm")
    if summary.get("truth_ppm") is not None:
        head.append(f"truth = {summary['truth_ppm']:.1f} ppm")
    return "\n".join(([" ; ".join(head)] if head else []) + lines + anova_lines(summary))


def anova_lines(summary: dict) -> list[str]:
    """One line per ANOVA of the summary (all methods; the t-test-consistent ones)."""
    out = []
    anova = summary.get("anova", {})
    for label, key in (("all methods", "all"), ("t-test-consistent methods", "consistent")):
        res = anova.get(key)
        if res and res.get("F") is not None:
            out.append(f"ANOVA ({label}: {', '.join(res['methods'])}): F = {res['F']:.2f}, "
                       f"p = {res['p']:.3f}")
    return out


def format_markdown(summary: dict) -> str:
    """The table as GitHub-flavoured Markdown."""
    rows = display_rows(summary, pm=" ± ", interval="{f} +{up}/−{down}", minus="−",
                        escape=escape_markdown)
    out = ["| " + " | ".join(rows[0]) + " |", "|" + "|".join("---" for _ in rows[0]) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows[1:]]
    return "\n".join(out) + "\n"


def _aastex(summary: dict, caption: str) -> str:
    rows = display_rows(summary, minus="--", pm=r"$\pm$", interval=r"{f}\ppm{{{up}}}{{{down}}}",
                        escape=escape_latex)
    heads = [h.replace("_mean", r"$_{\rm mean}$").replace("sigma", r"$\sigma$")
             .replace("_orig", r"$_{\rm orig}$").replace("_tot", r"$_{\rm TOT}$")
             .replace("f_dis", r"$f_{\rm dis}$") for h in rows[0]]
    table = Table(rows=rows[1:], names=heads, dtype=[str] * len(heads))
    buf = io.StringIO()
    table.write(buf, format="ascii.aastex", caption=caption,
                latexdict={"tabletype": "deluxetable*",
                           "preamble": r"\tablewidth{0pt}",
                           "units": {h: u for h, (_, _, u) in zip(heads, [c for c in TABLE_COLUMNS
                                     if c[1] in rows[0]], strict=True) if u}})
    return buf.getvalue()


def write_tables(summary: dict, dest: str | Path, *, stem: str = "eclipse_depth_stats",
                 caption: str = "Eclipse Depth Statistics") -> list[Path]:
    """Write ``stem.ecsv``, ``stem.tex`` (AASTeX deluxetable) and ``stem.md`` to ``dest``.

    ``caption`` is plain text (escaped for LaTeX here).

    Returns
    -------
    list of Path
        The files written (atomically).
    """
    dest = Path(dest)
    dest.mkdir(parents=True, exist_ok=True)
    caption = escape_latex(caption)  # a run's name, a title: printed as given
    if summary.get("sigma_phot_ppm") is not None:
        caption = f"{caption} ($\\sigma_{{\\rm phot}}\\approx {summary['sigma_phot_ppm']:.0f}$ ppm)"
    ecsv = dest / f"{stem}.ecsv"
    with atomic_path(ecsv) as tmp:
        stats_table(summary).write(tmp, format="ascii.ecsv")
    tex = write_text(dest / f"{stem}.tex", _aastex(summary, caption))
    md = write_text(dest / f"{stem}.md", format_markdown(summary))
    return [ecsv, tex, md]

