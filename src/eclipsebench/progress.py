"""Progress bars and logging that stay out of the way.

Bars are drawn on stderr only when it is a terminal and the user did not ask
for quiet; under CI, in pipes and with ``--quiet`` or ``--json`` they vanish.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Iterable

from tqdm.auto import tqdm

__all__ = ["configure", "progress", "get_logger"]

_state = {"quiet": False}


def configure(*, quiet: bool = False, verbose: bool = False) -> None:
    """Set the process-wide quiet flag and the logging level (CLI only)."""
    _state["quiet"] = bool(quiet)
    level = logging.DEBUG if verbose else (logging.WARNING if quiet else logging.INFO)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    logging.getLogger("eclipsebench").setLevel(level)


def bars_enabled() -> bool:
    """Whether a progress bar would be drawn now."""
    return not _state["quiet"] and sys.stderr.isatty()


def progress(iterable: Iterable | None = None, *, desc: str = "", total: int | None = None,
             unit: str = "it", leave: bool = False):
    """A tqdm bar on stderr, disabled when quiet or when stderr is not a terminal."""
    return tqdm(iterable, desc=desc, total=total, unit=unit, leave=leave,
                disable=not bars_enabled(), file=sys.stderr, dynamic_ncols=True)


def get_logger(name: str) -> logging.Logger:
    """A logger under the ``eclipsebench`` namespace."""
    return logging.getLogger(name if name.startswith("eclipsebench") else f"eclipsebench.{name}")
