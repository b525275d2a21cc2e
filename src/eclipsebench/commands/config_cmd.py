"""``eclipsebench config``: show or check a challenge configuration."""

from __future__ import annotations

import argparse

from ..astro.catalogue import get_system
from ..config import dump_toml, load_config, to_mapping
from ..errors import InputError
from .options import add_config_options

NAME = "config"
HELP = "Print the effective configuration (defaults: the built-in XO-3b challenge) or check a file."


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_config_options(p)
    p.add_argument("--show", action="store_true",
                   help="print the effective configuration as TOML (the default action)")


def _check_system(config, args: argparse.Namespace) -> None:
    """The planet must be in the catalogue: name ``system.name`` and where it was set."""
    try:
        get_system(config.system.name, config.system.catalogue or None)
    except InputError as exc:
        source = ("--set" if any(o.split("=", 1)[0].strip() == "system.name"
                                 for o in args.overrides) else args.config)
        where = f"{source}: " if source else ""
        raise InputError(f"{where}config key 'system.name': {exc}") from None


def run(args: argparse.Namespace) -> dict:
    config = load_config(args.config, args.overrides)
    _check_system(config, args)
    return to_mapping(config)


def format_text(result: dict) -> str:
    return dump_toml(result).rstrip("\n")
