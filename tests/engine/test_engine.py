"""The task engine: dependencies, resume from disk, atomic outputs, 1 vs 2 workers."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import cloudpickle
import numpy as np
import pytest

from eclipsebench.engine.tasks import Task, TaskFailed, run_tasks, stamp_path
from eclipsebench.errors import InputError
from eclipsebench.io.atomic import write_json
from eclipsebench.seeding import rng

# Dask workers cannot import test modules: ship this module's functions by value.
cloudpickle.register_pickle_by_value(sys.modules[__name__])


def make_numbers(path: str, seed: int, epoch: int) -> None:
    write_json(path, {"x": rng(seed, "toy", epoch).normal(size=3).tolist()})


def total(path: str, inputs: list[str], log: str) -> None:
    with open(log, "a") as fh:  # side channel: which tasks really ran
        fh.write(f"total {path}\n")
    values = [v for p in inputs for v in json.loads(Path(p).read_text())["x"]]
    write_json(path, {"sum": float(np.sum(values))})


def logged_numbers(path: str, seed: int, epoch: int, log: str) -> None:
    with open(log, "a") as fh:
        fh.write(f"numbers {epoch}\n")
    make_numbers(path, seed, epoch)


def fail(path: str) -> None:
    raise ValueError("boom")


def fail_input(path: str) -> None:
    raise InputError("option --x: expected y")


def forget(path: str) -> None:
    """Finishes without writing its output."""


def record_environment(path: str) -> None:
    import os

    import dask

    env = {k: os.environ.get(k) for k in ("MALLOC_TRIM_THRESHOLD_", "OPENBLAS_NUM_THREADS")}
    env["profile"] = dask.config.get("distributed.worker.profile.enabled")
    write_json(path, env)


def graph(root: Path, seed: int = 7, n: int = 4, log: Path | None = None):
    log = log or root / "log.txt"
    tasks = [Task(f"n/{e}", "numbers", logged_numbers, (str(root / f"n{e}.json"), seed, e, str(log)),
                  (root / f"n{e}.json",)) for e in range(n)]
    tasks.append(Task("total", "total", total,
                      (str(root / "total.json"), [str(root / f"n{e}.json") for e in range(n)],
                       str(log)), (root / "total.json",), tuple(f"n/{e}" for e in range(n))))
    return tasks


def test_sync_runs_in_dependency_order_and_resumes(tmp_path):
    tasks = graph(tmp_path)
    rep = run_tasks(list(reversed(tasks)), workers=1)
    assert rep.ran[-1] == "total" and len(rep.ran) == 5
    first = (tmp_path / "total.json").read_bytes()
    # interruption: two outputs lost; only those and their dependants rerun
    (tmp_path / "n2.json").unlink()
    (tmp_path / "total.json").unlink()
    (tmp_path / "log.txt").unlink()
    rep2 = run_tasks(tasks, workers=1)
    assert sorted(rep2.ran) == ["n/2", "total"]
    assert (tmp_path / "log.txt").read_text().splitlines() == ["numbers 2",
                                                               f"total {tmp_path / 'total.json'}"]
    assert (tmp_path / "total.json").read_bytes() == first
    rep3 = run_tasks(tasks, workers=1)
    assert rep3.ran == [] and len(rep3.skipped) == 5


def two_files(second: str, first: str) -> None:
    """Writes ``first`` then ``second`` (its outputs are listed out of name order)."""
    write_json(first, {"a": 1})
    write_json(second, {"b": 2})


def test_a_task_whose_outputs_are_not_in_name_order_is_done_on_resume(tmp_path):
    """The stamp's JSON sorts its keys; a task listing ``z.json`` before ``a.json`` was
    never found done and was redone on every resume."""
    task = Task("two", "two", two_files, (str(tmp_path / "a.json"), str(tmp_path / "z.json")),
                (tmp_path / "z.json", tmp_path / "a.json"))
    assert run_tasks([task], workers=1).ran == ["two"]
    assert run_tasks([task], workers=1).ran == []


def test_failure_keeps_other_outputs_and_blocks_dependants(tmp_path):
    tasks = graph(tmp_path, n=2)
    tasks[1] = Task("n/1", "numbers", fail, (str(tmp_path / "n1.json"),), (tmp_path / "n1.json",))
    with pytest.raises(TaskFailed, match="n/1: ValueError: boom"):
        run_tasks(tasks, workers=1)
    assert (tmp_path / "n0.json").exists() and not (tmp_path / "total.json").exists()


def test_input_error_reaches_the_user(tmp_path):
    t = Task("bad", "x", fail_input, (str(tmp_path / "a"),), (tmp_path / "a",))
    with pytest.raises(InputError, match="--x"):
        run_tasks([t])


def test_task_that_writes_nothing_fails(tmp_path):
    t = Task("lazy", "x", forget, (str(tmp_path / "a"),), (tmp_path / "a",))
    with pytest.raises(TaskFailed, match="without writing"):
        run_tasks([t])


def test_graph_errors(tmp_path):
    a = Task("a", "x", forget, (), (tmp_path / "a",), ("missing",))
    with pytest.raises(ValueError, match="unknown task"):
        run_tasks([a])
    b = Task("b", "x", forget, (), (tmp_path / "b",), ("c",))
    c = Task("c", "x", forget, (), (tmp_path / "c",), ("b",))
    with pytest.raises(ValueError, match="cycle"):
        run_tasks([b, c])


@pytest.mark.slow
def test_two_dask_workers_give_the_same_bytes(tmp_path):
    one, two = tmp_path / "one", tmp_path / "two"
    one.mkdir()
    two.mkdir()
    run_tasks(graph(one), workers=1)
    rep = run_tasks(graph(two), workers=2)
    assert "LocalCluster (2 processes)" in rep.executor and len(rep.ran) == 5
    for name in ["total.json", *[f"n{e}.json" for e in range(4)]]:
        assert (one / name).read_bytes() == (two / name).read_bytes()
    assert sorted(t.key for t in rep.timeline) == sorted(rep.ran)
    assert all(t.start_s >= 0 and t.seconds >= 0 and ":" in t.worker for t in rep.timeline)
    total_start = next(t.start_s for t in rep.timeline if t.key == "total")
    assert all(t.start_s + t.seconds <= total_start + 1e-3 for t in rep.timeline
               if t.key != "total")  # dependencies first


@pytest.mark.slow
def test_dask_workers_keep_glibc_malloc_dynamic(tmp_path):
    """No MALLOC_TRIM_THRESHOLD_ (every task ran 1.8x slower) and no statistical profiler
    (1.17x) in the workers; one BLAS thread."""
    out = tmp_path / "env.json"
    run_tasks([Task("env", "env", record_environment, (str(out),), (out,))], workers=2)
    env = json.loads(out.read_text())
    assert env == {"MALLOC_TRIM_THRESHOLD_": None, "OPENBLAS_NUM_THREADS": "1", "profile": False}


def test_truncated_or_edited_outputs_are_redone(tmp_path):
    tasks = graph(tmp_path)
    run_tasks(tasks, workers=1)
    first = (tmp_path / "total.json").read_bytes()
    text = (tmp_path / "n1.json").read_text()
    (tmp_path / "n1.json").write_text(text[:5])                  # truncated
    (tmp_path / "n3.json").write_text(text)                      # valid, but not what n/3 wrote
    rep = run_tasks(tasks, workers=1)
    assert sorted(rep.ran) == ["n/1", "n/3", "total"]
    assert (tmp_path / "total.json").read_bytes() == first
    assert stamp_path(tasks[-1]).is_file()


def test_a_result_made_from_other_inputs_is_redone(tmp_path):
    tasks = graph(tmp_path)
    run_tasks(tasks, workers=1)
    # n/1 redone elsewhere with another seed: whole and stamped, but total was made from
    # the old n1.json, so total (only) is redone
    other = graph(tmp_path, seed=8)[1]
    (tmp_path / "n1.json").unlink()
    run_tasks([other], workers=1)
    rep = run_tasks(tasks, workers=1)
    assert rep.ran == ["total"]


def test_a_check_refusing_the_outputs_redoes_the_task(tmp_path):
    out = tmp_path / "a.json"
    task = Task("a", "x", make_numbers, (str(out), 1, 1), (out,))
    run_tasks([task], workers=1)
    refusing = Task("a", "x", make_numbers, (str(out), 1, 1), (out,), check=lambda p: False)
    assert run_tasks([refusing], workers=1).ran == ["a"]
    assert run_tasks([task], workers=1).ran == []


def link_away(path: str, folder: str, elsewhere: str) -> None:
    """Replaces ``folder`` (inside the run) by a link to ``elsewhere`` while the run works."""
    import os
    import shutil

    shutil.rmtree(folder)
    os.symlink(elsewhere, folder)
    write_json(path, {"linked": True})


@pytest.mark.parametrize("workers", [1, pytest.param(2, marks=pytest.mark.slow)])
def test_a_link_made_during_the_run_does_not_redirect_an_output(tmp_path, workers):
    """Issue 37: the links were checked before the work only; a link made inside the run
    folder meanwhile sent later outputs out of it (checked in whichever process writes)."""
    root, elsewhere = tmp_path / "run", tmp_path / "elsewhere"
    (root / "report").mkdir(parents=True)
    elsewhere.mkdir()
    tasks = [Task("link", "x", link_away, (str(root / "a.json"), str(root / "report"),
                                           str(elsewhere)), (root / "a.json",)),
             Task("page", "x", make_numbers, (str(root / "report" / "index.json"), 1, 1),
                  (root / "report" / "index.json",), ("link",))]
    with pytest.raises(InputError, match="outside the run folder"):
        run_tasks(tasks, workers=workers, root=root)
    assert list(elsewhere.iterdir()) == []


def test_a_task_made_from_another_version_of_an_external_input_is_redone(tmp_path):
    """A task's ``sources`` (content digests of a user's file it reads) count in its stamp."""
    out = tmp_path / "a.json"
    made = Task("a", "x", make_numbers, (str(out), 1, 1), (out,), sources=("sha-of-table-1",))
    assert run_tasks([made], workers=1).ran == ["a"]
    assert run_tasks([made], workers=1).ran == []
    other = Task("a", "x", make_numbers, (str(out), 1, 1), (out,), sources=("sha-of-table-2",))
    assert run_tasks([other], workers=1).ran == ["a"]


def record_scratch(path: str) -> None:
    import os

    from distributed import get_worker

    folder = get_worker().local_directory   # <private>/dask-scratch-space/worker-...
    private = os.path.dirname(os.path.dirname(folder))
    write_json(path, {"folder": folder, "private": os.path.basename(private),
                      "mode": os.stat(private).st_mode & 0o777})


@pytest.mark.slow
def test_dask_workers_keep_their_scratch_in_a_private_folder(tmp_path):
    """Issue 37: the workers used the shared /tmp/dask-scratch-space."""
    out = tmp_path / "scratch.json"
    run_tasks([Task("s", "s", record_scratch, (str(out),), (out,))], workers=2)
    seen = json.loads(out.read_text())
    assert seen["private"].startswith("eclipsebench-dask-") and seen["mode"] == 0o700, seen
    assert not seen["folder"].startswith("/tmp/dask-scratch-space")


def swallow_sigterm(path: str) -> None:
    """A task in which a library swallows the interrupt (as emcee's ``random_state``
    setter does with its bare ``except: pass``), then writes its output."""
    import os
    import signal
    import time

    try:
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5.0)
    except KeyboardInterrupt:
        pass
    write_json(path, {"done": True})


def test_an_interrupt_a_task_swallowed_still_stops_the_run_at_the_next_task(tmp_path):
    """The SIGTERM test of tests/challenge/test_faults.py once saw exit 0 and an empty
    stderr: the run had gone to its end after the signal. A swallowed interrupt is
    raised again between tasks, so the next task does not run."""
    from eclipsebench.cli import _one_line_interrupt
    from eclipsebench.errors import Interrupted

    first = Task("a", "x", swallow_sigterm, (str(tmp_path / "a.json"),), (tmp_path / "a.json",))
    second = Task("b", "x", make_numbers, (str(tmp_path / "b.json"), 1, 1),
                  (tmp_path / "b.json",), deps=("a",))
    with pytest.raises(Interrupted) as caught, _one_line_interrupt():
        run_tasks([first, second], workers=1)
    assert caught.value.signum == 15
    assert (tmp_path / "a.json").exists() and not (tmp_path / "b.json").exists()
    assert stamp_path(first).exists()   # written whole: not redone on resume


def test_a_command_that_swallowed_its_interrupt_exits_143_in_one_line(monkeypatch, capsys):
    import os
    import signal

    from eclipsebench import cli
    from eclipsebench.commands import stats

    def swallowing(args):
        try:
            os.kill(os.getpid(), signal.SIGTERM)
        except KeyboardInterrupt:
            pass

    monkeypatch.setattr(stats, "run", swallowing)
    assert cli.main(["stats", "x.ecsv"]) == 143
    assert capsys.readouterr().err.splitlines() == [
        "eclipsebench stats: interrupted by SIGTERM; rerun the same command to resume"]


def warn_and_write(path: str) -> None:
    """Warns in three ways a task can (eclipsebench's logger, Python, astropy's logger), logs
    an error, and writes its output."""
    import logging
    import warnings

    from astropy.utils.exceptions import AstropyUserWarning

    logging.getLogger("eclipsebench.test").warning("a logged warning from a task")
    warnings.warn("a Python warning from a task", RuntimeWarning, stacklevel=1)
    warnings.warn("an astropy warning from a task", AstropyUserWarning, stacklevel=1)
    logging.getLogger("eclipsebench.test").error("a logged error from a task")
    write_json(path, {"done": True})


@pytest.mark.parametrize("quiet", [True, False])
def test_quiet_reaches_the_workers_errors_only(tmp_path, capfd, monkeypatch, quiet):
    """A command's --quiet silences its tasks' warnings in the Dask workers too (their stderr is
    the command's), and keeps their errors; without it the warnings show."""
    import eclipsebench.progress as progress

    monkeypatch.setitem(progress._state, "quiet", quiet)
    out = tmp_path / "w.json"
    run_tasks([Task("w", "w", warn_and_write, (str(out),), (out,))], workers=2)
    err = capfd.readouterr().err
    assert out.is_file() and "a logged error from a task" in err, err
    for text in ("a logged warning", "a Python warning", "an astropy warning"):
        assert (text in err) is not quiet, (text, err)
