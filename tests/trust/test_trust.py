"""Issue 26: digital twins of one observation, reduced like it, scored.

A small simulated observation (one short epoch: 16-frame cubes, the
eclipse inside) stands in for a real one where the real epoch is too large
for a unit test; the resemblance to the real epoch 1 is tested on it
(``shared_data``).
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from eclipsebench.astro.catalogue import get_system
from eclipsebench.cli import main
from eclipsebench.config.photometry import PhotometrySection
from eclipsebench.photometry.table import read_table, write_photometry
from eclipsebench.simulation.render import FrameModel, tick_moments
from eclipsebench.trust.observation import Observation, observation_from_table
from eclipsebench.trust.result import read_trust
from eclipsebench.trust.score import observation_statistics
from eclipsebench.trust.twin import TWIN_MODEL, ExposureMotion, make_recipe, twin_table

FAST = ["--methods", "poly2,kr-pmap", "--sampler", "leastsq", "--twins", "10", "--quiet"]


@pytest.fixture(scope="module")
def small_table(small_observation_table):
    """The photometry table (``eclipsebench photometry``) of a small simulated observation,
    made once per test run (tests/conftest.py, shared with test_folder and test_any_table)."""
    return small_observation_table


def _cubes_of_sub_2s(n_cubes: int) -> Observation:
    """An observation of ``n_cubes`` back-to-back 64-frame sub_2s cubes (2.02 s cadence)."""
    from eclipsebench.detector.constants import SUB_2S

    n = 64 * n_cubes
    t = 57000.0 + (np.arange(n) * 2.02 + (np.arange(n) // 64) * 0.2) / 86400.0
    return Observation(time_bmjd=t, aorkey=np.ones(n, int), expid=np.arange(n) // 64,
                       frame=np.arange(n) % 64, x_px=np.full(n, 15.0), y_px=np.full(n, 15.0),
                       flux_e=np.ones(n), background_e_per_px=np.ones(n), noise_pixels=np.ones(n),
                       flag=np.zeros(n, int), channel=2, mode=SUB_2S, read_noise_e=9.4)


def test_the_motion_within_an_exposure_is_the_simulator_s_block_scaled_jitter():
    obs = _cubes_of_sub_2s(24)
    model = FrameModel(mode=obs.mode, noise_model="physical", read_noise_e=9.4)
    motion = ExposureMotion(obs, model, 0.4, np.random.default_rng(1))
    rows = np.arange(obs.n_frames)
    dx, dy = motion.offsets(rows)
    mx, my, _ = tick_moments(dx, dy, model)
    assert np.allclose(mx, 0.0, atol=1e-12) and np.allclose(my, 0.0, atol=1e-12)
    # a frame's motion does not depend on the frames asked with it
    some = rows[[5, 700, 1500]]
    assert np.allclose(motion.offsets(some)[0], dx[some], rtol=0, atol=1e-12)
    # each whole 131-s block of the jitter peaks at A_fbm (the frames cover 99 % of it) ...
    block = motion.start_index // (2048 * 64)
    peaks = [np.max(np.abs(np.concatenate(
        [motion._pointing.fbm_samples(int(i), model.grid_samples_per_frame)[0]
         for i in motion.start_index[block == b]]))) for b in np.unique(block)[1:-1]]
    assert max(peaks) <= 0.4 + 1e-9 and min(peaks) > 0.3   # a peak can fall between frames
    assert np.median(peaks) == pytest.approx(0.4, rel=1e-9)
    # ... so its rms within an exposure changes from block to block (one rms throughout
    # would give a spread of 0.5 %, the average of 64 frames)
    var = np.array([np.mean(dx[block == b] ** 2 + dy[block == b] ** 2)
                    for b in np.unique(block)[1:-1]])
    assert 0.02 < var.std() / var.mean() < 0.2
    assert 0.06 < np.sqrt(0.5 * var.mean()) < 0.12   # 0.0895 px for the challenge's 0.4


def test_the_motion_s_moments_in_one_pass_are_those_of_its_offsets():
    """ExposureMotion.moments (what a twin renders with, issue 40) gives tick_moments of
    ExposureMotion.offsets, for frames within a block and across blocks, and for none."""
    obs = _cubes_of_sub_2s(6)
    model = FrameModel(mode=obs.mode, noise_model="physical", read_noise_e=9.4)
    motion = ExposureMotion(obs, model, 0.4, np.random.default_rng(3))
    for rows in (np.arange(64, 128), np.arange(obs.n_frames), np.array([3, 200, 383])):
        want = tick_moments(*motion.offsets(rows), model)
        got = motion.moments(rows)
        for w, g in zip(want, got, strict=True):
            assert g.shape == w.shape
            assert np.allclose(g, w, rtol=1e-12, atol=1e-15)
        assert np.abs(got[2][:, :, 3]).max() > 1e-4   # the motion is there
    still = ExposureMotion(obs, model, 0.0, np.random.default_rng(3)).moments(np.arange(64))
    assert np.array_equal(still[2], tick_moments(np.zeros((64, model.grid_samples_per_frame)),
                                                 np.zeros((64, model.grid_samples_per_frame)),
                                                 model)[2])


def test_the_calibration_s_one_draw_of_the_motion_gives_each_peak_s_offsets_byte_for_byte():
    """Issue 40: the calibration's draw of the motion, its blocks drawn once, gives at any peak
    the offsets of an ExposureMotion made at that peak with the same stream, for frames within
    a block and across blocks; the calibration asks for it once per observation and rows."""
    from eclipsebench.seeding import rng
    from eclipsebench.trust import twin as twin_module

    obs = _cubes_of_sub_2s(12)
    model = FrameModel(mode=obs.mode, noise_model="none", read_noise_e=9.4)
    rows = np.arange(1, obs.n_frames, 3)
    drawn = twin_module._AnyPeakMotion(obs, model, rng(0, "trust", "calibrate"), rows)
    assert 0 < np.count_nonzero(drawn._split < model.grid_samples_per_frame)   # across blocks
    for peak in (1.0, 0.677, 0.0):
        want = ExposureMotion(obs, model, peak, rng(0, "trust", "calibrate")).offsets(rows)
        got = drawn.offsets(peak)
        assert all(np.array_equal(g, w) for g, w in zip(got, want, strict=True)), peak
    first = twin_module._calibration_motion(obs, rows, model)
    assert twin_module._calibration_motion(obs, rows, model) is first
    assert twin_module._calibration_motion(obs, rows[1:], model) is not first


def test_a_twin_shares_times_flags_and_track_but_not_the_noise(small_table):
    table = read_table(small_table)
    obs = observation_from_table(table)
    recipe = make_recipe(obs, np.ones(obs.n_frames), radius_px=2.25)
    a = twin_table(recipe, PhotometrySection(), seed=3, twin=1)
    again = twin_table(recipe, PhotometrySection(), seed=3, twin=1)
    b = twin_table(recipe, PhotometrySection(), seed=3, twin=2)
    assert np.array_equal(np.asarray(a["time_bmjd"]), obs.time_bmjd)
    assert np.all((np.asarray(a["flag"]) & obs.flag) == obs.flag)   # real bad frames stay bad
    assert np.array_equal(np.asarray(a["flux"]), np.asarray(again["flux"]))
    assert not np.array_equal(np.asarray(a["flux"]), np.asarray(b["flux"]))
    good = np.asarray(a["flag"]) == 0
    assert np.median(np.abs(np.asarray(a["x"])[good] - obs.x_px[good])) < 0.01
    assert a.meta["TWIN"] == 1 and a.meta["SYSTEM"] == table.meta["SYSTEM"]


def test_the_twins_of_one_star_share_its_taylor_bases(small_table, monkeypatch):
    """Issue 40: the twins of a batch render their cubes with the Taylor bases and wings the
    first twin made (every twin's positions are the track's floats), and give the bytes of
    twins rendered each with a star of its own."""
    from eclipsebench.simulation.star import StarImager
    from eclipsebench.trust.twin import twin_star

    obs = observation_from_table(read_table(small_table))
    recipe = make_recipe(obs, np.ones(obs.n_frames), radius_px=2.25, motion_peak_px=0.3)
    options = PhotometrySection()
    alone = [twin_table(recipe, options, seed=3, twin=i) for i in (1, 2)]
    star = twin_star(recipe, options)
    made: dict[str, list] = {"taylor_basis": [], "image": []}

    def counted(name):
        method = getattr(StarImager, name)
        return lambda *a: made[name].append(1) or method(*a)

    for name in made:
        monkeypatch.setattr(StarImager, name, counted(name))
    first = twin_table(recipe, options, seed=3, twin=1, star=star)
    cubes = len(made["taylor_basis"])
    assert cubes == sum(len(np.unique(obs.expid[rows])) for rows in obs.aors())
    assert len(made["image"]) == cubes
    second = twin_table(recipe, options, seed=3, twin=2, star=star)
    assert len(made["taylor_basis"]) == cubes and len(made["image"]) == cubes
    for shared, own in zip((first, second), alone, strict=True):
        assert shared.colnames == own.colnames
        for name in own.colnames:
            assert np.asarray(shared[name]).tobytes() == np.asarray(own[name]).tobytes(), name


def test_a_twin_rendered_where_its_photometry_reads_measures_as_the_whole_frame(small_table,
                                                                               monkeypatch):
    """Noise-free (the noise draws differ with the pixels drawn), the twin rendered only in
    its photometry window gives the whole frame's photometry: the same flags, backgrounds,
    noise pixels and stamps, and centroids and fluxes equal to rounding (the window's
    coordinates are offset)."""
    import eclipsebench.trust.twin as twin_module
    from eclipsebench.trust.twin import photometry_window

    obs = observation_from_table(read_table(small_table))
    recipe = make_recipe(obs, np.ones(obs.n_frames), radius_px=2.25)
    x, y = obs.track_px()
    window = photometry_window(x, y, PhotometrySection(), (32, 32))
    assert window[2] * window[3] < 0.5 * 32 * 32
    part = twin_table(recipe, PhotometrySection(), seed=3, twin=1, noise_model="none")
    whole = twin_table(recipe, PhotometrySection(), seed=3, twin=1, noise_model="none",
                       whole_frame=True)
    assert part.colnames == whole.colnames
    for name in part.colnames:
        a, b = np.asarray(part[name]), np.asarray(whole[name])
        if name.startswith(("x", "y", "flux", "width", "aperture")):
            np.testing.assert_allclose(a, b, rtol=1e-13, atol=0, err_msg=name)
        else:
            assert np.array_equal(a, b, equal_nan=True), name
    # a window short of what the 7 px annulus reads changes the backgrounds
    monkeypatch.setattr(twin_module, "read_radius_px", lambda options: 4.0)
    short = twin_table(recipe, PhotometrySection(), seed=3, twin=1, noise_model="none")
    assert not np.array_equal(np.asarray(short["background"]), np.asarray(whole["background"]))


def test_twin_tasks_share_the_recipe_and_do_not_reread_the_real_table(small_table, tmp_path,
                                                                       monkeypatch):
    import eclipsebench.trust.recipe as recipe_module
    from eclipsebench.trust import run as trust_run

    obs = observation_from_table(read_table(small_table))
    recipe = make_recipe(obs, np.ones(obs.n_frames), radius_px=2.25)
    recipe_module.write_recipe(recipe, {"flux_aperture_e": recipe.flux_aperture_e,
                                        "x_ref_px": recipe.x_ref_px, "y_ref_px": recipe.y_ref_px,
                                        "motion_peak_px": 0.0, "gain": None},
                               tmp_path / "r.npz", tmp_path / "r.json")
    reads = []
    real_read = recipe_module.read_table
    monkeypatch.setattr(recipe_module, "read_table", lambda p: reads.append(p) or real_read(p))
    settings = trust_run.TrustSettings(table=str(small_table), system=get_system("XO-3b"),
                                       methods=("poly2",), n_twins=10, seed=3, reduce=None)
    assert trust_run.twin_batches(12) == [(1, 2, 3, 4, 5), (6, 7, 8, 9, 10), (11, 12)]
    for batch in trust_run.twin_batches(7):
        trust_run.twin_task(settings, str(tmp_path / "r.npz"), str(tmp_path / "r.json"), batch,
                            [str(tmp_path / f"twin_{i:03d}.fits") for i in batch])
    assert len(reads) <= 1
    # each table is the twin made alone
    alone = twin_table(recipe, PhotometrySection(), seed=3, twin=7)
    assert np.array_equal(np.asarray(read_table(tmp_path / "twin_007.fits")["flux"]),
                          np.asarray(alone["flux"]))


@pytest.mark.parametrize("extra, what", [
    (["--twins", "9"], "--twins"), (["--depth", "nan"], "--depth"),
    (["--depth", "-5"], "--depth"), (["--methods", "no-such"], "no-such"),
    (["--pmap", "no-such-map"], "no-such-map")])
def test_bad_input_is_one_line_exit_2_and_nothing_written(small_table, tmp_path, capsys,
                                                          extra, what):
    out = tmp_path / "trust"
    args = ["trust", str(small_table), "--out", str(out), "--sampler", "leastsq", "--quiet"]
    assert _code(args + extra) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and what in err and "Traceback" not in err, err
    assert not out.exists()


def test_a_table_with_fewer_than_100_good_frames_is_refused(small_table, tmp_path, capsys):
    short = read_table(small_table)[:90]
    write_photometry(short, tmp_path / "short.fits")
    assert main(["trust", str(tmp_path / "short.fits"), "--out", str(tmp_path / "t")] + FAST) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "good frames" in err and "100" in err, err
    assert not (tmp_path / "t").exists()


@pytest.mark.slow
def test_same_bytes_with_one_or_two_workers_and_an_interrupted_run_resumes(small_table,
                                                                           tmp_path, capsys):
    one, two = tmp_path / "one", tmp_path / "two"
    assert main(["trust", str(small_table), "--out", str(one), "--workers", "1"] + FAST) == 0
    assert main(["trust", str(small_table), "--out", str(two), "--workers", "2"] + FAST) == 0
    result = (one / "trust.json").read_bytes()
    assert result == (two / "trust.json").read_bytes()
    assert (one / "trust.ecsv").read_bytes() == (two / "trust.ecsv").read_bytes()
    summary = json.loads(result)
    assert summary["n_twins"] == 10 and set(summary["methods"]) == {"poly2"}
    # KR/Pmap without a calibration set cannot run on the table: listed with why, not failed
    assert set(summary["skipped"]) == {"kr-pmap"} and summary["skipped"]["kr-pmap"]
    assert summary["recommended"] in (None, "poly2")
    s = summary["methods"]["poly2"]
    assert summary["near_equals"] == []            # one method: nothing to tell it from
    assert s.get("mse_excess_sigma") == (0.0 if summary["recommended"] else None)
    assert s["honest_err_ppm"] >= s["depth_err_ppm"] and 0 <= s["coverage_1sigma"] <= 1
    # the real residuals' red noise against the twins': a fraction, flagged at 0.95
    assert 0 <= s["beta_red_twins_below"] <= 1 and s["beta_red_real"] > 0
    assert s["redder_than_twins"] == (s["beta_red_twins_below"] >= 0.95)
    answer = read_trust(one)           # the notebook face of trust.json
    assert answer == summary and "TrustResult" in repr(answer)
    assert len(answer._repr_html_()) < 2048
    assert answer.to_table()["rmse_ppm"].unit.to("") == pytest.approx(1e-6)
    # an interrupted run: a twin, a reduction and the answer missing; the rerun redoes them
    (one / "twins" / "twin_004.fits").unlink()
    (one / "twins" / "poly2" / "twin_007.json").unlink()
    (one / "twins" / "poly2" / "twin_008.lc.ecsv").unlink()   # redone: the one resume rule
    (one / "trust.json").unlink()
    shutil.rmtree(one / "report")
    assert main(["trust", str(small_table), "--out", str(one), "--workers", "1", "--json"]
                + FAST) == 0
    assert (one / "trust.json").read_bytes() == result
    assert (one / "twins" / "poly2" / "twin_008.lc.ecsv").is_file()
    # more twins in the same folder: the ten made are kept, the score covers twelve;
    # back to ten, the answer is the ten-twin one again (in one process: two workers give
    # the same bytes, above)
    made = (one / "twins" / "twin_001.fits").stat().st_mtime_ns
    more = [a if a != "10" else "12" for a in FAST]
    assert main(["trust", str(small_table), "--out", str(one), "--workers", "1"] + more) == 0
    assert json.loads((one / "trust.json").read_bytes())["n_twins"] == 12
    assert (one / "twins" / "twin_001.fits").stat().st_mtime_ns == made
    assert main(["trust", str(small_table), "--out", str(one), "--workers", "1"] + FAST) == 0
    assert (one / "trust.json").read_bytes() == result
    # other settings in the same folder are refused
    capsys.readouterr()
    assert main(["trust", str(small_table), "--out", str(one), "--seed", "5"] + FAST) == 2
    assert "other settings" in capsys.readouterr().err
    # and so are twins made another way (a folder from before twin_model 2 lacks the key)
    held = json.loads((one / "trust_config.json").read_text())
    assert held.pop("twin_model") == TWIN_MODEL
    (one / "trust_config.json").write_text(json.dumps(held, sort_keys=True, indent=1))
    assert main(["trust", str(small_table), "--out", str(one)] + FAST) == 2
    assert "other settings" in capsys.readouterr().err


@pytest.mark.shared_data
@pytest.mark.slow
def test_the_twins_resemble_real_epoch1(real_epoch1_table, real_epoch1_trust):
    """Median noise pixels, centroid rms in x and y and the residual rms after BLISS of the
    twins within 15 % of the real epoch's, the raw flux rms in 5-minute bins within 30 %.

    The twins are those ``trust`` makes of real epoch 1 (BLISS's real fit, the motion its
    residuals allow, the real correlated noise): the ten of the run made once per test run
    (tests/conftest.py, ``real_epoch1_trust``, shared with test_real_noise.py), each with
    its BLISS reduction; the real fit is that run's too.

    The raw flux is the one known shortfall (26 % at ``twin_model`` 3): the twins' motion
    within an exposure averages the gain once more, which a pixel map measured on moving
    frames already holds; sharpening the gain by that motion restored it but made BLISS's
    twin residuals 40 % redder than the real ones (``docs/trust.md``)."""
    from eclipsebench.trust.layout import TrustLayout

    layout = TrustLayout(real_epoch1_trust)
    real = _statistics(read_table(real_epoch1_table),
                       json.loads(layout.real("bliss").read_text()))
    twins = [_statistics(read_table(layout.twin(i)),
                         json.loads(layout.twin_result("bliss", i).read_text()))
             for i in range(1, 11)]
    for key, value in real.items():
        mean = float(np.mean([t[key] for t in twins]))
        within = 0.30 if key == "flux_rms_5min_ppm" else 0.15
        assert abs(mean / value - 1) < within, (key, mean, value)


def _code(argv: list[str]) -> int:
    """The exit code, usage errors (argparse's SystemExit) included."""
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code)


def _statistics(table, fit: dict) -> dict[str, float]:
    """``observation_statistics`` of a table and the rms of its BLISS result (its JSON)."""
    return {**observation_statistics(table), "bliss_residual_rms_ppm": float(fit["rms_ppm"])}


def test_a_link_out_of_the_trust_folder_is_refused_before_any_work(small_table, tmp_path, capsys):
    out, elsewhere = tmp_path / "trust", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / "twins").symlink_to(elsewhere)
    assert _code(["trust", str(small_table), "--out", str(out)] + FAST) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "outside the run folder" in err, err
    assert list(elsewhere.iterdir()) == [] and sorted(p.name for p in out.iterdir()) == ["twins"]


def test_workers_beyond_the_stated_limit_are_refused(small_table, tmp_path, capsys):
    assert _code(["trust", str(small_table), "--out", str(tmp_path / "t"), "--workers",
                  "100000"] + FAST) == 2
    assert "limit" in capsys.readouterr().err and not (tmp_path / "t").exists()


def test_a_twin_carries_the_gain_of_a_given_map_through_its_recipe(small_table, tmp_path):
    from eclipsebench.instrument.prf import GainPolynomial
    from eclipsebench.trust.recipe import read_recipe, write_recipe
    from eclipsebench.trust.twin import map_gain

    obs = observation_from_table(read_table(small_table))
    grid = np.linspace(14.501, 15.499, 60)
    xx, yy = np.meshgrid(grid, grid)
    tilted = 1.0 + 0.02 * (xx - 15.0)          # a map unlike the simulator's gain
    gain, text, info = map_gain(obs.channel, grid, grid, tilted, np.full(xx.shape, 50.0),
                                source="pmap_ch2_test_121212.fits")
    assert "pmap_ch2_test_121212.fits" in text and info["fit_rms"] < 1e-3
    recipe = make_recipe(obs, np.ones(obs.n_frames), radius_px=2.25, gain=gain)
    plain = make_recipe(obs, np.ones(obs.n_frames), radius_px=2.25)
    with_map = twin_table(recipe, PhotometrySection(), seed=3, twin=1)
    builtin = twin_table(plain, PhotometrySection(), seed=3, twin=1)
    assert not np.array_equal(np.asarray(with_map["flux"]), np.asarray(builtin["flux"]))
    write_recipe(recipe, {"flux_aperture_e": recipe.flux_aperture_e, "x_ref_px": recipe.x_ref_px,
                          "y_ref_px": recipe.y_ref_px, "motion_peak_px": 0.0,
                          "gain": {"powers": [list(p) for p in gain.powers],
                                   "coeffs": list(gain.coeffs), "box": None}},
                 tmp_path / "r.npz", tmp_path / "r.json")
    again, _ = read_recipe(str(small_table), tmp_path / "r.npz", tmp_path / "r.json")
    assert isinstance(again.gain, GainPolynomial) and again.gain.coeffs == gain.coeffs
    assert np.array_equal(np.asarray(twin_table(again, PhotometrySection(), seed=3, twin=1)["flux"]),
                          np.asarray(with_map["flux"]))


@pytest.mark.shared_data
def test_twins_of_real_epoch1_take_the_map_of_its_date(real_epoch1_table, shared_irac):
    from eclipsebench.trust.recipe import twin_gain

    obs = observation_from_table(read_table(real_epoch1_table))
    gain, text, info = twin_gain(obs, str(shared_irac))    # pmap_ch2 (120124), pmap_ch2_120827
    assert "120827" in text and "120827" in info["path"] and gain is not None
    none, default_text, _ = twin_gain(obs, None)
    assert none is None and "simulator's gain model" in default_text


def test_the_real_residuals_are_flagged_redder_than_the_twins_only_above_95_percent():
    from eclipsebench.trust.score import red_noise_check

    twins = [0.80 + 0.01 * i for i in range(20)] + [float("nan")]   # 0.80 ... 0.99
    above_19 = red_noise_check(0.995, twins)                          # above all 20
    assert above_19["beta_red_twins_below"] == 1.0 and above_19["redder_than_twins"]
    at_95 = red_noise_check(0.985, twins)                             # above 19 of 20
    assert at_95["beta_red_twins_below"] == pytest.approx(0.95) and at_95["redder_than_twins"]
    inside = red_noise_check(0.975, twins)                            # above 18 of 20
    assert inside["beta_red_twins_below"] == pytest.approx(0.90)
    assert not inside["redder_than_twins"]
    assert inside["beta_red_twins_median"] == pytest.approx(0.895)
    unknown = red_noise_check(float("nan"), twins)
    assert np.isnan(unknown["beta_red_twins_below"]) and not unknown["redder_than_twins"]


def test_the_paired_test_finds_near_equals_at_its_stated_rate_and_a_worse_method_most_times():
    from eclipsebench.trust.score import DISTINGUISHABLE_AT, mse_excess_sigma

    rng = np.random.default_rng(11)
    n_twins, trials = 30, 2000
    equal, worse = [], []
    for _ in range(trials):
        shared = rng.normal(0.0, 100.0, n_twins)       # the track's errors all methods share
        a = shared + rng.normal(0.0, 40.0, n_twins)
        b = shared + rng.normal(0.0, 40.0, n_twins)     # same law as a
        c = 1.5 * shared + rng.normal(0.0, 40.0, n_twins)
        ref = dict(enumerate(a))
        equal.append(mse_excess_sigma(dict(enumerate(b)), ref) >= DISTINGUISHABLE_AT)
        worse.append(mse_excess_sigma(dict(enumerate(c)), ref) >= DISTINGUISHABLE_AT)
    # one-sided 2-sigma: 2.3 % for a Gaussian mean; the squared differences are skewed
    assert 0.005 < np.mean(equal) < 0.05
    assert np.mean(worse) > 0.9
    assert np.isnan(mse_excess_sigma({1: 5.0, 2: 6.0}, {1: 5.0, 2: 6.0, 3: 1.0}))  # 2 common
    assert mse_excess_sigma({1: 1.0, 2: 2.0, 3: 3.0}, {1: 1.0, 2: 2.0, 3: 3.0}) == 0.0
