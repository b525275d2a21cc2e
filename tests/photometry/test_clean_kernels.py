"""The cosmic-ray rejection's running median in time and its column medians give scipy's and
numpy's values exactly (issue 40 replaced ``median_filter`` and ``nanmedian`` there for speed;
a twin's photometry must keep its bytes)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import median_filter

from eclipsebench.photometry.clean import (
    _median9_in_time,
    _median_in_time,
    nanmedian0,
    reject_cosmic_rays,
)


@pytest.mark.parametrize("m, k, size", [(7800, 21, 9), (40, 3, 9), (9, 2, 9), (5, 4, 9),
                                        (60, 5, 1), (50, 3, 21), (2, 2, 3)])
@pytest.mark.parametrize("step", [0.0, 0.5, 5.0])
def test_the_running_median_in_time_is_scipys(m, k, size, step):
    values = np.random.default_rng(m * 31 + size).normal(100.0, 10.0, (m, k))
    if step:  # ties, many of them at the coarsest step
        values = np.round(values / step) * step
    assert np.array_equal(_median_in_time(values, size),
                          median_filter(values, size=(size, 1), mode="nearest"))


@pytest.mark.parametrize("m, k", [(7800, 21), (9, 2), (5, 4), (1, 3)])
def test_the_nine_frame_network_is_scipys_running_median(m, k):
    """The default window's branch-free network (issue 40) gives scipy's values, ties and
    repeated ends included."""
    values = np.random.default_rng(m + k).normal(100.0, 10.0, (m, k))
    for data in (values, np.round(values / 5.0) * 5.0):
        assert np.array_equal(_median9_in_time(data),
                              median_filter(data, size=(9, 1), mode="nearest"))


def test_the_running_median_in_time_keeps_a_step_and_a_spike():
    values = np.concatenate([np.zeros(20), np.full(20, 7.0)])[:, None].copy()
    values[5, 0] = 1e6
    out = _median_in_time(values, 5)
    assert out[5, 0] == 0.0 and out[:18, 0].max() == 0.0 and out[22:, 0].min() == 7.0


@pytest.mark.parametrize("m", [1, 2, 599, 600, 601, 7800])
def test_the_column_median_without_nans_is_numpys_nanmedian(m):
    values = np.random.default_rng(m).normal(0.0, 1.0, (m, 7)).astype(np.float32).astype(float)
    assert np.array_equal(nanmedian0(values), np.nanmedian(values, axis=0))
    values[0, 3] = np.nan
    values[:, 5] = np.nan
    empty = np.isnan(values).all(axis=0)          # column 5, and column 3 of one frame
    expected = np.nanmedian(np.where(empty, 0.0, values), axis=0)
    expected[empty] = np.nan
    assert np.array_equal(nanmedian0(values), expected, equal_nan=True)


def test_a_cosmic_ray_is_replaced_by_the_running_median():
    rng = np.random.default_rng(4)
    cube = rng.normal(1000.0, 5.0, (200, 4, 4))
    cube[77, 2, 1] += 500.0
    cleaned, hits = reject_cosmic_rays(cube, 9, 5.0)
    assert np.argwhere(hits).tolist() == [[77, 2, 1]]
    expected = median_filter(cube[:, 2, 1], size=9, mode="nearest")[77]
    assert cleaned[77, 2, 1] == expected
