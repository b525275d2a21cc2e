"""Where the pilot twin is redder than the real residuals, trust says so (issue 36)."""

import numpy as np

from eclipsebench.trust.noise import correlated_component
from eclipsebench.trust.rows import cautions


def _red(g, n, rms, width_frames):
    kernel = np.exp(-0.5 * (np.arange(-4 * width_frames, 4 * width_frames + 1)
                            / width_frames) ** 2)
    slow = np.convolve(g.normal(0.0, 1.0, n), kernel, mode="same")
    return slow * rms / np.std(slow)


def test_a_pilot_redder_than_the_real_residuals_is_found_at_its_periods_and_adds_nothing():
    t = 57000.0 + np.arange(16384) * 2.0 / 86400
    g = np.random.default_rng(8)
    white = 4e-3
    real = (t, g.normal(0.0, white, t.size))
    # the pilot carries red noise on 5-minute scales the real residuals lack
    pilot = (t, g.normal(0.0, white, t.size) + _red(g, t.size, 8e-4, 150))
    c, info = correlated_component(t, real, pilot)
    assert info["bins_in_excess"] == 0 and np.all(c == 0.0)
    bands = info["periods_twin_in_excess_min"]
    assert info["bins_twin_in_excess"] == len(bands) > 0
    assert all(lo > 5.0 and ratio > 1.0 for lo, hi, ratio in bands), bands
    # the other way round (the test of test_real_noise.py): nothing is flagged
    _, other = correlated_component(t, pilot, real)
    assert other["bins_twin_in_excess"] == 0 and other["bins_in_excess"] > 0


def test_the_caution_names_the_periods_where_twins_are_redder():
    summary = {"methods": {}, "twins": {"correlated_noise": {
        "periods_twin_in_excess_min": [[13.5, 28.8, 3.2], [6.4, 8.6, 2.5]]}}}
    text = [c for c in cautions(summary) if "pilot twin" in c]
    assert text == ["the pilot twin's residuals are redder than the real ones at periods of "
                    "14-29 min (power x3.2), 6-9 min (power x2.5): the twins may over-predict "
                    "the error"]
    assert not [c for c in cautions({"methods": {}, "twins": {}}) if "pilot twin" in c]
