"""The answer of a trust run as a notebook object: ``trust.json``'s content, shown briefly.

:class:`TrustResult` is the dict :func:`eclipsebench.trust.run.run_trust`
reads back (so ``json.dumps`` and the CLI's ``--json`` take it as it is),
with a text and HTML summary (the line to quote, the per-method table and
the cautions), ``to_table()`` (one row per method with units) and
``plot()`` (a matplotlib Figure).

The per-method table and the cautions are :mod:`eclipsebench.trust.rows`', the
ones ``eclipsebench trust`` prints and the trust page shows.
"""

from __future__ import annotations

import html
import json
import math
import os
from pathlib import Path

import astropy.units as u
from astropy.table import QTable

from ..errors import InputError
from ..report.page import html_table
from .rows import cautions, method_rows, text_table

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
    result = TrustResult(data)
    result.folder = path.parent
    return result
