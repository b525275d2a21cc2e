"""The ``eclipsebench`` command: parses arguments, calls the API, prints.

Each subcommand is a module in :mod:`eclipsebench.commands` that defines
``NAME``, ``HELP``, ``add_arguments(parser)``, ``run(args) -> dict`` and,
optionally, ``format_text(result) -> str``. Commands return a plain dict of
numbers; ``--json`` prints it as one JSON object on stdout, otherwise
``format_text`` (or a key: value listing) is printed.

Exit codes: 0 success; 2 bad input or usage (one line on stderr naming the
file, key or option and what was expected); 3 an environment failure (a
full disk or quota, a folder that became unwritable, memory exhausted: one
line naming the folder, and the bytes needed when known, or the step that
ran out of memory; a run stops at the first); 130 interrupted by Ctrl-C
(SIGINT) and 143 by SIGTERM (what a batch scheduler sends at its wall-time
limit): one line on stderr, whatever a library prints while it unwinds is
dropped, the run's lock is released and the same command resumes; 1
unexpected internal error (``--debug`` shows the traceback). A command that
fails or is interrupted leaves no folder it created empty.
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import importlib
import json
import os
import signal
import sys
import threading
from collections.abc import Iterator, Sequence
from typing import Any, NoReturn

from . import __version__
from .errors import (
    EXIT_ENVIRONMENT,
    EnvironmentFailure,
    InputError,
    Interrupted,
    clear_interrupts,
    note_interrupt,
    raise_pending_interrupt,
)
from .io.paths import missing_folders, remove_empty_folders
from .io.plain import json_safe
from .progress import command_scope, configure

# Listed in the order ``--help`` shows them.
COMMAND_MODULES = (
    "run",
    "campaign",
    "simulate",
    "photometry",
    "reduce",
    "stats",
    "lightcurve",
    "trust",
    "photon_limit",
    "config_cmd",
)


class _HelpFormatter(argparse.HelpFormatter):
    """Appends "(default: X)" only when X is informative and the help does not say it."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        default = action.default
        if ("default" in text.lower() or default is None or default is argparse.SUPPRESS
                or default is False or default == [] or action.option_strings == []):
            return text
        return f"{text} (default: {default})"


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors are one line and exit code 2."""

    def error(self, message: str) -> NoReturn:  # noqa: D401 - argparse API
        self.exit(2, f"{self.prog}: error: {message}\n")


def _commands():
    for name in COMMAND_MODULES:
        try:
            yield importlib.import_module(f"{__package__}.commands.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{__package__}.commands.{name}":
                raise


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every available subcommand."""
    parser = _Parser(prog="eclipsebench",
                     description="Simulate, reduce and score Spitzer/IRAC eclipse photometry "
                                 "(Ingalls et al. 2016, AJ 152, 44).")
    parser.add_argument("--version", action="version", version=f"eclipsebench {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for module in _commands():
        p = sub.add_parser(module.NAME, help=module.HELP, description=module.HELP,
                           formatter_class=_HelpFormatter)
        module.add_arguments(p)
        p.add_argument("--json", action="store_true",
                       help="print one JSON object with the results on stdout")
        p.add_argument("--quiet", action="store_true",
                       help="errors and the answer only: no progress bars, log messages or "
                            "warnings (the workers' too)")
        p.add_argument("--debug", action="store_true",
                       help="show the full traceback of an internal error")
        p.set_defaults(_module=module)
    return parser


def _format_default(result: dict) -> str:
    width = max((len(str(k)) for k in result), default=0)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in result.items())


class _Silenced:
    """A text stream that drops everything (stands in for stdout/stderr after Ctrl-C)."""

    encoding = "utf-8"

    def write(self, text: str) -> int:
        return len(text)

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False


#: The signals that interrupt a command: Ctrl-C, and what a batch scheduler sends.
INTERRUPT_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def _one_line_interrupt() -> Iterator[None]:
    """On Ctrl-C or SIGTERM, silence stdout and stderr until the interrupt reaches :func:`main`.

    Both signals raise a KeyboardInterrupt (:class:`Interrupted`), so the
    same clean-up runs (the run's lock released, its Dask cluster closed).
    Libraries print while a KeyboardInterrupt unwinds through them (emcee
    prints the traceback of the likelihood call it was in); the user should
    see one line. The streams are silenced at the file-descriptor level too,
    so logging handlers that hold the original streams are quiet as well.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    saved: dict[str, Any] = {}

    def handler(signum, frame):
        if not saved:
            saved["stdout"], saved["stderr"] = sys.stdout, sys.stderr
            with contextlib.suppress(Exception):
                sys.stdout.flush()
                sys.stderr.flush()
            fds = {}
            with contextlib.suppress(OSError):
                devnull = os.open(os.devnull, os.O_WRONLY)
                for fd in (1, 2):
                    fds[fd] = os.dup(fd)
                    os.dup2(devnull, fd)
                os.close(devnull)
            saved["fds"] = fds
            sys.stdout = sys.stderr = _Silenced()
        note_interrupt(signum)   # raised again between tasks if something swallows this one
        raise Interrupted(signum)

    previous = {signum: signal.signal(signum, handler) for signum in INTERRUPT_SIGNALS}
    try:
        yield
    finally:
        for signum, old in previous.items():
            signal.signal(signum, old)
        clear_interrupts()
        if saved:
            for fd, copy in saved["fds"].items():
                with contextlib.suppress(OSError):
                    os.dup2(copy, fd)
                    os.close(copy)
            sys.stdout, sys.stderr = saved["stdout"], saved["stderr"]


def _memory_step(exc: BaseException) -> str:
    """The innermost eclipsebench function a MemoryError came out of (``module.function``)."""
    step = ""
    tb = exc.__traceback__
    while tb is not None:
        module = tb.tb_frame.f_globals.get("__name__", "")
        if module.startswith(__package__ + ".") and module != __name__:
            step = f"{module}.{tb.tb_frame.f_code.co_name}"
        tb = tb.tb_next
    return step or "this command"


def _environment_line(exc: BaseException) -> str:
    """One line for an environment failure: its own message, or the step out of memory."""
    if isinstance(exc, MemoryError):
        size = " ".join(str(exc).split())
        return (f"out of memory in {_memory_step(exc)}" + (f" ({size})" if size else "")
                + "; free memory, or ask for less (eclipsebench.limits), and rerun")
    return " ".join(str(exc).split())


def _usage_line(parser: argparse.ArgumentParser) -> str:
    names = ", ".join(module.NAME for module in _commands())
    return (f"{parser.prog}: error: a command is required; usage: {parser.prog} COMMAND "
            f"[options] with COMMAND one of {names} ({parser.prog} --help describes them)")


#: OpenBLAS (numpy's and scipy's BLAS) keeps each of its threads spinning for about 2**28
#: cycles after a call before it sleeps (its default ``OPENBLAS_THREAD_TIMEOUT``, 28). A fit
#: makes hundreds of small BLAS calls, so on 2 cores its idle threads spun through the whole
#: fit: ``reduce --method bliss`` used 3.9 s of CPU for 1.9 s of work (issue 40). 4, the
#: least, puts them to sleep at once; the number of threads, hence how each sum is split and
#: every result's bytes, is unchanged. OpenBLAS reads it when it loads, so it is set before
#: any command imports numpy; a value in the environment is kept.
BLAS_THREAD_TIMEOUT = ("OPENBLAS_THREAD_TIMEOUT", "4")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``eclipsebench`` console script; returns the exit code.

    Called without ``argv`` (the console script, ``python -m eclipsebench``), it runs the
    process's own command, after which the interpreter exits: everything left is then frozen
    out of the garbage collector (:func:`gc.freeze`), whose last full pass over the million
    objects numpy, scipy, astropy and numba leave cost about 0.3 s of CPU at exit (issue 40).
    Every file a command writes is written and closed before it returns. ``--quiet`` turns
    logging off below errors for the command only (:func:`~eclipsebench.progress.command_scope`).
    """
    with command_scope():
        code = _main(argv)
    if argv is None:
        gc.freeze()
    return code


def _main(argv: Sequence[str] | None) -> int:
    os.environ.setdefault(*BLAS_THREAD_TIMEOUT)
    parser = build_parser()
    args = parser.parse_args(argv)
    args._argv = list(sys.argv[1:] if argv is None else argv)   # shown on a trust page
    if args.command is None:
        print(_usage_line(parser), file=sys.stderr)
        return 2
    module = args._module
    configure(quiet=args.quiet or args.json)
    created = [folder for name in ("out", "plot")
               for folder in missing_folders(getattr(args, name, None))]
    clear_interrupts()
    try:
        with _one_line_interrupt():
            result = module.run(args)
            raise_pending_interrupt()   # one that something swallowed: still an interrupt
    except InputError as exc:
        remove_empty_folders(created)
        print(f"eclipsebench {module.NAME}: error: {' '.join(str(exc).split())}",
              file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        remove_empty_folders(created)
        signum = getattr(exc, "signum", signal.SIGINT)
        by = " by SIGTERM" if signum == signal.SIGTERM else ""
        print(f"eclipsebench {module.NAME}: interrupted{by}; rerun the same command to resume",
              file=sys.stderr)
        return 128 + int(signum)
    except (EnvironmentFailure, MemoryError) as exc:
        remove_empty_folders(created)
        print(f"eclipsebench {module.NAME}: error: {_environment_line(exc)}", file=sys.stderr)
        return EXIT_ENVIRONMENT
    except Exception as exc:  # the one place that turns a bug into exit code 1
        remove_empty_folders(created)
        if args.debug:
            raise
        text = " ".join(str(exc).split())
        print(f"eclipsebench {module.NAME}: internal error: {type(exc).__name__}: {text} "
              "(rerun with --debug for the traceback)", file=sys.stderr)
        return 1
    if result is None:
        return 0
    if args.json:
        text = json.dumps(json_safe(result), sort_keys=False)
    else:
        text = getattr(module, "format_text", _format_default)(result)
    try:
        print(text)
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. piped into head: the reader has all it wanted
        with contextlib.suppress(OSError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
