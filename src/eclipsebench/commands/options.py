"""Argument types and shared options for subcommands."""

from __future__ import annotations

import argparse
import math

from ..io.paths import check_output_path

__all__ = ["check_output_path", "finite_float", "positive_float", "nonnegative_float",
           "open_unit_float", "positive_int", "method_list", "add_config_options"]


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


def positive_int(minimum: int = 1):
    """An argparse type accepting integers >= ``minimum``."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected an integer >= {minimum}, got {text}")
        return value
    return parse


def method_list(text: str) -> list[str]:
    """An argparse type for ``a,b,c``: a non-empty list of method names."""
    names = [m.strip() for m in text.split(",") if m.strip()]
    if not names:
        raise argparse.ArgumentTypeError("expected a comma-separated list of method names")
    return names


def add_config_options(parser: argparse.ArgumentParser, *, config_positional: bool = True) -> None:
    """CONFIG and ``--set section.key=value``, shared by commands that read a config."""
    if config_positional:
        parser.add_argument("config", nargs="?", metavar="CONFIG",
                            help="challenge configuration (TOML); default: the built-in XO-3b challenge")
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="SECTION.KEY=VALUE",
                        help="override one configuration value (repeatable), e.g. "
                             "--set simulation.noise_model=iracsim2015")
