"""Exceptions that the command line turns into one clear line and an exit code.

Anything a user can get wrong (a file, a key, an option, a parameter value)
raises :class:`InputError` or one of its subclasses with a message that names
the file, key or option and says what was expected (exit code 2). A failure
of the machine rather than of the input (a full disk, a folder that became
unwritable, memory exhausted) is an :class:`EnvironmentFailure` (exit code
:data:`EXIT_ENVIRONMENT`). Everything else is an internal error (exit code 1).
"""

from __future__ import annotations

import errno
import signal

#: Exit code of an environment failure (disk full, permission, memory): not bad input.
EXIT_ENVIRONMENT = 3

#: ``errno`` values of a write that fail because of the machine, not of the input.
ENVIRONMENT_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EACCES,
                                errno.EPERM, errno.EROFS, errno.EIO, errno.ENOMEM})


class InputError(Exception):
    """Bad input: a file, option, configuration key or parameter value.

    The message is a single line that names what is wrong and what was
    expected; the CLI prints it without a traceback and exits with code 2.
    """


class ConfigError(InputError):
    """A configuration value is unknown, of the wrong type or out of range."""

    def __init__(self, key: str, problem: str):
        self.key = key
        self.problem = problem
        super().__init__(f"config key '{key}': {problem}")

    def __reduce__(self):  # raised in a Dask worker, re-raised in the run's process
        return type(self), (self.key, self.problem)


class DataError(InputError):
    """A data file is unreadable, truncated, or lacks what is needed."""

    def __init__(self, path: object, problem: str):
        self.path = str(path)
        self.problem = problem
        super().__init__(f"{self.path}: {problem}")

    def __reduce__(self):  # raised in a Dask worker, re-raised in the run's process
        return type(self), (self.path, self.problem)


class EnvironmentFailure(Exception):
    """The machine failed the run: no space left, permission lost, memory exhausted.

    The message is one line naming the folder (and the bytes needed when
    known); the CLI prints it once and exits with :data:`EXIT_ENVIRONMENT`.
    The engine stops a run at the first one (every other task would fail the
    same way).

    Parameters
    ----------
    message : str
        The one line, naming the folder or the step.
    folder : str, optional
        The folder that could not be written.
    bytes_needed : int, optional
        The size of the write that failed, when known.
    """

    def __init__(self, message: str, folder: str | None = None,
                 bytes_needed: int | None = None):
        self.folder = folder
        self.bytes_needed = bytes_needed
        super().__init__(message)

    def __reduce__(self):  # pickled across Dask workers with its attributes
        return type(self), (str(self), self.folder, self.bytes_needed)


class Interrupted(KeyboardInterrupt):
    """A KeyboardInterrupt that remembers the signal (SIGINT, SIGTERM) that raised it."""

    def __init__(self, signum: int):
        self.signum = signum
        super().__init__(signal.Signals(signum).name)


#: The interrupt signals received and not yet honoured (see :func:`raise_pending_interrupt`).
_pending_signals: list[int] = []


def note_interrupt(signum: int) -> None:
    """Remember that ``signum`` asked the command to stop (called by the CLI's signal handler)."""
    _pending_signals.append(int(signum))


def pending_interrupt() -> int | None:
    """The first interrupt signal received and not cleared, else None."""
    return _pending_signals[0] if _pending_signals else None


def clear_interrupts() -> None:
    """Forget the interrupts received (the CLI does at the start and end of a command)."""
    _pending_signals.clear()


def raise_pending_interrupt() -> None:
    """Raise :class:`Interrupted` again if an interrupt was received and swallowed.

    A signal handler raises where the main thread happens to be; code that
    catches everything (emcee's own ``random_state`` setter, which
    :mod:`eclipsebench.fit.mcmc`'s sampler replaces, has a bare ``except: pass``;
    an exception in ``__del__`` is only printed) can swallow
    it, and the run would go on to the end. The engine calls this between
    tasks, so such a run still stops at the next task boundary.
    """
    if _pending_signals:
        raise Interrupted(_pending_signals[0])


def require(condition: bool, name: str, expected: str) -> None:
    """Raise :class:`InputError` naming ``name`` unless ``condition`` holds.

    Parameters
    ----------
    condition : bool
        The check that must hold.
    name : str
        The option, key or parameter to name in the message.
    expected : str
        What the value should have been, e.g. ``"a positive number"``.
    """
    if not condition:
        raise InputError(f"{name}: expected {expected}")
