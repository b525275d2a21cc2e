"""Configuration: one TOML file, frozen dataclasses, validated at the edge.

The defaults of every section are the built-in XO-3b data challenge, so an
empty file (or no file) is that challenge; ``eclipsebench config --show``
prints it. Each section lives in the module of the stage that owns it.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from ..astro.catalogue import system_for
from ..errors import ConfigError, InputError
from .base import (
    apply_overrides,
    check,
    dump_toml,
    from_mapping,
    load_toml,
    parse_override,
    to_mapping,
)
from .photometry import PhotometrySection
from .reduce import ReduceSection
from .run import ChallengeSection, RunSection
from .simulation import ObservationSection, SimulationSection
from .system import SystemSection

__all__ = ["Config", "load_config", "default_config", "dump_toml", "to_mapping", "check",
           "from_mapping", "parse_override", "apply_overrides", "replace"]


@dataclass(frozen=True)
class Config:
    """The whole configuration of a challenge run, one field per TOML section."""

    challenge: ChallengeSection = field(default_factory=ChallengeSection)
    system: SystemSection = field(default_factory=SystemSection)
    observation: ObservationSection = field(default_factory=ObservationSection)
    simulation: SimulationSection = field(default_factory=SimulationSection)
    photometry: PhotometrySection = field(default_factory=PhotometrySection)
    reduce: ReduceSection = field(default_factory=ReduceSection)
    run: RunSection = field(default_factory=RunSection)


def default_config() -> Config:
    """The built-in XO-3b challenge configuration."""
    return Config()


def load_config(path: str | Path | None = None, overrides: list[str] | None = None) -> Config:
    """Read ``path`` (or the defaults), apply ``--set`` overrides, validate.

    Raises
    ------
    eclipsebench.errors.InputError
        With one line naming the file or the dotted key when anything is wrong.
    """
    mapping: dict[str, Any] = load_toml(path) if path is not None else {}
    mapping = apply_overrides(mapping, list(overrides or []))
    config = from_mapping(Config, mapping)
    _check_system(config, path, list(overrides or []))
    return config


def _check_system(config: Config, path: str | Path | None, overrides: list[str]) -> None:
    """The planet must be in a catalogue (or given by value, ``[system.planet]``): one line
    naming ``system.name``, the catalogues searched and where the name was set."""
    try:
        system_for(config.system)
    except InputError as exc:
        by_override = any(o.split("=", 1)[0].strip() == "system.name" for o in overrides)
        error = ConfigError("system.name", str(exc))
        if path is not None and not by_override:
            raise InputError(f"{path}: {error}") from None
        raise error from None
