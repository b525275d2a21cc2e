"""Bootstrap intervals on repeatability, reliability and accuracy.

Beyond the paper: ten epochs are few, so R, r and a carry a large sampling
uncertainty. Epochs are resampled with replacement (seeded through
:mod:`eclipsebench.seeding`, so the same seed gives the same interval); each
statistic is a monotonic function of one per-resample scale (the SD for R and
r, the RMSE for a), so the percentiles of that scale give the intervals.
"""

from __future__ import annotations

import math

import numpy as np

from ..seeding import rng

__all__ = ["bootstrap_intervals"]


def bootstrap_intervals(depth_ppm, *, sigma_phot_ppm: float | None = None,
                        truth_ppm: float | None = None, seed: int = 0,
                        n_resamples: int = 2000, level: float = 0.68) -> dict:
    """Percentile bootstrap intervals on R, r and a.

    Parameters
    ----------
    depth_ppm : array_like, shape (N,)
        One method's depths.
    sigma_phot_ppm, truth_ppm : float, optional
        Needed for r (sigma_phot) and a (both).
    seed : int
        The run's seed; the resampling stream is
        ``rng(seed, "stats", "bootstrap", N)``, shared by all methods with N
        epochs (a paired bootstrap over epochs).
    n_resamples : int
        Number of resamples; 0 returns an empty dict.
    level : float
        Central probability of the interval (0.68: 16th to 84th percentile).

    Returns
    -------
    dict
        ``{"R": (lo, hi), "r": (lo, hi), "a": (lo, hi)}`` for the statistics
        whose inputs were given. An unbounded side is ``inf``.
    """
    d = np.asarray(depth_ppm, dtype=float).ravel()
    n = d.size
    if n_resamples <= 0 or n < 2:
        return {}
    idx = rng(seed, "stats", "bootstrap", n).integers(0, n, size=(int(n_resamples), n))
    samples = d[idx]
    q = [50.0 * (1.0 - level), 50.0 * (1.0 + level)]
    sd_lo, sd_hi = np.percentile(np.std(samples, axis=1, ddof=1), q)
    m = n * (n - 1)
    # R of a resample (duplicated epochs give zero differences) is sqrt(2M/(M-1)) SD.
    factor = math.sqrt(2.0 * m / (m - 1))
    out = {"R": (float(factor * sd_lo), float(factor * sd_hi))}

    def ratio(num: float, den: float) -> float:
        return float(num / den) if den > 0 else math.inf

    if sigma_phot_ppm is not None:
        out["r"] = (ratio(sigma_phot_ppm, sd_hi), ratio(sigma_phot_ppm, sd_lo))
        if truth_ppm is not None:
            rmse = np.sqrt(np.mean((samples - float(truth_ppm)) ** 2, axis=1))
            rmse_lo, rmse_hi = np.percentile(rmse, q)
            out["a"] = (ratio(sigma_phot_ppm, rmse_hi), ratio(sigma_phot_ppm, rmse_lo))
    return out
