"""Ctrl-C during a long step: exit 130, exactly one stderr line, nothing partial left."""

from __future__ import annotations

import os
import signal

import emcee.ensemble
import pytest


def _interrupt_after(monkeypatch, calls: int) -> None:
    """Send SIGINT to this process from inside the likelihood after ``calls`` calls.

    The signal then lands inside emcee's wrapper, which prints the traceback
    of the call it was in before re-raising (what a user pressing Ctrl-C sees).
    """
    original = emcee.ensemble._FunctionWrapper.__init__
    count = {"n": 0}

    def init(self, f, args, kwargs):
        def wrapped(*a, **k):
            count["n"] += 1
            if count["n"] == calls:
                os.kill(os.getpid(), signal.SIGINT)
            return f(*a, **k)

        original(self, wrapped, args, kwargs)

    monkeypatch.setattr(emcee.ensemble._FunctionWrapper, "__init__", init)


@pytest.mark.parametrize("json_flag", [[], ["--json"]])
def test_ctrl_c_during_mcmc_is_one_line_exit_130(json_flag, tmp_path, cli, bad, monkeypatch):
    table = bad.xo3_table(tmp_path / "epoch_01.fits")
    _interrupt_after(monkeypatch, 50)
    before = bad.snapshot(tmp_path)
    # a job started with & by a shell without job control inherits SIGINT ignored
    handler = signal.getsignal(signal.SIGINT)
    code, out, err = cli("reduce", table, "--method", "segpoly", "--sampler", "mcmc",
                         "--walkers", "8", "--steps", "100", "--prayer-bead", "0",
                         "--out", tmp_path / "res" / "r.json", *json_flag)
    bad.assert_one_line(code, err, "interrupted", exit_code=130)
    assert "emcee" not in out and "Traceback" not in out
    assert bad.snapshot(tmp_path) == before  # no result, no light curve, no empty res/
    assert signal.getsignal(signal.SIGINT) is handler   # the command put back what it found


def test_interrupt_outside_the_handler_is_still_one_line(tmp_path, cli, bad, monkeypatch):
    """A KeyboardInterrupt raised directly (no signal) is one line too."""
    import eclipsebench.astro.lightcurve as lightcurve  # the command imports it when it runs

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(lightcurve, "light_curve_function", interrupted)
    code, _, err = cli("lightcurve", "--out", tmp_path / "new" / "lc.ecsv")
    bad.assert_one_line(code, err, "interrupted", exit_code=130)
    assert bad.snapshot(tmp_path) == set()
