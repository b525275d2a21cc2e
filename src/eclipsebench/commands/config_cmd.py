"""``eclipsebench config``: show or check a challenge configuration."""

from __future__ import annotations

import argparse

from ..config import dump_toml, load_config, to_mapping
from .options import add_config_options, add_planet_options, planet_overrides

NAME = "config"
HELP = "Print the effective configuration (defaults: the built-in XO-3b challenge) or check a file."


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_config_options(p)
    add_planet_options(p)
    p.add_argument("--show", action="store_true",
                   help="print the effective configuration as TOML (the default action)")


def run(args: argparse.Namespace) -> dict:
    config = load_config(args.config, args.overrides + planet_overrides(args))
    return to_mapping(config)


def format_text(result: dict) -> str:
    return dump_toml(result).rstrip("\n")
