"""Run a graph of file-producing tasks on Dask, resuming from what is on disk.

A :class:`Task` is a module-level function, its arguments, the files it
writes (atomically) and the tasks it needs. Results pass between tasks
through those files, never through memory, so the outcome cannot depend on
where or in which order tasks ran.

Resuming. When a task finishes, the engine writes its *stamp* beside its
last output (``.<name>.task.json``): the SHA-256 of each output's bytes and
of the inputs it was made from (the bytes of its dependencies' outputs, and
the content digests of the external inputs it reads, ``Task.sources``). A
task is done, and is not run again, only when

* every output exists and its bytes match the stamp (a truncated or edited
  file is redone),
* the inputs recorded in the stamp are the current ones (a result made from
  a photometry table that has since been redone is redone),
* the task's own ``check`` accepts the outputs (e.g. the JSON parses and has
  the fields of its schema; the cubes an AOR's marker stands for exist),
* and every task it depends on is done.

So rerunning the same graph after an interruption (Ctrl-C, a killed worker,
a killed process, a truncated file) redoes exactly what is missing or not
trustworthy, and its dependants.

Executors:

* ``workers == 1`` and no scheduler: in-process and synchronous (tasks run
  one after another in dependency order in this process; what Dask's
  synchronous scheduler would do, without its overhead; the debugging mode).
* ``workers >= 2``: a :class:`distributed.LocalCluster` of ``workers``
  single-threaded processes.
* ``scheduler="tcp://host:port"``: an existing Dask cluster (its workers
  must see the same file system).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import socket
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cloudpickle
import numba
from threadpoolctl import threadpool_limits

from ..errors import EnvironmentFailure, InputError, raise_pending_interrupt
from ..io.atomic import confined_to, write_json
from ..io.digest import file_sha256
from ..io.paths import check_inside
from ..progress import (
    ProgressLines,
    errors_only,
    get_logger,
    is_quiet,
    lines_enabled,
    progress,
)
from .cluster import ClusterOptions, open_client
from .cluster import close as close_cluster

__all__ = ["Task", "TaskTiming", "RunReport", "TaskFailed", "run_tasks", "stamp_path",
           "is_done", "check_outputs_inside"]

#: Suffix of a task's stamp, written beside its last output as ``.<name>.task.json``.
STAMP_SUFFIX = ".task.json"

log = get_logger("challenge")


@dataclass(frozen=True)
class Task:
    """One unit of work whose result is a set of files.

    Attributes
    ----------
    key : str
        Unique name, e.g. ``"reduce/bliss/epoch_03"``.
    stage : str
        Progress-bar group (``simulate``, ``photometry``, ``reduce``...).
    func : callable
        A module-level (picklable) function called as ``func(*args)``; it
        must write every path of ``outputs`` atomically, the last one last.
    args : tuple
        Picklable arguments.
    outputs : tuple of Path
        The files it writes (see the module docstring for when it is done).
    deps : tuple of str
        Keys of the tasks that must be done first.
    check : callable, optional
        ``check(*outputs) -> bool``, run in the calling process on resume:
        whether the outputs are whole and of the expected schema (beyond the
        stamp's byte hashes). ``None``: the stamp alone decides.
    sources : tuple of str
        Digests of the external inputs the task reads (a user's table, pixel
        map or planet: :mod:`eclipsebench.io.digest`), computed once by the
        planner; they count among the inputs of its stamp, so a task made
        from another version of them is not done. Empty for a task that
        reads only its dependencies' outputs.
    """

    key: str
    stage: str
    func: Callable[..., object]
    args: tuple = ()
    outputs: tuple[Path, ...] = ()
    deps: tuple[str, ...] = ()
    check: Callable[..., bool] | None = None
    sources: tuple[str, ...] = ()


def stamp_path(task: Task) -> Path:
    """Where ``task``'s stamp lives: ``.<name>.task.json`` beside its last output."""
    last = Path(task.outputs[-1])
    return last.with_name(f".{last.name}{STAMP_SUFFIX}")


class _Hashes:
    """SHA-256 of files, computed once per run (forgotten when a task rewrites them)."""

    def __init__(self) -> None:
        self._memo: dict[Path, str] = {}

    def of(self, path: Path) -> str:
        path = Path(path)
        digest = self._memo.get(path)
        if digest is None:
            digest = self._memo[path] = file_sha256(path)
        return digest

    def forget(self, paths: Iterable[Path]) -> None:
        for p in paths:
            self._memo.pop(Path(p), None)


def _inputs_digest(task: Task, by_key: dict[str, Task], hashes: _Hashes) -> str:
    """SHA-256 over the bytes of every output of every dependency, in order, and the
    digests of the task's external inputs (``sources``) when it has any."""
    h = hashlib.sha256()
    for d in task.deps:
        for p in by_key[d].outputs:
            h.update(hashes.of(p).encode())
    for source in task.sources:
        h.update(f"source:{source}".encode())
    return h.hexdigest()


def _write_stamp(task: Task, by_key: dict[str, Task], hashes: _Hashes) -> None:
    hashes.forget(task.outputs)
    write_json(stamp_path(task), {
        "task": task.key,
        "inputs_sha256": _inputs_digest(task, by_key, hashes),
        "outputs_sha256": {Path(p).name: hashes.of(p) for p in task.outputs}})


def is_done(task: Task, by_key: dict[str, Task], hashes: _Hashes | None = None) -> bool:
    """Whether ``task``'s outputs can be trusted as they are (its dependencies aside)."""
    hashes = hashes or _Hashes()
    if not task.outputs or not all(Path(p).is_file() for p in task.outputs):
        return False
    try:
        stamp = json.loads(stamp_path(task).read_text())
        recorded = stamp["outputs_sha256"]
        # the stamp's JSON keeps its keys sorted: outputs are compared as a set of names
        if stamp["task"] != task.key or sorted(recorded) != sorted(Path(p).name
                                                                   for p in task.outputs):
            return False
        if any(recorded[Path(p).name] != hashes.of(p) for p in task.outputs):
            return False
        if stamp["inputs_sha256"] != _inputs_digest(task, by_key, hashes):
            return False
    except (OSError, ValueError, KeyError, TypeError):
        return False  # no stamp, an unreadable one or a dependency output missing
    try:
        return task.check is None or bool(task.check(*task.outputs))
    except Exception:  # a check that cannot read the file: not trusted, redone
        return False


@dataclass(frozen=True)
class TaskTiming:
    """When and where one task ran.

    Attributes
    ----------
    key : str
        The task's key.
    start_s : float
        Start, seconds after the run began (same clock in every process).
    seconds : float
        Duration of the task's function.
    worker : str
        ``host:pid`` of the process that ran it.
    """

    key: str
    start_s: float
    seconds: float
    worker: str


@dataclass
class RunReport:
    """What a run did: the keys it ran and found done, each task's timing, the wall time."""

    ran: list[str] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    wall_s: float = 0.0
    executor: str = ""
    timeline: list[TaskTiming] = field(default_factory=list)
    started_unix: float = 0.0

    def record(self, key: str, timing: tuple[float, float, str]) -> None:
        """Store what :func:`_call` returned for ``key``."""
        start_unix, seconds, worker = timing
        self.timeline.append(TaskTiming(key, start_unix - self.started_unix, seconds, worker))

    def stage_seconds(self) -> dict[str, float]:
        """Task time summed per stage prefix (``simulate``, ``reduce``...), seconds."""
        out: dict[str, float] = {}
        for t in self.timeline:
            stage = t.key.split("/", 1)[0]
            out[stage] = out.get(stage, 0.0) + t.seconds
        return out


class TaskFailed(RuntimeError):
    """One or more tasks raised; the others completed and their files are kept."""

    def __init__(self, failures: dict[str, BaseException]):
        self.failures = failures
        first_key, first = next(iter(failures.items()))
        super().__init__(f"{len(failures)} task(s) failed; first {first_key}: "
                         f"{type(first).__name__}: {first}")


def check_outputs_inside(tasks: Sequence[Task], root: str | Path) -> None:
    """Refuse, before any work, an output that resolves outside ``root``.

    Each output is resolved with its symbolic links followed: a run folder
    holding ``results -> elsewhere`` (from an unpacked archive, say) would
    otherwise have its results written through the link. The folders already
    resolved are remembered, so a run of thousands of tasks resolves each
    folder once.

    Raises
    ------
    InputError
        One line naming the first such output and where it leads.
    """
    seen: set[Path] = set()
    for task in tasks:
        for path in task.outputs:
            folder = Path(path).parent
            if folder not in seen:
                check_inside(folder, root)
                seen.add(folder)
            check_inside(path, root)


def _check_graph(tasks: Sequence[Task]) -> dict[str, Task]:
    by_key: dict[str, Task] = {}
    for t in tasks:
        if t.key in by_key:
            raise ValueError(f"duplicate task key {t.key}")
        if not t.outputs:
            raise ValueError(f"task {t.key} declares no output files")
        by_key[t.key] = t
    for t in tasks:
        for d in t.deps:
            if d not in by_key:
                raise ValueError(f"task {t.key} depends on unknown task {d}")
    return by_key


def _order(by_key: dict[str, Task]) -> list[str]:
    """Topological order (Kahn), stable in the given order."""
    indeg = {k: len(t.deps) for k, t in by_key.items()}
    users: dict[str, list[str]] = {k: [] for k in by_key}
    for k, t in by_key.items():
        for d in t.deps:
            users[d].append(k)
    ready = [k for k in by_key if indeg[k] == 0]
    out = []
    while ready:
        k = ready.pop(0)
        out.append(k)
        for u in users[k]:
            indeg[u] -= 1
            if indeg[u] == 0:
                ready.append(u)
    if len(out) != len(by_key):
        raise ValueError("the task graph has a cycle")
    return out


def _call_pickled(func_bytes: bytes, args: tuple, root: str | None = None,
                  quiet: bool = False) -> tuple[float, float, str]:
    """:func:`_call` of a function shipped as cloudpickle bytes, logging errors only when the
    command that submitted it is quiet (``--quiet``: a worker's warnings reach the same
    terminal; :func:`~eclipsebench.progress.errors_only`).

    Dask pickles a callable by reference whenever the standard pickle can, so
    a function of a module registered for pickling by value (a test module
    that workers cannot import) would reach the workers as a name they cannot
    resolve, and the task would wait forever; cloudpickle honours the
    registration.
    """
    with errors_only(quiet):
        return _call(cloudpickle.loads(func_bytes), args, root)


def _call(func: Callable[..., object], args: tuple, root: str | None = None
          ) -> tuple[float, float, str]:
    # Every task runs single-threaded wherever it runs (in this process, a local
    # worker or a remote scheduler's): multi-threaded BLAS splits sums differently,
    # and the same seed must give the same bytes with any number of workers.
    # Its writes stay in the run folder ``root`` (checked at write time).
    previous = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        with threadpool_limits(limits=1), confined_to(root):
            start_unix = time.time()
            t0 = time.perf_counter()
            func(*args)
            return start_unix, time.perf_counter() - t0, f"{socket.gethostname()}:{os.getpid()}"
    finally:
        numba.set_num_threads(previous)


class _Bars:
    """A bar per stage on a terminal; off one, :class:`ProgressLines` in the log."""

    def __init__(self, tasks: Iterable[Task]):
        totals: dict[str, int] = {}
        for t in tasks:
            totals[t.stage] = totals.get(t.stage, 0) + 1
        self.bars = {s: progress(total=n, desc=s, unit="task", leave=True)
                     for s, n in totals.items()}
        self.lines = ProgressLines(totals).start() if lines_enabled() else None

    def update(self, stage: str) -> None:
        self.bars[stage].update(1)
        if self.lines is not None:
            self.lines.update(stage)

    def close(self) -> None:
        for b in self.bars.values():
            b.close()
        if self.lines is not None:
            self.lines.close()


def run_tasks(tasks: Sequence[Task], *, workers: int = 1, scheduler: str | None = None,
              keep_going: bool = True, cluster: ClusterOptions | None = None,
              root: str | os.PathLike | None = None) -> RunReport:
    """Run every task that is not done, respecting dependencies.

    Parameters
    ----------
    tasks : sequence of Task
        The whole graph (done tasks included; they are skipped).
    workers : int
        1: in-process synchronous; N >= 2: a local Dask cluster of N processes
        (on 127.0.0.1, TLS with temporary credentials: :mod:`.cluster`).
    scheduler : str, optional
        Address of an existing Dask scheduler (overrides ``workers``).
    keep_going : bool
        After a failure, keep running the tasks that do not depend on it
        (never after an environment failure: every other task would meet it).
    cluster : ClusterOptions, optional
        Dashboard, connection timeout and TLS files of the Dask cluster.
    root : path, optional
        The run folder: every file a task or the engine writes is checked, at
        write time, to resolve inside it (:func:`eclipsebench.io.atomic.confined_to`),
        so a symbolic link made during the run cannot redirect an output.

    Returns
    -------
    RunReport

    Raises
    ------
    EnvironmentFailure
        A task could not write (disk full, permission) or ran out of memory:
        the run stops at the first, and this names the folder or the task.
    TaskFailed
        If any task raised (after the others finished when ``keep_going``).
        A task that raised an :class:`~eclipsebench.errors.InputError` is
        re-raised as that error (it is the user's to fix).
    SchedulerUnreachable
        The scheduler named did not answer in time; nothing was run.

    Notes
    -----
    On an interrupt (Ctrl-C, SIGTERM: a KeyboardInterrupt), a task whose
    outputs were all written while the run was stopping gets its stamp, so
    that a rerun does not redo it.
    """
    with confined_to(root):
        return _run_tasks(tasks, workers=workers, scheduler=scheduler, keep_going=keep_going,
                          cluster=cluster, root=None if root is None else os.path.abspath(root))


def _run_tasks(tasks: Sequence[Task], *, workers: int, scheduler: str | None, keep_going: bool,
               cluster: ClusterOptions | None, root: str | None) -> RunReport:
    by_key = _check_graph(tasks)
    order = _order(by_key)
    report = RunReport(started_unix=time.time())
    hashes = _Hashes()
    done: set[str] = set()
    for k in order:  # dependencies first: a task is done only if all it needs is
        if all(d in done for d in by_key[k].deps) and is_done(by_key[k], by_key, hashes):
            done.add(k)
    report.skipped = [k for k in order if k in done]
    todo = [k for k in order if k not in done]
    t0 = time.perf_counter()
    if not todo:
        report.executor = "none (all outputs exist)"
        return report
    bars = _Bars(by_key[k] for k in todo)
    run = _Run(by_key, done, bars, report, hashes, keep_going, root)
    try:
        if scheduler is None and workers <= 1:
            report.executor = "in-process (synchronous)"
            _run_sync(run, todo)
        else:
            _run_dask(run, todo, workers=workers, scheduler=scheduler, options=cluster)
    except KeyboardInterrupt:
        run.stamp_written_in_flight()
        raise
    finally:
        bars.close()
        report.wall_s = time.perf_counter() - t0
    _raise_failures(run.failures)
    return report


def _raise_failures(failures: dict[str, BaseException]) -> None:
    """The environment failure first, then the user's (InputError), then the rest."""
    if not failures:
        return
    for key, exc in failures.items():
        if isinstance(exc, EnvironmentFailure):
            raise exc
        if isinstance(exc, MemoryError):
            size = " ".join(str(exc).split())
            raise EnvironmentFailure(f"out of memory in task {key}" + (f" ({size})" if size
                                                                       else "")
                                     + "; free memory, or ask for less (eclipsebench.limits), "
                                       "and rerun")
    for exc in failures.values():
        if isinstance(exc, InputError):
            raise exc
    raise TaskFailed(failures)


def _blocked(task: Task, failed: set[str]) -> bool:
    return any(d in failed for d in task.deps)


def _finish(task: Task, by_key: dict[str, Task], hashes: _Hashes) -> None:
    missing = [str(p) for p in task.outputs if not Path(p).exists()]
    if missing:
        raise RuntimeError(f"task {task.key} finished without writing {', '.join(missing)}")
    _write_stamp(task, by_key, hashes)


def _is_fatal(exc: BaseException) -> bool:
    """An environment failure: every other task would meet it too, so the run stops."""
    return isinstance(exc, (EnvironmentFailure, MemoryError))


#: File times come from the kernel's coarse clock (a few ms behind ``time.time_ns``).
_MTIME_SLACK_NS = 50_000_000


@dataclass
class _Run:
    """The state of one invocation of :func:`run_tasks` shared by its executors."""

    by_key: dict[str, Task]
    done: set[str]
    bars: _Bars
    report: RunReport
    hashes: _Hashes
    keep_going: bool
    root: str | None = None
    failures: dict[str, BaseException] = field(default_factory=dict)
    #: key -> time.time_ns() at submission, for the tasks not settled yet
    in_flight: dict[str, int] = field(default_factory=dict)

    @property
    def stopped(self) -> bool:
        """Whether no more tasks should start (a failure without keep_going, or a fatal one)."""
        return bool(self.failures) and (not self.keep_going
                                         or any(map(_is_fatal, self.failures.values())))

    def settle(self, key: str, outcome: Callable[[], Any]) -> bool:
        """Record a task's outcome (its timing, its stamp) or its failure; True if it succeeded."""
        task = self.by_key[key]
        try:
            timing = outcome()  # an interrupt here leaves the task in flight
            self.in_flight.pop(key, None)
            self.report.record(key, timing)
            _finish(task, self.by_key, self.hashes)
        except Exception as exc:  # collected and re-raised after the others ran
            self.in_flight.pop(key, None)
            self.failures[key] = exc
            if not _is_fatal(exc):  # said once, by whoever catches it
                log.error("task %s failed: %s: %s", key, type(exc).__name__, exc)
            return False
        self.done.add(key)
        self.report.ran.append(key)
        self.bars.update(task.stage)
        return True

    def stamp_written_in_flight(self) -> None:
        """After an interrupt: stamp the tasks whose outputs were all written since submission.

        Each output is written atomically, the declared last output last, so
        a last output newer than the task's submission that the task's check
        accepts was written whole by that task. Without its stamp the task
        would be redone once by the next run.
        """
        for key, submitted_ns in list(self.in_flight.items()):
            task = self.by_key[key]
            with contextlib.suppress(OSError):
                if os.stat(task.outputs[-1]).st_mtime_ns < submitted_ns - _MTIME_SLACK_NS:
                    continue
                if not all(Path(p).is_file() for p in task.outputs):
                    continue
                if task.check is not None and not task.check(*task.outputs):
                    continue
                _write_stamp(task, self.by_key, self.hashes)


def _run_sync(run: _Run, todo: list[str]) -> None:
    for key in todo:
        task = run.by_key[key]
        if _blocked(task, set(run.failures)) or not all(d in run.done for d in task.deps):
            continue  # a dependency failed: not run
        run.in_flight[key] = time.time_ns()
        run.settle(key, functools.partial(_call, task.func, task.args, run.root))
        raise_pending_interrupt()
        if run.stopped:
            break


def _run_dask(run: _Run, todo: list[str], *, workers: int, scheduler: str | None,
              options: ClusterOptions | None) -> None:
    from distributed import as_completed  # heavy, optional: only with a cluster

    client, cluster, run.report.executor = open_client(workers, scheduler, options)
    waiting = list(todo)
    futures = {}
    # Dask runs the queued task of highest priority first: the plan's order (a campaign puts a
    # long joint fit that waits for no reduction before the reductions), not the order in
    # which dependencies happened to finish
    rank = {k: len(run.by_key) - i for i, k in enumerate(run.by_key)}
    try:
        ac = as_completed()

        def submit_ready() -> None:
            for key in list(waiting):
                task = run.by_key[key]
                if _blocked(task, set(run.failures)):
                    waiting.remove(key)
                    continue
                if all(d in run.done for d in task.deps):
                    waiting.remove(key)
                    # no retries: a task that raises would raise again; a task whose
                    # worker died is rescheduled by Dask itself (allowed-failures)
                    run.in_flight[key] = time.time_ns()
                    fut = client.submit(_call_pickled, cloudpickle.dumps(task.func), task.args,
                                        run.root, is_quiet(), key=f"{key}#{time.time_ns()}",
                                        pure=False, priority=rank[key])
                    futures[fut.key] = key
                    ac.add(fut)

        submit_ready()
        for fut in ac:
            key = futures.pop(fut.key)
            run.settle(key, fut.result)
            raise_pending_interrupt()
            if run.stopped:
                client.cancel(list(ac.futures))  # the others would meet the same failure
                break
            submit_ready()
    finally:
        close_cluster(client, cluster)
