"""Comparisons between methods (Section 3.5 of the paper).

Pure functions on a depth table (columns ``method``, ``epoch``, ``depth_ppm``,
``error_ppm``): the closest match of each method (the other method whose
per-epoch differences have the smallest ``|mean| + SD``), the unpaired
Student t-test p-value matrix, and the one-way ANOVA F test for all methods
and for any subset.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from scipy import stats as _sps

from ..errors import InputError

__all__ = ["MethodDepths", "group_by_method", "paired_differences", "closest_matches",
           "ttest_matrix", "anova", "compare_methods"]


class MethodDepths:
    """One method's depths, sorted by epoch (epochs unique).

    Attributes
    ----------
    epoch : ndarray of int
    depth_ppm, error_ppm : ndarray of float
    """

    __slots__ = ("epoch", "depth_ppm", "error_ppm")

    def __init__(self, epoch, depth_ppm, error_ppm):
        order = np.argsort(np.asarray(epoch), kind="stable")
        self.epoch = np.asarray(epoch)[order]
        self.depth_ppm = np.asarray(depth_ppm, dtype=float)[order]
        self.error_ppm = np.asarray(error_ppm, dtype=float)[order]


def group_by_method(table, methods: Sequence[str] | None = None) -> dict[str, MethodDepths]:
    """Split a depth table into one :class:`MethodDepths` per method.

    Parameters
    ----------
    table : astropy Table or mapping of columns
        Columns ``method``, ``epoch``, ``depth_ppm``, ``error_ppm``.
    methods : sequence of str, optional
        Keep only these methods, in this order (default: all, in order of
        first appearance).

    Raises
    ------
    InputError
        A method asked for is absent, or an epoch appears twice for a method.
    """
    names = np.asarray([str(m) for m in table["method"]])
    epoch = np.asarray(table["epoch"])
    depth = np.asarray(table["depth_ppm"], dtype=float)
    error = np.asarray(table["error_ppm"], dtype=float)
    present = list(dict.fromkeys(names.tolist()))
    if methods is None:
        wanted = present
    else:
        wanted = list(methods)
        missing = [m for m in wanted if m not in present]
        if missing:
            raise InputError(f"--methods: {', '.join(missing)} not in the table "
                             f"(present: {', '.join(present)})")
    out = {}
    for name in wanted:
        sel = names == name
        ep = epoch[sel]
        if np.unique(ep).size != ep.size:
            raise InputError(f"method '{name}': an epoch appears more than once")
        out[name] = MethodDepths(ep, depth[sel], error[sel])
    return out


def paired_differences(a: MethodDepths, b: MethodDepths) -> np.ndarray:
    """``D_a - D_b`` on the epochs both methods measured, in epoch order."""
    common, ia, ib = np.intersect1d(a.epoch, b.epoch, return_indices=True)
    return a.depth_ppm[ia] - b.depth_ppm[ib]


def closest_matches(groups: Mapping[str, MethodDepths]) -> dict[str, dict]:
    """The closest match of each method (Table 4, column 10).

    The other method ``k`` minimising ``|mean(Delta)| + SD(Delta)`` with
    ``Delta = D_this - D_k`` per common epoch (SD with N - 1; at least two
    common epochs). Ties go to the method listed first.

    Returns
    -------
    dict
        ``{method: {"method": k, "mean_ppm": ..., "sd_ppm": ..., "n": ...}}``;
        ``method`` is ``None`` when no other method shares two epochs.
    """
    out = {}
    for name, g in groups.items():
        best: dict[str, Any] = {"method": None, "mean_ppm": None, "sd_ppm": None, "n": 0}
        best_score = math.inf
        for other, h in groups.items():
            if other == name:
                continue
            diff = paired_differences(g, h)
            if diff.size < 2:
                continue
            mean, sd = float(np.mean(diff)), float(np.std(diff, ddof=1))
            if abs(mean) + sd < best_score:
                best_score = abs(mean) + sd
                best = {"method": other, "mean_ppm": mean, "sd_ppm": sd, "n": int(diff.size)}
        out[name] = best
    return out


def _ttest(a: np.ndarray, b: np.ndarray) -> tuple[float | None, float | None]:
    if a.size < 2 or b.size < 2 or (np.ptp(a) == 0 and np.ptp(b) == 0):
        return None, None
    res = _sps.ttest_ind(a, b, equal_var=True)
    return float(res.statistic), float(res.pvalue)


def ttest_matrix(groups: Mapping[str, MethodDepths]) -> dict:
    """Unpaired Student t-test between every pair of methods (Section 3.5).

    ``scipy.stats.ttest_ind`` with equal variances (the classic unpaired
    test the paper describes) on all of each method's depths.

    Returns
    -------
    dict
        ``{"methods": [...], "t": {a: {b: t}}, "p": {a: {b: p}}}``; the
        diagonal and degenerate pairs (both constant) are ``None``.
    """
    names = list(groups)
    t: dict[str, dict[str, float | None]] = {a: {} for a in names}
    p: dict[str, dict[str, float | None]] = {a: {} for a in names}
    for a in names:
        for b in names:
            if a == b:
                t[a][b] = p[a][b] = None
            else:
                t[a][b], p[a][b] = _ttest(groups[a].depth_ppm, groups[b].depth_ppm)
    return {"methods": names, "t": t, "p": p, "test": "scipy.stats.ttest_ind(equal_var=True)"}


def anova(groups: Mapping[str, MethodDepths], methods: Iterable[str] | None = None) -> dict:
    """One-way ANOVA F test of equal means (``scipy.stats.f_oneway``).

    Parameters
    ----------
    groups : mapping
        From :func:`group_by_method`.
    methods : iterable of str, optional
        The subset to test (default: all).

    Returns
    -------
    dict
        ``{"methods", "F", "p", "df_between", "df_within"}``; ``F`` and ``p``
        are ``None`` with fewer than two methods or when every group is
        constant.
    """
    names = list(groups) if methods is None else list(methods)
    unknown = [m for m in names if m not in groups]
    if unknown:
        raise InputError(f"anova: unknown methods {', '.join(unknown)}")
    samples = [groups[m].depth_ppm for m in names]
    k = len(samples)
    n_total = int(sum(s.size for s in samples))
    out: dict[str, Any] = {"methods": names, "F": None, "p": None, "df_between": k - 1,
                           "df_within": n_total - k}
    if k < 2 or n_total - k < 1 or all(np.ptp(s) == 0 for s in samples):
        return out
    res = _sps.f_oneway(*samples)
    out["F"], out["p"] = float(res.statistic), float(res.pvalue)
    return out


def _reject_greedily(p: Mapping[str, Mapping[str, float | None]], names: list[str],
                     alpha: float) -> list[str]:
    left, rejected = list(names), []

    def failures(a: str) -> list[float]:
        return [v for b in left if b != a and (v := p[a][b]) is not None and v < alpha]

    def badness(a: str) -> tuple[int, float]:
        fails = failures(a)
        return len(fails), -sum(math.log(max(v, 1e-300)) for v in fails)

    while left:
        worst = max(left, key=badness)
        if badness(worst)[0] == 0:
            break
        left.remove(worst)
        rejected.append(worst)
    return rejected


def compare_methods(table, *, methods: Sequence[str] | None = None, alpha: float = 0.05) -> dict:
    """Closest matches, t-test matrix and ANOVA for a depth table.

    Parameters
    ----------
    table : astropy Table or mapping of columns
        Columns ``method``, ``epoch``, ``depth_ppm``, ``error_ppm``.
    methods : sequence of str, optional
        Restrict to these methods.
    alpha : float
        Significance level of the t-tests for the ``consistent`` subset.

    Returns
    -------
    dict
        ``closest_match`` (see :func:`closest_matches`), ``ttest`` (see
        :func:`ttest_matrix`) and ``anova`` with ``all`` (every method) and
        ``consistent`` (the methods left after dropping, one at a time, the
        method with the most t-tests at p < alpha -- ties: the smallest
        product of those p -- until none fails, as the paper's second F test
        drops KR/Pmap and SP(K2)), plus ``rejected``: those dropped, in order.
    """
    groups = group_by_method(table, methods)
    tt = ttest_matrix(groups)
    rejected = _reject_greedily(tt["p"], list(groups), alpha)
    consistent = [m for m in groups if m not in rejected]
    return {
        "closest_match": closest_matches(groups),
        "ttest": tt,
        "anova": {"all": anova(groups), "consistent": anova(groups, consistent),
                  "rejected": rejected, "alpha": alpha},
    }
