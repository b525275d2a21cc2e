"""BLISS: knot grid, nearest-knot means, bilinear interpolation, sparse knots, options."""

from __future__ import annotations

import dataclasses

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


def test_grid_is_laid_out_as_poet_does():
    # Relative to the rounded median (15), x spans [0.012, 0.087]: POET's grid
    # runs from floor(0.12)/10 - 0.03 = -0.03 to ceil(0.87)/10 + 0.03 = 0.13,
    # with int(0.16 / 0.03 + 1) = 6 knots spread evenly (step 0.032, not 0.03).
    x = np.array([15.012, 15.05, 15.087])
    y = np.array([14.96, 15.0, 15.04])
    grid = bliss_setup(x, y, dx_px=0.03, dy_px=0.07, min_points=1)
    np.testing.assert_allclose(grid.x_knots, 15.0 + np.linspace(-0.03, 0.13, 6))
    # y: [-0.04, 0.04] -> -0.1 - 0.07 = -0.17 .. 0.1 + 0.07 = 0.17, int(0.34 / 0.07 + 1) = 5
    np.testing.assert_allclose(grid.y_knots, 15.0 + np.linspace(-0.17, 0.17, 5))
    assert grid.n_knots == 30 and grid.keep.all()
    assert grid.steps_px == pytest.approx((0.032, 0.085))


def _cell_epoch():
    # Knots every 0.1 px from 14.8 to 15.3 (POET's edges around x in
    # [14.98, 15.12]: floor/ceil to 0.1 px, one step beyond); five frames near each of the four knots (15.0, 15.0),
    # (15.1, 15.0), (15.0, 15.1), (15.1, 15.1) with ratios whose means are 10,
    # 20, 30 and 40, and frames spread inside that cell.
    off = np.array([-0.025, -0.015, 0.005, 0.015, 0.025])
    knots = {(15.0, 15.0): 10.0, (15.1, 15.0): 20.0, (15.0, 15.1): 30.0, (15.1, 15.1): 40.0}
    xs, ys, fs = [], [], []
    for (kx, ky), mean in knots.items():
        xs += list(kx + off)
        ys += list(ky - off)
        fs += list(mean + np.array([-2.0, -1.0, 0.0, 1.0, 2.0]))
    return np.array(xs), np.array(ys), np.array(fs)


def test_knot_means_and_bilinear_interpolation_by_hand():
    x, y, f = _cell_epoch()
    grid = bliss_setup(x, y, dx_px=0.1, dy_px=0.1, min_points=4)
    assert grid.n_live == 4 and grid.keep.all()
    np.testing.assert_allclose(grid.x_knots, [14.8, 14.9, 15.0, 15.1, 15.2, 15.3], atol=1e-12)
    gain = bliss_gain(grid, f)
    inside = (x > 15.0) & (x < 15.1) & (y > 15.0) & (y < 15.1)
    u, v = (x - 15.0) / 0.1, (y - 15.0) / 0.1
    expected = 10 * (1 - u) * (1 - v) + 20 * u * (1 - v) + 30 * (1 - u) * v + 40 * u * v
    np.testing.assert_allclose(gain[inside], expected[inside], rtol=1e-10)
    # Outside the populated cell a corner is empty: the frame takes its own knot's mean.
    own = np.select([(np.abs(x - 15.0) < 0.05) & (np.abs(y - 15.0) < 0.05),
                     (np.abs(x - 15.1) < 0.05) & (np.abs(y - 15.0) < 0.05),
                     (np.abs(x - 15.0) < 0.05) & (np.abs(y - 15.1) < 0.05)], [10.0, 20.0, 30.0],
                    40.0)
    np.testing.assert_allclose(gain[~inside], own[~inside], rtol=1e-12)
    assert np.count_nonzero(grid.nearest_neighbour) == np.count_nonzero(~inside)


def test_sparse_knot_frames_are_masked_and_counted():
    # Spacing 0.15 px: POET's grid spans 14.85-15.65 with int(0.8 / 0.15 + 1) = 6
    # knots (step 0.16: 14.85, 15.01, 15.17, 15.33, 15.49, 15.65). Five frames
    # near knot 15.01, four near 15.49, one alone near each of 15.17 and 15.33.
    # With POET's minnumpts = 2 the two lone frames are masked: they leave the
    # fit instead of joining a knot 0.16 px away (the stand-in merged them into
    # the nearest live knot's mean).
    x = np.array([15.0] * 5 + [15.15, 15.3] + [15.45] * 4)
    y = np.full_like(x, 15.0)
    f = np.arange(1.0, 12.0)
    data = _data(x, y, f)
    model = get_method("bliss")(data, knot_spacing_px=0.15, min_points_per_knot=2)
    assert model.dropped_frames() == {"sparse_knot": 2}
    assert model.diagnostics()["n_sparse_knot_frames"] == 2
    assert len(model.data) == 9
    np.testing.assert_array_equal(model.data.time_bmjd, np.r_[0:5, 7:11].astype(float))
    np.testing.assert_array_equal(model.data.flux, f[np.r_[0:5, 7:11]])
    # Each kept frame's cell has a corner without frames: it takes its own knot's mean.
    expected = np.r_[np.full(5, f[:5].mean()), np.full(4, f[7:].mean())]
    np.testing.assert_allclose(model.predict(np.ones(9)), expected, rtol=1e-12)
    assert model.n_effective_params() == 2


def test_sparse_frames_on_a_drift_track_are_masked(epoch_sys):
    # A stray excursion of 30 frames far along the drift track: with a spacing
    # of 0.01 px each of its knots holds one or two frames. They are masked and
    # counted, never modelled with the mean of a knot hundredths of a pixel away.
    data = epoch_sys.data
    x = data.x.copy()
    y = data.y.copy()
    x[5000:5030] = x.max() + 0.02 + 0.015 * np.arange(30)
    model = get_method("bliss")(dataclasses.replace(data, x=x, y=y), knot_spacing_px=0.01)
    dropped = model.dropped_frames()["sparse_knot"]
    assert dropped >= 30
    assert len(model.data) == len(data) - dropped
    assert not np.any(np.isin(model.data.time_bmjd, data.time_bmjd[5000:5030]))


def test_all_sparse_is_refused():
    x = np.array([15.0, 15.3, 15.6])
    with pytest.raises(InputError, match="min_points_per_knot"):
        bliss_setup(x, np.full(3, 15.0), dx_px=0.1, dy_px=0.1, min_points=2)


def test_class_options_and_effective_params(epoch_sys):
    data = epoch_sys.data
    model = get_method("bliss")(data, knot_spacing_px=0.01)
    assert model.knot_spacing_px == (0.01, 0.01)
    # Independent count of knots with >= 4 nearest frames, on POET's grid
    # (first knot one step below the tenth of a pixel under the smallest centroid).
    xk0 = np.floor(10 * data.x.min()) / 10 - 0.01
    yk0 = np.floor(10 * data.y.min()) / 10 - 0.01
    ix = np.rint((data.x - xk0) / 0.01).astype(int)
    iy = np.rint((data.y - yk0) / 0.01).astype(int)
    _, counts = np.unique(np.column_stack([ix, iy]), axis=0, return_counts=True)
    assert model.n_effective_params() == int(np.sum(counts >= 4))
    default = get_method("bliss")(data)
    dx = np.sqrt(np.mean(np.diff(data.x) ** 2))
    assert default.knot_spacing_px[0] == pytest.approx(dx)
    assert get_method("bliss").record.policy.preferred_move == "de"
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
    assert model.dropped_frames()["sparse_knot"] > 0
    keep = model.grid.keep
    new_flux = model.data.flux * 1.01
    other = model.with_flux(new_flux)
    assert other.grid is model.grid
    np.testing.assert_allclose(other.predict(epoch_sys.astro[keep]),
                               1.01 * model.predict(epoch_sys.astro[keep]))
    np.testing.assert_array_equal(model.data.flux, epoch_sys.data.flux[keep])


def test_centroids_that_barely_move_are_refused_before_allocating():
    """A static pointing (spacing ~1e-13 px) asked for 1e24 knots: MemoryError before."""
    import numpy as np
    import pytest

    from eclipsebench.decorrelate import get_method
    from eclipsebench.decorrelate.base import EpochData
    from eclipsebench.errors import InputError

    n = 2000
    i = np.arange(n)
    d = EpochData(time_bmjd=i / 1440, flux=np.full(n, 1e5), flux_err=np.full(n, 300.0),
                  x=15.0 + 1e-13 * (i % 3), y=15.0 + 1e-13 * (i % 2))
    with pytest.raises(InputError, match="knots for 2000 frames"):
        get_method("bliss")(d)
