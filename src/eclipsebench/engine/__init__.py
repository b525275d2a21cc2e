"""The task engine: file-producing tasks run in dependency order, here or on Dask.

:mod:`.tasks` runs a list of :class:`~.tasks.Task` (one process, a local
Dask cluster or an existing scheduler; resumable through each task's stamp),
:mod:`.cluster` starts or reaches the Dask cluster (closed to other
processes), :mod:`.layout` says where each file of a run folder lives, and
:mod:`.lock` keeps a second run out of a folder. Each stage package
(simulation, photometry, reduce, stats, report) plans its own tasks with
these; the challenge package composes them.

The names below are imported when first used, so that importing
:mod:`.cluster` (for the command line's options) does not import numba.
"""

from __future__ import annotations

import importlib

__all__ = ["ClusterOptions", "Layout", "RunReport", "Task", "run_lock", "run_tasks"]

_HOME = {"ClusterOptions": ".cluster", "Layout": ".layout", "RunReport": ".tasks",
         "Task": ".tasks", "run_lock": ".lock", "run_tasks": ".tasks"}


def __getattr__(name: str):
    if name in _HOME:
        return getattr(importlib.import_module(_HOME[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
