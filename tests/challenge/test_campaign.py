"""``eclipsebench campaign`` (issue 38, item 1): the same depths and Table 3 statistics as
``run`` on a run's photometry tables, resume, 1 vs 2 workers, bad input, real K2-141b."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.challenge.campaign import (
    combined_depth,
    epochs_from_inputs,
    read_campaign_file,
    run_campaign,
)
from eclipsebench.challenge.runner import Layout, run_challenge
from eclipsebench.cli import main
from eclipsebench.config import load_config
from eclipsebench.photometry.table import read_photometry, write_photometry

from ..conftest import (
    SMALL_OBSERVATION_LEAD_D,
    SMALL_OBSERVATION_SETS,
    page_built_in_an_svg_process,
    simulate_eclipse_epoch,
)

# The tiny challenge of tests/challenge/test_runner.py, least squares, one profile.
TINY = ["challenge.epochs=2", "observation.pre_cubes=1", "observation.frames_per_cube=2",
        "simulation.subsamples=1", "simulation.calibration_frames=2000",
        'run.methods=["pld", "bliss"]', "run.bootstrap=50", "run.report=false",
        "run.empirical_photon_limit=false", 'run.profiles=["controlled"]',
        'reduce.sampler="leastsq"']
# What a campaign reads of the configuration (no simulation, no truth).
CAMPAIGN = ['run.methods=["pld", "bliss"]', "run.bootstrap=50", 'run.profiles=["controlled"]',
            'reduce.sampler="leastsq"']
#: Table 3's columns (no truth): equal to run's, to the bit.
TABLE3 = ("N", "D_mean", "sigma_mean", "SD", "sigma_orig", "f_dis", "f_dis_raw", "f_dis_lo",
          "f_dis_hi", "sigma_tot", "R", "R_lo", "R_hi", "mean_ppm", "chi2", "closest_match",
          "closest_match_mean_ppm", "closest_match_sd_ppm")


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """A tiny run, then a campaign over its photometry tables only (one worker)."""
    run_root = tmp_path_factory.mktemp("run")
    summary, _ = run_challenge(load_config(None, TINY), run_root, workers=1)
    tables = [str(Layout(run_root).photometry(e)) for e in (1, 2)]
    camp_root = tmp_path_factory.mktemp("campaign") / "c"
    camp, report = run_campaign(load_config(None, CAMPAIGN), camp_root,
                                epochs_from_inputs(tables), workers=1)
    return run_root, summary, tables, camp_root, camp, report


def test_a_campaign_gives_run_s_depths_and_table3_statistics(tiny):
    run_root, summary, _, camp_root, camp, report = tiny
    assert {k.split("/")[0] for k in report.ran} == {"photometry", "reduce", "joint", "stats",
                                                     "report"}
    ran = Table.read(Layout(run_root).depths, format="ascii.ecsv")
    got = Table.read(Layout(camp_root).depths, format="ascii.ecsv")
    assert [(r["method"], r["epoch"], r["depth_ppm"], r["error_ppm"]) for r in ran] == \
        [(r["method"], r["epoch"], r["depth_ppm"], r["error_ppm"]) for r in got]
    group = camp["profiles"]["controlled"]["channels"]["ch2"]
    for m in ("pld", "bliss"):
        for key in TABLE3:
            assert group["methods"][m][key] == summary["methods"][m][key], (m, key)
        # r: the photon limit at the mean measured depth (run's is at the true depth)
        s = group["methods"][m]
        assert s["r"] == pytest.approx(group["photon_limit"]["sigma_phot_ppm"] / s["SD"])
        assert s["bias"] is None and s["RMSE"] is None    # no truth in a campaign
    assert group["ttest"] == summary["ttest"] and group["anova"] == summary["anova"]
    for m in ("pld", "bliss"):
        joint = camp["joint"]["ch2"][m]
        assert joint["epochs"] == [1, 2] and np.isfinite(joint["depth_ppm"])
        assert joint["depth_err_ppm"] > 0
    combined = group["combined"]
    d = [group["methods"][m]["D_mean"] for m in ("pld", "bliss")]
    assert combined["depth_ppm"] == pytest.approx(np.mean(d))
    assert combined["sigma_sys_ppm"] == pytest.approx(np.std(d, ddof=1))
    assert (camp_root / "tables" / "table3_controlled_ch2.tex").is_file()
    assert all("none" in e["time_conversion"] for e in camp["epochs"])


def test_the_report_shows_the_real_data_figures_and_every_epoch_s_light_curves(tiny):
    """Issue 38's report: ``DIR/report/index.html`` names every figure it drew, each file
    exists, and the paper's real-data figures and each epoch's light curves are there."""
    import re

    camp_root = tiny[3]
    index = camp_root / "report" / "index.html"
    page = index.read_text()
    shown = re.findall(r'<img src="([^"]+)"', page)
    assert shown and all((index.parent / s).is_file() for s in shown)
    drawn = {p.relative_to(index.parent).as_posix()
             for p in index.parent.rglob("*.png")}
    assert set(shown) == drawn                      # every figure drawn is on the page
    for name in ("controlled_ch2/depths.png", "controlled_ch2/visit_differences.png",
                 "controlled_ch2/method_differences.png",
                 "controlled_ch2/repeatability_reliability.png",
                 "lightcurves/lightcurves_epoch_01.png", "lightcurves/lightcurves_epoch_02.png"):
        assert name in shown, name
    assert "Eclipse depth statistics, ch2, controlled profile" in page
    assert "Joint fits" in page and "Combined over methods" in page


def test_building_the_report_leaves_matplotlib_s_backend_alone(tiny, tmp_path):
    """In a fresh process whose backend is svg: the page is written (with a trust table, the
    recommended method highlighted), the backend is still svg and pyplot never imported."""
    page = page_built_in_an_svg_process(f"""
import json
import numpy as np
from eclipsebench.report.campaign import build_campaign_report
summary = json.loads(open({str(tiny[3] / "summary.json")!r}).read())
x = np.linspace(-2.0, 2.0, 50)
curve = {{"hours": x, "flux_corrected": 1 + 0 * x, "astro_model": 1 + 0 * x}}
trust = {{1: ({{"n_twins": 10, "recommended": "pld",
               "methods": {{"pld": {{"depth_ppm": 1900.0, "honest_err_ppm": 80.0}}}}}}, None)}}
page = build_campaign_report({str(tmp_path / "report")!r}, summary=summary,
                             lightcurves={{1: {{"pld": curve}}}}, trust=trust)
""")
    text = Path(page).read_text()
    assert "Epoch 1: 10 twins" in text and "pld (recommended)" in text
    assert '<tr class="chosen">' in text


def test_a_campaign_file_of_aor_folders_measures_them_as_run_does(tiny, tmp_path):
    """Each epoch's Pre and Main AOR folders, named in a campaign file: the photometry of
    the run, the time conversion named."""
    run_root = tiny[0]
    aors = sorted(p.name for p in (run_root / "simulation").glob("r*") if p.is_dir())
    assert len(aors) == 4
    sim = run_root / "simulation"
    (tmp_path / "campaign.toml").write_text(
        "".join(f'[[epoch]]\ninputs = ["{sim / a}", "{sim / b}"]\n\n'
                for a, b in (aors[:2], aors[2:])))
    cfg = load_config(None, ['run.methods=["pld"]', "run.bootstrap=50",
                             'run.profiles=["controlled"]', 'reduce.sampler="leastsq"'])
    summary, _ = run_campaign(cfg, tmp_path / "c",
                              read_campaign_file(tmp_path / "campaign.toml"), workers=1)
    for e in (1, 2):
        ours = read_photometry(Layout(tmp_path / "c").photometry(e))
        theirs = read_photometry(Layout(run_root).photometry(e))
        for col in ("time_bmjd", "flux", "x", "y", "background"):
            assert np.array_equal(np.asarray(ours[col]), np.asarray(theirs[col])), (e, col)
    assert all(e["time_conversion"].startswith("BCD headers") for e in summary["epochs"])
    assert summary["planet"] == "XO-3b" and summary["epochs"][0]["kind"] == "bcd"
    assert len(summary["profiles"]["controlled"]["channels"]["ch2"]["depths"]) == 2


def test_combined_depth_adds_the_methods_spread():
    per = {"a": {"D_mean": 100.0, "sigma_tot": 30.0}, "b": {"D_mean": 140.0, "sigma_tot": 40.0}}
    c = combined_depth(per)
    assert c["depth_ppm"] == 120.0 and c["sigma_stat_ppm"] == 35.0
    assert c["sigma_sys_ppm"] == pytest.approx(40.0 / 2**0.5)
    assert c["error_ppm"] == pytest.approx((35.0**2 + 800.0) ** 0.5)
    assert combined_depth({"a": per["a"]}) is None


def test_an_interrupted_campaign_resumes_to_the_same_bytes(tiny, tmp_path):
    """A result lost, another's light curve lost (the one resume rule,
    :func:`eclipsebench.fit.result.result_ok`) and a joint fit cut short: only they (and
    what is made from them: the stats, the two epochs' light-curve figures and the report)
    are redone."""
    _, _, tables, camp_root, _, _ = tiny
    root = tmp_path / "c"
    shutil.copytree(camp_root, root)
    (root / "results" / "pld" / "epoch_02.json").unlink()
    (root / "results" / "bliss" / "epoch_01.lc.ecsv").unlink()
    joint = root / "joint" / "bliss_ch2.json"
    joint.write_text(joint.read_text()[:40])
    _, report = run_campaign(load_config(None, CAMPAIGN), root, epochs_from_inputs(tables),
                             workers=1)
    # BLISS's joint fit starts from its reductions (redone with them); PLD's does not
    # (its bin size is a maximum-likelihood setting, fit.joint.start_of)
    assert sorted(report.ran) == ["joint/bliss_ch2", "reduce/bliss/epoch_01",
                                  "reduce/pld/epoch_02", "report",
                                  "report/lightcurves/epoch_01",
                                  "report/lightcurves/epoch_02", "stats"]
    assert (root / "results" / "bliss" / "epoch_01.lc.ecsv").is_file()
    assert (root / "summary.json").read_bytes() == (camp_root / "summary.json").read_bytes()


def test_the_joint_fits_start_from_the_reductions_and_answer_as_if_fitted_alone(
        tiny, tmp_path, monkeypatch):
    """Each joint task waits for its method's reductions and is given them, so no epoch is
    fitted alone twice (issue 38's speed); its answer is the bytes of the joint fit that
    fits every epoch alone itself (``result_paths=None``)."""
    from dataclasses import replace

    from eclipsebench.challenge.campaign import (
        _channels,
        build_campaign_tasks,
        campaign_planet,
    )
    from eclipsebench.fit import joint as fit_joint

    _, _, tables, camp_root, _, _ = tiny
    epochs = epochs_from_inputs(tables)
    cfg = load_config(None, CAMPAIGN)
    system = campaign_planet(epochs, cfg.system)
    cfg = replace(cfg, system=replace(cfg.system, name=system.name))
    tasks = build_campaign_tasks(cfg, camp_root, epochs, system, _channels(epochs))
    joints = {t.key: t for t in tasks if t.stage == "joint"}
    assert sorted(joints) == ["joint/bliss_ch2", "joint/pld_ch2"]
    calls: list[int] = []
    real = fit_joint.fit_leastsq
    monkeypatch.setattr(fit_joint, "fit_leastsq", lambda *a, **k: calls.append(1) or real(*a, **k))
    for key, task in joints.items():
        m = key.split("/")[1].removesuffix("_ch2")
        *args, out, starts = task.args
        if m == "pld":   # its bin size is set by maximum likelihood: not started, not waiting
            assert starts is None and not any(d.startswith("reduce/") for d in task.deps)
            continue
        assert {f"reduce/{m}/epoch_01", f"reduce/{m}/epoch_02"} <= set(task.deps)
        assert starts == [str(camp_root / "results" / m / f"epoch_{e:02d}.json")
                          for e in (1, 2)]
        calls.clear()
        seeded = tmp_path / f"{m}_seeded.json"
        task.func(*args, str(seeded), starts)
        assert calls == [] and seeded.read_bytes() == Path(out).read_bytes(), m
        alone = tmp_path / f"{m}.json"
        task.func(*args, str(alone), None)
        assert calls == [1, 1]      # each epoch fitted alone
        assert alone.read_bytes() == Path(out).read_bytes(), m


def test_a_campaign_stopped_by_ctrl_c_resumes_where_it_stopped(tiny, tmp_path, monkeypatch):
    """Ctrl-C at BLISS's joint fit (the last task before the statistics: it waits for the
    reductions, PLD's joint fit, which waits for none, runs before them): the rerun does only
    that joint fit, the light-curve figure not drawn before it (epoch 2's: in one process
    the tasks run in the plan's dependency order), the statistics and the report."""
    import eclipsebench.challenge.campaign as campaign

    _, _, tables, camp_root, _, _ = tiny
    real = campaign.joint_task

    def interrupted(*args, **kwargs):
        if args[3] == "bliss":
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(campaign, "joint_task", interrupted)
    root = tmp_path / "c"
    with pytest.raises(KeyboardInterrupt):
        run_campaign(load_config(None, CAMPAIGN), root, epochs_from_inputs(tables), workers=1)
    assert not (root / "summary.json").exists() and not (root / "run.lock").exists()
    monkeypatch.setattr(campaign, "joint_task", real)
    _, report = run_campaign(load_config(None, CAMPAIGN), root, epochs_from_inputs(tables),
                             workers=1)
    assert sorted(report.ran) == ["joint/bliss_ch2", "report", "report/lightcurves/epoch_02",
                                  "stats"]
    assert (root / "summary.json").read_bytes() == (camp_root / "summary.json").read_bytes()


#: Two small simulated eclipses (tests/trust's observation), a day apart in their lead.
TWIN_SETS = SMALL_OBSERVATION_SETS


def test_twins_give_table3_with_the_honest_errors_beside_the_reported(tmp_path, capsys,
                                                                       small_observation_table):
    """``--twins 10``: each epoch's trust run, and Table 3 again with its honest errors."""
    # the first epoch is tests/trust's observation, made once per test run (tests/conftest.py)
    assert SMALL_OBSERVATION_LEAD_D == 0.12
    tables = [str(small_observation_table),
              str(simulate_eclipse_epoch(tmp_path / "e2", TWIN_SETS, 0.10))]
    capsys.readouterr()   # what simulate and photometry printed
    out = tmp_path / "c"
    code = main(["campaign", *tables, "--out", str(out), "--methods", "poly2", "--profiles",
                 "controlled", "--sampler", "leastsq", "--twins", "10", "--workers", "1",
                 "--set", "run.bootstrap=50", "--json", "--quiet"])
    assert code == 0, capsys.readouterr().err
    summary = json.loads(capsys.readouterr().out)
    group = summary["profiles"]["controlled"]["channels"]["ch2"]
    honest = group["honest"]
    for e in (1, 2):
        trust = json.loads((out / "twins" / f"epoch_{e:02d}" / "trust.json").read_text())
        assert trust["n_twins"] == 10
        assert summary["twins"][str(e)]["methods"]["poly2"]["honest_err_ppm"] == \
            trust["methods"]["poly2"]["honest_err_ppm"]
    reported = {d["epoch"]: d for d in group["depths"]}
    for d in honest["depths"]:
        assert d["depth_ppm"] == reported[d["epoch"]]["depth_ppm"]
        assert d["error_ppm"] == summary["twins"][str(d["epoch"])]["methods"]["poly2"][
            "honest_err_ppm"]
    w = 1 / np.array([d["error_ppm"] for d in honest["depths"]]) ** 2
    mean = np.sum(w * [d["depth_ppm"] for d in honest["depths"]]) / np.sum(w)
    assert honest["methods"]["poly2"]["D_mean"] == pytest.approx(mean)
    assert (out / "tables" / "table3_controlled_ch2_honest.tex").is_file()


def test_two_workers_give_the_same_bytes(tiny, tmp_path):
    _, _, tables, camp_root, _, _ = tiny
    _, report = run_campaign(load_config(None, CAMPAIGN), tmp_path / "c2",
                             epochs_from_inputs(tables), workers=2)
    assert report.executor.startswith("dask")
    for name in ("summary.json", "depths.ecsv", "joint/pld_ch2.json", "joint/bliss_ch2.json",
                 "report/index.html"):
        assert (tmp_path / "c2" / name).read_bytes() == (camp_root / name).read_bytes(), name


def test_the_command_names_the_report(tiny, tmp_path, capsys):
    """A finished campaign rerun from the command line: nothing to do, the report named."""
    _, _, tables, camp_root, _, _ = tiny
    root = tmp_path / "c"
    shutil.copytree(camp_root, root)
    code = main(["campaign", *tables, "--out", str(root), "--methods", "pld,bliss",
                 "--profiles", "controlled", "--sampler", "leastsq", "--quiet", "--workers", "1",
                 "--set", "run.bootstrap=50"])
    out = capsys.readouterr().out
    assert code == 0 and f"report in {root / 'report' / 'index.html'}" in out, out


def test_another_campaign_into_the_folder_is_refused(tiny, capsys):
    _, _, tables, camp_root, _, _ = tiny
    code = main(["campaign", tables[1], tables[0], "--out", str(camp_root), "--methods",
                 "pld,bliss", "--profiles", "controlled", "--sampler", "leastsq", "--quiet",
                 "--set", "run.bootstrap=50"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert "use another --out" in err


def test_a_table_replaced_at_the_same_path_is_refused(tiny, tmp_path, capsys):
    """A rerun never reuses results made from other inputs: a table rewritten in place
    (same path, other bytes) is refused in one line naming it, nothing redone."""
    tables = [str(shutil.copy(t, tmp_path / f"t{i}.fits")) for i, t in enumerate(tiny[2])]
    argv = ["campaign", *tables, "--out", str(tmp_path / "c"), "--methods", "pld",
            "--profiles", "controlled", "--sampler", "leastsq", "--set", "run.bootstrap=50",
            "--set", "run.report=false", "--workers", "1", "--quiet"]
    assert main(argv) == 0
    summary = (tmp_path / "c" / "summary.json").read_bytes()
    table = read_photometry(tables[0])
    table["flux"] *= 1.001
    write_photometry(table, tables[0])
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and tables[0] in err[0], err
    assert (tmp_path / "c" / "summary.json").read_bytes() == summary


def test_a_table_is_standardised_once_per_process_and_again_when_its_bytes_change(
        tmp_path, monkeypatch):
    """The campaign's check and its photometry task read a table once between them (in one
    process), and a copy: a caller's change never reaches the next; other bytes, another
    table."""
    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.challenge import campaign as camp

    path = tmp_path / "lc.csv"
    t = 57000.0 + np.arange(200) * 2e-4
    columns = {"time_bmjd": t, "flux": np.full(200, 1.0e5), "flux_err": np.full(200, 100.0),
               "x": np.full(200, 15.0), "y": np.full(200, 15.0)}
    Table(columns).write(path, format="ascii.csv")
    made = []
    standardise = camp._standard_table
    monkeypatch.setattr(camp, "_standard_table", lambda *a: made.append(a) or standardise(*a))
    monkeypatch.setattr(camp, "_KEPT_TABLES", {})
    epoch = camp.epochs_from_inputs([path])[0]
    system = get_system("XO-3b")
    first = camp.standard_table(epoch, system)
    first["flux"][0] = -1.0
    second = camp.standard_table(epoch, system)
    assert len(made) == 1
    fresh = standardise(epoch, system, None)
    assert second.colnames == fresh.colnames and second.meta == fresh.meta
    assert all(np.array_equal(second[c], fresh[c]) for c in fresh.colnames)
    Table({**columns, "flux": np.full(200, 2.0e5)}).write(path, format="ascii.csv",
                                                         overwrite=True)
    third = camp.standard_table(epoch, system)
    assert len(made) == 2 and np.all(np.asarray(third["flux"]) == 2.0e5)
    monkeypatch.setattr(camp, "_KEPT_TABLES", {})
    monkeypatch.setattr(camp, "KEPT_TABLE_BYTES", 0)   # too large to keep: made each time
    camp.standard_table(epoch, system)
    camp.standard_table(epoch, system)
    assert len(made) == 4


def _refused(capsys, tmp_path, *argv):
    out = tmp_path / "out"
    code = main(["campaign", *argv, "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert not out.exists()
    return err


def test_an_input_that_is_neither_folder_bcd_nor_table_exits_2(tiny, tmp_path, capsys):
    notes = tmp_path / "notes.txt"
    notes.write_text("hello\n")
    err = _refused(capsys, tmp_path, tiny[2][0], str(notes))
    assert str(notes) in err and "neither an AOR folder" in err
    empty = tmp_path / "empty"
    empty.mkdir()
    assert "neither an AOR folder" in _refused(capsys, tmp_path, tiny[2][0], str(empty))


def test_epochs_of_two_planets_exit_2(tiny, tmp_path, capsys):
    other = read_photometry(tiny[2][1])
    other.meta["SYSTEM"] = "HD 189733b"
    path = tmp_path / "hd189733.fits"
    write_photometry(other, path)
    err = _refused(capsys, tmp_path, tiny[2][0], str(path))
    assert "HD 189733b" in err and "XO-3b" in err and "one planet" in err


def test_a_table_whose_time_scale_cannot_be_told_exits_2(tiny, tmp_path, capsys):
    paths = []
    for k, src in enumerate(tiny[2], start=1):
        t = read_photometry(src)
        csv = Table({"jd": np.asarray(t["time_bmjd"]) + 2400000.5, "flux": t["flux"],
                     "flux_err": t["flux_err"], "x": t["x"], "y": t["y"]})
        paths.append(tmp_path / f"visit{k}.csv")
        csv.write(paths[-1], format="ascii.csv")
    err = _refused(capsys, tmp_path, *map(str, paths), "--time-column", "jd", "--time-format",
                   "jd", "--observer", "geocentre", "--system", "XO-3b")
    assert "--time-scale" in err and "scale" in err


# ------------------------------------------------------------------ real data: K2-141b
#: K2-141b as a user catalogue row (it is not in the built-in catalogue): Malavolta et al.
#: 2018 (AJ 155, 107); P, T0 and i as PyORBIT's documentation quotes them from that paper;
#: a/R* and Rp/R* derived from a = 0.00716 au, Rp = 1.51 R_earth, R* = 0.681 R_sun
#: (docs/campaign.md).
K2_141 = """["K2-141b"]
period_days = 0.2803244
t_transit_bjd = 2457744.07160
ecc = 0.0
omega_deg = 90.0
inc_deg = 86.3
a_rs = 2.261
rp_rs = 0.02033
teff_star_k = 4599.0
r_star_rsun = 0.681
ra_deg = 350.91654
dec_deg = -1.18928
"""


@pytest.mark.shared_data
def test_the_real_k2_141b_campaign_runs_end_to_end(shared_irac, tmp_path, capsys):
    """Three visits of another pipeline's CSVs as they are (JD_UTC at frame end)."""
    catalogue = tmp_path / "k2141.toml"
    catalogue.write_text(K2_141)
    folder = shared_irac / "real_k2141_ch2_csv"
    csvs = sorted(str(p) for p in folder.glob("k2141_ch2_*.csv"))
    assert len(csvs) == 3
    out = tmp_path / "k2141"
    code = main(["campaign", *csvs, "--out", str(out), "--catalogue", str(catalogue),
                 "--system", "K2-141b", "--event", "phase-curve", "--sampler", "leastsq",
                 "--methods", "poly2", "--profiles", "controlled", "--channel", "2",
                 "--columns", "flux=raw_flux,flux_err=err,x=xcent,y=ycent",
                 "--time-column", "time", "--time-format", "jd", "--time-scale", "utc",
                 "--time-at", "end", "--observer", "geocentre", "--workers", "1", "--json",
                 "--quiet"])
    assert code == 0, capsys.readouterr().err
    summary = json.loads(capsys.readouterr().out)
    assert summary["planet"] == "K2-141b" and summary["event"] == "phase-curve"
    for e in summary["epochs"]:
        assert e["time_conversion"].startswith("time: JD_UTC at frame end")
    group = summary["profiles"]["controlled"]["channels"]["ch2"]
    assert [d["epoch"] for d in group["depths"]] == [1, 2, 3]
    assert all(np.isfinite(d["depth_ppm"]) and d["error_ppm"] > 0 for d in group["depths"])
    for d in group["depths"]:
        res = json.loads((out / "results" / "poly2" / f"epoch_{d['epoch']:02d}.json").read_text())
        assert res["time_conversion"].startswith("time: JD_UTC at frame end")
    joint = summary["joint"]["ch2"]["poly2"]
    assert joint["epochs"] == [1, 2, 3] and joint["depth_err_ppm"] > 0
    assert joint["n_points"] == sum(len(Table.read(p, format="ascii.csv")) for p in csvs)


@pytest.mark.shared_data
@pytest.mark.timeout(1800)
def test_real_epoch1_beside_two_simulated_epochs_with_twins(shared_irac, tmp_path, capsys):
    """Issue 38: real epoch 1 from its AOR folders (Pre and Main) and two simulated epochs,
    ``--twins 10``: Table 3 with the reported and the honest errors, and the report with
    the real-data figures."""
    # simulated as the catalogue's XO-3b (not the 2015 challenge's variant): one planet
    sets = TWIN_SETS + ['system.name="XO-3b"']
    tables = [simulate_eclipse_epoch(tmp_path / f"e{k}", sets, lead)
              for k, lead in ((2, 0.12), (3, 0.10))]
    real = shared_irac / "real_xo3_eclipse1"
    aors = sorted(str(p) for p in real.iterdir() if p.name.startswith("r"))
    assert len(aors) == 2
    spec = tmp_path / "campaign.toml"
    spec.write_text("[[epoch]]\ninputs = " + json.dumps(aors) + "\nchannel = 2\n"
                    + "".join(f"\n[[epoch]]\ninputs = [{json.dumps(str(t))}]\n" for t in tables))
    capsys.readouterr()
    out = tmp_path / "c"
    code = main(["campaign", "--file", str(spec), "--out", str(out), "--system", "XO-3b",
                 "--methods", "poly2", "--profiles", "controlled", "--sampler", "leastsq",
                 "--twins", "10", "--workers", "1", "--set", "run.bootstrap=50", "--json",
                 "--quiet"])
    assert code == 0, capsys.readouterr().err
    summary = json.loads(capsys.readouterr().out)
    group = next(iter(summary["profiles"]["controlled"]["channels"].values()))
    assert [d["epoch"] for d in group["depths"]] == [1, 2, 3]
    assert {"D_mean", "f_dis", "sigma_tot", "R"} <= set(group["methods"]["poly2"])
    honest = group["honest"]
    for d in honest["depths"]:
        answer = json.loads((out / "twins" / f"epoch_{d['epoch']:02d}" / "trust.json")
                            .read_text())
        assert answer["n_twins"] == 10
        assert d["error_ppm"] == answer["methods"]["poly2"]["honest_err_ppm"]
    w = 1 / np.array([d["error_ppm"] for d in honest["depths"]]) ** 2
    assert honest["methods"]["poly2"]["D_mean"] == pytest.approx(
        np.sum(w * [d["depth_ppm"] for d in honest["depths"]]) / np.sum(w))
    # the real epoch's photometry came from its BCDs, with its own time conversion named
    assert summary["epochs"][0]["time_conversion"].startswith("BCD headers")
    page = (out / "report" / "index.html").read_text()
    assert "honest" in page.lower() and page.count("<img") >= 4
    for src in __import__("re").findall(r"src='([^']+)'|src=\"([^\"]+)\"", page):
        name = next(s for s in src if s)
        assert (out / "report" / name).is_file(), name
