"""The answer of a trust run as a notebook object: ``trust.json``'s content, shown briefly.

:class:`TrustResult` is the dict :func:`eclipsebench.trust.run.run_trust`
reads back (so ``json.dumps`` and the CLI's ``--json`` take it as it is),
with a short text and HTML summary (:mod:`eclipsebench.fit.display`) and
``to_table()``: one row per method with units.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import astropy.units as u
from astropy.table import QTable

from ..errors import InputError
from ..fit.display import html_repr, text_repr

__all__ = ["TrustResult", "read_trust"]

#: parts per million of the star's flux (astropy has no named unit for it)
_PPM_UNIT = u.def_unit("ppm", 1e-6 * u.dimensionless_unscaled)
_PPM = ("bias_ppm", "sd_ppm", "rmse_ppm", "mean_err_ppm", "depth_ppm", "depth_err_ppm",
        "honest_err_ppm")
_SECONDS = ("t_bias_s", "t_sd_s", "t_rmse_s", "t_mean_err_s", "t_err_s", "t_honest_err_s")

#: A whole phase curve's statistics (``trust.ecsv``'s columns), where the twins carry one.
_PHASE = tuple(f"phase_{name}_{stat}" for name, unit in (("amplitude", "ppm"), ("offset", "deg"))
               for stat in (unit, f"err_{unit}", f"honest_err_{unit}", f"bias_{unit}",
                            f"sd_{unit}", f"rmse_{unit}", f"mean_err_{unit}", "z_rms",
                            "coverage_1sigma", "coverage_2sigma"))


class TrustResult(dict):
    """``trust.json``'s content (a dict) with a notebook face.

    The headline is the line to quote (the recommended method's real depth
    with its honest error) and whether the twins rank the methods;
    ``to_table()`` gives every method's statistics (the mid-event time's in s).
    """

    def _fields(self) -> dict[str, Any]:
        best = self.get("recommended")
        row = self.get("methods", {}).get(best, {}) if best else {}
        return {"quote": (self.get("quote") or {}).get("text"),
                "ranking": (self.get("ranking") or {}).get("text"),
                "method": f"{best} (recommended)" if best else "none recommended",
                "near_equals": ", ".join(self.get("near_equals") or []) or "none",
                "system": self.get("system"), "profile": self.get("profile"),
                "depth_ppm": row.get("depth_ppm"), "depth_err_ppm": row.get("honest_err_ppm"),
                "twins": f"{self.get('n_twins')} at {self.get('twin_depth_ppm', float('nan')):.1f}"
                         " ppm",
                "methods": ", ".join(self.get("methods", {})) or "none",
                "skipped": ", ".join(self.get("skipped", {})) or "none"}

    def __repr__(self) -> str:
        return text_repr("TrustResult", self._fields())

    def _repr_html_(self) -> str:
        return html_repr("TrustResult", self._fields())

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
        for key in _PHASE:   # a whole phase curve's amplitude (ppm) and peak offset (deg)
            values = [self["methods"][m].get(key) for m in methods]
            if any(v is not None for v in values):
                values = [float("nan") if v is None else v for v in values]
                table[key] = (u.Quantity(values, _PPM_UNIT) if key.endswith("_ppm") else
                              u.Quantity(values, u.deg) if key.endswith("_deg") else values)
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
    return TrustResult(data)
