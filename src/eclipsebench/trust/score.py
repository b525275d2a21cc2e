"""How well each method measured the twins: bias, spread, error calibration, a recommendation.

Pure functions on arrays and dicts. For one method, the twins' depths
``D_i`` with reported errors ``sigma_i`` against the injected depth ``D``
give (``docs/trust.md``):

- ``bias_ppm = mean(D_i - D)``, ``sd_ppm`` (sample standard deviation),
  ``rmse_ppm = sqrt(mean((D_i - D)^2))`` -- the paper's accuracy statistics
  (Section 3.3) over twins of one observation instead of challenge epochs;
- ``mean_err_ppm = mean(sigma_i)`` and ``z_rms = sqrt(mean(z_i^2))`` with
  ``z_i = (D_i - D) / sigma_i``: 1 when the reported errors are honest;
- 1- and 2-sigma coverage with exact binomial intervals
  (:func:`eclipsebench.stats.ensemble.coverage`);
- the honest error of the real depth: its reported error times
  ``max(1, z_rms)``.

The recommended method has the lowest RMSE among those whose 1-sigma
coverage interval contains 68.3 %. Whether another such method is
distinguishable from it is a paired test over the twins both reduced
(:func:`mse_excess_sigma`, the loss-differential test of Diebold & Mariano
1995 with squared error as the loss): the mean of ``r_i^2 - r_best,i^2`` in
units of its standard error. Below :data:`DISTINGUISHABLE_AT` the twins
cannot tell the two apart (:func:`near_equals`).

:func:`red_noise_check` compares the real fit's ``beta_red`` (the
time-averaging factor of its residuals) with the twins': where the real
residuals are redder than :data:`REDDER_THAN` of the twins', they hold
correlated noise the twins lack, and the twin RMSE may under-predict the
error (``docs/trust.md``, "Validation").
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..photometry.binning import bin_indices, bin_values
from ..stats.ensemble import GAUSS_1SIGMA, coverage

__all__ = ["method_score", "recommend", "score_methods", "red_noise_check", "REDDER_THAN",
           "observation_statistics", "mse_excess_sigma", "near_equals", "DISTINGUISHABLE_AT"]

#: The real residuals are flagged redder than the twins' when their ``beta_red`` exceeds
#: this fraction of the twins' (a one-sided test at 5 %).
REDDER_THAN = 0.95

#: Another method ranks below the recommended one only when its mean squared twin error
#: exceeds the recommended one's by at least this many paired standard errors (2.3 %
#: one-sided for a Gaussian mean).
DISTINGUISHABLE_AT = 2.0


def method_score(depth_ppm: Sequence[float], error_ppm: Sequence[float], truth_ppm: float
                 ) -> dict[str, Any]:
    """The twin statistics of one method (module docstring).

    Examples
    --------
    >>> s = method_score([1010.0, 990.0, 1020.0, 980.0], [20.0] * 4, 1000.0)
    >>> s["bias_ppm"], round(s["rmse_ppm"], 2), round(s["z_rms"], 3)
    (0.0, 15.81, 0.791)
    """
    d = np.asarray(depth_ppm, float)
    e = np.asarray(error_ppm, float)
    resid = d - float(truth_ppm)
    z = resid / e
    c1, c1_lo, c1_hi = coverage(d, e, truth_ppm, 1.0)
    c2, c2_lo, c2_hi = coverage(d, e, truth_ppm, 2.0)
    return {"n_twins": int(d.size), "bias_ppm": float(resid.mean()),
            "sd_ppm": float(resid.std(ddof=1)) if d.size > 1 else float("nan"),
            "rmse_ppm": float(np.sqrt(np.mean(resid**2))), "mean_err_ppm": float(e.mean()),
            "z_rms": float(np.sqrt(np.mean(z**2))),
            "coverage_1sigma": c1, "coverage_1sigma_interval": [c1_lo, c1_hi],
            "coverage_2sigma": c2, "coverage_2sigma_interval": [c2_lo, c2_hi]}


def recommend(scores: Mapping[str, Mapping[str, Any]]) -> tuple[str | None, str]:
    """The lowest-RMSE method whose 1-sigma coverage is consistent with 68.3 %, and why.

    Examples
    --------
    >>> recommend({"a": {"rmse_ppm": 50.0, "coverage_1sigma_interval": [0.3, 0.5]},
    ...            "b": {"rmse_ppm": 60.0, "coverage_1sigma_interval": [0.6, 0.8]}})
    ('b', 'lowest RMSE (60.0 ppm) of the 1 method(s) whose 1-sigma coverage is consistent with 68%')
    """
    honest = {m: s for m, s in scores.items()
              if s["coverage_1sigma_interval"][0] <= GAUSS_1SIGMA
              <= s["coverage_1sigma_interval"][1]}
    if not honest:
        return None, "no method's 1-sigma coverage is consistent with 68%: none recommended"
    best = min(honest, key=lambda m: (honest[m]["rmse_ppm"], m))
    return best, (f"lowest RMSE ({honest[best]['rmse_ppm']:.1f} ppm) of the {len(honest)} "
                  "method(s) whose 1-sigma coverage is consistent with 68%")


def mse_excess_sigma(resid_ppm: Mapping[int, float], reference_ppm: Mapping[int, float]
                     ) -> float:
    """How many paired standard errors one method's mean squared twin error exceeds another's.

    Parameters
    ----------
    resid_ppm, reference_ppm : mapping
        ``{twin: depth - truth}`` of the method and of the reference; only the
        twins both reduced count.

    Returns
    -------
    float
        ``mean(d) / (sd(d) / sqrt(n))`` with ``d_i = r_i^2 - ref_i^2``; NaN
        with fewer than 3 common twins, 0 when the two agree on every twin.

    Examples
    --------
    >>> round(mse_excess_sigma({1: 3.0, 2: -2.0, 3: 2.5, 4: -3.0},
    ...                        {1: 1.0, 2: -1.0, 3: 0.5, 4: -1.5}), 2)
    5.59
    """
    common = sorted(set(resid_ppm) & set(reference_ppm))
    if len(common) < 3:
        return float("nan")
    d = (np.array([resid_ppm[i] for i in common], float) ** 2
         - np.array([reference_ppm[i] for i in common], float) ** 2)
    se = float(d.std(ddof=1) / np.sqrt(d.size))
    if se == 0.0:
        return 0.0 if float(d.mean()) == 0.0 else float(np.sign(d.mean()) * np.inf)
    return float(d.mean()) / se


def near_equals(scores: Mapping[str, Mapping[str, Any]],
                resid_ppm: Mapping[str, Mapping[int, float]], best: str | None) -> list[str]:
    """The other coverage-consistent methods the twins cannot tell from the recommended one.

    Those whose :func:`mse_excess_sigma` against ``best`` is below
    :data:`DISTINGUISHABLE_AT` (or undefined), in the order of their RMSE.

    Examples
    --------
    >>> scores = {m: {"rmse_ppm": r, "coverage_1sigma_interval": [0.6, 0.8]}
    ...           for m, r in (("a", 1.0), ("b", 1.1), ("c", 3.0))}
    >>> resid = {"a": {1: 1.0, 2: -1.0, 3: 1.2, 4: -0.8}, "b": {1: 1.1, 2: -0.9, 3: 1.3, 4: -1.0},
    ...          "c": {1: 3.0, 2: -3.1, 3: 2.9, 4: -3.0}}
    >>> near_equals(scores, resid, "a")
    ['b']
    """
    if best is None:
        return []
    out = []
    for m, s in sorted(scores.items(), key=lambda kv: (kv[1]["rmse_ppm"], kv[0])):
        lo, hi = s["coverage_1sigma_interval"]
        if m == best or not lo <= GAUSS_1SIGMA <= hi:
            continue
        excess = mse_excess_sigma(resid_ppm[m], resid_ppm[best])
        if not excess >= DISTINGUISHABLE_AT:
            out.append(m)
    return out


def score_methods(twin_depths: Mapping[str, tuple[Sequence[float], Sequence[float]]],
                  real: Mapping[str, Mapping[str, float]], truth_ppm: float
                  ) -> dict[str, dict[str, Any]]:
    """:func:`method_score` of every method, with its real depth and honest error.

    Parameters
    ----------
    twin_depths : mapping
        ``{method: (depths_ppm, errors_ppm)}`` over the twins.
    real : mapping
        ``{method: {"depth_ppm", "depth_err_ppm"}}`` on the real observation.
    truth_ppm : float
        The depth injected into the twins.
    """
    out = {}
    for method, (depths, errors) in twin_depths.items():
        s = method_score(depths, errors, truth_ppm)
        err = float(real[method]["depth_err_ppm"])
        s.update({"depth_ppm": float(real[method]["depth_ppm"]), "depth_err_ppm": err,
                  "honest_err_ppm": err * max(1.0, s["z_rms"])})
        out[method] = s
    return out


def red_noise_check(real_beta_red: float, twin_beta_red: Sequence[float]) -> dict[str, Any]:
    """Whether the real residuals hold more correlated noise than the twins'.

    Returns ``beta_red_real``, ``beta_red_twins_median``, ``beta_red_twins_below``
    (the fraction of twins whose ``beta_red`` is below the real one; non-finite
    values left out) and ``redder_than_twins`` (that fraction at least
    :data:`REDDER_THAN`).

    Examples
    --------
    >>> c = red_noise_check(1.14, [0.85, 0.88, 0.9, 0.92, 0.87])
    >>> c["beta_red_twins_below"], c["redder_than_twins"]
    (1.0, True)
    """
    twins = np.asarray(twin_beta_red, float)
    twins = twins[np.isfinite(twins)]
    real = float(real_beta_red)
    below = float(np.mean(twins < real)) if twins.size and np.isfinite(real) else float("nan")
    return {"beta_red_real": real,
            "beta_red_twins_median": float(np.median(twins)) if twins.size else float("nan"),
            "beta_red_twins_below": below, "redder_than_twins": bool(below >= REDDER_THAN)}


def observation_statistics(table) -> dict[str, float]:
    """What a twin must share with its observation, measured on a photometry table's good frames.

    The median noise pixels, the centroid rms in x and y (px) and the raw
    flux rms in 5-minute bins (relative, ppm): ``docs/trust.md``,
    "Validation".
    """
    good = np.asarray(table["flag"]) == 0
    flux = np.asarray(table["flux"], float)[good]
    bins = bin_indices(np.asarray(table["time_bmjd"])[good], width_days=5.0 / 1440.0)
    binned, _ = bin_values(flux, bins)
    return {"noise_pixels_median": float(np.median(np.asarray(table["noise_pixels"])[good])),
            "x_rms_px": float(np.std(np.asarray(table["x"], float)[good])),
            "y_rms_px": float(np.std(np.asarray(table["y"], float)[good])),
            "flux_rms_5min_ppm": float(np.std(binned / np.median(binned)) * 1e6)}
