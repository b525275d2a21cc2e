"""The statistics JSON of a run: every method, the averages, t-tests and ANOVA.

``{"methods": {NAME: method_statistics + closest match}, "average": {...},
"ttest": {...}, "anova": {...}}`` -- the contract of ``eclipsebench stats
--json`` and of ``summary.json``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..limits import MAX_BOOTSTRAP, check_size
from .compare import compare_methods, group_by_method
from .ensemble import method_statistics, validate_depths

__all__ = ["summarize", "AVERAGED_KEYS"]

#: Columns averaged straight across methods (the paper's "Average" row, note j).
AVERAGED_KEYS = ("D_mean", "sigma_mean", "SD", "sigma_orig", "f_dis", "sigma_tot", "R", "r",
                 "RMSE", "bias", "a", "coverage", "coverage_2sigma", "z_rms")


def summarize(table, *, sigma_phot_ppm: float | None = None, truth_ppm: float | None = None,
              methods: Sequence[str] | None = None, seed: int = 0,
              n_bootstrap: int = 2000) -> dict:
    """Per-method statistics and method comparisons of a depth table.

    Parameters
    ----------
    table : astropy Table or mapping of columns
        Columns ``method``, ``epoch``, ``depth_ppm``, ``error_ppm``.
    sigma_phot_ppm, truth_ppm : float, optional
        Photon limit and true depth (see :func:`.ensemble.method_statistics`).
    methods : sequence of str, optional
        Restrict to these methods (also for the t-tests and ANOVA).
    seed, n_bootstrap : int
        Bootstrap resampling (``n_bootstrap`` at most
        :data:`eclipsebench.limits.MAX_BOOTSTRAP`).

    Returns
    -------
    dict
        ``methods`` (each with ``closest_match``, ``closest_match_mean_ppm``,
        ``closest_match_sd_ppm``), ``average``, ``ttest``, ``anova``,
        ``sigma_phot_ppm`` and ``truth_ppm``.
    """
    check_size("n_bootstrap", n_bootstrap, MAX_BOOTSTRAP, "resamples")
    groups = group_by_method(table, methods)
    per_method = {}
    for name, g in groups.items():
        validate_depths(g.depth_ppm, g.error_ppm, name=f"method '{name}'")
        per_method[name] = method_statistics(g.depth_ppm, g.error_ppm,
                                             sigma_phot_ppm=sigma_phot_ppm, truth_ppm=truth_ppm,
                                             seed=seed, n_bootstrap=n_bootstrap)
        per_method[name]["epochs"] = [int(e) for e in g.epoch]
    comparison = compare_methods(table, methods=list(groups))
    for name, match in comparison["closest_match"].items():
        per_method[name]["closest_match"] = match["method"]
        per_method[name]["closest_match_mean_ppm"] = match["mean_ppm"]
        per_method[name]["closest_match_sd_ppm"] = match["sd_ppm"]
    average = {}
    for key in AVERAGED_KEYS:
        values = [s[key] for s in per_method.values() if s[key] is not None]
        average[key] = float(np.mean(values)) if values and np.all(np.isfinite(values)) else None
    return {"methods": per_method, "average": average, "ttest": comparison["ttest"],
            "anova": comparison["anova"], "sigma_phot_ppm": sigma_phot_ppm,
            "truth_ppm": truth_ppm}
