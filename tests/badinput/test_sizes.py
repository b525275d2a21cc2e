"""Issue 28: every size that allocates in proportion is refused before any work.

Before the limits (eclipsebench.limits) these took memory for seconds to
minutes and ended in "internal error: MemoryError" (exit 1), some after
writing part of a run folder.
"""

from __future__ import annotations

import time

import pytest

from eclipsebench.cli import main
from eclipsebench.config import load_config
from eclipsebench.errors import EXIT_ENVIRONMENT, ConfigError, InputError
from eclipsebench.limits import (
    MAX_BOOTSTRAP,
    MAX_EPOCHS,
    MAX_MCMC_WALKER_STEPS,
    MAX_MCMC_WALKERS,
    check_size,
)
from eclipsebench.stats.summary import summarize


def _cli(capsys, *argv):
    """Exit code and stderr lines, a usage error (argparse's SystemExit) included."""
    try:
        code = main([str(a) for a in argv])
    except SystemExit as stop:
        code = stop.code
    out, err = capsys.readouterr()
    return code, out, err.splitlines()


#: generous: the refusal is argument parsing or configuration validation (milliseconds)
WITHIN_S = 5.0


@pytest.mark.parametrize("argv,names", [
    (["run", "--epochs", "1000000000"], ["--epochs", "1000000000", str(MAX_EPOCHS)]),
    (["run", "--set", "challenge.epochs=1000000000"],
     ["challenge.epochs", "1000000000", str(MAX_EPOCHS)]),
    (["simulate", "--epochs", "1000000000"], ["--epochs", "1000000000", str(MAX_EPOCHS)]),
    (["simulate", "--set", "observation.main_cubes=1000000000"],
     ["observation.main_cubes", "1000000000", "100000"]),
    (["simulate", "--set", "observation.frames_per_cube=100000000"],
     ["observation.frames_per_cube", "100000000"]),
    (["simulate", "--set", "simulation.calibration_frames=100000000000"],
     ["simulation.calibration_frames", "100000000000"]),
    (["run", "--set", "reduce.mcmc_block_steps=1000000000"],
     ["reduce.mcmc_block_steps", "16 walkers x 1000000000", str(MAX_MCMC_WALKER_STEPS)]),
    (["run", "--set", "run.bootstrap=1000000000000"],
     ["run.bootstrap", "1000000000000", str(MAX_BOOTSTRAP)]),
    (["run", "--workers", "100000"], ["--workers", "100000", "256"]),
])
def test_a_size_above_its_limit_is_one_line_before_any_work(argv, names, tmp_path, capsys, bad):
    out = tmp_path / "out"
    start = time.perf_counter()
    code, _, err = _cli(capsys, *argv, "--out", out, "--quiet")
    assert time.perf_counter() - start < WITHIN_S
    bad.assert_one_line(code, err, *names)
    assert bad.snapshot(tmp_path) == set()


def test_reduce_walkers_and_walker_steps_are_bounded(tmp_path, capsys, bad):
    table = bad.xo3_table(tmp_path / "epoch_01.fits")
    before = bad.snapshot(tmp_path)
    start = time.perf_counter()
    code, _, err = _cli(capsys, "reduce", table, "--method", "pld", "--walkers", "100000000")
    assert time.perf_counter() - start < WITHIN_S
    bad.assert_one_line(code, err, "--walkers", "100000000", str(MAX_MCMC_WALKERS))
    code, _, err = _cli(capsys, "reduce", table, "--method", "pld", "--walkers", "2000",
                       "--steps", "1000000")
    bad.assert_one_line(code, err, "mcmc_steps", "2000 walkers x 1000000")
    assert bad.snapshot(tmp_path) == before


def test_stats_bootstrap_is_bounded(tmp_path, capsys, bad):
    depths = tmp_path / "d.csv"
    depths.write_text("method,epoch,depth_ppm,error_ppm\na,1,1800,50\na,2,1850,50\n")
    start = time.perf_counter()
    code, out, err = _cli(capsys, "stats", depths, "--bootstrap", "1000000000000")
    assert time.perf_counter() - start < WITHIN_S
    bad.assert_one_line(code, err, "--bootstrap", "1000000000000", str(MAX_BOOTSTRAP))
    assert out == "" and bad.snapshot(tmp_path) == {"d.csv"}
    with pytest.raises(InputError, match="n_bootstrap: 10000000 resamples is above"):
        summarize({"method": ["a", "a"], "epoch": [1, 2], "depth_ppm": [1800.0, 1850.0],
                   "error_ppm": [50.0, 50.0]}, n_bootstrap=10_000_000)


def test_the_limits_do_not_touch_the_defaults_or_a_monte_carlo():
    cfg = load_config(None, ["challenge.epochs=100"])
    assert cfg.challenge.epochs == 100 and cfg.run.bootstrap == 2000
    assert load_config("xo3b-phase-curve").observation.event == "phase-curve"
    assert load_config(None, ["observation.phase_curve_duration_d=100",
                              "observation.event=\"phase-curve\""]) is not None


def test_check_size_names_key_value_and_limit():
    check_size("k", 3, 3)
    with pytest.raises(ConfigError, match=r"config key 'k': 4 x is above the limit of 3"):
        check_size("k", 4, 3, "x", config=True)


def test_a_memory_error_is_one_line_naming_the_step(tmp_path, capsys, monkeypatch):
    """Before: "internal error: MemoryError ..." (exit 1)."""
    import eclipsebench.stats.summary as summary_module

    def exhausted(*args, **kwargs):
        raise MemoryError("Unable to allocate 36.4 TiB for an array")

    monkeypatch.setattr(summary_module, "method_statistics", exhausted)
    depths = tmp_path / "d.csv"
    depths.write_text("method,epoch,depth_ppm,error_ppm\na,1,1800,50\na,2,1850,50\n")
    code, out, err = _cli(capsys, "stats", depths)
    assert code == EXIT_ENVIRONMENT and len(err) == 1 and out == "", err
    assert "out of memory in eclipsebench.stats.summary.summarize" in err[0]
    assert "36.4 TiB" in err[0] and "internal error" not in err[0]
