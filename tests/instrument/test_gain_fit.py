"""The intra-pixel gain fitted to a gridded warm map (instrument/gain_fit.py).

Analytic answers on synthetic maps; the committed coefficients again from the
real SSC map (``shared_data``).
"""

from __future__ import annotations

import numpy as np
import pytest

from eclipsebench.errors import InputError
from eclipsebench.instrument.gain_fit import fit_centroid_gain, fit_true_phase_gain
from eclipsebench.instrument.prf import BuiltinPRF, GainPolynomial, load_gainmap_coefficients
from eclipsebench.photometry.estimators import aperture_flux, centroid_col

GRID = np.linspace(14.501, 15.499, 120)


def _map(poly: GainPolynomial):
    xx, yy = np.meshgrid(GRID, GRID)
    return GRID, GRID, poly.evaluate(xx, yy), np.full(xx.shape, 100.0)


SLOPED = GainPolynomial(((0, 0), (1, 0), (0, 1), (2, 0), (0, 2)),
                        (1.0, 0.012, -0.008, -0.03, -0.02))


def test_the_centroid_fit_recovers_a_polynomial_and_keeps_off_nan_cells():
    x, y, gain, occ = _map(SLOPED)
    poly, info = fit_centroid_gain(x, y, gain, occ, degree=2)
    assert info["fit_rms"] < 1e-12 and info["box"] is None
    xs, ys = np.meshgrid(GRID[::7], GRID[::7])
    assert np.allclose(poly.evaluate(xs, ys), SLOPED.evaluate(xs, ys), rtol=0, atol=1e-10)
    holed = gain.copy()
    holed[:, :30] = np.nan           # cells no calibration star reached
    occ_holed = np.where(np.isnan(holed), 0.0, occ)
    poly, info = fit_centroid_gain(x, y, holed, occ_holed, degree=2)
    (u_lo, u_hi), _ = info["box"]
    assert u_lo == pytest.approx(GRID[30] - 15.0) and u_hi == pytest.approx(GRID[-1] - 15.0)
    inside = xs >= GRID[30]
    assert np.allclose(poly.evaluate(xs, ys)[inside], SLOPED.evaluate(xs, ys)[inside], atol=1e-9)
    assert poly.evaluate(14.6, 15.0) == pytest.approx(poly.evaluate(GRID[30], 15.0))  # clamped


def test_the_true_phase_gain_makes_aperture_photometry_follow_the_map():
    prf = BuiltinPRF(gain=False, channel=2)
    poly, info = fit_true_phase_gain(prf, *_map(SLOPED), radius_px=3.0, degree=6)
    assert info["fit_rms"] < 2e-4 and prf.gain is None
    rng = np.random.default_rng(5)
    xs, ys = 15.0 + rng.uniform(-0.3, 0.3, 40), 15.0 + rng.uniform(-0.3, 0.3, 40)
    prf.gain = poly
    images = prf.render(xs, ys)
    xc, yc = centroid_col(images, around=(15, 15))
    ratio = aperture_flux(images, xc, yc, 3.0) / SLOPED.evaluate(xc, yc)
    assert np.std(ratio / ratio.mean()) < 3e-4


def test_a_map_of_the_wrong_shape_or_never_sampled_is_one_line():
    x, y, gain, occ = _map(SLOPED)
    with pytest.raises(InputError, match="shape"):
        fit_centroid_gain(x, y[:-1], gain, occ)
    with pytest.raises(InputError, match="occupancy"):
        fit_centroid_gain(x, y, gain, np.zeros_like(occ))


@pytest.mark.shared_data
def test_the_real_map_gives_the_committed_gain_again(shared_irac):
    from eclipsebench.io.pmap_files import load_gridded_pmap

    pm = load_gridded_pmap(shared_irac / "pmap_ch2")
    coeff = load_gainmap_coefficients(2)
    poly, _ = fit_true_phase_gain(BuiltinPRF(gain=False, channel=2), pm.x_grid, pm.y_grid,
                                  pm.gain, pm.occupancy)
    centroid, _ = fit_centroid_gain(pm.x_grid, pm.y_grid, pm.gain, pm.occupancy)
    assert np.allclose(poly.coeffs, coeff["builtin"]["gain"]["coeffs"], rtol=1e-9, atol=1e-12)
    assert np.allclose(centroid.coeffs, coeff["pmap_poly"]["coeffs"], rtol=1e-9, atol=1e-12)
