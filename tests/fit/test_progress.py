"""Progress on long work (issue 29): a bar on a terminal, log lines off one."""

from __future__ import annotations

import fcntl
import os
import pty
import struct
import subprocess
import sys
import termios
from pathlib import Path

import pytest

from eclipsebench.progress import ProgressLines


def _run_on_a_pty(args: list[str], cwd) -> tuple[int, str]:
    """Run ``python -m eclipsebench ARGS`` with stdout and stderr on a pseudo-terminal."""
    leader, follower = pty.openpty()
    # an 80-column terminal (a fresh pseudo-terminal has no size, and a bar no width)
    fcntl.ioctl(follower, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
    proc = subprocess.Popen([sys.executable, "-m", "eclipsebench", *args], cwd=cwd,
                            stdout=follower, stderr=follower, stdin=subprocess.DEVNULL)
    os.close(follower)
    chunks = []
    while True:
        try:
            data = os.read(leader, 4096)
        except OSError:   # EIO: the child closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    os.close(leader)
    return proc.wait(timeout=300), b"".join(chunks).decode("utf-8", "replace")


@pytest.mark.slow   # GP's fit and 1,200 GP likelihoods: about a minute on a loaded 2-core box
def test_reduce_gp_shows_an_mcmc_bar_on_a_terminal(tmp_path, xo3_epoch):
    path = tmp_path / "epoch_03.fits"
    xo3_epoch["table"](seed=21)[::16].write(path)
    args = [str(path), "--method", "gp", "--phase", "flat", "--sampler", "mcmc", "--walkers",
            "12", "--steps", "100", "--prayer-bead", "0", "--out", str(tmp_path / "r.json")]
    code, text = _run_on_a_pty(["reduce", *args], tmp_path)
    assert code == 0, text
    assert "MCMC (gp)" in text and "step" in text    # the tqdm bar, drawn on the terminal
    # off a terminal (a pipe): no bar
    piped = subprocess.run([sys.executable, "-m", "eclipsebench", "reduce", *args],
                           cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert piped.returncode == 0 and "MCMC (gp)" not in piped.stderr + piped.stdout


def test_progress_lines_are_rate_limited_to_one_a_minute():
    now = [0.0]
    lines: list[str] = []
    p = ProgressLines({"photometry": 2, "reduce": 4}, emit=lines.append, clock=lambda: now[0])
    assert lines == ["6 tasks to run (photometry 2, reduce 4)"]
    for t in (1.0, 30.0):                       # two tasks in the first minute: no line yet
        now[0] = t
        p.update("photometry")
    assert lines[1:] == ["photometry: 2/2 tasks done"]   # a line per stage
    now[0] = 59.9
    p.tick()
    assert len(lines) == 2
    now[0] = 60.0                                # a minute since the start: one line
    p.tick()
    now[0] = 70.0
    p.update("reduce")                           # within the minute after it: none
    assert lines[2:] == ["progress: 2 / 6 tasks done (reduce 0/4)"]
    now[0] = 125.0                               # a long task: the heartbeat's tick writes
    p.tick()
    assert lines[3:] == ["progress: 3 / 6 tasks done (reduce 1/4)"]


def test_the_heartbeat_ticks_while_a_task_runs():
    import threading

    seen = threading.Event()
    p = ProgressLines({"reduce": 1}, emit=lambda line: seen.set() if "progress" in line else None,
                      every_s=0.0)
    p.start(poll_s=0.01)
    try:
        assert seen.wait(5.0)
    finally:
        p.close()


def _write_one(path: str) -> None:
    Path(path).write_text("1\n")


def test_a_run_off_a_terminal_logs_its_stages(tmp_path, caplog, monkeypatch):
    """The engine (what ``run`` uses) writes log lines when stderr is not a terminal."""
    import logging

    from eclipsebench.engine.tasks import Task, run_tasks

    # pytest captures stderr (not a terminal) but also runs quiet-free: force the choice
    monkeypatch.setattr("eclipsebench.engine.tasks.lines_enabled", lambda: True)
    tasks = [Task(f"photometry/epoch_{i:02d}", "photometry", _write_one,
                  (str(tmp_path / f"p{i}.txt"),), (tmp_path / f"p{i}.txt",)) for i in (1, 2)]
    with caplog.at_level(logging.INFO, logger="eclipsebench"):
        run_tasks(tasks, workers=1)
    lines = [r.getMessage() for r in caplog.records if r.name == "eclipsebench.progress"]
    assert lines == ["2 tasks to run (photometry 2)", "photometry: 2/2 tasks done"]
