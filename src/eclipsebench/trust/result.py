"""The answer of a trust run as a notebook object: ``trust.json``'s content, shown briefly.

:class:`TrustResult` is the dict :func:`eclipsebench.trust.run.run_trust`
reads back (so ``json.dumps`` and the CLI's ``--json`` take it as it is),
with a text and HTML summary (the line to quote, the per-method table and
the cautions), ``to_table()`` (one row per method with units) and
``plot()`` (a matplotlib Figure).

The per-method table (:func:`method_rows`, :data:`DEPTH_COLUMNS`,
:data:`TIME_COLUMNS`) and the cautions (:func:`cautions`) are the ones
``eclipsebench trust`` prints and the trust page shows.
"""

from __future__ import annotations

import html
import json
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import astropy.units as u
from astropy.table import QTable

from ..errors import InputError
from ..report.page import html_table

__all__ = ["TrustResult", "read_trust", "DEPTH_COLUMNS", "TIME_COLUMNS", "method_rows",
           "text_table", "cautions"]

#: The per-method table of the depth: (heading, unit, key, scale, format). Coverage and the
#: bootstrap's frequency are shown in per cent.
DEPTH_COLUMNS = (
    ("depth", "ppm", "depth_ppm", 1.0, "{:.1f}"),
    ("honest err", "ppm", "honest_err_ppm", 1.0, "{:.1f}"),
    ("reported err", "ppm", "depth_err_ppm", 1.0, "{:.1f}"),
    ("bias", "ppm", "bias_ppm", 1.0, "{:.1f}"),
    ("SD", "ppm", "sd_ppm", 1.0, "{:.1f}"),
    ("RMSE", "ppm", "rmse_ppm", 1.0, "{:.1f}"),
    ("mean err", "ppm", "mean_err_ppm", 1.0, "{:.1f}"),
    ("z_rms", "", "z_rms", 1.0, "{:.2f}"),
    ("1-sigma cov", "%", "coverage_1sigma", 100.0, "{:.0f}"),
    ("2-sigma cov", "%", "coverage_2sigma", 100.0, "{:.0f}"),
    ("recommended in", "%", "recommended_frequency", 100.0, "{:.0f}"),
)
#: The mid-event time's table (seconds against the injected time), where the fits freed it.
TIME_COLUMNS = (
    ("error", "s", "t_err_s", 1.0, "{:.1f}"),
    ("honest err", "s", "t_honest_err_s", 1.0, "{:.1f}"),
    ("bias", "s", "t_bias_s", 1.0, "{:.1f}"),
    ("SD", "s", "t_sd_s", 1.0, "{:.1f}"),
    ("RMSE", "s", "t_rmse_s", 1.0, "{:.1f}"),
    ("mean err", "s", "t_mean_err_s", 1.0, "{:.1f}"),
    ("z_rms", "", "t_z_rms", 1.0, "{:.2f}"),
    ("1-sigma cov", "%", "t_coverage_1sigma", 100.0, "{:.0f}"),
)


def _cell(value: Any, scale: float, fmt: str) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    return fmt.format(float(value) * scale)


def method_rows(summary: Mapping[str, Any], columns: Sequence[tuple] = DEPTH_COLUMNS
                ) -> tuple[list[str], list[str], list[list[str]]]:
    """Headings, units and one row of text per method (the first cell its name).

    A method is in the time's table (:data:`TIME_COLUMNS`) only where its
    twins' fits freed the time.

    Examples
    --------
    >>> head, units, rows = method_rows({"methods": {"pld": {"depth_ppm": 1801.72}}},
    ...                                 DEPTH_COLUMNS[:1])
    >>> head, units, rows
    (['method', 'depth'], ['', 'ppm'], [['pld', '1801.7']])
    """
    timed = columns is TIME_COLUMNS
    rows = [[m, *(_cell(s.get(key), scale, fmt) for _, _, key, scale, fmt in columns)]
            for m, s in summary.get("methods", {}).items() if not timed or "t_rmse_s" in s]
    return (["method", *(c[0] for c in columns)], ["", *(c[1] for c in columns)], rows)


def text_table(head: Sequence[str], units: Sequence[str], rows: Sequence[Sequence[str]],
               indent: str = "") -> list[str]:
    """Fixed-width lines: the headings, their units beneath, then the rows.

    Examples
    --------
    >>> print("\\n".join(text_table(["method", "depth"], ["", "ppm"], [["pld", "1801.7"]])))
    method   depth
               ppm
    pld     1801.7
    """
    widths = [max(len(str(r[i])) for r in (head, units, *rows)) for i in range(len(head))]

    def line(cells: Sequence[str]) -> str:
        return (indent + "  ".join(str(c).ljust(w) if i == 0 else str(c).rjust(w)
                                   for i, (c, w) in enumerate(zip(cells, widths, strict=True)))
                ).rstrip()

    return [line(head), line(units), *(line(r) for r in rows)]


def cautions(summary: Mapping[str, Any], *, ranking: bool = True) -> list[str]:
    """What to be careful of, one sentence each: too few twins to rank the methods (with
    ``ranking``), no method recommended, real residuals redder than the twins', methods
    skipped, twins a method failed to reduce."""
    out = []
    rank = summary.get("ranking") or {}
    if ranking and rank.get("text") and not rank.get("resolved"):
        out.append(str(rank["text"]))
    if summary.get("methods") and summary.get("recommended") is None:
        out.append("no method recommended: no method's 1-sigma coverage interval holds "
                   "68.3 % (its reported errors are too small or too large for its twins)")
    for m, s in summary.get("methods", {}).items():
        if s.get("redder_than_twins"):
            out.append(f"{m}: the real residuals are redder than {s['beta_red_twins_below']:.0%} "
                       f"of the twins' (beta_red {s['beta_red_real']:.2f}, twins' median "
                       f"{s['beta_red_twins_median']:.2f}): its RMSE may under-predict the error")
        if s.get("n_twins_failed"):
            out.append(f"{m}: {s['n_twins_failed']} twins not reduced (scored over the others)")
    for m, why in (summary.get("skipped") or {}).items():
        out.append(f"{m} skipped: {why}")
    return out

#: parts per million of the star's flux (astropy has no named unit for it)
_PPM_UNIT = u.def_unit("ppm", 1e-6 * u.dimensionless_unscaled)
_PPM = ("bias_ppm", "sd_ppm", "rmse_ppm", "mean_err_ppm", "depth_ppm", "depth_err_ppm",
        "honest_err_ppm")
_SECONDS = ("t_bias_s", "t_sd_s", "t_rmse_s", "t_mean_err_s", "t_err_s", "t_honest_err_s")


class TrustResult(dict):
    """``trust.json``'s content (a dict) with a notebook face.

    The headline is the line to quote (the recommended method's real depth
    with its honest error) and whether the twins rank the methods;
    ``to_table()`` gives every method's statistics (the mid-event time's in s).
    """

    #: The trust folder this answer was read from (``read_trust``), for ``plot()``'s twins.
    folder: Path | None = None

    def _headline(self) -> str:
        return (f"{self.get('system')}: {self.get('n_twins')} twins with a "
                f"{float(self.get('twin_depth_ppm') or math.nan):.1f} ppm "
                f"{(self.get('twins') or {}).get('event', 'eclipse')} ({self.get('profile')} "
                f"profile, {self.get('sampler')})")

    def _notes(self) -> list[tuple[str, str]]:
        best = self.get("recommended")
        near = self.get("near_equals") or []
        return ([("quote", str((self.get("quote") or {}).get("text")))]
                + [("recommended", f"{best}" + (f"; the twins cannot tell {', '.join(near)} "
                                                "from it" if near else ""))]
                + [("caution", c) for c in cautions(self)])

    def __repr__(self) -> str:
        head, units, rows = method_rows(self)
        return "\n".join([f"TrustResult: {self._headline()}",
                          *(f"  {k:<11} {v}" for k, v in self._notes()[:2]),
                          *text_table(head, units, rows, indent="  "),
                          *(f"  {k:<11} {v}" for k, v in self._notes()[2:])])

    def _repr_html_(self) -> str:
        esc = html.escape
        head, units, rows = method_rows(self)
        best = self.get("recommended")
        chosen = [i for i, r in enumerate(rows) if r[0] == best]
        notes = "".join(f"<li><b>{esc(k)}</b>: {esc(v)}</li>" for k, v in self._notes())
        return (f"<div><b>TrustResult</b> {esc(self._headline())}<ul>{notes}</ul>"
                + html_table([[f"{h} ({u})" if u else h for h, u in zip(head, units,
                                                                         strict=True)],
                              *rows], chosen=chosen) + "</div>")

    def plot(self, *, twins: bool = True):
        """A matplotlib Figure of the answer: per method the real depth with its honest and
        reported errors, the twins' depths (where the trust folder is known, ``twins``), the
        depth injected into them; the recommended method highlighted.

        No backend is chosen and pyplot is not used: the Figure is shown by a
        notebook as it is, or written with ``fig.savefig(path)``.
        """
        from .page import load_twins, twin_depths_figure  # matplotlib: only when drawn

        depths = None
        if twins and self.folder is not None and (Path(self.folder) / "twins").is_dir():
            depths = {m: t[0] for m, t in load_twins(self.folder, self).items()}
        return twin_depths_figure(self, depths)

    def to_table(self) -> QTable:
        """One row per scored method: the statistics, ppm columns with their unit."""
        methods = list(self.get("methods", {}))
        table = QTable({"method": methods})
        for key in ("n_twins", *_PPM, "z_rms", "coverage_1sigma", "coverage_2sigma",
                    "beta_red_real", "beta_red_twins_below", "recommended_frequency"):
            values = [self["methods"][m].get(key) for m in methods]
            table[key] = u.Quantity(values, _PPM_UNIT) if key in _PPM else values
        for key in _SECONDS:   # the mid-event time, where the fits freed it
            values = [self["methods"][m].get(key, float("nan")) for m in methods]
            if any(v == v for v in values):
                table[key] = u.Quantity(values, u.s)
        table.meta.update({"recommended": self.get("recommended"),
                           "twin_depth_ppm": self.get("twin_depth_ppm")})
        return table


def read_trust(path: str | os.PathLike) -> TrustResult:
    """The :class:`TrustResult` of a trust folder or of its ``trust.json``.

    Raises
    ------
    InputError
        One line naming the file when it is missing or not a trust answer.
    """
    path = Path(path)
    if path.is_dir():
        path = path / "trust.json"
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: not a readable trust.json ({type(exc).__name__})") from None
    if not isinstance(data, dict) or "methods" not in data:
        raise InputError(f"{path}: not a trust answer (no 'methods')")
    result = TrustResult(data)
    result.folder = path.parent
    return result
