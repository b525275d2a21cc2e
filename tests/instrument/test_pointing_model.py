"""Pointing model (paper Appendix A.1): terms, Table-5 draws, chunk independence."""

from __future__ import annotations

import numpy as np
import pytest

from eclipsebench.errors import InputError
from eclipsebench.instrument.pointing import (
    PointingModel,
    PointingParams,
    PointingRanges,
    draw_pointing_params,
    fbm_segments,
    skewed_sine,
)

QUIET = dict(a_j_px=0.0, a_fbm_px=0.0, a_w_px=0.0, da_w_max_px=0.0, dp_w_max_s=0.0,
             a_sd_px=0.0, a_ld_arcsec_per_hr=0.0)


def model(seed=0, duration_s=600.0, starts=(0.0,), **kw):
    params = PointingParams(**{**QUIET, **kw})
    return PointingModel(params, duration_s=duration_s, dt_s=1e-3,
                         rng=np.random.default_rng(seed), aor_starts_s=starts)


def test_jitter_sine_projected_on_its_axis():
    m = model(a_j_px=0.04, p_j_s=60.0, phi_j_rad=0.3, theta_j_deg=-45.0)
    t = np.array([0.0, 7.5, 15.0, 31.0])
    dx, dy = m.offsets(t)
    s = 0.04 * np.sin(2 * np.pi * t / 60.0 + 0.3)
    np.testing.assert_allclose(dx, s * np.cos(np.deg2rad(-45)), atol=1e-12)
    np.testing.assert_allclose(dy, s * np.sin(np.deg2rad(-45)), atol=1e-12)


def test_skewed_sine_peaks_at_s_w_and_is_a_sine_for_quarter():
    t = np.linspace(0, 1000, 10001)
    np.testing.assert_allclose(skewed_sine(t, 1000.0, 0.25, 0.0), np.sin(2 * np.pi * t / 1000),
                               atol=1e-12)
    for s_w in (0.1, 0.18, 0.4):
        w = skewed_sine(t, 1000.0, s_w, 0.0)
        assert t[np.argmax(w)] / 1000 == pytest.approx(s_w, abs=2e-4)
        assert w.max() == pytest.approx(1.0, abs=1e-6)
        assert np.max(np.abs(np.diff(w))) < 0.01  # continuous


def test_short_term_drift_starts_at_zero_offset_and_settles_by_a_sd():
    # s(t0) = A_sd; s -> 0: the "asymptotic decay" A_sd is the initial minus final value
    m = model(a_sd_px=0.6, tau_sd_s=300.0, theta_sd_deg=100.0, duration_s=20000.0)
    dx, dy = m.offsets(np.array([0.0, 19000.0]))
    s = np.hypot(dx, dy) * np.sign(dy)
    assert s[0] == pytest.approx(0.6, rel=1e-9)
    assert abs(s[1]) < 1e-12
    # a negative tau: same decay time, opposite sign
    m2 = model(a_sd_px=0.6, tau_sd_s=-300.0, duration_s=20000.0)
    np.testing.assert_allclose(m2.offsets(np.array([0.0, 500.0]))[1],
                               -m.offsets(np.array([0.0, 500.0]))[1])


def test_long_term_drift_restarts_at_each_aor():
    m = model(a_ld_arcsec_per_hr=0.0208, theta_ld_deg=-90.0, duration_s=7200.0,
              starts=(0.0, 1800.0))
    dx, dy = m.offsets(np.array([1799.999, 1800.0, 5400.0]))
    rate = 0.0208 / 1.2 / 3600.0
    np.testing.assert_allclose(dy, [-rate * 1799.999, 0.0, -rate * 3600.0], atol=1e-12)


def test_fbm_is_normalised_to_its_peak_per_block_and_has_the_spectral_index():
    m = model(a_fbm_px=0.4, beta_fbm=1.0, duration_s=300.0, seed=5)
    x = m.fbm_samples(0, 2048 * 64)
    assert np.max(np.abs(x[0])) == pytest.approx(0.4)
    assert np.max(np.abs(x[1])) == pytest.approx(0.4)
    z = fbm_segments(np.random.default_rng(1), 400, 2048, 2.0)
    p = (np.abs(np.fft.rfft(z, axis=1)) ** 2).mean(0)
    f = np.fft.rfftfreq(2048)
    sel = (f > 0.01) & (f < 0.2)
    slope = np.polyfit(np.log(f[sel]), np.log(p[sel]), 1)[0]
    assert slope == pytest.approx(-2.0, abs=0.1)


def test_same_time_same_offset_in_any_chunk():
    m = PointingModel(draw_pointing_params(np.random.default_rng(7)), duration_s=1000.0,
                      dt_s=1e-3, rng=np.random.default_rng(8), aor_starts_s=(0.0, 400.0))
    full = m.offsets_grid(0, 400_000)
    part = m.offsets_grid(262_000, 10_000)
    np.testing.assert_array_equal(part[0], full[0][262_000:272_000])
    np.testing.assert_array_equal(part[1], full[1][262_000:272_000])
    t = np.array([399.9, 12.3456, 262.0005, 131.072])
    dx, dy = m.offsets(t)
    dx2, dy2 = m.offsets(t[::-1])
    np.testing.assert_array_equal(dx, dx2[::-1])
    # grid fast path agrees with the general path on grid times
    k = np.array([123, 262_001, 399_000])
    gx = full[0][k]
    np.testing.assert_allclose(m.offsets(k * 1e-3)[0], gx, atol=2e-6)
    # sparse times spread over many FBM blocks (the block-by-block path)
    k = np.array([5, 140_000, 270_000, 399_990, 131_071, 131_072])
    np.testing.assert_allclose(m.offsets(k * 1e-3)[1], full[1][k], atol=2e-6)
    # a fresh model with the same rng seed gives the same bytes
    m2 = PointingModel(draw_pointing_params(np.random.default_rng(7)), duration_s=1000.0,
                       dt_s=1e-3, rng=np.random.default_rng(8), aor_starts_s=(0.0, 400.0))
    assert m2.offsets_grid(0, 5000)[0].tobytes() == full[0][:5000].tobytes()


def test_table5_draws_respect_ranges_and_types():
    rng = np.random.default_rng(11)
    draws = [draw_pointing_params(rng) for _ in range(300)]
    a_w = np.array([d.a_w_px for d in draws])
    assert a_w.min() >= 0.018 and a_w.max() <= 0.034
    tau = np.array([d.tau_sd_s for d in draws])
    assert tau.min() >= -1800 and tau.max() <= 1800 and (tau < 0).any()
    assert all(d.a_fbm_px == 0.4 and d.p_sd_s == 395.6 for d in draws)
    th_w = np.array([d.theta_w_deg for d in draws])
    assert th_w.mean() == pytest.approx(-62.5, abs=3.0)
    assert th_w.std() == pytest.approx(17.5, rel=0.2)
    assert all(0.02 <= d.s_w <= 0.48 for d in draws)
    assert PointingRanges().a_ld_arcsec_per_hr.hi == 0.0208


def test_bad_parameters_raise_input_errors():
    with pytest.raises(InputError, match="s_w"):
        PointingParams(s_w=0.6)
    with pytest.raises(InputError, match="p_j_s"):
        PointingParams(p_j_s=0.0)
    m = model()
    with pytest.raises(InputError, match="t_s"):
        m.offsets(np.array([-1.0]))


def test_ten_drawn_epochs_have_table2_like_centroid_statistics():
    """Main-AOR frame positions of ten Table-5 epochs vs Table 2 (within a factor of 2).

    Table 2 (simulated set): sd_x 0.02-0.03 px, sd_y 0.03-0.10 px,
    cov_xy -20.9e-4 .. -4.6e-4 px^2. The pre AOR is 11 cubes of 64 frames
    every 2.008 s, the main AOR starts 120 s after it and has 233 cubes.
    """
    main0 = 11 * 64 * 2.008 + 120.0
    t = main0 + np.arange(233 * 64) * 2.008 + 1.0
    for epoch in range(10):
        p = draw_pointing_params(np.random.default_rng([2015, epoch]))
        m = PointingModel(p, duration_s=t[-1] + 10.0, dt_s=1e-3,
                          rng=np.random.default_rng([2016, epoch]), aor_starts_s=(0.0, main0))
        dx, dy = m.smooth_offsets(t)  # the FBM adds 0.007 px per frame, negligible here
        c = np.cov(dx, dy)
        assert 0.01 <= np.sqrt(c[0, 0]) <= 0.06
        assert 0.015 <= np.sqrt(c[1, 1]) <= 0.20
        assert -41.8e-4 <= c[0, 1] <= -2.3e-4
