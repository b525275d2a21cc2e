"""Issue 38: one resume rule for every reduction of the three runners (``run``, ``trust``'s
real and twin reductions, ``campaign``), :func:`eclipsebench.fit.result.result_ok`.

Each runner's planned reduce tasks are held to it by behaviour: a finished result (JSON
and light curve) is accepted; the same result without its light curve, edited to another
method or another epoch, or truncated is not (the engine then redoes the task); a
recorded refusal is accepted and not retried.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from eclipsebench.astro.catalogue import get_system
from eclipsebench.challenge.campaign import EpochInput, build_campaign_tasks
from eclipsebench.challenge.runner import build_tasks
from eclipsebench.config import load_config
from eclipsebench.config.reduce import ReduceSection
from eclipsebench.engine.tasks import Task
from eclipsebench.fit.result import lightcurve_path, result_ok, write_failure
from eclipsebench.trust.layout import TrustLayout
from eclipsebench.trust.run import TrustSettings, plan_real, plan_twins

RUN = ["challenge.epochs=2", 'run.methods=["pld", "bliss"]', 'run.profiles=["controlled"]',
       "run.empirical_photon_limit=false"]


def _run_tasks(root: Path) -> list[Task]:
    return build_tasks(load_config(None, RUN), root)


def _campaign_tasks(root: Path) -> list[Task]:
    epochs = [EpochInput(n, (str(root / f"t{n}.fits"),), "table") for n in (1, 2)]
    return build_campaign_tasks(load_config(None, RUN), root, epochs, get_system("XO-3b"),
                                {1: 2, 2: 2})


def _trust_tasks(root: Path) -> list[Task]:
    settings = TrustSettings(table=str(root / "table.fits"), system=get_system("XO-3b"),
                             methods=("pld", "bliss"), n_twins=10, seed=0,
                             reduce=ReduceSection(), table_epoch=3)
    layout = TrustLayout(root)
    return plan_real(settings, layout) + plan_twins(settings, layout, ["pld", "bliss"])


def _finished(path: Path, method: str, epoch: int | None) -> None:
    """A finished result as the one writer leaves it: the light curve, then the JSON."""
    path.parent.mkdir(parents=True, exist_ok=True)
    lightcurve_path(path).write_text("# %ECSV 1.0\n")
    path.write_text(json.dumps({"method": method, "epoch": epoch, "depth_ppm": 1875.0,
                                "depth_err_ppm": 60.0}))


def _accepts(task: Task) -> bool:
    try:
        return bool(task.check(*task.outputs))
    except Exception:   # what the engine does with a check that cannot read the file
        return False


@pytest.mark.parametrize("plan, expected", [
    (_run_tasks, {("pld", 1), ("pld", 2), ("bliss", 1), ("bliss", 2)}),
    (_campaign_tasks, {("pld", 1), ("pld", 2), ("bliss", 1), ("bliss", 2)}),
    (_trust_tasks, {("pld", 3), ("bliss", 3)}
     | {(m, i) for m in ("pld", "bliss") for i in range(1, 11)}),
], ids=["run", "campaign", "trust"])
def test_every_runner_redoes_a_reduction_the_one_rule_refuses(tmp_path, plan, expected):
    tasks = [t for t in plan(tmp_path) if t.stage in ("reduce", "real")]
    seen = set()
    for task in tasks:
        assert task.check.func is result_ok, task.key     # the one rule, not a copy
        method, epoch = task.check.args
        seen.add((method, epoch))
        out = Path(task.outputs[0])
        _finished(out, method, epoch)
        assert _accepts(task), task.key
        lightcurve_path(out).unlink()                      # the light curve lost
        assert not _accepts(task), task.key
        _finished(out, method, epoch)
        data = json.loads(out.read_text())
        out.write_text(json.dumps({**data, "method": "gp"}))   # another method's result
        assert not _accepts(task), task.key
        out.write_text(json.dumps({**data, "epoch": (epoch or 0) + 100}))   # another epoch's
        assert not _accepts(task), task.key
        out.write_text(json.dumps(data)[:30])                 # truncated
        assert not _accepts(task), task.key
        lightcurve_path(out).unlink()
        write_failure(out, method, epoch, "the method refused the table")   # a refusal
        assert _accepts(task), task.key
    assert seen == expected


def test_a_refusal_without_its_message_or_with_a_depth_is_not_a_result(tmp_path):
    path = tmp_path / "epoch_01.json"
    write_failure(path, "pld", 1, "no stamps")
    data = json.loads(path.read_text())
    assert result_ok("pld", 1, path)
    path.write_text(json.dumps({**data, "error": None}))
    assert not result_ok("pld", 1, path)
    path.write_text(json.dumps({**data, "depth_ppm": "1875"}))
    assert not result_ok("pld", 1, path)
    path.write_text(json.dumps({k: v for k, v in data.items() if k != "epoch"}))
    assert not result_ok("pld", None, path)    # the epoch is part of the schema
