"""The reduce stage of a run: every method on every epoch's photometry table.

:func:`plan_reduce_tasks` turns the configuration, the run folder
(:class:`eclipsebench.engine.layout.Layout`), the epochs and the methods into engine tasks
``reduce[_flat|_paper]/<method>/epoch_NN``; :func:`reduce_task` is the one place
that calls the fitting package (:func:`eclipsebench.fit.reduce.reduce_epoch`)
for a run. Keep it small: the method seam's context (seeded generator,
loaded calibration set) is threaded here.
"""

from __future__ import annotations

from functools import partial

from ..astro.catalogue import system_for
from ..config import Config
from ..decorrelate.base import MethodOptions
from ..engine.layout import Layout
from ..engine.tasks import Task
from ..errors import InputError
from ..fit import reduce as fit_reduce
from ..fit.result import result_ok, write_failure, write_result
from ..progress import get_logger
from .photometry_stage import photometry_key

__all__ = ["reduce_key", "reduce_task", "plan_reduce_tasks", "result_ok"]

log = get_logger("challenge")


def reduce_key(method: str, epoch: int, flat: bool = False, profile: str = "controlled") -> str:
    """The task key of one method on one epoch (``reduce_paper/...`` in the paper profile)."""
    suffix = ("_flat" if flat else "") + ("" if profile == "controlled" else f"_{profile}")
    return f"reduce{suffix}/{method}/epoch_{epoch:02d}"


def reduce_task(cfg: Config, table_path: str, method: str, epoch: int,
                method_options: MethodOptions, out_path: str,
                profile: str = "controlled") -> None:
    """Reduce one epoch with one method; write the light curve, then the result JSON.

    ``method_options`` are the method's options as the planner resolved them
    (:func:`plan_reduce_tasks`); the run seed is ``cfg.challenge.seed``.

    A method that refuses the epoch's data (an :class:`InputError`, e.g.
    frames outside KR/Pmap's calibration coverage) is an outcome of the
    benchmark, not a crash: the JSON records ``failed`` and the message, the
    statistics leave that epoch out and list it, and a rerun does not retry it
    (it would fail the same way).
    """
    system = system_for(cfg.system)
    try:
        result = fit_reduce.reduce_epoch(table_path, method, options=cfg.reduce, system=system,
                                         seed=cfg.challenge.seed, epoch=epoch,
                                         method_options=method_options, profile=profile)
    except InputError as exc:
        log.warning("%s epoch %d: %s", method, epoch, exc)
        write_failure(out_path, method, epoch, str(exc), profile=profile)
        return
    write_result(result, out_path)


def plan_reduce_tasks(cfg: Config, layout: Layout, epochs: list[int], methods: list[str], *,
                      flat: bool = False, profile: str = "controlled") -> list[Task]:
    """One task per (method, epoch) in one profile, each after its epoch's photometry task.

    ``[reduce.options.<method>]`` is parsed first, once: a bad key stops the run
    before any work, naming it. Each method's options (its table, and its team's
    in the paper profile) are resolved here into its options dataclass, which
    every task of the method gets.
    """
    configured = fit_reduce.configured_method_options(cfg.reduce)
    if profile != "controlled":
        for m in methods:
            fit_reduce.resolve_profile(m, cfg.reduce, profile)  # an unknown method stops here
    method_options = {m: fit_reduce.resolve_method_options(m, cfg.reduce, profile=profile,
                                                           configured=configured)
                      for m in methods}
    tasks = []
    for e in epochs:
        table = layout.photometry(e, flat)
        for m in methods:
            out = layout.result(m, e, flat, profile)
            tasks.append(Task(reduce_key(m, e, flat, profile), "reduce", reduce_task,
                              (cfg, str(table), m, e, method_options[m], str(out), profile),
                              (out,), (photometry_key(e, flat),),
                              check=partial(result_ok, m, e)))
    return tasks
