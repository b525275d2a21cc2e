"""How well each method measured the twins: bias, spread, error calibration, a recommendation.

Pure functions on arrays and dicts. For one method, the twins' depths
``D_i`` with reported errors ``sigma_i`` against the injected depth ``D``
give (``docs/trust.md``):

- ``bias_ppm = mean(D_i - D)`` (the plain mean, as ``run``'s Table 4 bias),
  ``sd_ppm`` (sample standard deviation), ``rmse_ppm = sqrt(mean((D_i - D)^2))``,
  ``mean_err_ppm = mean(sigma_i)``, ``z_rms = sqrt(mean(z_i^2))`` with
  ``z_i = (D_i - D) / sigma_i`` (1 when the reported errors are honest) and the
  1- and 2-sigma coverage with exact binomial intervals: the paper's accuracy
  statistics (Section 3.4.3) over twins of one observation instead of challenge
  epochs, computed by :func:`eclipsebench.stats.ensemble.accuracy_statistics`
  (the one definition) and only named here;
- the honest error of the real depth: its reported error times
  ``max(1, z_rms)``.

The same statistics of any quantity come from :func:`error_score` (the
mid-event time's in seconds, :func:`timing_score`; a whole phase curve's
semi-amplitude in ppm and peak offset in deg, :func:`phase_score`, the
offset's errors wrapped into [-180, 180) deg).

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

from ..limits import MAX_TWINS
from ..photometry.binning import bin_indices, bin_values
from ..seeding import rng
from ..stats.ensemble import GAUSS_1SIGMA, accuracy_statistics, binomial_interval

__all__ = ["method_score", "recommend", "score_methods", "red_noise_check", "REDDER_THAN",
           "observation_statistics", "mse_excess_sigma", "near_equals", "DISTINGUISHABLE_AT",
           "recommendation_frequency", "ranking_resolution", "RECOMMEND_DRAWS", "RESOLVED_AT",
           "timing_score", "error_score", "phase_score", "PHASE_QUANTITIES",
           "quote"]

#: Bootstrap resamples of the twins behind the recommendation frequencies.
RECOMMEND_DRAWS = 2000
#: The recommendation is resolved when the bootstrap makes it in at least this fraction of
#: the resamples (and the paired test separates it: :func:`ranking_resolution`).
RESOLVED_AT = 0.9

#: The real residuals are flagged redder than the twins' when their ``beta_red`` exceeds
#: this fraction of the twins' (a one-sided test at 5 %).
REDDER_THAN = 0.95

#: Another method ranks below the recommended one only when its mean squared twin error
#: exceeds the recommended one's by at least this many paired standard errors (2.3 %
#: one-sided for a Gaussian mean).
DISTINGUISHABLE_AT = 2.0


def error_score(resid: Sequence[float] | np.ndarray, error: Sequence[float] | np.ndarray, *,
                unit: str = "ppm", prefix: str = "") -> dict[str, Any]:
    """The twin statistics of one quantity from its errors against the truth (module
    docstring): ``resid`` the twins' values minus the injected one, ``error`` their reported
    errors, both in ``unit``; keys ``{prefix}n_twins``, ``{prefix}bias_{unit}``,
    ``{prefix}sd_{unit}``, ``{prefix}rmse_{unit}``, ``{prefix}mean_err_{unit}``,
    ``{prefix}z_rms``, ``{prefix}coverage_1sigma`` and ``_2sigma`` (+ ``_interval``).

    Examples
    --------
    >>> s = error_score([10.0, -10.0, 20.0, -20.0], [20.0] * 4, unit="deg", prefix="offset_")
    >>> s["offset_bias_deg"], round(s["offset_rmse_deg"], 2), s["offset_coverage_1sigma"]
    (0.0, 15.81, 1.0)
    """
    return _named(accuracy_statistics(resid, error, 0.0), unit, prefix)


def _named(acc: Mapping[str, Any], unit: str, prefix: str) -> dict[str, Any]:
    """:func:`~eclipsebench.stats.ensemble.accuracy_statistics` under trust's names
    (``trust.json``, ``trust.ecsv``: ``bias_ppm``, ``sd_ppm``, ``coverage_1sigma``...)."""
    def interval(key: str) -> list[float] | None:
        return None if acc[key] is None else [acc[f"{key}_lo"], acc[f"{key}_hi"]]

    return {f"{prefix}n_twins": acc["N"], f"{prefix}bias_{unit}": acc["bias"],
            f"{prefix}sd_{unit}": acc["SD"], f"{prefix}rmse_{unit}": acc["RMSE"],
            f"{prefix}mean_err_{unit}": acc["sigma_mean"], f"{prefix}z_rms": acc["z_rms"],
            f"{prefix}coverage_1sigma": acc["coverage"],
            f"{prefix}coverage_1sigma_interval": interval("coverage"),
            f"{prefix}coverage_2sigma": acc["coverage_2sigma"],
            f"{prefix}coverage_2sigma_interval": interval("coverage_2sigma")}


def method_score(depth_ppm: Sequence[float], error_ppm: Sequence[float], truth_ppm: float
                 ) -> dict[str, Any]:
    """The twin statistics of one method's depth (:func:`error_score`).

    Examples
    --------
    >>> s = method_score([1010.0, 990.0, 1020.0, 980.0], [20.0] * 4, 1000.0)
    >>> s["bias_ppm"], round(s["rmse_ppm"], 2), round(s["z_rms"], 3)
    (0.0, 15.81, 0.791)
    """
    return error_score(np.asarray(depth_ppm, float) - float(truth_ppm), error_ppm)


#: A whole phase curve's quantities scored over the twins besides the depth: ``(name, unit,
#: angle)``, the keys of a phase-curve result (``{name}_{unit}``, ``{name}_err_{unit}``) and
#: of the twins' truth; an angle's errors are wrapped into [-180, 180) deg.
PHASE_QUANTITIES = (("phase_amplitude", "ppm", False), ("phase_offset", "deg", True))


def phase_score(name: str, unit: str, values: Sequence[float], errors: Sequence[float],
                truth: float, real: float | None, real_err: float | None, *,
                angle: bool = False) -> dict[str, Any] | None:
    """A whole phase curve's amplitude or peak offset over the twins, and an honest error.

    ``values``, ``errors``: the twins' fitted ``name`` and reported errors
    (``unit``); ``truth`` the injected value (:func:`eclipsebench.trust.recipe.phase_truth`),
    ``real`` and ``real_err`` the real fit's. The twins with a finite value count
    (None with fewer than 3). Their errors against the truth (an ``angle``'s
    wrapped into [-180, 180) deg) give :func:`error_score` with prefix ``{name}_``,
    and the real value's honest error ``{name}_honest_err_{unit}``, its error times
    ``max(1, z_rms)``. Where a twin's fit gave no error (not finite and > 0) only the
    bias, SD and RMSE are given: ``{name}_no_error`` says how many lacked one, and the
    error statistics and the honest error are None (none is invented).

    Examples
    --------
    >>> s = phase_score("phase_offset", "deg", [179.0, -179.0, -179.0, 179.0], [2.0] * 4, 180.0,
    ...                 178.0, 2.0, angle=True)   # errors of -1, 1, 1, -1 deg across +-180
    >>> s["phase_offset_bias_deg"], s["phase_offset_rmse_deg"], s["phase_offset_honest_err_deg"]
    (0.0, 1.0, 2.0)
    >>> s = phase_score("phase_amplitude", "ppm", [200.0, 210.0, 190.0], [float("nan")] * 3,
    ...                 200.0, 205.0, None)
    >>> s["phase_amplitude_z_rms"], s["phase_amplitude_no_error"]
    (None, "3 of 3 twins' fits gave no error for phase_amplitude")
    """
    v = np.asarray(values, float)
    e = np.asarray(errors, float)
    ok = np.isfinite(v)
    if ok.sum() < 3:
        return None
    resid = v[ok] - float(truth)
    if angle:
        resid = (resid + 180.0) % 360.0 - 180.0
    err = e[ok]
    has_err = np.isfinite(err) & (err > 0)
    prefix = f"{name}_"
    if has_err.all():
        out = error_score(resid, err, unit=unit, prefix=prefix)
    else:
        out = {**_named(accuracy_statistics(resid, None, 0.0), unit, prefix),
               f"{prefix}no_error": f"{int((~has_err).sum())} of {resid.size} twins' fits gave "
                                    f"no error for {name}"}
    value = float(real) if real is not None and np.isfinite(real) else None
    sigma = (float(real_err) if real_err is not None and np.isfinite(real_err) and real_err > 0
             else None)
    z_rms = out[f"{prefix}z_rms"]
    out.update({f"{name}_{unit}": value, f"{name}_err_{unit}": sigma,
                f"{prefix}honest_err_{unit}": (sigma * max(1.0, z_rms)
                                               if sigma is not None and z_rms is not None
                                               else None)})
    return out


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


def recommendation_frequency(resid_ppm: Mapping[str, Mapping[int, float]],
                             err_ppm: Mapping[str, Mapping[int, float]], *, seed: int = 0,
                             n_draws: int = RECOMMEND_DRAWS) -> dict[str, float]:
    """How often each method would be recommended, over bootstrap resamples of the twins.

    The twins every method reduced are resampled with replacement
    (``rng(seed, "trust", "recommend")``); on each resample :func:`recommend`'s
    rule is applied as it is (the lowest RMSE among the methods whose 1-sigma
    coverage interval contains 68.3 %). A frequency near 1 is a recommendation
    the twins hold to; several methods near equal frequencies are a choice
    among near equals. ``"none"`` counts the resamples with no method
    recommended. Empty with fewer than 3 common twins.

    Examples
    --------
    >>> a = {i: (0.5 if i <= 14 else 2.0) * (-1) ** i for i in range(1, 21)}
    >>> resid = {"a": a, "b": {i: 1.2 * r for i, r in a.items()}}   # b: 20 % worse throughout
    >>> err = {"a": dict.fromkeys(a, 1.5), "b": dict.fromkeys(a, 1.8)}
    >>> recommendation_frequency(resid, err)   # "none": resamples whose coverage is off
    {'a': 0.783, 'b': 0.0, 'none': 0.217}
    """
    methods = sorted(resid_ppm)
    if not methods:
        return {}
    common = sorted(set.intersection(*(set(resid_ppm[m]) & set(err_ppm[m]) for m in methods)))
    n = len(common)
    if n < 3:
        return {}
    draws = rng(seed, "trust", "recommend").integers(0, n, size=(n_draws, n))
    honest_count = np.array([binomial_interval(k, n, 0.68)[0] <= GAUSS_1SIGMA
                             <= binomial_interval(k, n, 0.68)[1] for k in range(n + 1)])
    rmse = np.empty((len(methods), n_draws))
    honest = np.empty((len(methods), n_draws), dtype=bool)
    for j, m in enumerate(methods):
        r = np.array([resid_ppm[m][i] for i in common], float)
        e = np.array([err_ppm[m][i] for i in common], float)
        covered = (np.abs(r) <= e)[draws].sum(axis=1)
        honest[j] = honest_count[covered]
        rmse[j] = np.sqrt(np.mean((r**2)[draws], axis=1))
    ranked = np.where(honest, rmse, np.inf)
    best = np.argmin(ranked, axis=0)    # ties: the first by name, as recommend's rule
    none = ~honest.any(axis=0)
    out = {m: float(np.mean((best == j) & ~none)) for j, m in enumerate(methods)}
    out["none"] = float(np.mean(none))
    return out


def _twins_for(z: float, n: int) -> float:
    """Twins for a statistic ``z`` at ``n`` twins to reach :data:`DISTINGUISHABLE_AT`, if it
    grows as the square root of the twins (infinite for ``z <= 0``)."""
    return n * (DISTINGUISHABLE_AT / z) ** 2 if z > 0 else float("inf")


def _coverage_z(p: float, n: int) -> float:
    """How many binomial standard errors the 1-sigma coverage ``p`` of ``n`` twins lies from
    68.3 % (the coverage verdict of :func:`recommend`)."""
    q = min(max(p, 0.5 / n), 1.0 - 0.5 / n)
    return abs(p - GAUSS_1SIGMA) / np.sqrt(q * (1.0 - q) / n)


def ranking_resolution(scores: Mapping[str, Mapping[str, Any]],
                       resid_ppm: Mapping[str, Mapping[int, float]], best: str | None,
                       n_twins: int, frequency: Mapping[str, float] | None = None
                       ) -> dict[str, Any]:
    """Whether the twins run settle the recommendation, and if not about how many twins would.

    Resolved when the bootstrap recommends ``best`` in at least
    :data:`RESOLVED_AT` of the resamples (:func:`recommendation_frequency`)
    and the paired test (:func:`mse_excess_sigma`) puts every other
    coverage-consistent method at least :data:`DISTINGUISHABLE_AT` standard
    errors behind it. Otherwise the verdicts that decide between ``best`` and
    its contenders (the methods recommended in at least 5 % of the
    resamples, or within the paired test's reach): the paired test against
    each coverage-consistent contender, and for a contender whose coverage
    was found inconsistent, how far its 1-sigma coverage lies from 68.3 % in
    binomial standard errors. Each such statistic ``z`` grows as the square
    root of the twins, so reaching :data:`DISTINGUISHABLE_AT` takes about
    ``n (DISTINGUISHABLE_AT / z)^2`` twins; the largest is
    ``twins_to_resolve`` (None beyond
    :data:`~eclipsebench.limits.MAX_TWINS`: equal to the twins' precision).
    An estimate: the statistics are themselves measured on ``n`` twins.

    Examples
    --------
    >>> scores = {m: {"coverage_1sigma_interval": [0.6, 0.8], "coverage_1sigma": 0.7}
    ...           for m in "ab"}
    >>> resid = {"a": {i: 1.0 + 0.1 * (i % 3) for i in range(10)},
    ...          "b": {i: 1.05 + 0.1 * ((i + 1) % 3) for i in range(10)}}
    >>> r = ranking_resolution(scores, resid, "a", 10, {"a": 0.6, "b": 0.4, "none": 0.0})
    >>> r["resolved"], r["twins_to_resolve"], r["text"][:27]
    (False, 24, 'too few twins to rank: run ')
    """
    frequency = dict(frequency or {})
    if best is None:
        return {"resolved": False, "twins_to_resolve": None, "excess_sigma": {},
                "text": "no method recommended, so nothing to rank"}

    def consistent(m):
        lo, hi = scores[m]["coverage_1sigma_interval"]
        return lo <= GAUSS_1SIGMA <= hi

    others = [m for m in scores if m != best and consistent(m)]
    excess = {m: mse_excess_sigma(resid_ppm[m], resid_ppm[best]) for m in others}
    share = frequency.get(best, 1.0)
    if share >= RESOLVED_AT and all(z >= DISTINGUISHABLE_AT for z in excess.values()):
        text = (f"ranking resolved: {best} in {100 * share:.0f} % of bootstrap resamples, "
                + (f"every other coverage-consistent method at least {DISTINGUISHABLE_AT:g} "
                   "paired standard errors behind" if others
                   else "the only coverage-consistent method"))
        return {"resolved": True, "twins_to_resolve": None, "excess_sigma": excess,
                "text": text}
    contenders = [m for m, f in frequency.items() if m not in (best, "none") and f >= 0.05]
    contenders += [m for m, z in excess.items() if z < DISTINGUISHABLE_AT and m not in contenders]
    needed = [_twins_for(excess[m], n_twins) for m in contenders if m in excess]
    coverage_of = [m for m in contenders if m in scores and not consistent(m)]
    needed += [_twins_for(_coverage_z(scores[m]["coverage_1sigma"], n_twins), n_twins)
               for m in coverage_of]
    most = max(needed, default=float("nan"))
    rivals = ", ".join(sorted(contenders)) or "no method"
    if np.isfinite(most) and n_twins < most <= MAX_TWINS:
        n = int(np.ceil(most))
        text = (f"too few twins to rank: run --twins {n} ({best} is recommended in "
                f"{100 * share:.0f} % of bootstrap resamples; against {rivals}, the paired test "
                "and the coverage verdicts grow as the square root of the twins)")
        return {"resolved": False, "twins_to_resolve": n, "excess_sigma": excess, "text": text}
    if np.isfinite(most) and most <= n_twins:
        text = (f"ranking not resolved: {best} is recommended in {100 * share:.0f} % of "
                f"bootstrap resamples, against {rivals} (each verdict is decided at "
                f"{n_twins} twins, but the choice between them is not)")
        return {"resolved": False, "twins_to_resolve": None, "excess_sigma": excess, "text": text}
    text = (f"the twins cannot rank {best} and {rivals}: equal to the twins' precision (more "
            f"than {MAX_TWINS} twins would be needed)")
    return {"resolved": False, "twins_to_resolve": None, "excess_sigma": excess, "text": text}


def timing_score(t_bmjd: Sequence[float], t_err_d: Sequence[float], truth_bmjd: float,
                 real_t_bmjd: float, real_t_err_d: float) -> dict[str, Any] | None:
    """The mid-event time's statistics over the twins, in seconds, and an honest timing error.

    Only twins whose fit freed the time (a finite error > 0) count; None when
    fewer than 3 did (the time was fixed). ``t_bias_s``, ``t_sd_s``,
    ``t_rmse_s``: the twins' times minus the injected one; ``t_mean_err_s``,
    ``t_z_rms``, ``t_coverage_1sigma`` (+ interval): as for the depth;
    ``t_event_bmjd``, ``t_err_s``: the real fit's time and its error;
    ``t_honest_err_s``: that error times ``max(1, t_z_rms)``.

    Examples
    --------
    >>> s = timing_score([1.0 + 10 / 86400, 1.0 - 10 / 86400, 1.0 + 20 / 86400],
    ...                  [15 / 86400] * 3, 1.0, 1.0, 15 / 86400)
    >>> round(s["t_rmse_s"], 1), round(s["t_honest_err_s"], 1)
    (14.1, 15.0)
    """
    t = np.asarray(t_bmjd, float)
    e = np.asarray(t_err_d, float)
    ok = np.isfinite(t) & np.isfinite(e) & (e > 0)
    if ok.sum() < 3:
        return None
    seconds = 86400.0
    score = error_score(t[ok] * seconds - float(truth_bmjd) * seconds, e[ok] * seconds,
                        unit="s", prefix="t_")
    err_s = float(real_t_err_d) * seconds
    kept = ("t_n_twins", "t_bias_s", "t_sd_s", "t_rmse_s", "t_mean_err_s", "t_z_rms",
            "t_coverage_1sigma", "t_coverage_1sigma_interval")
    return {**{k: score[k] for k in kept},
            "t_event_bmjd": float(real_t_bmjd), "t_err_s": err_s,
            "t_honest_err_s": err_s * max(1.0, score["t_z_rms"])}


def quote(scores: Mapping[str, Mapping[str, Any]], best: str | None) -> dict[str, Any]:
    """The line a user should quote: the recommended method's real depth and honest error.

    Examples
    --------
    >>> quote({"bliss": {"depth_ppm": 1801.7, "honest_err_ppm": 95.26}}, "bliss")["text"]
    'bliss: depth 1801.7 +- 95.3 ppm (honest error)'
    """
    if best is None:
        return {"method": None, "depth_ppm": None, "honest_err_ppm": None,
                "text": "no method recommended: no depth to quote without its cautions"}
    s = scores[best]
    return {"method": best, "depth_ppm": s["depth_ppm"], "honest_err_ppm": s["honest_err_ppm"],
            "text": f"{best}: depth {s['depth_ppm']:.1f} +- {s['honest_err_ppm']:.1f} ppm "
                    "(honest error)"}


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
    "Validation". A table without noise pixels gives NaN for them.
    """
    good = np.asarray(table["flag"]) == 0
    flux = np.asarray(table["flux"], float)[good]
    bins = bin_indices(np.asarray(table["time_bmjd"])[good], width_days=5.0 / 1440.0)
    binned, _ = bin_values(flux, bins)
    noise_pixels = (np.asarray(table["noise_pixels"], float)[good]
                    if "noise_pixels" in table.colnames else np.array([np.nan]))
    return {"noise_pixels_median": float(np.median(noise_pixels)),
            "x_rms_px": float(np.std(np.asarray(table["x"], float)[good])),
            "y_rms_px": float(np.std(np.asarray(table["y"], float)[good])),
            "flux_rms_5min_ppm": float(np.std(binned / np.median(binned)) * 1e6)}
