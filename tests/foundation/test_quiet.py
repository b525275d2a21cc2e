"""``--quiet``: errors and the answer only (its help said "no progress bars or log messages").

It set the log level to WARNING, so warnings still reached stderr; now it keeps errors only,
and what a warning said that changes how to read the result is in the result itself.
"""

from __future__ import annotations

import logging

from eclipsebench.cli import main
from eclipsebench.progress import is_quiet

#: A tiny simulation (one epoch of 5 two-frame cubes) that starts 1.2 days after an eclipse of
#: XO-3b, so that its planning warns that the epoch holds no eclipse.
NO_ECLIPSE = ["--epochs", "1", "--no-calibration", "--workers", "1",
              "--set", "observation.pre_cubes=1", "--set", "observation.frames_per_cube=2",
              "--set", "observation.main_cubes=4", "--set", "simulation.subsamples=2",
              "--set", "observation.start_times_jd=[2207.5]"]


def test_quiet_simulate_prints_its_answer_and_no_warning(tmp_path, capfd, caplog):
    caplog.set_level(logging.INFO)
    ours = logging.getLogger("eclipsebench").level
    code = main(["simulate", "--out", str(tmp_path / "quiet"), *NO_ECLIPSE, "--quiet"])
    out, err = capfd.readouterr()
    assert code == 0 and err == "", err
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING], caplog.text
    assert " ecl nan " in out   # the answer says what the warning said: no eclipse time
    # the command's quiet does not outlive it (a test or a notebook goes on logging)
    assert logging.root.manager.disable == logging.NOTSET and not is_quiet()
    assert logging.getLogger("eclipsebench").level == ours   # a later test's warnings are seen
    # without --quiet the same command warns (the test could fail)
    caplog.clear()
    assert main(["simulate", "--out", str(tmp_path / "loud"), *NO_ECLIPSE]) == 0
    assert "holds no eclipse of XO-3b" in caplog.text
