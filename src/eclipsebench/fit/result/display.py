"""Short text and HTML summaries of a result, for a terminal and a notebook.

Every result class (:class:`~eclipsebench.fit.result.EpochResult`, the joint
result, and any other that reports one depth) gives its ``__repr__`` and
``_repr_html_`` by calling :func:`text_repr` and :func:`html_repr` with a dict
of fields:

- ``depth_ppm`` and ``depth_err_ppm``: the headline, "depth 1875.3 ± 42.1 ppm";
- ``method``, ``epoch``, ``system``, ``profile``: what was measured, on the first line;
- every other key: a diagnostic, shown as ``key value`` in the order given
  (``rms_ppm`` as "rms 4229.2 ppm").

A value is shown as given when it is a string; a float ends ``_ppm`` gets one
decimal and " ppm", any other float four significant figures, None "n/a".
The HTML is one small table (well under 2 kB), its text escaped.
"""

from __future__ import annotations

import html
import math
from collections.abc import Mapping
from typing import Any

__all__ = ["text_repr", "html_repr", "format_value"]

#: What was measured (the first line), in this order.
IDENTITY = ("method", "epoch", "system", "profile")
#: The headline value and its error.
HEADLINE = ("depth_ppm", "depth_err_ppm")


def format_value(key: str, value: Any) -> str:
    """One field's value as shown: strings as given, ppm to 0.1, floats to 4 figures.

    Examples
    --------
    >>> format_value("rms_ppm", 5123.456), format_value("beta_red", 1.23456)
    ('5123.5 ppm', '1.235')
    >>> format_value("bic", None), format_value("epoch", 3)
    ('n/a', '3')
    """
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    if isinstance(value, bool) or not isinstance(value, float):
        return str(value)
    if key.endswith("_ppm"):
        return f"{value:.1f} ppm"
    return f"{value:.4g}"


def _identity(fields: Mapping[str, Any]) -> str:
    parts = []
    for key in IDENTITY:
        value = fields.get(key)
        if value is None:
            continue
        if key == "epoch":
            value = f"epoch {value}"
        elif key == "profile":
            value = f"{value} profile"
        parts.append(str(value))
    return ", ".join(parts)


def _headline(fields: Mapping[str, Any]) -> str:
    depth, err = (fields.get(k) for k in HEADLINE)
    if depth is None:
        return ""
    if err is None:
        return f"depth {depth:.1f} ppm"
    return f"depth {depth:.1f} ± {err:.1f} ppm"


def _details(fields: Mapping[str, Any]) -> list[tuple[str, str]]:
    """(label, shown value) of the diagnostics; a ``_ppm`` key loses the suffix its value has."""
    return [(key.removesuffix("_ppm"), format_value(key, value)) for key, value in fields.items()
            if key not in IDENTITY and key not in HEADLINE]


def text_repr(name: str, fields: Mapping[str, Any]) -> str:
    """Two lines: ``name: identity``, then the headline and the diagnostics.

    Examples
    --------
    >>> print(text_repr("EpochResult", {"method": "pld", "epoch": 1, "system": "XO-3b",
    ...                                 "depth_ppm": 1875.33, "depth_err_ppm": 42.1,
    ...                                 "beta_red": 1.05, "bic": "2358.1 on 227 bins"}))
    EpochResult: pld, epoch 1, XO-3b
      depth 1875.3 ± 42.1 ppm | beta_red 1.05 | bic 2358.1 on 227 bins
    """
    second = [_headline(fields)] + [f"{k} {v}" for k, v in _details(fields)]
    return f"{name}: {_identity(fields)}\n  " + " | ".join(p for p in second if p)


def html_repr(name: str, fields: Mapping[str, Any]) -> str:
    """A small HTML table: the name and identity, the headline in bold, one row per diagnostic.

    Examples
    --------
    >>> out = html_repr("EpochResult", {"method": "a<b", "depth_ppm": 1875.0,
    ...                                 "depth_err_ppm": 42.0, "chi2_red": 1.01})
    >>> "a&lt;b" in out and "1875.0 ± 42.0 ppm" in out and len(out) < 2000
    True
    """
    esc = html.escape
    rows = "".join(f"<tr><td style='text-align:left'>{esc(k)}</td>"
                   f"<td style='text-align:left'>{esc(v)}</td></tr>"
                   for k, v in _details(fields))
    headline = _headline(fields)
    return (f"<div><b>{esc(name)}</b> {esc(_identity(fields))}"
            + (f"<br><b>{esc(headline)}</b>" if headline else "")
            + (f"<table>{rows}</table>" if rows else "") + "</div>")
