"""Twin model 6 (issue 40): the twins' photon noise is one Gaussian draw per pixel of the
physical model's mean and variance; the recipe's calibration keeps the exact draws."""

from __future__ import annotations

import numpy as np
import pytest

from eclipsebench.config.photometry import PhotometrySection
from eclipsebench.photometry.table import read_table
from eclipsebench.trust.observation import observation_from_table
from eclipsebench.trust.recipe import PILOT_TWIN, photometry_options, pilot_twin
from eclipsebench.trust.twin import GAUSSIAN_SKEW, TWIN_MODEL, make_recipe, twin_table


@pytest.fixture(scope="module")
def recipe(small_observation_table):
    obs = observation_from_table(read_table(small_observation_table))
    return make_recipe(obs, np.ones(obs.n_frames), radius_px=2.25)


def _frame_rms(table) -> tuple[float, float]:
    """The good frames' flux rms from frame to frame (relative) and mean flux."""
    good = np.asarray(table["flag"]) == 0
    flux = np.asarray(table["flux"], float)[good]
    return float(np.std(np.diff(flux)) / np.sqrt(2) / flux.mean()), float(flux.mean())


def test_twins_draw_gaussian_photon_noise_with_the_exact_draws_statistics(recipe):
    """Twins of the small observation made both ways with the same seeds (the same motion):
    the noise draws differ, the frame-to-frame flux scatter and the mean flux do not (within
    3 standard errors of the paired difference over 8 twins)."""
    assert TWIN_MODEL == 6 and GAUSSIAN_SKEW > 0
    options = PhotometrySection()
    rms, mean = [], []
    for twin in range(1, 9):
        fast = twin_table(recipe, options, seed=3, twin=twin)
        exact = twin_table(recipe, options, seed=3, twin=twin, gaussian_skew=0.0)
        assert not np.array_equal(np.asarray(fast["flux"]), np.asarray(exact["flux"]))
        (r_fast, m_fast), (r_exact, m_exact) = _frame_rms(fast), _frame_rms(exact)
        rms.append((r_fast, r_exact))
        mean.append((m_fast, m_exact))
    for pairs in (rms, mean):
        a = np.array(pairs)
        diff = a[:, 0] - a[:, 1]
        se = np.std(diff, ddof=1) / np.sqrt(diff.size)
        assert abs(diff.mean()) < 3 * se, (diff.mean(), se)
    # the scatter is the photon and read noise's, not a shadow of it
    assert np.mean([r for r, _ in rms]) == pytest.approx(np.mean([r for _, r in rms]), rel=0.03)


def test_the_pilot_twin_keeps_the_exact_draws(recipe):
    """The recipe's pilot is made as twins were before model 6, so the motion's bound it
    decides (and with it the recipe) is model 5's; a twin of the same number is not."""
    import dataclasses

    options = photometry_options(recipe.obs)
    pilot = pilot_twin(recipe, seed=3)
    plain = dataclasses.replace(recipe, correlated=None)
    exact = twin_table(plain, options, seed=3, twin=PILOT_TWIN, gaussian_skew=0.0)
    fast = twin_table(plain, options, seed=3, twin=PILOT_TWIN)
    assert np.array_equal(np.asarray(pilot["flux"]), np.asarray(exact["flux"]))
    assert not np.array_equal(np.asarray(pilot["flux"]), np.asarray(fast["flux"]))
