"""Ensemble statistics of one method's eclipse depths over many epochs.

Pure functions on arrays (Section 3.2 and 3.4 of Ingalls et al. 2016): the
weighted mean and its uncertainty, the dispersion factor ``f_dis`` with its
68% interval, the repeatability ``R``, the reliability ``r`` and, given the
true depth, the RMSE, bias and accuracy ``a``. Every column of the paper's
Tables 3 and 4 (``eclipse_depth_stats``, ``eclipse_depth_stats_sim``) except
the closest match, which needs the other methods (:mod:`.compare`).

Beyond the paper, given the true depth: the normalised residuals
``(D_i - truth) / sigma_i`` and the 1- and 2-sigma coverage of the truth
with exact (Clopper-Pearson) binomial intervals, which say whether the
reported errors are honest once a Monte Carlo has many epochs.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats as _sps

from ..errors import InputError
from .bootstrap import bootstrap_intervals

__all__ = ["validate_depths", "weighted_mean", "dispersion_factor", "dispersion_interval",
           "pairwise_differences", "repeatability", "normalised_residuals", "binomial_interval",
           "coverage", "accuracy_statistics", "method_statistics", "STAT_KEYS", "GAUSS_1SIGMA",
           "GAUSS_2SIGMA"]

#: The keys of :func:`method_statistics`, in the order of the paper's Table 4.
STAT_KEYS = ("N", "D_mean", "sigma_mean", "SD", "sigma_orig", "f_dis", "f_dis_raw", "f_dis_lo",
             "f_dis_hi", "sigma_tot", "R", "r", "RMSE", "bias", "a", "mean_ppm", "chi2",
             "coverage", "coverage_lo", "coverage_hi", "coverage_2sigma", "coverage_2sigma_lo",
             "coverage_2sigma_hi", "z_rms", "sigma_phot_ppm", "truth_ppm", "R_lo", "R_hi", "r_lo",
             "r_hi", "a_lo", "a_hi")

#: Probability that a Gaussian deviate lies within 1 sigma of its mean (0.6827).
GAUSS_1SIGMA = math.erf(1.0 / math.sqrt(2.0))
#: Probability that a Gaussian deviate lies within 2 sigma of its mean (0.9545).
GAUSS_2SIGMA = math.erf(2.0 / math.sqrt(2.0))


def validate_depths(depth_ppm, error_ppm, *, name: str = "depths") -> tuple[np.ndarray, np.ndarray]:
    """Check and return the depths and errors as float arrays.

    Raises
    ------
    InputError
        Fewer than two epochs, different lengths, non-finite values or
        non-positive errors (named by ``name``).
    """
    d = np.asarray(depth_ppm, dtype=float).ravel()
    e = np.asarray(error_ppm, dtype=float).ravel()
    if d.shape != e.shape:
        raise InputError(f"{name}: expected as many errors as depths, got {e.size} and {d.size}")
    if d.size < 2:
        raise InputError(f"{name}: expected at least 2 epochs, got {d.size}")
    if not (np.all(np.isfinite(d)) and np.all(np.isfinite(e))):
        raise InputError(f"{name}: expected finite depth_ppm and error_ppm (found NaN or inf)")
    if np.any(e <= 0):
        raise InputError(f"{name}: expected positive error_ppm values")
    return d, e


def weighted_mean(depth_ppm, error_ppm) -> tuple[float, float]:
    """Inverse-variance weighted mean and its original uncertainty.

    Eq. ``weighted_mean`` with ``w_i = 1 / sigma_i^2`` (``f_dis`` cancels in
    the mean); ``sigma_orig^2 = 1 / sum(w_i)``.

    Returns
    -------
    tuple of float
        ``(D_mean, sigma_orig)`` in the units of the inputs.
    """
    d, e = validate_depths(depth_ppm, error_ppm)
    w = 1.0 / e**2
    return float(np.sum(w * d) / np.sum(w)), float(1.0 / math.sqrt(np.sum(w)))


def dispersion_factor(depth_ppm, error_ppm) -> float:
    """The raw dispersion factor (Eq. ``f_dis``), not floored.

    ``f_dis^2 = sum((D_i - D_mean)^2 / sigma_i^2) / (N - 1)``, which makes the
    chi-square of Eq. ``chisquared`` equal to N - 1.
    """
    d, e = validate_depths(depth_ppm, error_ppm)
    mean, _ = weighted_mean(d, e)
    return float(math.sqrt(np.sum((d - mean) ** 2 / e**2) / (d.size - 1)))


def dispersion_interval(f_dis: float, n: int, level: float = 0.68) -> tuple[float, float]:
    """The ``level`` confidence interval on ``f_dis`` (Section 3.2).

    The sum of Eq. ``chisquared`` with the true factor ``f`` follows a
    chi-square distribution with ``N - 1`` degrees of freedom, and that sum
    equals ``(N - 1) f_dis^2 / f^2``; the bounds are the ``f`` at which it
    reaches the (1 + level)/2 and (1 - level)/2 quantiles (84% and 16%).
    For N = 10 and f_dis = 1.5 this is 1.25-2.03, i.e. +0.5/-0.3 (Table 3).

    Returns
    -------
    tuple of float
        ``(f_lo, f_hi)``, absolute bounds (not offsets).
    """
    if n < 2:
        raise InputError(f"dispersion interval: expected N >= 2, got {n}")
    dof = n - 1
    q_hi = _sps.chi2.ppf(0.5 + level / 2.0, dof)
    q_lo = _sps.chi2.ppf(0.5 - level / 2.0, dof)
    return float(f_dis * math.sqrt(dof / q_hi)), float(f_dis * math.sqrt(dof / q_lo))


def pairwise_differences(depth_ppm) -> np.ndarray:
    """All differences ``D_i - D_j`` for ``i != j``, each pair in both orders.

    Section 3.4.1: "each pair must be counted twice, with the order of the
    indices reversed", so there are ``N (N - 1)`` differences with mean zero.
    """
    d = np.asarray(depth_ppm, dtype=float).ravel()
    diff = d[:, None] - d[None, :]
    return diff[~np.eye(d.size, dtype=bool)]


def repeatability(depth_ppm) -> float:
    """Repeatability ``R = SD(Delta_ij)`` (Section 3.4.1), sample SD (M - 1).

    Over the ``M = N (N - 1)`` ordered differences, ``R / SD = sqrt(2 M / (M - 1))``
    exactly; for N = 10 that is ``sqrt(2 * 90 / 89)``.
    """
    diffs = pairwise_differences(depth_ppm)
    if diffs.size < 2:
        raise InputError(f"repeatability: expected at least 2 epochs, got {np.size(depth_ppm)}")
    return float(np.std(diffs, ddof=1))


def normalised_residuals(depth_ppm, error_ppm, truth_ppm: float) -> np.ndarray:
    """``z_i = (D_i - truth) / sigma_i``: unit Gaussian deviates if the errors are honest.

    Examples
    --------
    >>> normalised_residuals([1900.0, 1800.0], [50.0, 100.0], 1875.0).tolist()
    [0.5, -0.75]
    """
    d, e = validate_depths(depth_ppm, error_ppm)
    return (d - float(truth_ppm)) / e


def binomial_interval(k: int, n: int, level: float = 0.68) -> tuple[float, float]:
    """Exact (Clopper-Pearson) ``level`` interval on a proportion of ``k`` in ``n``.

    The bounds are the proportions ``p`` at which seeing ``k`` or more
    (lower bound) or ``k`` or fewer (upper bound) successes has probability
    ``(1 - level) / 2``: the Beta quantiles ``B((1 - level)/2; k, n - k + 1)``
    and ``B((1 + level)/2; k + 1, n - k)``, with 0 for ``k = 0`` and 1 for
    ``k = n`` (then the other bound is ``((1 - level)/2)^(1/n)`` from the
    nearer end). The same as ``scipy.stats.binomtest(k, n).proportion_ci(level)``.

    Exact rather than Wilson: it covers the true proportion with probability
    at least ``level`` for every proportion and ``n``; Wilson's does so only
    on average (for n = 10 its 68% interval covers a proportion 0.5 with
    probability 0.39 at worst; for n = 100 and p = 0.9545 with 0.67). The
    price is width: 0.627-0.729 instead of 0.632-0.724 for 68 of 100.

    Examples
    --------
    >>> lo, hi = binomial_interval(10, 10)
    >>> round(lo, 4), hi
    (0.8326, 1.0)
    """
    if n < 1 or not 0 <= k <= n:
        raise InputError(f"binomial interval: expected 0 <= k <= n and n >= 1, got k={k}, n={n}")
    tail = (1.0 - level) / 2.0
    lo = 0.0 if k == 0 else float(_sps.beta.ppf(tail, k, n - k + 1))
    hi = 1.0 if k == n else float(_sps.beta.ppf(1.0 - tail, k + 1, n - k))
    return lo, hi


def coverage(depth_ppm, error_ppm, truth_ppm: float, n_sigma: float = 1.0,
             level: float = 0.68) -> tuple[float, float, float]:
    """Fraction of epochs with ``|D_i - truth| <= n_sigma * sigma_i`` and its interval.

    Each epoch covers the truth or not, independently, so the count is
    binomial; the interval is :func:`binomial_interval` at ``level``. Honest
    Gaussian errors give :data:`GAUSS_1SIGMA` (0.683) for ``n_sigma = 1``
    and :data:`GAUSS_2SIGMA` (0.954) for 2.

    Returns
    -------
    tuple of float
        ``(fraction, lo, hi)``.

    Examples
    --------
    >>> f, lo, hi = coverage([1880.0, 1875.0, 2100.0, 1700.0], [10.0] * 4, 1875.0)
    >>> f
    0.5
    """
    z = normalised_residuals(depth_ppm, error_ppm, truth_ppm)
    k = int(np.sum(np.abs(z) <= n_sigma))
    lo, hi = binomial_interval(k, z.size, level)
    return k / z.size, lo, hi


def accuracy_statistics(depth_ppm, error_ppm, truth_ppm: float) -> dict:
    """How far depths of a known truth fall from it (Section 3.4.3): plain means throughout.

    The one definition of the accuracy statistics, used by :func:`method_statistics`
    (Table 4's ``RMSE`` and ``bias``) and by ``trust``'s scores over its twins
    (:func:`eclipsebench.trust.score.error_score`). With ``r_i = D_i - D_t``:

    - ``bias = mean(r_i)``, the paper's mean bias ``B = D - D_t`` with ``D`` the plain
      mean of the depths (the equation after Eq. ``mse``; not the weighted mean);
    - ``SD``, the sample SD of ``r_i`` (N - 1; NaN for one depth), which is that of ``D_i``;
    - ``RMSE = sqrt(mean(r_i^2))`` (Eq. ``mse``);
    - with errors ``sigma_i``: ``sigma_mean = mean(sigma_i)``, ``z_rms = sqrt(mean(z_i^2))``
      with ``z_i = r_i / sigma_i`` (1 when the errors are honest) and the 1- and 2-sigma
      :func:`coverage` of the truth with their binomial intervals (``coverage``,
      ``coverage_lo``, ``coverage_hi``, ``coverage_2sigma``...).

    Parameters
    ----------
    depth_ppm : array_like, shape (N,)
        The measured values (N >= 1), finite; any unit (ppm for depths).
    error_ppm : array_like, shape (N,) or None
        Their reported 1-sigma errors, finite and positive; None: the error statistics
        are None.
    truth_ppm : float
        The true value (0 for values that are already errors against the truth).

    Examples
    --------
    >>> s = accuracy_statistics([1010.0, 990.0, 1020.0, 980.0], [20.0] * 4, 1000.0)
    >>> s["bias"], round(s["RMSE"], 2), round(s["z_rms"], 3), s["coverage"]
    (0.0, 15.81, 0.791, 1.0)
    """
    d = np.asarray(depth_ppm, dtype=float).ravel()
    if d.size < 1 or not np.all(np.isfinite(d)):
        raise InputError(f"accuracy: expected at least one finite value, got {d.size}")
    r = d - float(truth_ppm)
    out: dict = {"N": int(r.size), "bias": float(r.mean()),
                 "SD": float(r.std(ddof=1)) if r.size > 1 else float("nan"),
                 "RMSE": float(np.sqrt(np.mean(r**2))),   # Eq. mse
                 "sigma_mean": None, "z_rms": None,
                 "coverage": None, "coverage_lo": None, "coverage_hi": None,
                 "coverage_2sigma": None, "coverage_2sigma_lo": None, "coverage_2sigma_hi": None}
    if error_ppm is None:
        return out
    e = np.asarray(error_ppm, dtype=float).ravel()
    if e.shape != r.shape or not np.all(np.isfinite(e)) or np.any(e <= 0):
        raise InputError(f"accuracy: expected {r.size} finite positive errors")
    z = r / e
    out["sigma_mean"] = float(e.mean())
    out["z_rms"] = float(np.sqrt(np.mean(z**2)))
    for key, n_sigma in (("coverage", 1.0), ("coverage_2sigma", 2.0)):
        out[key], out[f"{key}_lo"], out[f"{key}_hi"] = coverage(r, e, 0.0, n_sigma)
    return out


def method_statistics(depth_ppm, error_ppm, *, sigma_phot_ppm: float | None = None,
                      truth_ppm: float | None = None, seed: int = 0,
                      n_bootstrap: int = 2000) -> dict:
    """Every per-method statistic of the paper's Tables 3 and 4.

    Parameters
    ----------
    depth_ppm, error_ppm : array_like, shape (N,)
        One method's eclipse depths and reported 1-sigma errors, N >= 2.
    sigma_phot_ppm : float, optional
        Photon-noise limit of one depth (Eq. ``photon_noise``); gives ``r``
        and, with ``truth_ppm``, ``a``.
    truth_ppm : float, optional
        The true depth; gives ``RMSE`` (Eq. ``mse``), ``bias`` and ``coverage``.
    seed : int
        Seed of the bootstrap resampling (:mod:`eclipsebench.seeding`).
    n_bootstrap : int
        Bootstrap resamples for the intervals on R, r and a (0: none).

    Returns
    -------
    dict
        ``N``; ``D_mean`` (Eq. ``weighted_mean``); ``sigma_mean`` (mean
        reported error); ``SD`` (sample SD, N - 1); ``sigma_orig``;
        ``f_dis`` (Eq. ``f_dis`` floored at 1), ``f_dis_raw``, ``f_dis_lo``,
        ``f_dis_hi`` (68% interval on ``f_dis_raw``); ``sigma_tot = f_dis
        sigma_orig``; ``R``; ``r = sigma_phot / SD``; ``RMSE``; ``bias =
        mean(D_i - truth)``, the plain mean (:func:`accuracy_statistics`, the one
        definition); ``a = sigma_phot / RMSE``; ``mean_ppm`` (unweighted
        mean); ``chi2`` (Eq. ``chisquared`` with f_dis = 1); ``coverage``
        (fraction of epochs with ``|D_i - truth| <= sigma_i``); bootstrap
        68% intervals ``R_lo``.. ``a_hi``. Values that need an input not
        given are ``None``. All in ppm except the ratios.
    """
    d, e = validate_depths(depth_ppm, error_ppm)
    n = d.size
    d_mean, sigma_orig = weighted_mean(d, e)
    chi2 = float(np.sum((d - d_mean) ** 2 / e**2))
    f_raw = math.sqrt(chi2 / (n - 1))
    f_lo, f_hi = dispersion_interval(f_raw, n)
    f_dis = max(1.0, f_raw)
    sd = float(np.std(d, ddof=1))
    out: dict = {
        "N": int(n),
        "D_mean": d_mean,
        "sigma_mean": float(np.mean(e)),
        "SD": sd,
        "sigma_orig": sigma_orig,
        "f_dis": f_dis,
        "f_dis_raw": f_raw,
        "f_dis_lo": f_lo,
        "f_dis_hi": f_hi,
        "sigma_tot": f_dis * sigma_orig,
        "R": repeatability(d),
        "r": None, "RMSE": None, "bias": None, "a": None,
        "mean_ppm": float(np.mean(d)),
        "chi2": chi2,
        "coverage": None, "coverage_lo": None, "coverage_hi": None,
        "coverage_2sigma": None, "coverage_2sigma_lo": None, "coverage_2sigma_hi": None,
        "z_rms": None,
        "sigma_phot_ppm": None if sigma_phot_ppm is None else float(sigma_phot_ppm),
        "truth_ppm": None if truth_ppm is None else float(truth_ppm),
    }
    if sigma_phot_ppm is not None:
        out["r"] = float(sigma_phot_ppm) / sd if sd > 0 else math.inf
    if truth_ppm is not None:
        acc = accuracy_statistics(d, e, truth_ppm)
        rmse = acc["RMSE"]
        out.update({k: acc[k] for k in ("RMSE", "bias", "z_rms", "coverage", "coverage_lo",
                                        "coverage_hi", "coverage_2sigma", "coverage_2sigma_lo",
                                        "coverage_2sigma_hi")})
        if sigma_phot_ppm is not None:
            out["a"] = float(sigma_phot_ppm) / rmse if rmse > 0 else math.inf
    boot = bootstrap_intervals(d, sigma_phot_ppm=sigma_phot_ppm, truth_ppm=truth_ppm, seed=seed,
                               n_resamples=n_bootstrap)
    for name in ("R", "r", "a"):
        lo, hi = boot.get(name, (None, None))
        out[f"{name}_lo"], out[f"{name}_hi"] = lo, hi
    return out
