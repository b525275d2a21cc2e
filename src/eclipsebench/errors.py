"""Exceptions that the command line turns into one clear line and exit code 2.

Anything a user can get wrong (a file, a key, an option, a parameter value)
raises :class:`InputError` or one of its subclasses with a message that names
the file, key or option and says what was expected. Everything else is an
internal error (exit code 1).
"""

from __future__ import annotations


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


class DataError(InputError):
    """A data file is unreadable, truncated, or lacks what is needed."""

    def __init__(self, path: object, problem: str):
        self.path = str(path)
        self.problem = problem
        super().__init__(f"{self.path}: {problem}")


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
