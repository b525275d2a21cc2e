"""The paper's Tables 3 and 4 as data, and a run's profile set beside them.

Ingalls et al. (2016), Table 3 (real XO-3b data) and Table 4 (the simulated
2015 challenge, input depth 1875 ppm). ``f_dis`` carries its 68 % interval
where the paper gives one (``f_dis_lo``, ``f_dis_hi``); 1.0 without an
interval is the paper's floor (its note e: f_dis < 1 is reported as 1).
The numbers are for comparison only: nothing in the package is set from them.

Examples
--------
>>> TABLE4["PLD"]["D_mean"], TABLE4["SP(K2)"]["bias"]
(1880.0, -162.0)
>>> comparison_rows({"methods": {"pld": {"D_mean": 1870.0}}}, TABLE4)[0][:3]
['pld', 'PLD', '1870']
"""

from __future__ import annotations

from collections.abc import Mapping

from ..decorrelate.base import get_method
from ..errors import InputError
from .tables import escape_markdown

__all__ = ["TABLE3", "TABLE4", "paper_name", "COMPARED_KEYS", "comparison_rows",
           "comparison_markdown"]



def paper_name(method: str) -> str:
    """The paper's name of a registered method (its record's label), "" if not one of the seven.

    Examples
    --------
    >>> paper_name("kr-data"), paper_name("poly2"), paper_name("no-such-method")
    ('KR/Data', '', '')
    """
    try:
        record = get_method(method).record
    except InputError:
        return ""
    return record.label if record.in_paper else ""


_T4_KEYS = ("D_mean", "sigma_mean", "SD", "sigma_orig", "f_dis", "sigma_tot", "R", "r", "RMSE",
            "bias", "a")
_T3_KEYS = ("D_mean", "sigma_mean", "SD", "sigma_orig", "f_dis", "sigma_tot", "R", "r")


def _rows(keys, rows):
    out = {}
    for name, values, interval in rows:
        out[name] = {k: float(v) for k, v in zip(keys, values, strict=True)}
        if interval is not None:
            out[name]["f_dis_hi"] = out[name]["f_dis"] + interval[0]
            out[name]["f_dis_lo"] = out[name]["f_dis"] - interval[1]
    return out


#: Table 4, simulated data (sigma_phot about 53 ppm; truth 1875 ppm).
TABLE4 = _rows(_T4_KEYS, [
    ("BLISS", (1815, 131, 120, 41, 1.0, 41, 171, 0.44, 131, -59, 0.40), None),
    ("GP", (1829, 154, 211, 43, 1.2, 54, 300, 0.25, 215, -45, 0.25), (0.4, 0.2)),
    ("ICA", (1827, 148, 144, 45, 1.1, 48, 205, 0.37, 148, -47, 0.36), (0.4, 0.2)),
    ("KR/Data", (1821, 128, 217, 40, 1.6, 65, 309, 0.24, 219, -53, 0.24), (0.6, 0.3)),
    ("KR/Pmap", (1772, 125, 180, 32, 1.3, 41, 256, 0.29, 181, -102, 0.29), (0.4, 0.2)),
    ("PLD", (1880, 108, 140, 33, 1.4, 45, 199, 0.38, 134, 5, 0.39), (0.5, 0.2)),
    ("SP(K2)", (1712, 51, 226, 16, 4.6, 74, 322, 0.23, 266, -162, 0.20), (1.6, 0.8)),
])

#: Table 3, real data (sigma_phot about 53 ppm).
TABLE3 = _rows(_T3_KEYS, [
    ("BLISS", (1543, 85, 133, 27, 1.5, 40, 189, 0.40), (0.5, 0.3)),
    ("GP", (1513, 152, 155, 40, 1.0, 40, 220, 0.34), None),
    ("ICA", (1560, 111, 71, 34, 1.0, 34, 101, 0.74), None),
    ("KR/Data", (1570, 94, 79, 28, 1.0, 28, 113, 0.66), None),
    ("KR/Pmap", (1460, 117, 81, 36, 1.0, 36, 116, 0.65), None),
    ("PLD", (1573, 107, 111, 33, 1.0, 33, 158, 0.48), None),
    ("SP(K2)", (1421, 48, 137, 15, 2.8, 43, 195, 0.39), (1.0, 0.5)),
])

#: The columns set beside the paper's, in its order.
COMPARED_KEYS = ("D_mean", "sigma_mean", "SD", "f_dis", "R", "r", "RMSE", "bias", "a")


def _fmt(v, key: str) -> str:
    if v is None:
        return "n/a"
    return f"{v:.2f}" if key in ("f_dis", "r", "a") else f"{v:.0f}"


def comparison_rows(summary: Mapping, table: Mapping[str, Mapping[str, float]],
                    keys: tuple[str, ...] = COMPARED_KEYS) -> list[list[str]]:
    """One row per method of ``summary["methods"]``: name, paper name, then ours / paper per key.

    Each key gives two cells, ours and the paper's ("" for a method the paper
    did not run, or a key the table lacks).
    """
    rows = []
    for name, stats in summary["methods"].items():
        paper = table.get(paper_name(name), {})
        row = [name, paper_name(name)]
        for k in keys:
            row += [_fmt(stats.get(k), k), _fmt(paper[k], k) if k in paper else ""]
        rows.append(row)
    return rows


def comparison_markdown(summary: Mapping, table: Mapping[str, Mapping[str, float]],
                        keys: tuple[str, ...] = COMPARED_KEYS) -> str:
    """A Markdown table of :func:`comparison_rows` (``ours / paper`` in each cell).

    Method names are escaped for Markdown (a plugin's name may hold ``_``).
    """
    head = "| method | paper's name | " + " | ".join(keys) + " |"
    lines = [head, "|" + " --- |" * (len(keys) + 2)]
    for row in comparison_rows(summary, table, keys):
        cells = [f"{row[2 + 2 * i]} / {row[3 + 2 * i]}" if row[3 + 2 * i] else row[2 + 2 * i]
                 for i in range(len(keys))]
        lines.append(f"| {escape_markdown(row[0])} | {escape_markdown(row[1])} | "
                     + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
