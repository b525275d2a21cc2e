"""Method comparisons: closest match, Student t-test, ANOVA, all computed by hand."""

from __future__ import annotations

import math

import pytest
from scipy import stats as sps

from eclipsebench.errors import InputError
from eclipsebench.stats.compare import compare_methods, group_by_method
from eclipsebench.stats.summary import summarize

A = [1800.0, 1900.0, 1850.0, 1700.0, 2000.0]
B = [1810.0, 1880.0, 1870.0, 1690.0, 2010.0]   # A - B = -10 20 -20 10 -10: mean -2
C = [1500.0, 1600.0, 1550.0, 1400.0, 1700.0]   # A - C = 300 each: mean 300, SD 0


def table(**methods):
    rows = {"method": [], "epoch": [], "depth_ppm": [], "error_ppm": []}
    for name, depths in methods.items():
        for i, d in enumerate(depths):
            rows["method"].append(name)
            rows["epoch"].append(i + 1)
            rows["depth_ppm"].append(d)
            rows["error_ppm"].append(100.0)
    return rows


def sd(xs):
    m = sum(xs) / len(xs)
    return math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1))


def student_p(x, y):
    nx, ny = len(x), len(y)
    sp2 = ((nx - 1) * sd(x) ** 2 + (ny - 1) * sd(y) ** 2) / (nx + ny - 2)
    t = (sum(x) / nx - sum(y) / ny) / math.sqrt(sp2 * (1 / nx + 1 / ny))
    return t, 2 * sps.t.sf(abs(t), nx + ny - 2)


def anova_by_hand(groups):
    allx = [x for g in groups for x in g]
    grand = sum(allx) / len(allx)
    ssb = sum(len(g) * (sum(g) / len(g) - grand) ** 2 for g in groups)
    ssw = sum(sum((x - sum(g) / len(g)) ** 2 for x in g) for g in groups)
    k, n = len(groups), len(allx)
    f = (ssb / (k - 1)) / (ssw / (n - k))
    return f, sps.f.sf(f, k - 1, n - k)


def test_closest_match_picks_smallest_abs_mean_plus_sd():
    res = compare_methods(table(a=A, b=B, c=C))
    diff_ab = [x - y for x, y in zip(A, B, strict=True)]
    m = res["closest_match"]
    assert m["a"]["method"] == "b"
    assert m["a"]["mean_ppm"] == pytest.approx(sum(diff_ab) / 5)
    assert m["a"]["sd_ppm"] == pytest.approx(sd(diff_ab))
    assert m["b"]["mean_ppm"] == pytest.approx(-sum(diff_ab) / 5)
    # c is 300 below a (SD 0: score 300) and b - c = 310 -280 320 290 310 (score ~ 318)
    assert m["c"]["method"] == "a"
    assert m["c"]["mean_ppm"] == pytest.approx(-300.0)
    assert m["c"]["sd_ppm"] == pytest.approx(0.0, abs=1e-9)


def test_closest_match_uses_common_epochs_only():
    t = table(a=A, b=B)
    t["epoch"][5:] = [2, 3, 4, 5, 6]  # b shifted by one epoch
    res = compare_methods(t)
    pairs = [A[i] - B[i - 1] for i in range(1, 5)]
    assert res["closest_match"]["a"]["n"] == 4
    assert res["closest_match"]["a"]["mean_ppm"] == pytest.approx(sum(pairs) / 4)


def test_ttest_matrix_is_student_unpaired():
    res = compare_methods(table(a=A, b=B, c=C))
    t_ac, p_ac = student_p(A, C)
    assert res["ttest"]["p"]["a"]["c"] == pytest.approx(p_ac)
    assert res["ttest"]["t"]["a"]["c"] == pytest.approx(t_ac)
    assert res["ttest"]["t"]["c"]["a"] == pytest.approx(-t_ac)
    assert res["ttest"]["p"]["a"]["a"] is None


def test_anova_all_and_consistent_subset():
    res = compare_methods(table(a=A, b=B, c=C))
    f, p = anova_by_hand([A, B, C])
    assert res["anova"]["all"]["F"] == pytest.approx(f)
    assert res["anova"]["all"]["p"] == pytest.approx(p)
    assert res["anova"]["all"]["df_between"] == 2 and res["anova"]["all"]["df_within"] == 12
    # c differs from a and b at p < 0.05, so the consistent subset is a, b
    assert student_p(A, C)[1] < 0.05 and student_p(B, C)[1] < 0.05
    assert res["anova"]["rejected"] == ["c"]
    f2, p2 = anova_by_hand([A, B])
    assert set(res["anova"]["consistent"]["methods"]) == {"a", "b"}
    assert res["anova"]["consistent"]["F"] == pytest.approx(f2)
    assert res["anova"]["consistent"]["p"] == pytest.approx(p2)


def test_subset_restricts_everything():
    res = summarize(table(a=A, b=B, c=C), methods=["c", "a"], n_bootstrap=0)
    assert list(res["methods"]) == ["c", "a"]
    assert res["anova"]["all"]["methods"] == ["c", "a"]
    f, p = anova_by_hand([C, A])
    assert res["anova"]["all"]["F"] == pytest.approx(f)
    assert res["methods"]["a"]["closest_match"] == "c"


def test_unknown_method_is_an_input_error():
    with pytest.raises(InputError, match="--methods: zz"):
        group_by_method(table(a=A), ["zz"])


def test_summary_average_row_is_straight_mean():
    res = summarize(table(a=A, b=B, c=C), sigma_phot_ppm=53.0, truth_ppm=1875.0, n_bootstrap=0)
    for key in ("D_mean", "SD", "R", "r", "RMSE", "bias", "a", "f_dis"):
        vals = [res["methods"][m][key] for m in "abc"]
        assert res["average"][key] == pytest.approx(sum(vals) / 3)
