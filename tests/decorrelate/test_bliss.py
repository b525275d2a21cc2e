"""BLISS: knot grid, nearest-knot means, bilinear interpolation, sparse knots, options."""

from __future__ import annotations

import numpy as np
import pytest

from eclipsebench.decorrelate import get_method
from eclipsebench.decorrelate.base import EpochData
from eclipsebench.decorrelate.bliss import bliss_gain, bliss_setup, knot_spacing_from_data
from eclipsebench.errors import InputError


def _data(x, y, flux, **kw):
    n = len(x)
    return EpochData(time_bmjd=np.arange(n, dtype=float), flux=np.asarray(flux, float),
                     flux_err=np.ones(n), x=np.asarray(x, float), y=np.asarray(y, float), **kw)


def test_default_spacing_is_rms_frame_to_frame_motion():
    x = np.array([0.0, 0.3, 0.1, 0.4])
    y = np.array([1.0, 1.0, 1.2, 1.1])
    dx, dy = knot_spacing_from_data(x, y)
    assert dx == pytest.approx(np.sqrt((0.09 + 0.04 + 0.09) / 3))
    assert dy == pytest.approx(np.sqrt((0.0 + 0.04 + 0.01) / 3))


def test_knot_means_and_bilinear_interpolation_by_hand():
    # Knots at x = 0, 1 and y = 0, 1 (spacing 1). Frames sit near each knot,
    # four per knot, with ratios chosen so the knot means are 10, 20, 30, 40.
    off = np.array([[-0.1, -0.1], [0.1, 0.1], [-0.1, 0.1], [0.1, -0.1]])
    knots = {(0, 0): 10.0, (1, 0): 20.0, (0, 1): 30.0, (1, 1): 40.0}
    xs, ys, fs = [], [], []
    for (kx, ky), mean in knots.items():
        for j, (ox, oy) in enumerate(off):
            xs.append(min(max(kx + ox, 0.0), 1.0))
            ys.append(min(max(ky + oy, 0.0), 1.0))
            fs.append(mean + (-1.5, -0.5, 0.5, 1.5)[j])
    x, y, f = map(np.array, (xs, ys, fs))
    grid = bliss_setup(x, y, dx_px=1.0, dy_px=1.0, min_points=4)
    assert grid.n_knots == 4 and grid.n_live == 4
    gain = bliss_gain(grid, f)
    # Independent bilinear interpolation of the knot means 10, 20, 30, 40.
    expected = (10 * (1 - x) * (1 - y) + 20 * x * (1 - y) + 30 * (1 - x) * y + 40 * x * y)
    np.testing.assert_allclose(gain, expected, rtol=1e-12)


def test_sparse_knot_frames_join_the_nearest_live_knot():
    # Knots at x = 0, 1, 2, 3 (spacing 1). Knot 0 has five frames, knot 3 four;
    # knots 1 and 2 have one frame each and are dead with min_points = 2: the
    # frame at x = 1 joins knot 0 (nearest live), the one at x = 1.5 rounds to
    # knot 2 and joins knot 3. Dead knots take their nearest live knot's value.
    x = np.array([0.0] * 5 + [1.0, 1.5] + [3.0] * 4)
    y = np.zeros_like(x)
    f = np.arange(1.0, 12.0)
    grid = bliss_setup(x, y, dx_px=1.0, dy_px=1.0, min_points=2)
    assert grid.n_live == 2
    mean0 = f[[0, 1, 2, 3, 4, 5]].mean()
    mean3 = f[[6, 7, 8, 9, 10]].mean()
    expected = np.array([mean0] * 6 + [0.5 * mean0 + 0.5 * mean3] + [mean3] * 4)
    np.testing.assert_allclose(bliss_gain(grid, f), expected, rtol=1e-12)


def test_dead_knots_take_nearest_live_value():
    rng = np.random.default_rng(1)
    x = np.concatenate([rng.uniform(0.0, 0.4, 200), [2.9]])     # one stray frame far away
    y = np.concatenate([rng.uniform(0.0, 0.4, 200), [0.1]])
    f = np.concatenate([np.full(200, 7.0), [9.0]])
    grid = bliss_setup(x, y, dx_px=1.0, dy_px=1.0, min_points=4)
    gain = bliss_gain(grid, f)
    # Only knot (0, 0) is live: the stray frame joins it, so every value is the mean.
    assert grid.n_live == 1
    np.testing.assert_allclose(gain, f.mean())


def test_class_options_and_effective_params(epoch_sys):
    data = epoch_sys.data
    model = get_method("bliss")(data, knot_spacing_px=0.01)
    assert model.knot_spacing_px == (0.01, 0.01)
    # Independent count of knots with >= 4 nearest frames.
    xk0, yk0 = data.x.min(), data.y.min()
    ix = np.rint((data.x - xk0) / 0.01).astype(int)
    iy = np.rint((data.y - yk0) / 0.01).astype(int)
    _, counts = np.unique(np.column_stack([ix, iy]), axis=0, return_counts=True)
    assert model.n_effective_params() == int(np.sum(counts >= 4))
    default = get_method("bliss")(data)
    dx = np.sqrt(np.mean(np.diff(data.x) ** 2))
    assert default.knot_spacing_px[0] == pytest.approx(dx)
    assert get_method("bliss").preferred_move == "de"
    with pytest.raises(InputError, match="knot_spacing_px"):
        get_method("bliss")(data, knot_spacing_px=-0.01)
    with pytest.raises(InputError, match="unknown option"):
        get_method("bliss")(data, knots=3)
    with pytest.raises(InputError, match="min_points_per_knot"):
        get_method("bliss")(data, min_points_per_knot=0)


def test_static_pointing_needs_explicit_spacing():
    n = 50
    data = _data(np.full(n, 15.0), np.full(n, 15.0), np.ones(n))
    with pytest.raises(InputError, match="knot_spacing_px"):
        get_method("bliss")(data)
    model = get_method("bliss")(data, knot_spacing_px=0.01)
    np.testing.assert_allclose(model.predict(np.ones(n)), 1.0)


def test_with_flux_reuses_grid(epoch_sys):
    model = get_method("bliss")(epoch_sys.data)
    new_flux = epoch_sys.data.flux * 1.01
    other = model.with_flux(new_flux)
    assert other.grid is model.grid
    np.testing.assert_allclose(other.predict(epoch_sys.astro), 1.01 * model.predict(epoch_sys.astro))
    np.testing.assert_array_equal(model.data.flux, epoch_sys.data.flux)
