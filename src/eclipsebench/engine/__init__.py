"""The task engine: file-producing tasks run in dependency order, here or on Dask.

:mod:`.tasks` runs a list of :class:`~.tasks.Task` (one process, a local
Dask cluster or an existing scheduler; resumable through each task's stamp),
:mod:`.layout` says where each file of a run folder lives, and :mod:`.lock`
keeps a second run out of a folder. Each stage package (simulation,
photometry, reduce, stats, report) plans its own tasks with these; the
challenge package composes them.
"""

from .layout import Layout
from .lock import run_lock
from .tasks import RunReport, Task, run_tasks

__all__ = ["Layout", "RunReport", "Task", "run_lock", "run_tasks"]
