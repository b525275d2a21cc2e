"""The challenge runner on a tiny real challenge: every stage, resume, 1 vs 2 workers, CLI."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.challenge.runner import Layout, build_tasks, run_challenge
from eclipsebench.cli import main
from eclipsebench.config import load_config
from eclipsebench.errors import InputError

# Two epochs of 233 two-frame cubes (the eclipse stays inside the Main AOR), one sub-sample.
TINY = ["challenge.epochs=2", "observation.pre_cubes=1", "observation.frames_per_cube=2",
        "simulation.subsamples=1", "simulation.calibration_frames=2000",
        'run.methods=["pld", "bliss"]', "run.bootstrap=50", "run.report=false",
        "run.empirical_photon_limit=false"]


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    root = tmp_path_factory.mktemp("run")
    cfg = load_config(None, TINY)
    summary, report = run_challenge(cfg, root, workers=1)
    return cfg, root, summary, report


def test_every_stage_ran_and_the_summary_is_complete(tiny_run):
    cfg, root, summary, report = tiny_run
    lay = Layout(root)
    stages = {k.split("/")[0] for k in report.ran}
    assert stages == {"simulate", "photometry", "reduce", "stats"}
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
    assert sorted(k.split("/")[0] for k in report.ran) == ["reduce"] * 4 + ["stats"]
    assert (tmp_path / "summary.json").read_bytes() == (root / "summary.json").read_bytes()


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
    assert keys[-2:] == ["stats", "report"]


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


def test_a_method_refusing_an_epoch_is_recorded_not_fatal(tiny_run, tmp_path, monkeypatch):
    cfg, root, _, _ = tiny_run
    for name in ("simulation", "photometry", "results"):
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
