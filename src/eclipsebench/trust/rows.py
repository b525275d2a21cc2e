"""The answer of a trust run as rows of text: the per-method tables (depth and mid-event
time, with their units) and the cautions, shared by ``eclipsebench trust``'s printout,
:class:`~eclipsebench.trust.result.TrustResult`'s views and the trust page."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from .score import PHASE_QUANTITIES

__all__ = ["DEPTH_COLUMNS", "TIME_COLUMNS", "PHASE_HEAD", "method_rows", "phase_rows", "phase_units", "text_table",
           "cautions"]

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
    noise = (summary.get("twins") or {}).get("correlated_noise") or {}
    if noise.get("periods_twin_in_excess_min"):
        bands = noise["periods_twin_in_excess_min"]
        out.append("the pilot twin's residuals are redder than the real ones at periods of "
                   + ", ".join(f"{lo:.0f}-{hi:.0f} min (power x{ratio:.1f})"
                               for lo, hi, ratio in bands)
                   + ": the twins may over-predict the error")
    for m, why in (summary.get("skipped") or {}).items():
        out.append(f"{m} skipped: {why}")
    return out


#: The headings of :func:`phase_rows`' rows after the method (the unit is the quantity's,
#: but for z_rms and the coverages, in per cent as in :data:`DEPTH_COLUMNS`).
PHASE_HEAD = ("real", "error", "honest err", "bias", "SD", "RMSE", "mean err", "z_rms",
              "1-sigma cov", "2-sigma cov")


def _number(value: Any, fmt: str) -> str:
    """``value`` formatted, or "none" where a fit gave none."""
    return "none" if value is None else format(value, fmt)


def _percent(fraction: Any) -> str:
    return "none" if fraction is None else f"{100 * fraction:.0f}"


def phase_units(unit: str) -> list[str]:
    """The units beneath :data:`PHASE_HEAD` for a quantity in ``unit``."""
    return [unit] * 7 + ["", "%", "%"]


def phase_rows(summary: Mapping[str, Any]) -> list[tuple[str, str, list[list[str]]]]:
    """A whole phase curve's statistics per quantity, for stdout and the page: ``(name,
    unit, rows)``, each row a method's real value, error, honest error, bias, SD, RMSE,
    mean error, z_rms and 1- and 2-sigma coverage as text ("none" where its fits gave no
    error); empty for an eclipse or a transit."""
    out = []
    for name, unit, _ in PHASE_QUANTITIES:
        if f"twin_{name}_{unit}" not in summary:
            continue
        rows = []
        for m, s in summary["methods"].items():
            if f"{name}_rmse_{unit}" not in s:
                continue
            rows.append([m, _number(s[f"{name}_{unit}"], ".1f"),
                         _number(s[f"{name}_err_{unit}"], ".1f"),
                         _number(s[f"{name}_honest_err_{unit}"], ".1f"),
                         _number(s[f"{name}_bias_{unit}"], ".1f"),
                         _number(s[f"{name}_sd_{unit}"], ".1f"),
                         _number(s[f"{name}_rmse_{unit}"], ".1f"),
                         _number(s[f"{name}_mean_err_{unit}"], ".1f"),
                         _number(s[f"{name}_z_rms"], ".2f"),
                         _percent(s[f"{name}_coverage_1sigma"]),
                         _percent(s[f"{name}_coverage_2sigma"])])
        out.append((name, unit, rows))
    return out
