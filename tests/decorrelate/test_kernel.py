"""KR/Data and KR/Pmap against brute-force kernel regression; pixel-map loading."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from astropy.io import fits
from scipy.optimize import minimize_scalar

from eclipsebench.decorrelate import get_method
from eclipsebench.decorrelate.base import EpochData
from eclipsebench.decorrelate.pmap import interpolate_grid, kernel_occupancy
from eclipsebench.errors import DataError, InputError
from eclipsebench.io.pmap_files import (
    CalibrationSet,
    GriddedPmap,
    find_pmap_path,
    load_calibration_table,
    load_pmap,
    pmap_versions,
)


def _kr_pmap(data, pmap, **options):
    """KR/Pmap built as the reducer builds it: the calibration set loaded into the context."""
    return get_method("kr-pmap").build(data, resources={"pmap": pmap}, **options)


def _random_epoch(n=400, seed=3, meta=None):
    g = np.random.default_rng(seed)
    x = 15.1 + 0.03 * g.standard_normal(n)
    y = 15.0 + 0.05 * g.standard_normal(n)
    beta = 4.0 + 0.3 * g.standard_normal(n) ** 2
    flux = 1e5 * (1 + 0.01 * (x - 15.1) - 0.02 * (y - 15.0) ** 2) + g.normal(0, 50, n)
    return EpochData(time_bmjd=np.arange(n) / 43200.0, flux=flux, flux_err=np.full(n, 300.0),
                     x=x, y=y, noise_pixels=beta, meta=dict(meta or {}))


def _brute_kr(qx, qy, qb, tx, ty, tb, values, k, scales, exclude_self):
    """Kernel regression the slow way: every distance, sort, k smallest, Gaussian weights."""
    out = np.empty(len(qx))
    for i in range(len(qx)):
        d2 = ((tx - qx[i]) / scales[0]) ** 2 + ((ty - qy[i]) / scales[1]) ** 2
        if qb is not None:
            d2 = d2 + ((np.sqrt(tb) - np.sqrt(qb[i])) / scales[2]) ** 2
        if exclude_self:
            d2[i] = np.inf
        nn = np.argsort(d2)[:k]
        w = np.exp(-0.5 * d2[nn])
        out[i] = np.sum(w * values[nn]) / np.sum(w)
    return out


def _brute_kr_data(x, y, beta, values, k):
    """KR/Data the slow way: Euclidean k nearest others, widths = std of their offsets."""
    cols = [x, y] + ([np.sqrt(beta)] if beta is not None else [])
    pts = np.column_stack(cols)
    out = np.empty(len(x))
    trace = 0.0
    for i in range(len(x)):
        d = np.sum((pts - pts[i]) ** 2, axis=1)
        d[i] = np.inf
        nn = np.argsort(d)[:k]
        off = pts[nn] - pts[i]
        z = np.sum((off / off.std(axis=0)) ** 2, axis=1)
        w = np.exp(-0.5 * z)
        out[i] = np.sum(w * values[nn]) / np.sum(w)
        trace += 1.0 / (1.0 + np.sum(w))
    return out, trace


@pytest.mark.parametrize("use_np", [False, True])
def test_kr_data_matches_brute_force(use_np):
    data = _random_epoch()
    astro = 1 + 1e-3 * np.sin(np.arange(len(data)) / 50.0)
    model = get_method("kr-data")(data, k=12, use_noise_pixels=use_np)
    kr, trace = _brute_kr_data(data.x, data.y, data.noise_pixels if use_np else None,
                               data.flux / astro, 12)
    np.testing.assert_allclose(model.predict(astro), astro * kr, rtol=1e-12)
    assert model.n_effective_params() == round(trace)


@pytest.mark.parametrize("n_walkers", [16, 3, 9])
def test_kr_data_walkers_batch_gives_the_bytes_of_the_sparse_product(n_walkers):
    """The compiled walkers' pass sums as scipy's product does: equal values, not close ones
    (8 curves at a time, a part-filled block of 8, frames stored in another order)."""
    data = _random_epoch()
    model = get_method("kr-data")(data, k=12)
    assert not np.array_equal(model._rank, np.arange(len(data)))
    g = np.random.default_rng(5)
    astro = 1 + 1e-3 * g.standard_normal((n_walkers, len(data)))
    expected = astro * (model.smoother @ (data.flux / astro).T).T
    assert np.array_equal(model.log_likelihood_batch(astro),
                          model._white_log_likelihood_batch(expected, 1.0))
    assert np.array_equal(model.log_likelihood_batch(astro[:1]),
                          [model.log_likelihood(astro[0])])


def test_kr_data_widths_come_from_each_frames_neighbours():
    # Two clouds of the same shape, one ten times wider: with epoch-wide widths
    # the narrow cloud's weights would all be ~1 (a plain mean); with the
    # neighbours' own spread both clouds get the same weight pattern.
    g = np.random.default_rng(4)
    base = g.standard_normal((300, 2)) * [0.01, 0.02]
    x = np.concatenate([15 + base[:, 0], 16 + 10 * base[:, 0]])
    y = np.concatenate([15 + base[:, 1], 16 + 10 * base[:, 1]])
    n = len(x)
    data = EpochData(time_bmjd=np.arange(n) / 43200.0, flux=np.full(n, 1e5),
                     flux_err=np.full(n, 300.0), x=x, y=y)
    model = get_method("kr-data")(data, k=20)
    w = model.smoother.toarray()
    np.testing.assert_allclose(w[:300, :300], w[300:, 300:], atol=1e-9)
    np.testing.assert_allclose(model.widths[300:], 10 * model.widths[:300], rtol=1e-9)


def test_kr_data_kernel_weighs_on_the_synthetic_epoch(epoch_sys):
    # The epoch-wide widths of the stand-in gave a median largest/smallest weight
    # ratio of 1.0066 here: a plain 50-nearest-neighbour mean.
    model = get_method("kr-data")(epoch_sys.data)
    diag = model.diagnostics()
    assert diag["weight_ratio_median"] > 1.5
    assert np.all(np.asarray(diag["width_median"]) > 0)


def test_kr_data_excludes_the_point_itself():
    # Two far-apart clusters of k+1 frames: each frame's estimate is a weighted
    # mean of the other k frames of its cluster, never its own value.
    x = np.concatenate([np.zeros(6), np.ones(6)]) + np.linspace(0, 1e-3, 12)
    y = np.concatenate([np.zeros(6), np.ones(6)])
    f = np.arange(12.0) + 100
    data = EpochData(time_bmjd=np.arange(12.0), flux=f, flux_err=np.ones(12), x=x, y=y)
    model = get_method("kr-data")(data, k=5)
    w = model.smoother.toarray()
    assert np.all(np.diag(w) == 0)
    assert np.all(w[:6, 6:] == 0) and np.all(w[6:, :6] == 0)
    np.testing.assert_allclose(w.sum(axis=1), 1.0)


def test_kr_data_options():
    data = _random_epoch()
    with pytest.raises(InputError, match="option 'k'"):
        get_method("kr-data")(data, k=0)
    assert get_method("kr-pmap").Options().min_occupancy == 20
    with pytest.raises(InputError, match="unknown option"):
        get_method("kr-data")(data, neighbours=5)
    with pytest.raises(InputError, match="noise_pixels"):
        get_method("kr-data")(EpochData(time_bmjd=data.time_bmjd, flux=data.flux,
                                        flux_err=data.flux_err, x=data.x, y=data.y),
                              use_noise_pixels=True)
    with pytest.raises(InputError, match="k\\+1"):
        get_method("kr-data")(data, k=len(data))


def _write_table(path, **cols):
    fits.BinTableHDU.from_columns(
        [fits.Column(name=n, format="D", array=np.asarray(v, float)) for n, v in cols.items()]
    ).writeto(path, overwrite=True)
    return path


def _calibration(tmp_path, n=3000, seed=5):
    g = np.random.default_rng(seed)
    x = g.uniform(14.9, 15.3, n)
    y = g.uniform(14.8, 15.2, n)
    beta = g.uniform(3.8, 5.0, n)
    flux = 2e5 * (1 + 0.01 * (x - 15.1) - 0.02 * (y - 15.0) ** 2)
    return _write_table(tmp_path / "cal.fits", x=x, y=y, noise_pixels=beta, flux=flux,
                        flux_err=np.sqrt(flux))


@pytest.mark.parametrize("use_np", [True, False])
def test_kr_pmap_matches_brute_force_and_closed_form_scale(tmp_path, use_np):
    path = _calibration(tmp_path)
    cal = load_calibration_table(path)
    data = _random_epoch()
    astro = 1 + 1e-3 * np.cos(np.arange(len(data)) / 70.0)
    model = _kr_pmap(data, str(path), k=15, use_noise_pixels=use_np,
                     match_noise_pixels=False, min_occupancy=0)
    scales = [np.std(data.x), np.std(data.y)] + ([np.std(np.sqrt(data.noise_pixels))] if use_np else [])
    gain = _brute_kr(data.x, data.y, data.noise_pixels if use_np else None, cal.x, cal.y,
                     cal.noise_pixels, cal.flux, 15, scales, exclude_self=False) / cal.flux.mean()
    np.testing.assert_allclose(model.gain, gain, rtol=1e-12)
    # F0 minimises the weighted chi-square of flux = F0 * astro * gain.
    chi2 = lambda f0: np.sum(((data.flux - f0 * astro * gain) / data.flux_err) ** 2)  # noqa: E731
    best = minimize_scalar(chi2, bracket=(9e4, 1.1e5), tol=1e-12).x
    np.testing.assert_allclose(model.predict(astro), best * astro * gain, rtol=1e-8)
    assert model.n_effective_params() == 1


def test_kr_pmap_removes_the_noise_pixel_offset_of_the_calibration_set(tmp_path):
    # Calibration noise pixels are a smooth function of position; the science
    # frames' are the same function plus 0.3 (longer exposures, more smear).
    g = np.random.default_rng(8)
    n = 20000
    cx, cy = g.uniform(14.9, 15.3, n), g.uniform(14.8, 15.2, n)

    def beta(x, y):
        return 4.0 + 2.0 * (x - 15.1) ** 2 + 3.0 * (y - 15.0) ** 2

    flux = 2e5 * (1 + 0.01 * (cx - 15.1) - 0.02 * (cy - 15.0) ** 2)
    path = _write_table(tmp_path / "cal.fits", x=cx, y=cy, noise_pixels=beta(cx, cy), flux=flux,
                        flux_err=np.sqrt(flux))
    data = _random_epoch()
    shifted = EpochData(time_bmjd=data.time_bmjd, flux=data.flux, flux_err=data.flux_err,
                        x=data.x, y=data.y, noise_pixels=beta(data.x, data.y) + 0.3)
    same = EpochData(time_bmjd=data.time_bmjd, flux=data.flux, flux_err=data.flux_err,
                     x=data.x, y=data.y, noise_pixels=beta(data.x, data.y))
    matched = _kr_pmap(shifted, str(path), min_occupancy=0)
    assert matched.noise_pixels_offset == pytest.approx(0.3, abs=0.002)
    reference = _kr_pmap(same, str(path), match_noise_pixels=False, min_occupancy=0)
    np.testing.assert_allclose(matched.gain, reference.gain, rtol=2e-5)
    unmatched = _kr_pmap(shifted, str(path), match_noise_pixels=False, min_occupancy=0)
    assert np.max(np.abs(unmatched.gain - reference.gain)) > 10 * np.max(
        np.abs(matched.gain - reference.gain))


def test_kr_pmap_finds_the_simulation_calibration_set(epoch_sys, simdir):
    model = get_method("kr-pmap").build(epoch_sys.data)
    assert model.diagnostics()["pmap"] == str(simdir / "calibration" / "pmap_calibration.fits")


def test_kr_pmap_without_any_pmap_is_a_clear_error(tmp_path):
    data = _random_epoch()
    with pytest.raises(InputError, match="needs a pmap"):
        get_method("kr-pmap").build(data)
    with pytest.raises(InputError, match="does not exist"):
        get_method("kr-pmap").build(_random_epoch(meta={"SIMDIR": str(tmp_path)}))
    with pytest.raises(InputError, match="no such file"):
        _kr_pmap(data, str(tmp_path / "nope.fits"))


def test_calibration_table_problems_are_data_errors(tmp_path):
    bad = _write_table(tmp_path / "bad.fits", x=[1.0, 2.0], y=[1.0, 2.0], flux=[1.0, 1.0])
    with pytest.raises(DataError, match="noise_pixels, flux_err"):
        load_calibration_table(bad)
    with pytest.raises(DataError, match="not found"):
        load_calibration_table(tmp_path / "missing.fits")


def test_kr_pmap_refuses_frames_the_map_does_not_cover(tmp_path):
    path = _calibration(tmp_path)
    data = _random_epoch()
    far = EpochData(time_bmjd=data.time_bmjd, flux=data.flux, flux_err=data.flux_err,
                    x=data.x + 1.0, y=data.y, noise_pixels=data.noise_pixels)
    with pytest.raises(InputError, match="max_distance_px"):
        _kr_pmap(far, str(path), min_occupancy=0)
    with pytest.raises(InputError, match="every frame .400. falls where the map's occupancy"):
        _kr_pmap(far, str(path))
    # A few uncovered frames are tolerated and counted.
    x = data.x.copy()
    x[:3] += 1.0
    few = EpochData(time_bmjd=data.time_bmjd, flux=data.flux, flux_err=data.flux_err,
                    x=x, y=data.y, noise_pixels=data.noise_pixels)
    model = _kr_pmap(few, str(path), min_occupancy=0)
    assert model.n_uncovered == 3 and np.all(np.isfinite(model.gain))
    with pytest.raises(InputError, match="max_uncovered_fraction"):
        _kr_pmap(few, str(path), max_uncovered_fraction=0.0, min_occupancy=0)


def _write_grid(folder, suffix="test_0001.fits", n=41):
    folder.mkdir(parents=True, exist_ok=True)
    g = 14.5 + (np.arange(n) + 0.5) / n
    xg, yg = np.meshgrid(g, g)
    gain = 1 + 0.01 * (xg - 15.0) + 0.02 * (yg - 15.0)
    for part, arr in (("pmap", gain), ("xgrid", xg), ("ygrid", yg),
                      ("occu", np.full_like(xg, 50.0) * (yg < 15.3) + 1.0),
                      ("psigma", np.full_like(xg, 1e-4))):
        fits.PrimaryHDU(arr).writeto(folder / f"{part}_ch2_{suffix}", overwrite=True)
    return folder


def test_gridded_pmap_is_interpolated(tmp_path):
    folder = _write_grid(tmp_path / "grid")
    pm = load_pmap(folder)
    assert isinstance(pm, GriddedPmap)
    assert isinstance(load_pmap(next(folder.glob("pmap_*.fits"))), GriddedPmap)
    data = _random_epoch()
    astro = np.ones(len(data))
    model = _kr_pmap(data, str(folder))
    # The gain is linear, so bilinear interpolation reproduces it exactly.
    expected_gain = 1 + 0.01 * (data.x - 15.0) + 0.02 * (data.y - 15.0)
    np.testing.assert_allclose(model.gain, expected_gain, rtol=1e-12)
    f0 = np.sum(data.flux * expected_gain) / np.sum(expected_gain**2)
    np.testing.assert_allclose(model.predict(astro), f0 * expected_gain, rtol=1e-10)
    assert model.n_low_occupancy == 0          # occupancy 51 below y = 15.3, 1 above
    assert model.dropped_frames() == {"low_occupancy": 0}
    high = EpochData(time_bmjd=data.time_bmjd, flux=data.flux, flux_err=data.flux_err,
                     x=data.x, y=data.y + 0.4)
    kept = _kr_pmap(high, str(folder))
    n_low = kept.n_low_occupancy
    # Beyond one cell above the step every frame is low, one cell below none is.
    assert np.sum(high.y > 15.3 + 1 / 41) <= n_low <= np.sum(high.y > 15.3 - 1 / 41)
    assert n_low > 300
    # The low frames are out of the fit (as iracpc_pmap_corr sets them MISSING).
    assert len(kept.data) == len(high) - n_low and np.all(kept.data.y < 15.3 + 1 / 41)
    assert kept.dropped_frames() == {"low_occupancy": n_low}
    assert kept.diagnostics()["n_low_occupancy"] == n_low
    assert len(kept.predict(np.ones(len(kept.data)))) == len(kept.data)
    assert _kr_pmap(high, str(folder), min_occupancy=0).n_low_occupancy == 0
    with pytest.raises(InputError, match="min_occupancy"):
        _kr_pmap(_random_epoch(n=400, seed=9), str(folder), min_occupancy=1e9)


def test_kernel_occupancy_is_the_gaussian_weighted_count():
    g = np.random.default_rng(11)
    cx, cy = g.uniform(0, 0.1, 3000), g.uniform(0, 0.1, 3000)
    x, y = g.uniform(0, 0.1, 50), g.uniform(0, 0.1, 50)
    sigma = 0.004
    brute = np.array([np.sum(np.exp(-((cx - a) ** 2 + (cy - b) ** 2) / (2 * sigma**2)))
                      for a, b in zip(x, y, strict=True)])
    np.testing.assert_allclose(kernel_occupancy(cx, cy, x, y, sigma_px=sigma), brute, rtol=1e-5)


def test_kr_pmap_drops_and_counts_frames_of_low_calibration_occupancy(epoch_sys):
    # The synthetic calibration set with a hole (no calibration point within
    # 0.01 px of the median science position): the science frames in the hole
    # have occupancy below 20 and leave the fit, counted; the others stay.
    cal = load_pmap(epoch_sys.data.meta["SIMDIR"] + "/calibration/pmap_calibration.fits")
    data = epoch_sys.data
    x0, y0 = np.median(data.x), np.median(data.y)
    out = np.hypot(cal.x - x0, cal.y - y0) > 0.01
    holed = CalibrationSet(x=cal.x[out], y=cal.y[out], noise_pixels=cal.noise_pixels[out],
                           flux=cal.flux[out], flux_err=cal.flux_err[out], source="holed")
    occ = kernel_occupancy(holed.x, holed.y, data.x, data.y, sigma_px=0.004)
    expected = int(np.sum(occ < 20))
    assert expected > 100
    in_hole = np.hypot(data.x - x0, data.y - y0) < 0.005
    assert np.all(occ[in_hole] < 20)
    model = _kr_pmap(data, holed)
    assert model.dropped_frames() == {"low_occupancy": expected}
    assert model.diagnostics()["n_low_occupancy"] == expected
    assert len(model.data) == len(data) - expected
    np.testing.assert_array_equal(model.data.time_bmjd, data.time_bmjd[occ >= 20])
    assert model.gain.shape == (len(model.data),)
    # The whole calibration set covers every frame: nothing dropped.
    assert _kr_pmap(data, cal).dropped_frames() == {"low_occupancy": 0}
    # min_occupancy = 0 keeps every frame.
    assert len(_kr_pmap(data, holed, min_occupancy=0).data) == len(data)


def test_gridded_pmap_with_a_missing_companion(tmp_path):
    folder = _write_grid(tmp_path / "grid")
    next(folder.glob("occu_*.fits")).unlink()
    with pytest.raises(DataError, match="occu_"):
        load_pmap(folder)


def test_interpolate_grid_clamps_outside_and_hits_nodes():
    xg = np.array([0.0, 1.0, 2.0])
    yg = np.array([10.0, 11.0])
    v = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    np.testing.assert_allclose(interpolate_grid(v, xg, yg, np.array([0.0, 2.0, 1.5, -5.0, 9.0]),
                                                np.array([10.0, 11.0, 10.5, 10.0, 12.0])),
                               [1.0, 6.0, 4.0, 1.0, 6.0])


@pytest.mark.shared_data
def test_real_warm_pmap_uses_our_zero_based_convention(shared_irac):
    pm = load_pmap(shared_irac / "pmap_ch2")
    assert pm.gain.shape == (500, 500)
    assert pm.x_grid[0] == pytest.approx(14.501) and pm.x_grid[-1] == pytest.approx(15.499)
    assert pm.y_grid[0] == pytest.approx(14.501) and pm.y_grid[-1] == pytest.approx(15.499)
    assert 0.96 < pm.gain.min() and pm.gain.max() < 1.03
    # The map covers 0-based pixel (15, 15); the real XO-3 centroids of the
    # paper's Table 1 (mean 15.18, 15.03 in the same convention) fall in its
    # well-measured sweet spot (occupancy above the IRSA threshold of 20).
    occ = interpolate_grid(pm.occupancy, pm.x_grid, pm.y_grid, np.array([15.18]), np.array([15.03]))
    assert occ[0] > 20
    iy, ix = 123, 321
    assert interpolate_grid(pm.gain, pm.x_grid, pm.y_grid, pm.x_grid[[ix]],
                            pm.y_grid[[iy]])[0] == pytest.approx(pm.gain[iy, ix])


@pytest.mark.shared_data
@pytest.mark.parametrize("folder", ["pmap_ch2", "pmap_ch2_120827"])
def test_both_real_channel2_maps_load_and_cover_the_real_xo3_centroids(shared_irac, folder):
    pm = load_pmap(shared_irac / folder)
    assert isinstance(pm, GriddedPmap) and pm.gain.shape == (500, 500)
    assert pm.x_grid[0] == pytest.approx(14.501) and pm.y_grid[-1] == pytest.approx(15.499)
    assert 0.95 < np.median(pm.gain) < 1.05
    # A cloud at the paper's Table 1 mean centroid of the real XO-3 epochs: kept.
    g = np.random.default_rng(2)
    n = 500
    x, y = 15.18 + 0.01 * g.standard_normal(n), 15.03 + 0.01 * g.standard_normal(n)
    data = EpochData(time_bmjd=np.arange(n) / 43200.0, flux=np.full(n, 7e4),
                     flux_err=np.full(n, 300.0), x=x, y=y)
    model = _kr_pmap(data, pm)
    assert model.n_low_occupancy < n / 10
    assert np.all(np.isfinite(model.gain)) and model.n_uncovered == 0


def test_pmap_versions_are_picked_by_the_observation_date(tmp_path):
    _write_grid(tmp_path / "maps" / "a", suffix="early_120124.fits")
    _write_grid(tmp_path / "maps" / "b", suffix="later_120827.fits")
    versions = pmap_versions(tmp_path / "maps", 2)
    assert [d.isoformat() for d, _ in versions] == ["2012-01-24", "2012-08-27"]
    assert pmap_versions(tmp_path / "maps", 1) == []
    meta = {"CHANNEL": 2}
    # 2012-11-09 (the real epoch 1): the later map; 2012-03-01: the earlier one.
    assert find_pmap_path(tmp_path / "maps", meta, 56240.74).parent.name == "b"
    assert find_pmap_path(tmp_path / "maps", meta, 55987.0).parent.name == "a"
    assert find_pmap_path(tmp_path / "maps", meta, 50000.0).parent.name == "a"
    # One version's own folder is that map, whatever the date.
    assert find_pmap_path(tmp_path / "maps" / "a", meta, 56240.74).name == "a"
    with pytest.raises(InputError, match="observation date"):
        find_pmap_path(tmp_path / "maps", meta)
    # KR/Pmap given the library loads the version of the data's date.
    late = _random_epoch(meta=meta)
    late = EpochData(time_bmjd=late.time_bmjd + 56240.74, flux=late.flux,
                     flux_err=late.flux_err, x=late.x, y=late.y,
                     noise_pixels=late.noise_pixels, meta=meta)
    picked = get_method("kr-pmap").load_resources(late, {"pmap": str(tmp_path / "maps")})
    assert Path(picked["pmap"].source).parent.name == "b"


@pytest.mark.shared_data
def test_real_epoch1_date_picks_the_120827_channel2_map(shared_irac):
    path = find_pmap_path(shared_irac, {"CHANNEL": 2}, 56240.74)   # 2012-11-09
    assert path.name.endswith("_120827.fits")
    assert find_pmap_path(shared_irac, {"CHANNEL": 2}, 55950.0).name.endswith("_120124.fits")
    assert find_pmap_path(shared_irac, {"CHANNEL": 1}, 56240.74).name.endswith("_120828.fits")
