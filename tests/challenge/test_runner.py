"""The challenge runner on a tiny real challenge: every stage, resume, 1 vs 2 workers, CLI."""

from __future__ import annotations

import json
import shutil
import socket
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.challenge.runner import Layout, build_tasks, run_challenge
from eclipsebench.cli import main
from eclipsebench.config import load_config
from eclipsebench.errors import InputError

from ..conftest import TINY_RUN_SETS

# Two epochs of 233 two-frame cubes (the eclipse stays inside the Main AOR), one sub-sample.
TINY = TINY_RUN_SETS


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory, tiny_run_once):
    """The tiny challenge, run once per test run in one process (tests/conftest.py, shared with
    tests/engine/test_cluster.py), copied: these tests change the folder. ``report`` holds
    what that run ran (``report.ran``)."""
    done, summary, ran = tiny_run_once
    root = tmp_path_factory.mktemp("run")
    shutil.copytree(done, root, dirs_exist_ok=True)
    return load_config(None, TINY), root, summary, SimpleNamespace(ran=ran)


def test_every_stage_ran_and_the_summary_is_complete(tiny_run):
    cfg, root, summary, report = tiny_run
    lay = Layout(root)
    stages = {k.split("/")[0] for k in report.ran}
    assert stages == {"simulate", "photometry", "reduce", "reduce_paper", "stats"}
    assert (root / "simulation" / "truth.ecsv").is_file()
    for e in (1, 2):
        assert lay.photometry(e).is_file()
        for m in ("pld", "bliss"):
            res = json.loads(lay.result(m, e).read_text())
            assert res["method"] == m and res["epoch"] == e
            assert lay.result(m, e).with_suffix(".lc.ecsv").is_file()
    depths = Table.read(lay.depths, format="ascii.ecsv")
    assert len(depths) == 4
    assert set(summary["methods"]) == {"pld", "bliss"}
    assert summary["truth_ppm"] == pytest.approx(1875.0)
    assert summary["seed"] == cfg.challenge.seed
    assert summary["sigma_phot_ppm"] == summary["sigma_phot_ppm_analytic"] > 0
    assert "workers" not in summary["config"]["run"]
    pld = summary["methods"]["pld"]
    d = [r["depth_ppm"] for r in depths if r["method"] == "pld"]
    assert pld["SD"] == pytest.approx(abs(d[0] - d[1]) / 2**0.5)
    assert json.loads(lay.summary.read_text()) == summary


def test_both_profiles_are_scored_side_by_side(tiny_run):
    """Issue 15: the paper profile beside the controlled one, each with the same structure."""
    cfg, root, summary, _ = tiny_run
    lay = Layout(root)
    assert cfg.run.profiles == ("controlled", "paper")
    assert set(summary["profiles"]) == {"controlled", "paper"}
    assert summary["profile"] == "controlled"
    assert summary["profiles"]["controlled"]["methods"] == summary["methods"]
    paper = summary["profiles"]["paper"]
    assert set(paper) >= {"methods", "average", "ttest", "anova", "method_names"}
    for e in (1, 2):
        pld = json.loads(lay.result("pld", e, profile="paper").read_text())
        bliss = json.loads(lay.result("bliss", e, profile="paper").read_text())
        assert pld["profile"] == "paper" and pld["phase"] == "quadratic"
        assert pld["depth_err_method"] == "time_averaging"
        assert pld["depth_err_ppm"] == pytest.approx(pld["depth_err_time_averaging_ppm"])
        assert bliss["sampler"] == "mcmc" and bliss["depth_err_method"] == "mcmc"
        assert len(bliss["profile_detail"]["bic"]) == 8  # 4 phases x 2 ramps, least BIC kept
        best = min(bliss["profile_detail"]["bic"], key=bliss["profile_detail"]["bic"].get)
        assert best == f"{bliss['phase']}/{bliss['ramp']}"
        ctrl = json.loads(lay.result("pld", e).read_text())
        assert ctrl["profile"] == "controlled"
    paper_depths = Table.read(lay.depths_of("paper"), format="ascii.ecsv")
    assert len(paper_depths) == 4
    assert paper["methods"]["pld"]["D_mean"] != summary["methods"]["pld"]["D_mean"]


def test_resume_redoes_only_what_is_missing(tiny_run):
    cfg, root, summary, _ = tiny_run
    lay = Layout(root)
    before = lay.summary.read_bytes()
    lay.result("bliss", 2).unlink()
    lay.summary.unlink()
    again, report = run_challenge(cfg, root, workers=1)
    assert sorted(report.ran) == ["reduce/bliss/epoch_02", "stats"]
    assert lay.summary.read_bytes() == before
    timings = Table.read(lay.timings, format="ascii.ecsv")  # what this invocation ran
    assert sorted(timings["key"]) == sorted(report.ran)
    assert list(timings["stage"]) == [k.split("/")[0] for k in timings["key"]]
    assert np.all(np.diff(timings["start_s"]) >= 0) and np.all(timings["seconds"] >= 0)


def test_two_workers_give_the_same_summary(tiny_run, tmp_path):
    cfg, root, summary, _ = tiny_run
    # same simulation and photometry; every reduction and the statistics redone on 2 workers
    shutil.copytree(root / "simulation", tmp_path / "simulation")
    shutil.copytree(root / "photometry", tmp_path / "photometry")
    shutil.copy(root / "run_config.toml", tmp_path / "run_config.toml")
    _, report = run_challenge(cfg, tmp_path, workers=2)
    assert "LocalCluster (2 processes)" in report.executor
    assert sorted(k.split("/")[0] for k in report.ran) == ["reduce"] * 4 + ["reduce_paper"] * 4 + ["stats"]
    assert (tmp_path / "summary.json").read_bytes() == (root / "summary.json").read_bytes()


def test_a_paper_only_run_reports_the_paper_profile(tiny_run, tmp_path):
    """``--profiles paper``: the report reads the paper profile's depths (it once read the
    controlled profile's, which such a run never writes, and failed at the last task)."""
    cfg, root, _, _ = tiny_run
    for folder in ("simulation", "photometry"):
        shutil.copytree(root / folder, tmp_path / folder)
    paper = load_config(None, [*TINY, 'run.profiles=["paper"]', "run.report=true"])
    summary, report = run_challenge(paper, tmp_path, workers=1)
    assert not (tmp_path / "depths.ecsv").exists() and (tmp_path / "depths_paper.ecsv").is_file()
    assert set(summary["profiles"]) == {"paper"}
    assert (tmp_path / "report" / "index.html").is_file() and "report" in report.ran


def test_a_folder_of_another_run_is_refused(tiny_run):
    _, root, _, _ = tiny_run
    other = load_config(None, [*TINY, "challenge.seed=99"])
    with pytest.raises(InputError, match="different configuration"):
        run_challenge(other, root, workers=1)


def test_graph_with_twins_and_report():
    cfg = load_config(None, [*TINY[:-2], "run.photon_limit_method=pld"])
    keys = [t.key for t in build_tasks(cfg, "/nonexistent")]
    assert "simulate/calibration" in keys and "simulate_flat/truth" in keys
    assert "reduce_flat/pld/epoch_02" in keys and "reduce_flat/bliss/epoch_02" not in keys
    assert keys[-4:] == ["stats", "report/figures-results-1", "report/figures-results-2", "report"]
    assert keys.index("report/figures-photometry") < keys.index("reduce/pld/epoch_01")
    # the engine's priority: the twin's chain before the many reductions that end the run
    assert keys.index("reduce_flat/pld/epoch_02") < keys.index("reduce/pld/epoch_01")


def test_cli_json_prints_the_summary(tiny_run, capsys):
    _, root, summary, _ = tiny_run
    args = ["run", "--out", str(root), "--workers", "1", "--json"]
    for item in TINY:
        args += ["--set", item]
    assert main(args) == 0
    assert json.loads(capsys.readouterr().out) == json.loads((root / "summary.json").read_text())


def test_out_that_is_a_file_exits_2(tmp_path, capsys):
    target = tmp_path / "taken"
    target.write_text("not a run folder")
    assert main(["run", "--out", str(target), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "exists and is not a folder" in err
    assert target.read_text() == "not a run folder"


def test_cli_unknown_method_exits_2(tmp_path, capsys):
    assert main(["run", "--out", str(tmp_path), "--methods", "nope"]) == 2
    assert "run.methods" in capsys.readouterr().err


def test_cli_bad_profiles_exit_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:   # argparse's own exit, one usage line
        main(["run", "--out", str(tmp_path), "--profiles", "team"])
    assert stop.value.code == 2 and "--profiles" in capsys.readouterr().err
    assert main(["run", "--out", str(tmp_path), "--set", 'run.profiles=["paper", "paper"]']) == 2
    assert "run.profiles" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_a_transit_run_is_refused_before_any_work(tmp_path, capsys):
    assert main(["run", "--out", str(tmp_path / "r"), "--set", 'observation.event="transit"']) == 2
    assert "observation.event" in capsys.readouterr().err and not (tmp_path / "r").exists()


def test_a_method_refusing_an_epoch_is_recorded_not_fatal(tiny_run, tmp_path, monkeypatch):
    cfg, root, _, _ = tiny_run
    for name in ("simulation", "photometry", "results", "results_paper"):
        shutil.copytree(root / name, tmp_path / name)
    shutil.copy(root / "run_config.toml", tmp_path / "run_config.toml")
    lay = Layout(tmp_path)
    lay.result("bliss", 2).unlink()

    import eclipsebench.fit.reduce as fit_reduce

    def refuse(*args, **kwargs):
        raise InputError("--pmap cal.fits: 7 frames lie outside the calibration data")

    monkeypatch.setattr(fit_reduce, "reduce_epoch", refuse)
    summary, report = run_challenge(cfg, tmp_path, workers=1)
    assert sorted(report.ran) == ["reduce/bliss/epoch_02", "stats"]
    assert json.loads(lay.result("bliss", 2).read_text())["failed"] is True
    assert summary["failures"] == [{"method": "bliss", "epoch": 2, "error":
                                    "--pmap cal.fits: 7 frames lie outside the calibration data"}]
    assert summary["methods_excluded"] == ["bliss"] and list(summary["methods"]) == ["pld"]
    assert len(Table.read(lay.depths, format="ascii.ecsv")) == 3


def _copy_run(root, dest):
    shutil.copytree(root, dest, dirs_exist_ok=True)
    (dest / "run.lock").unlink(missing_ok=True)
    return Layout(dest)


def _cli(root, *extra):
    args = ["run", "--out", str(root), "--workers", "1", "--quiet", *extra]
    for item in TINY:
        args += ["--set", item]
    return args


def test_a_truncated_result_is_redone_and_the_summary_is_the_same(tiny_run, tmp_path):
    """Issue 18: resume trusted a truncated result (then failed on it with exit 1)."""
    cfg, root, _, _ = tiny_run
    lay = _copy_run(root, tmp_path / "run")
    text = lay.result("pld", 1).read_text()
    lay.result("pld", 1).write_text(text[: len(text) // 2])
    lay.summary.unlink()
    lay.depths.unlink()
    _, report = run_challenge(cfg, lay.root, workers=1)
    assert sorted(report.ran) == ["reduce/pld/epoch_01", "stats"]
    assert lay.result("pld", 1).read_text() == text
    assert lay.summary.read_bytes() == (root / "summary.json").read_bytes()


def test_a_result_edited_or_made_from_other_inputs_is_redone(tiny_run, tmp_path):
    cfg, root, _, _ = tiny_run
    lay = _copy_run(root, tmp_path / "run")
    # valid JSON of the right schema, but not the bytes the task wrote: not trusted
    res = json.loads(lay.result("bliss", 2).read_text())
    lay.result("bliss", 2).write_text(json.dumps({**res, "depth_ppm": 1.0}))
    # a photometry table lost: redone, and every result made from it with it
    lay.photometry(1).unlink()
    _, report = run_challenge(cfg, lay.root, workers=1)
    assert sorted(report.ran) == ["photometry/epoch_01", "reduce/bliss/epoch_01",
                                  "reduce/bliss/epoch_02", "reduce/pld/epoch_01",
                                  "reduce_paper/bliss/epoch_01", "reduce_paper/pld/epoch_01",
                                  "stats"]
    assert lay.summary.read_bytes() == (root / "summary.json").read_bytes()


def test_a_second_run_in_the_same_folder_exits_2_naming_the_lock(tiny_run, tmp_path, capsys):
    _, root, _, _ = tiny_run
    lay = _copy_run(root, tmp_path / "run")
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        lay.lock.write_text(f"{holder.pid} {socket.gethostname()}\n")
        assert main(_cli(lay.root)) == 2
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
        assert str(lay.lock) in err and str(holder.pid) in err
        assert lay.lock.read_text().split()[0] == str(holder.pid)  # not taken from its owner
    finally:
        holder.kill()
        holder.wait()
    # the holder is gone: its lock is stale and taken over; released at the end
    assert main(_cli(lay.root)) == 0
    assert not lay.lock.exists()


def test_without_a_report_none_is_announced(tiny_run, capsys):
    _, root, _, _ = tiny_run
    assert main(_cli(root)) == 0
    out = capsys.readouterr().out
    assert f"summary in {root / 'summary.json'}" in out
    assert "report in" not in out and "index.html" not in out


@pytest.mark.parametrize("option", [["--set", "challenge.epochs=1"], ["--epochs", "1"]])
def test_one_epoch_is_refused_before_any_work(tmp_path, capsys, option):
    out = tmp_path / "one"
    assert main(["run", "--out", str(out), "--quiet", *option]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "challenge.epochs" in err and "at least 2 epochs" in err
    assert not out.exists()


def _listing(root):
    return {str(p.relative_to(root)): p.stat().st_mtime_ns for p in sorted(root.rglob("*"))}


def test_trust_into_a_run_folder_is_refused_before_any_write(tiny_run, capsys):
    """Issue 37: trust --out into a finished run folder overwrote its report."""
    _, root, _, _ = tiny_run
    before = _listing(root)
    table = root / "photometry" / "epoch_01.fits"
    assert main(["trust", str(table), "--out", str(root), "--methods", "pld", "--twins", "10",
                 "--sampler", "leastsq", "--workers", "1", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'eclipsebench run'" in err and "another --out" in err, err
    assert _listing(root) == before


def test_a_run_folder_from_before_the_marker_resumes_with_the_built_in_catalogue(tiny_run,
                                                                                 tmp_path):
    cfg, root, _, _ = tiny_run
    lay = _copy_run(root, tmp_path / "run")
    lay.marker.unlink()                     # as an earlier version left it
    _, report = run_challenge(cfg, lay.root, workers=1)
    assert report.ran == [] and json.loads(lay.marker.read_text())["kind"] == "run"


def _toml(items):
    sections = {}
    for item in items:
        key, _, value = item.partition("=")
        section, _, name = key.partition(".")
        sections.setdefault(section, []).append(f"{name} = {value}")
    return "\n".join(f"[{s}]\n" + "\n".join(lines) for s, lines in sections.items()) + "\n"


def _catalogue(path, ecc):
    path.write_text(f'["my-b"]\nperiod_days = 3.1915239\nt_transit_bjd = 2454449.86816\n'
                    f'ecc = {ecc}\nomega_deg = 346.0\ninc_deg = 84.20\na_rs = 7.07\n'
                    'rp_rs = 0.0906\nteff_star_k = 6429.0\nr_star_rsun = 1.377\n')


def test_a_configuration_and_its_catalogue_edited_in_place_are_refused(tmp_path, monkeypatch,
                                                                       capsys):
    """Issue 37: run_config.toml recorded the catalogue's path only ("0 tasks run", the old
    summary); the planet is now recorded by its elements, the catalogue's path aside."""
    import eclipsebench.challenge.runner as runner

    cat, config, out = tmp_path / "cat.toml", tmp_path / "run.toml", tmp_path / "run"
    _catalogue(cat, 0.2884)
    items = TINY + ['system.name="my-b"', f'system.catalogue="{cat}"', "challenge.seed=1"]
    config.write_text(_toml(items))
    argv = ["run", str(config), "--out", str(out), "--workers", "1", "--quiet"]
    calls = []

    def stop(*args, **kwargs):   # the work starts: this folder now holds a run of these inputs
        calls.append(1)
        raise KeyboardInterrupt

    monkeypatch.setattr(runner, "run_tasks", stop)
    assert main(argv) == 130
    capsys.readouterr()
    _catalogue(cat, 0.25)                                  # the planet edited in place
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "the elements of planet 'my-b' changed" in err, err
    _catalogue(cat, 0.2884)
    config.write_text(_toml(items[:-1] + ["challenge.seed=2"]))   # the configuration edited
    assert main(argv) == 2
    assert "different configuration" in capsys.readouterr().err
    # the same planet from a catalogue at another path is the same run
    moved = tmp_path / "moved.toml"
    shutil.copyfile(cat, moved)
    config.write_text(_toml(TINY + ['system.name="my-b"', f'system.catalogue="{moved}"',
                                    "challenge.seed=1"]))
    assert main(argv) == 130 and len(calls) == 2


def test_a_run_that_would_not_fit_the_free_space_is_refused_before_any_write(tmp_path,
                                                                            monkeypatch, capsys):
    from collections import namedtuple

    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage(10**9, 10**9 - 10**6, 10**6))
    out = tmp_path / "run"
    assert main(_cli(out)) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "simulated cubes" in err and "free" in err, err
    assert not out.exists()
