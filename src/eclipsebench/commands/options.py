"""Argument types and shared options for subcommands."""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

from ..astro.catalogue import (
    PLANET_KEYS,
    REQUIRED_KEYS,
    PlanetSystem,
    planet_table_from_pairs,
    system_for,
    system_from_pairs,
)
from ..config import builtin_config_names, load_config
from ..config.base import parse_override
from ..errors import InputError
from ..io.paths import check_output_path
from ..limits import size_problem

__all__ = ["check_output_path", "finite_float", "positive_float", "nonnegative_float",
           "open_unit_float", "positive_int", "method_list", "add_config_options",
           "add_planet_options", "planet_overrides", "planet_from_args", "method_options"]


def _number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def finite_float():
    """An argparse type accepting any finite number (not nan, not inf)."""
    return _number


def positive_float():
    """An argparse type accepting numbers > 0 (argparse names the option)."""
    def parse(text: str) -> float:
        value = _number(text)
        if value <= 0:
            raise argparse.ArgumentTypeError(f"expected a positive number, got {text}")
        return value
    return parse


def nonnegative_float():
    """An argparse type accepting numbers >= 0."""
    def parse(text: str) -> float:
        value = _number(text)
        if value < 0:
            raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text}")
        return value
    return parse


def open_unit_float():
    """An argparse type accepting numbers strictly between 0 and 1."""
    def parse(text: str) -> float:
        value = _number(text)
        if not 0 < value < 1:
            raise argparse.ArgumentTypeError(f"expected a number in (0, 1), got {text}")
        return value
    return parse


def positive_int(minimum: int = 1, maximum: int | None = None):
    """An argparse type accepting integers >= ``minimum`` (and <= ``maximum``, a stated limit).

    ``maximum`` is one of :mod:`eclipsebench.limits`' constants: a value above
    it is refused while the arguments are parsed, before any work.
    """
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected an integer >= {minimum}, got {text}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(size_problem(value, maximum))
        return value
    return parse


def method_list(text: str) -> list[str]:
    """An argparse type for ``a,b,c``: a non-empty list of method names."""
    names = [m.strip() for m in text.split(",") if m.strip()]
    if not names:
        raise argparse.ArgumentTypeError("expected a comma-separated list of method names")
    return names


def method_options(items: list[str], method: str | None = None) -> dict[str, dict[str, Any]]:
    """``--option [METHOD.]KEY=VALUE`` (repeatable), the one grammar of every command.

    The value is read as a TOML literal (as ``--set``'s), else kept as text.
    ``METHOD.`` may be left out when the command runs one ``method``
    (``reduce``); with several (``trust``) it is required.

    Returns
    -------
    dict
        ``{method: {key: value}}``.

    Examples
    --------
    >>> method_options(["kr-data.k=40", "gp.bin_seconds=30"])
    {'kr-data': {'k': 40}, 'gp': {'bin_seconds': 30}}
    >>> method_options(["k=40"], method="kr-data")
    {'kr-data': {'k': 40}}
    """
    grammar = "[METHOD.]KEY=VALUE" if method is not None else "METHOD.KEY=VALUE"
    out: dict[str, dict[str, Any]] = {}
    for item in items:
        head, sep, raw = item.partition("=")
        name, dot, key = head.strip().rpartition(".")
        if not sep or not key or (dot and not name) or (not dot and method is None):
            raise InputError(f"--option {item!r}: expected {grammar}")
        name = name if dot else str(method)
        if method is not None and name != method:
            raise InputError(f"--option {item!r}: names method {name!r}, not --method "
                             f"{method!r}")
        out.setdefault(name, {})[key] = parse_override(f"{key}={raw}")[1]
    return out


def add_config_options(parser: argparse.ArgumentParser, *, config_positional: bool = True) -> None:
    """CONFIG and ``--set section.key=value``, shared by commands that read a config."""
    if config_positional:
        parser.add_argument("config", nargs="?", metavar="CONFIG",
                            help="challenge configuration: a TOML file or a built-in name ("
                                 + ", ".join(builtin_config_names())
                                 + "); default: the built-in XO-3b challenge")
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="SECTION.KEY=VALUE",
                        help="override one configuration value (repeatable), e.g. "
                             "--set simulation.noise_model=iracsim2015")


# ------------------------------------------------------------------ the planet
def add_planet_options(parser: argparse.ArgumentParser) -> None:
    """``--catalogue FILE`` and ``--planet KEY=VALUE``, shared by every command that takes a planet.

    Read back with :func:`planet_overrides` (commands that load a configuration)
    or :func:`planet_from_args`.
    """
    parser.add_argument("--catalogue", metavar="FILE.toml", default=None,
                        help="a user catalogue of systems (TOML, as the built-in one), searched "
                             "before the built-in catalogue ([system] catalogue)")
    parser.add_argument("--planet", action="append", default=[], metavar="KEY=VALUE",
                        help="a planet in no catalogue, one value per option (repeatable): "
                             "name=... and " + ", ".join(REQUIRED_KEYS) + " (required), "
                             + ", ".join(k for k in PLANET_KEYS[1:] if k not in REQUIRED_KEYS)
                             + " (optional; ld_quadratic=U1,U2); checked as a catalogue row "
                             "([system.planet])")


def _toml(value: Any) -> str:
    """A TOML literal of a string, a number or a list of numbers (for ``--set``-style overrides)."""
    if isinstance(value, str):
        return json.dumps(value)  # a JSON string is a valid TOML basic string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(float(value))


def planet_overrides(args: argparse.Namespace, name: str | None = None,
                     label: str = "--system") -> list[str]:
    """The ``[system]`` overrides (``section.key=value``) of ``--catalogue``, ``--planet`` and a name.

    ``name`` is the planet a command was given by name (``label`` names that
    argument in errors); it cannot be given with ``--planet``. ``--planet``
    pairs are checked here, so that a missing or bad value is one line naming
    ``--planet``; the configuration then holds them as ``system.planet``.
    """
    out = []
    catalogue = getattr(args, "catalogue", None)
    pairs = getattr(args, "planet", None) or []
    if catalogue is not None:
        if not str(catalogue).strip():
            raise InputError("--catalogue: expected the path of a TOML catalogue")
        out.append(f"system.catalogue={_toml(str(catalogue))}")
    if pairs:
        if name is not None:
            raise InputError(f"{label} {name!r} and --planet: give the planet by name or by its "
                             "values, not both")
        system_from_pairs(pairs)  # every check, one line naming --planet
        planet_name, table = planet_table_from_pairs(pairs)
        inline = ", ".join(f"{key} = {_toml(value)}" for key, value in table.items())
        out += [f"system.name={_toml(planet_name)}", f"system.planet={{{inline}}}"]
    elif name is not None:
        out.append(f"system.name={_toml(name)}")
    return out


def planet_from_args(args: argparse.Namespace, name: str | None = None,
                     label: str = "SYSTEM") -> PlanetSystem:
    """The planet of a command that takes no configuration: ``name``, ``--catalogue``, ``--planet``.

    Resolved as ``[system]`` is (the built-in challenge's planet when none is
    given), so an unknown name is the same one line naming ``system.name``
    and the catalogues searched.
    """
    cfg = load_config(None, planet_overrides(args, name, label))
    return system_for(cfg.system)


def run_overrides(args) -> list[str]:
    """``[run]`` overrides of a runner's ``--methods``, ``--profiles`` and ``--workers``
    (each left to the configuration when not given)."""
    extra = []
    if args.methods is not None:
        extra.append("run.methods=[" + ", ".join(f'"{m}"' for m in args.methods) + "]")
    if args.profiles is not None:
        extra.append("run.profiles=[" + ", ".join(f'"{p}"' for p in args.profiles) + "]")
    if args.workers is not None:
        extra.append(f"run.workers={args.workers}")
    return extra
