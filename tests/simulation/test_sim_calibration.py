"""The calibration-star set is measured by the science photometry, with its settings."""

from __future__ import annotations

import numpy as np
import pytest

from eclipsebench.config import load_config
from eclipsebench.config.detector import read_noise_of
from eclipsebench.detector.constants import SUB_0P1S
from eclipsebench.photometry.measure import measure_stack
from eclipsebench.simulation.calibration import (
    CALIBRATION_COLUMNS,
    calibration_chunk,
    calibration_frames,
    calibration_stamp_half_px,
)

N_FRAMES = 200


def _science_photometry(cfg, frames):
    """The science photometry on 32x32 frames holding each stamp in a corner, NaN elsewhere.

    A pixel outside the stamp that any estimator used would make its result
    differ (NaN in an aperture or box, one pixel fewer in the annulus).
    """
    n, size, _ = frames.frames_e.shape
    science = np.full((n, 32, 32), np.nan)
    science[:, :size, :size] = frames.frames_e
    half = size // 2
    return measure_stack(science, guess_x=half, guess_y=half, options=cfg.photometry,
                         fowler=SUB_0P1S.fowler, wait=SUB_0P1S.wait,
                         read_noise_e=read_noise_of(cfg))


@pytest.mark.parametrize("overrides", [
    [],
    ["photometry.centroid=gauss", "photometry.radius_px=3.0", "photometry.annulus_px=[4.0, 9.0]",
     "photometry.background=median", "photometry.noise_read=paper"],
])
def test_calibration_set_is_the_science_photometry_of_its_stamps(overrides):
    cfg = load_config(None, overrides)
    stored = calibration_chunk(cfg, 0, N_FRAMES)
    frames = calibration_frames(cfg, 0, N_FRAMES)
    m = _science_photometry(cfg, frames)
    expected = {"x": frames.x0 + m["x"], "y": frames.y0 + m["y"],
                "noise_pixels": m["noise_pixels"], "flux": m["flux"], "flux_err": m["flux_err"],
                "background": m["background"], "x_true": frames.x_true,
                "y_true": frames.y_true}
    assert set(stored) == set(CALIBRATION_COLUMNS)
    for key in CALIBRATION_COLUMNS:
        assert np.array_equal(stored[key], expected[key]), key
    assert np.all(np.isfinite(stored["flux"])) and np.all(np.abs(stored["x"] - 15.0) < 0.8)
    # the whole annulus about each centroid (pixel centres at r_in <= d <= r_out)
    r_in, r_out = cfg.photometry.annulus_px
    k = np.arange(-20, 21)
    dx = k[None, None, :] - (m["x"] - np.rint(m["x"]))[:, None, None]
    dy = k[None, :, None] - (m["y"] - np.rint(m["y"]))[:, None, None]
    d2 = dx**2 + dy**2
    full = ((d2 >= r_in**2) & (d2 <= r_out**2)).sum(axis=(1, 2))
    assert np.array_equal(m["background_npix"], full)


def test_stamp_is_big_enough_for_the_configured_photometry():
    assert calibration_stamp_half_px(load_config(None, []).photometry) == 8
    cfg = load_config(None, ["photometry.annulus_px=[3.0, 10.5]"])
    assert calibration_stamp_half_px(cfg.photometry) == 12
    assert calibration_frames(cfg, 0, 3).frames_e.shape == (3, 25, 25)
