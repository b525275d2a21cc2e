"""Observation plans: Table 2 start times, AORKEYs, frame counts, later epochs."""

from __future__ import annotations

import numpy as np
import pytest

from eclipsebench.config import load_config
from eclipsebench.simulation.plan import epoch_start_times_bmjd, plan_challenge, plan_epoch

TABLE2 = [2206.1459, 2209.2927, 2212.5079, 2215.7214, 2218.9047, 2222.0547, 2225.2356,
          2228.4898, 2231.6296, 2234.8406]
P_XO3 = 3.1915239


def test_default_starts_are_table2_in_bmjd():
    obs = load_config().observation
    starts = epoch_start_times_bmjd(obs.start_times_jd, 10, P_XO3)
    np.testing.assert_allclose(starts, np.array(TABLE2) + 2455000.0 - 2400000.5, atol=1e-9)


def test_default_challenge_has_156160_frames_and_table2_aorkeys():
    plans = plan_challenge(load_config().observation, 10, P_XO3, seed=1)
    assert sum(p.n_frames for p in plans) == 156_160
    keys = [(p.aors[0].aorkey, p.aors[1].aorkey) for p in plans]
    assert keys[0] == (20150000, 20150001) and keys[-1] == (20150018, 20150019)
    assert [a.label for a in plans[0].aors] == ["Pre", "Main"]
    assert plans[0].aors[0].n_cubes == 11 and plans[0].aors[1].n_cubes == 233


def test_epoch_timing_follows_the_config():
    obs = load_config().observation
    p = plan_epoch(obs, 3, 57000.0, seed=4)
    pre, main = p.aors
    starts = pre.frame_starts_s()
    assert starts.shape == (11, 64)
    np.testing.assert_allclose(np.diff(starts[0]), 2.008)
    np.testing.assert_allclose(np.diff(pre.cube_starts_s()), 129.4)
    assert main.t0_s == pytest.approx(10 * 129.4 + 64 * 2.008 + 300.0)
    assert p.duration_s == pytest.approx(main.t0_s + 232 * 129.4 + 64 * 2.008)
    np.testing.assert_allclose(p.to_bmjd(86400.0), 57001.0)


def test_later_epochs_continue_on_later_orbits_at_new_phases():
    starts = epoch_start_times_bmjd(TABLE2, 25, P_XO3)
    base = np.array(TABLE2) + 54999.5
    assert np.all(np.diff(starts) > 0)
    assert starts[10] > base[-1] + P_XO3
    # phase of each start relative to its Table-2 twin differs between cycles
    ph = np.mod((starts[10:20] - base) / P_XO3, 1.0)
    ph2 = np.mod((starts[20:25] - base[:5]) / P_XO3, 1.0)
    assert np.allclose(ph, ph[0]) and np.allclose(ph2, ph2[0])
    d1 = min(ph[0], 1 - ph[0])
    d2 = min(ph2[0], 1 - ph2[0])
    assert 0 < d1 <= 0.01 and 0 < d2 <= 0.01 and abs(d1 - d2) > 1e-4


def test_peakup_scatter_is_gaussian_with_the_configured_width():
    obs = load_config().observation
    xs = np.array([[a.x0_px, a.y0_px] for e in range(1, 401)
                   for a in plan_epoch(obs, e, 57000.0, seed=9).aors])
    assert abs(xs[:, 0].mean() - 15.15) < 0.006 and abs(xs[:, 1].mean() - 15.20) < 0.006
    assert 0.036 < xs[:, 0].std() < 0.044 and 0.036 < xs[:, 1].std() < 0.044
    # same seed, same plan; different seed, different peak-ups
    a = plan_epoch(obs, 2, 57000.0, seed=9)
    assert a == plan_epoch(obs, 2, 57000.0, seed=9)
    assert a.aors[0].x0_px != plan_epoch(obs, 2, 57000.0, seed=10).aors[0].x0_px
