"""Progress bars and logging that stay out of the way.

Bars are drawn on stderr only when it is a terminal and the user did not ask
for quiet; under CI, in pipes and with ``--quiet`` or ``--json`` they vanish.
Off a terminal (a batch job, ``run ... > log 2>&1``) long work reports through
:class:`ProgressLines` instead: a line when a stage is done and, at most once
a minute (and at least once a minute while work is running), a line with the
tasks done out of the total.
"""

from __future__ import annotations

import contextlib
import logging
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping

__all__ = ["configure", "progress", "get_logger", "bars_enabled", "lines_enabled",
           "ProgressLines", "is_quiet", "errors_only", "command_scope"]

_state = {"quiet": False}


def configure(*, quiet: bool = False, verbose: bool = False) -> None:
    """Set the process-wide quiet flag and the logging level (CLI only).

    Python warnings (a method plugin that failed to load, say) are logged as
    one line each (``WARNING eclipsebench.warnings: RuntimeWarning: ...``)
    instead of Python's two (the message, then the source line).

    Quiet (``--quiet``, ``--json``) leaves errors only, from every logger:
    eclipsebench's warnings, Python warnings and those of libraries with
    their own handlers (astropy's ``WARNING: ... [astropy...]``), here and,
    through :func:`errors_only`, in the processes that run the command's
    tasks. What changes how to read a result is written in the result
    itself (a method that refused an epoch in its JSON and the summary; a
    trust caution on stdout and its page), not only logged.
    """
    _state["quiet"] = bool(quiet)
    level = logging.DEBUG if verbose else (logging.ERROR if quiet else logging.INFO)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    logging.getLogger("eclipsebench").setLevel(level)
    # a level of the manager, not of a logger: astropy's logger, made when astropy is first
    # imported (after this), sets its own level and handler
    logging.disable(logging.WARNING if quiet else logging.NOTSET)
    warnings.showwarning = _log_warning


def is_quiet() -> bool:
    """Whether :func:`configure` asked for quiet (errors only) in this process."""
    return bool(_state["quiet"])


@contextlib.contextmanager
def command_scope() -> Iterator[None]:
    """Restore, after the body (one command), the quiet flag, the logging manager's level and
    eclipsebench's logger's level that :func:`configure` set for it, so a command called in a process that goes on (a test,
    a notebook) does not leave logging off."""
    ours = logging.getLogger("eclipsebench")
    quiet, disabled, level = _state["quiet"], logging.root.manager.disable, ours.level
    try:
        yield
    finally:
        _state["quiet"] = quiet
        logging.disable(disabled)
        ours.setLevel(level)


@contextlib.contextmanager
def errors_only(quiet: bool) -> Iterator[None]:
    """While the body runs, with ``quiet``, log errors only and Python warnings as log lines
    (as :func:`configure` does) in this process; the previous state is restored after it.

    For a task run where the command did not configure logging (a Dask worker, its own
    process, of a command run with ``--quiet``); without ``quiet`` nothing changes.
    """
    if not quiet:
        yield
        return
    previous, shown = logging.root.manager.disable, warnings.showwarning
    logging.disable(max(previous, logging.WARNING))
    warnings.showwarning = _log_warning   # Python's own would print them
    try:
        yield
    finally:
        logging.disable(previous)
        warnings.showwarning = shown


def _log_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """:func:`warnings.showwarning` as one log line."""
    get_logger("warnings").warning("%s: %s", category.__name__, " ".join(str(message).split()))


def bars_enabled() -> bool:
    """Whether a progress bar would be drawn now."""
    return not _state["quiet"] and sys.stderr.isatty()


def lines_enabled() -> bool:
    """Whether progress goes to log lines: not quiet and stderr not a terminal."""
    return not _state["quiet"] and not sys.stderr.isatty()


def progress(iterable: Iterable | None = None, *, desc: str = "", total: int | None = None,
             unit: str = "it", leave: bool = False):
    """A tqdm bar on stderr, disabled when quiet or when stderr is not a terminal."""
    # tqdm.std, not tqdm.auto: a bar is drawn only on a terminal (never in a notebook, whose
    # stderr is not one), where auto's choice is std anyway, and auto imports asyncio (0.05 s)
    from tqdm.std import tqdm  # about 0.05 s: not paid by `eclipsebench --help`

    return tqdm(iterable, desc=desc, total=total, unit=unit, leave=leave,
                disable=not bars_enabled(), file=sys.stderr, dynamic_ncols=True)


def get_logger(name: str) -> logging.Logger:
    """A logger under the ``eclipsebench`` namespace."""
    return logging.getLogger(name if name.startswith("eclipsebench") else f"eclipsebench.{name}")


class ProgressLines:
    """Tasks done out of the total as log lines, for a log file instead of a bar.

    ``update(stage)`` counts one task of ``stage`` done: the stage's last task
    writes "``stage``: N/N tasks done", and :meth:`tick` (called on every
    update, and every few seconds by the heartbeat thread of :meth:`start`)
    writes "progress: d / n tasks done (...)" when ``every_s`` has passed
    since the last such line: at most one a minute, and at least one a minute
    while the work runs. ``clock`` and ``emit`` are injectable for tests.

    Examples
    --------
    >>> now = [0.0]
    >>> lines = []
    >>> p = ProgressLines({"reduce": 3}, emit=lines.append, clock=lambda: now[0])
    >>> p.update("reduce"); now[0] = 61.0; p.update("reduce"); p.update("reduce")
    >>> lines
    ['3 tasks to run (reduce 3)', 'progress: 2 / 3 tasks done (reduce 2/3)', 'reduce: 3/3 tasks done']
    """

    def __init__(self, totals: Mapping[str, int], *, emit: Callable[[str], None] | None = None,
                 clock: Callable[[], float] = time.monotonic, every_s: float = 60.0):
        self.totals = dict(totals)
        self.done = dict.fromkeys(self.totals, 0)
        self.emit = emit or get_logger("progress").info
        self.clock = clock
        self.every_s = float(every_s)
        self.last = clock()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        stages = ", ".join(f"{s} {n}" for s, n in self.totals.items())
        self.emit(f"{sum(self.totals.values())} tasks to run ({stages})")

    def update(self, stage: str) -> None:
        """One task of ``stage`` done."""
        with self._lock:
            self.done[stage] += 1
            if self.done[stage] == self.totals[stage]:
                self.emit(f"{stage}: {self.totals[stage]}/{self.totals[stage]} tasks done")
        self.tick()

    def tick(self) -> None:
        """Write the tasks done / total if ``every_s`` has passed since the last such line."""
        with self._lock:
            now = self.clock()
            if now - self.last < self.every_s:
                return
            self.last = now
            stages = ", ".join(f"{s} {self.done[s]}/{n}" for s, n in self.totals.items()
                               if self.done[s] < n)
            self.emit(f"progress: {sum(self.done.values())} / {sum(self.totals.values())} "
                      f"tasks done ({stages})")

    def start(self, poll_s: float = 5.0) -> ProgressLines:
        """Tick every ``poll_s`` seconds in a daemon thread (a line a minute during long tasks)."""
        def beat():
            while not self._stop.wait(poll_s):
                self.tick()
        self._thread = threading.Thread(target=beat, name="eclipsebench-progress", daemon=True)
        self._thread.start()
        return self

    def close(self) -> None:
        """Stop the heartbeat."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
