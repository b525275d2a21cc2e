"""The result of one epoch's fit: its schema, its JSON summary and its light curve.

:class:`EpochResult` is what :func:`eclipsebench.fit.reduce.reduce_epoch`
returns; ``to_dict()`` is what ``RESULT.json`` holds (``docs/fitting.md``
lists the keys).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from astropy.table import Table

from ..errors import InputError
from ..io.atomic import atomic_path

__all__ = ["EpochResult", "jsonable"]


@dataclass(frozen=True)
class EpochResult:
    """The eclipse measured in one epoch by one method.

    ``to_dict()`` gives the JSON-able summary (``docs/fitting.md`` lists the
    keys); ``lightcurve`` holds the decorrelated light curve.
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
    t_ecl_bmjd: float
    t_ecl_err_d: float
    t_ecl_predicted_bmjd: float
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
    #: ``t_ecl_*`` the mid-transit time, which ``to_dict`` names ``t_transit_*``.
    event_detail: dict[str, Any] = field(default_factory=dict)

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
            "t_ecl_bmjd": self.t_ecl_bmjd, "t_ecl_err_d": self.t_ecl_err_d,
            "t_ecl_predicted_bmjd": self.t_ecl_predicted_bmjd,
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
            out["profile_detail"] = jsonable(self.profile_detail)
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
        if self.event_detail.get("event") == "transit":   # its times under their own names
            for key in ("t_ecl_bmjd", "t_ecl_err_d", "t_ecl_predicted_bmjd"):
                del out[key]
        if self.event_detail:
            out.update(jsonable(self.event_detail))
        return out

    def lightcurve_table(self):
        """The decorrelated light curve as an astropy Table (``RESULT.lc.ecsv`` columns)."""
        t = Table({k: self.lightcurve[k] for k in
                   ("time_bmjd", "flux_corrected", "astro_model", "residual")})
        t.meta.update({"method": self.method, "epoch": self.epoch, "depth_ppm": self.depth_ppm,
                       "phase": self.phase})
        return t


def jsonable(obj: Any) -> Any:
    """Diagnostics as plain JSON types (numpy scalars and arrays become numbers and lists)."""
    if isinstance(obj, Mapping):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, np.ndarray)):
        return [jsonable(v) for v in np.asarray(obj, dtype=object).tolist()] \
            if isinstance(obj, np.ndarray) else [jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    return obj
