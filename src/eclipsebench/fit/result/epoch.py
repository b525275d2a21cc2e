"""The result of one epoch's fit: its schema, its JSON summary and its light curve.

:class:`EpochResult` is what :func:`eclipsebench.fit.reduce.reduce_epoch`
returns; ``to_dict()`` is what ``RESULT.json`` holds (``docs/fitting.md``
lists the keys) and :meth:`EpochResult.from_dict` reads it back,
:meth:`EpochResult.lightcurve_table` is what ``RESULT.lc.ecsv`` holds. In a
notebook a result shows itself (``_repr_html_``), draws itself
(:meth:`EpochResult.plot`) and gives its light curve as an astropy ``QTable``
with units and a ``Time`` column (:meth:`EpochResult.to_table`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from astropy.table import QTable, Table
from astropy.time import Time

from ... import __version__
from ...astro.events import event_for
from ...errors import InputError
from ...io.atomic import atomic_path
from ...io.plain import json_safe
from . import plot as figures  # light: matplotlib is imported when a figure is made
from .display import html_repr, text_repr

__all__ = ["EpochResult", "lightcurve_errors", "bic_data", "LIGHTCURVE_COLUMNS", "TIME_META"]

#: ``RESULT.lc.ecsv``'s columns: their description (all relative fluxes, units of the star).
LIGHTCURVE_COLUMNS = {
    "time_bmjd": "mid-exposure time (or bin centre), BMJD_TDB",
    "flux_corrected": "decorrelated flux: flux / systematics_model",
    "astro_model": "the fitted eclipse and phase-curve model",
    "residual": "flux_corrected - astro_model",
    "flux_err": "uncertainty of flux_corrected (the table's flux_err, decorrelated)",
    "systematics_model": "the fitted systematics, flux / flux_corrected over its median",
}
#: The time keys of RESULT.lc.ecsv's meta (FITS time conventions: barycentric TDB days).
TIME_META = {"TIMESYS": "TDB", "TIMEREF": "SOLARSYSTEM", "TIMEUNIT": "d", "MJDREF": 0.0}


@dataclass(frozen=True)
class EpochResult:
    """The eclipse measured in one epoch by one method.

    ``to_dict()`` gives the JSON-able summary (``docs/fitting.md`` lists the
    keys); ``lightcurve`` holds the decorrelated light curve. In a notebook
    (``docs/api.md``, "Results in a notebook", runs as a doctest): ``repr``
    is two lines and ``_repr_html_`` a small table (depth and error, method,
    epoch, system, profile, diagnostics); :meth:`plot` returns a Figure,
    :meth:`to_table` a ``QTable`` with units and a TDB ``Time``;
    :func:`read_result` reads a written result back.
    """

    method: str
    epoch: int | None
    depth_ppm: float
    depth_err_ppm: float
    depth_err_method: str
    depth_leastsq_ppm: float
    depth_err_jacobian_ppm: float
    depth_err_prayer_bead_ppm: float | None
    depth_err_mcmc_ppm: float | None
    depth_err_separation_ppm: float
    #: The fitted event time (mid-eclipse, or a transit's mid-transit), its error and the
    #: predicted one; ``to_dict`` writes them as the event's keys (``t_ecl_bmjd``...).
    t_event_bmjd: float
    t_event_err_d: float
    t_event_predicted_bmjd: float
    bic: float
    aic: float
    k: int
    log_likelihood: float
    chi2_red: float
    rms_ppm: float
    beta_red: float
    cadence_s: float
    n_frames: int
    n_frames_dropped: dict[str, int]
    n_points: int
    phase: str
    ramp: str
    eclipse_shape: str
    sampler: str
    converged: bool
    params: dict[str, float]
    param_errors: dict[str, float]
    mcmc: dict[str, Any] | None
    system: str
    seed: int
    options: dict[str, Any]
    diagnostics: dict[str, Any]
    depth_err_own_ppm: dict[str, float]
    lightcurve: dict[str, np.ndarray] = field(repr=False, compare=False)
    #: "controlled" or "paper" (:mod:`eclipsebench.fit.profiles`).
    profile: str = "controlled"
    #: The paper profile's choices: team, centroid columns, BIC of each phase/ramp tried.
    profile_detail: dict[str, Any] = field(default_factory=dict)
    #: The MCMC's flat posterior samples (``{"names", "samples"}``), or None without MCMC.
    chain: dict[str, np.ndarray] | None = field(default=None, repr=False, compare=False)
    #: A transit's keys (``rp_rs``, ``rp_rs_err``, ``t_transit_bmjd``, ...; empty for an
    #: eclipse): its ``depth_*`` fields then hold the transit depth rp_rs^2 and
    #: ``t_event_*`` the mid-transit time, which ``to_dict`` names ``t_transit_*``.
    event_detail: dict[str, Any] = field(default_factory=dict)
    #: The points BIC and AIC were computed on: frames, or a binned method's bins.
    bic_n_points: int | None = None
    #: How the table's times became BMJD_TDB at mid-exposure (:mod:`eclipsebench.astro.timescales`);
    #: None for a table already in BMJD_TDB.
    time_conversion: str | None = None

    def __post_init__(self) -> None:
        # plain JSON types (tuples as lists, numpy scalars as numbers), so that a result
        # read back from its RESULT.json equals the one that wrote it
        for name in ("n_frames_dropped", "options", "diagnostics", "profile_detail",
                     "event_detail", "mcmc"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, json_safe(value, nonfinite="keep"))

    @property
    def t_ecl_bmjd(self) -> float:
        """The old name of :attr:`t_event_bmjd` (read-only; kept for callers of 0.2)."""
        return self.t_event_bmjd

    @property
    def t_ecl_err_d(self) -> float:
        """The old name of :attr:`t_event_err_d` (read-only)."""
        return self.t_event_err_d

    @property
    def t_ecl_predicted_bmjd(self) -> float:
        """The old name of :attr:`t_event_predicted_bmjd` (read-only)."""
        return self.t_event_predicted_bmjd

    def _fields_shown(self) -> dict[str, Any]:
        """The fields of the text and HTML summaries (:mod:`eclipsebench.fit.result.display`)."""
        return {"method": self.method, "epoch": self.epoch, "system": self.system,
                "profile": self.profile, "depth_ppm": self.depth_ppm,
                "depth_err_ppm": self.depth_err_ppm, "error from": self.depth_err_method,
                "beta_red": self.beta_red, "rms_ppm": self.rms_ppm, "chi2_red": self.chi2_red,
                "BIC": f"{self.bic:.1f} on {bic_data(vars(self))}",
                "phase / ramp": f"{self.phase} / {self.ramp}", "sampler": self.sampler}

    def __repr__(self) -> str:
        return text_repr(type(self).__name__, self._fields_shown())

    def _repr_html_(self) -> str:
        return html_repr(type(self).__name__, self._fields_shown())

    def plot(self, kind: str = "lightcurve", *, bin_minutes: float = 5.0, bins: int = 30):
        """A matplotlib Figure: ``"lightcurve"`` (flux and model over residuals, two axes)
        or ``"corner"`` (the MCMC posterior).

        Raises
        ------
        InputError
            An unknown ``kind``; ``"corner"`` of a fit without MCMC; a result
            read without its light curve.
        """

        if kind == "corner":
            if self.chain is None:
                raise InputError("plot(kind='corner'): no posterior (the fit ran no MCMC; "
                                 "sampler='mcmc')")
            return figures.corner_figure(self.chain["names"], self.chain["samples"], bins=bins)
        if kind != "lightcurve":
            raise InputError(f"plot: kind {kind!r}: expected 'lightcurve' or 'corner'")
        if not self.lightcurve:
            raise InputError("plot: this result has no light curve (its RESULT.lc.ecsv was "
                             "not found beside the RESULT.json)")
        return figures.lightcurve_figure(self, bin_minutes=bin_minutes)

    def write_chain(self, path) -> None:
        """Write the posterior samples as ``.npz`` (``names``, ``samples``; depth as a fraction).

        Raises
        ------
        InputError
            No MCMC was run for this result.
        """
        if self.chain is None:
            raise InputError(f"{path}: no chain to write (the fit ran no MCMC; --sampler mcmc)")
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, names=self.chain["names"], samples=self.chain["samples"])

    def to_dict(self) -> dict[str, Any]:
        """A flat, JSON-able dict (no arrays): the contract keys and the diagnostics."""
        out: dict[str, Any] = {
            "method": self.method, "epoch": self.epoch,
            "depth_ppm": self.depth_ppm, "depth_err_ppm": self.depth_err_ppm,
            "depth_err_method": self.depth_err_method,
            "depth_leastsq_ppm": self.depth_leastsq_ppm,
            "depth_err_jacobian_ppm": self.depth_err_jacobian_ppm,
            "depth_err_prayer_bead_ppm": self.depth_err_prayer_bead_ppm,
            "depth_err_mcmc_ppm": self.depth_err_mcmc_ppm,
            "depth_err_separation_ppm": self.depth_err_separation_ppm,
            "t_ecl_bmjd": self.t_event_bmjd, "t_ecl_err_d": self.t_event_err_d,
            "t_ecl_predicted_bmjd": self.t_event_predicted_bmjd,
            "bic": self.bic, "aic": self.aic, "k": self.k,
            "log_likelihood": self.log_likelihood, "chi2_red": self.chi2_red,
            "rms_ppm": self.rms_ppm, "beta_red": self.beta_red, "cadence_s": self.cadence_s,
            "n_frames": self.n_frames, "n_frames_dropped": dict(self.n_frames_dropped),
            "n_points": self.n_points,
            "phase": self.phase, "ramp": self.ramp, "eclipse_shape": self.eclipse_shape,
            "sampler": self.sampler, "converged": self.converged,
            "system": self.system, "seed": self.seed, "profile": self.profile,
        }
        if self.profile_detail:
            out["profile_detail"] = json_safe(self.profile_detail, nonfinite="keep")
        for name, value in self.params.items():
            if name not in ("depth", "t_ecl_bmjd", "rp_rs", "t_transit_bmjd"):
                out[name] = value
                out[f"{name}_err"] = self.param_errors[name]
        lo = hi = self.depth_err_ppm
        if self.mcmc is not None:
            out.update({f"mcmc_{k}": v for k, v in self.mcmc.items()})
            if self.depth_err_method.split("+")[0] == "mcmc":
                lo, hi = self.mcmc["depth_err_lo_ppm"], self.mcmc["depth_err_hi_ppm"]
                if self.depth_err_method.endswith("+separation"):
                    extra = self.depth_err_separation_ppm
                    lo, hi = float(np.hypot(lo, extra)), float(np.hypot(hi, extra))
        out["depth_err_lo_ppm"], out["depth_err_hi_ppm"] = lo, hi
        out.update({f"depth_err_{k}_ppm": v for k, v in self.depth_err_own_ppm.items()})
        out["options"] = dict(self.options)
        out["diagnostics"] = dict(self.diagnostics)
        for key in event_for(self.event_detail.get("event")).replaced_time_keys:
            del out[key]   # a transit's: its detail holds its times under their own names
        if self.event_detail:
            out.update(json_safe(self.event_detail, nonfinite="keep"))
            out["event_keys"] = list(self.event_detail)
        out.update({"params": dict(self.params), "param_errors": dict(self.param_errors),
                    "depth_err_own_ppm": dict(self.depth_err_own_ppm),
                    "bic_n_points": self.bic_n_points, "eclipsebench_version": __version__})
        out["bic_data"] = bic_data(out)
        if self.time_conversion is not None:
            out["time_conversion"] = self.time_conversion
        return out

    def lightcurve_table(self) -> Table:
        """The decorrelated light curve as written to ``RESULT.lc.ecsv``.

        Columns :data:`LIGHTCURVE_COLUMNS` (those the fit made), ``time_bmjd``
        in days, the fluxes dimensionless (units of the star), each with its
        description; meta: the time scale (``TIMESYS = 'TDB'``, barycentric),
        the method, epoch, system, profile, depth and the software version.
        """
        t = Table()
        for name, text in LIGHTCURVE_COLUMNS.items():
            if name in self.lightcurve:
                t[name] = np.asarray(self.lightcurve[name], dtype=float)
                t[name].unit = "d" if name == "time_bmjd" else ""
                t[name].description = text
        t.meta.update({"method": self.method, "epoch": self.epoch, "depth_ppm": self.depth_ppm,
                       "phase": self.phase, "system": self.system, "profile": self.profile,
                       **TIME_META, "eclipsebench_version": __version__})
        return t

    def to_table(self):
        """The decorrelated light curve as an astropy ``QTable`` with units.

        ``time`` is an astropy ``Time`` (``format="mjd"``, ``scale="tdb"``;
        barycentric: BMJD_TDB), the flux columns are dimensionless Quantities
        (units of the star): ``flux_corrected``, ``flux_err``, ``astro_model``,
        ``systematics_model``, ``residual`` (those the fit made).
        """
        plain = self.lightcurve_table()
        table = QTable(meta=dict(plain.meta))
        table["time"] = Time(np.asarray(plain["time_bmjd"]), format="mjd", scale="tdb")
        table["time"].info.description = "mid-exposure time, barycentric (BMJD_TDB)"
        for name in plain.colnames[1:]:
            table[name] = plain[name].quantity
            table[name].info.description = plain[name].description
        return table

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], lightcurve: Mapping[str, Any] | None = None,
                  chain: Mapping[str, Any] | None = None) -> EpochResult:
        """The result whose :meth:`to_dict` is ``data`` (with its light curve and chain).

        Raises
        ------
        KeyError
            ``data`` lacks a key this version writes (``params``, say: written
            by an older eclipsebench).
        """
        return cls(**_fields_from_dict(cls, data), lightcurve=dict(lightcurve or {}),
                   chain=None if chain is None else dict(chain))


#: Fields that to_dict writes as they are (the rest are rebuilt by _fields_from_dict).
_NOT_FLAT = ("params", "param_errors", "mcmc", "depth_err_own_ppm", "event_detail",
             "profile_detail", "lightcurve", "chain", "t_event_bmjd", "t_event_err_d",
             "t_event_predicted_bmjd")


def _fields_from_dict(cls, data: Mapping[str, Any]) -> dict[str, Any]:
    """The constructor's keywords (except the light curve and chain) from a RESULT.json dict.

    A null float (NaN, written as null by the command line) comes back as NaN.
    """
    out: dict[str, Any] = {}
    for f in fields(cls):
        if f.name in _NOT_FLAT or f.name not in data:
            continue
        value = data[f.name]
        out[f.name] = float("nan") if value is None and f.type == "float" else value
    event = {k: data[k] for k in data.get("event_keys", [])}
    prefix = event_for(event.get("event")).time_prefix
    out.update(t_event_bmjd=data[f"{prefix}_bmjd"], t_event_err_d=data[f"{prefix}_err_d"],
               t_event_predicted_bmjd=data[f"{prefix}_predicted_bmjd"])
    mcmc = {k[5:]: v for k, v in data.items() if k.startswith("mcmc_")}
    out.update(params=dict(data["params"]), param_errors=dict(data["param_errors"]),
               mcmc=mcmc or None, depth_err_own_ppm=dict(data["depth_err_own_ppm"]),
               event_detail=event, profile_detail=dict(data.get("profile_detail", {})))
    return out


def lightcurve_errors(flux: np.ndarray, flux_err: np.ndarray,
                      corrected: np.ndarray) -> dict[str, np.ndarray]:
    """The decorrelated flux error and the relative systematics model.

    ``flux / corrected`` is the systematics times the star's flux (electrons
    for this package's tables); ``flux_err`` divided by it is the error of
    the decorrelated (relative) flux, and divided by its median it is the
    systematics relative to their median (dimensionless).

    Examples
    --------
    >>> out = lightcurve_errors(np.array([2.0, 4.0]), np.array([0.2, 0.2]), np.array([1.0, 1.0]))
    >>> out["flux_err"].tolist(), out["systematics_model"].tolist()
    ([0.1, 0.05], [0.6666666666666666, 1.3333333333333333])
    """
    flux = np.asarray(flux, dtype=float)
    corrected = np.asarray(corrected, dtype=float)
    if flux.shape != corrected.shape:   # a method that corrects other points than it fits
        return {}
    systematic = flux / corrected
    return {"flux_err": np.asarray(flux_err, dtype=float) / systematic,
            "systematics_model": systematic / np.median(systematic)}


def bic_data(result: Mapping[str, Any]) -> str:
    """What a result's BIC and AIC were computed on: ``"14418 frames"`` or
    ``"227 bins of 14525 frames"``.

    Two BICs compare only when this (and the epoch) is the same: a binned
    fit's likelihood is over fewer, less noisy points.

    Examples
    --------
    >>> bic_data({"bic_n_points": 227, "n_frames": 14525})
    '227 bins of 14525 frames'
    """
    n, frames = result.get("bic_n_points"), result.get("n_frames")
    if n is None:
        return "points not recorded"
    if frames is None or n == frames:
        return f"{n} frames"
    return f"{n} bins of {frames} frames"
