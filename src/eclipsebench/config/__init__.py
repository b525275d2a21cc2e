"""Configuration: one TOML file, frozen dataclasses, validated at the edge.

The defaults of every section are the built-in XO-3b data challenge, so an
empty file (or no file) is that challenge; ``eclipsebench config --show``
prints it. Each section lives in the module of the stage that owns it.
Built-in configurations (``eclipsebench/data/configs/<name>.toml``, e.g.
``xo3b-phase-curve``) are taken by name wherever a file is
(:func:`resolve_config`).
"""

from __future__ import annotations

import os
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any

from ..astro.catalogue import system_for
from ..errors import ConfigError, InputError
from .base import (
    apply_overrides,
    apply_sections,
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
           "from_mapping", "parse_override", "apply_overrides", "replace", "builtin_config_names",
           "resolve_config"]

#: Folder of the built-in configurations (package data), one ``<name>.toml`` each.
BUILTIN_CONFIG_DIR = "configs"


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


def builtin_config_names() -> list[str]:
    """Names of the built-in configurations (``eclipsebench/data/configs/<name>.toml``).

    Examples
    --------
    >>> "xo3b-phase-curve" in builtin_config_names()
    True
    """
    folder = resources.files("eclipsebench.data").joinpath(BUILTIN_CONFIG_DIR)
    return sorted(f.name[:-5] for f in folder.iterdir() if f.name.endswith(".toml"))


def resolve_config(path: str | os.PathLike[str]) -> tuple[str, str | None]:
    """Where configuration ``path`` comes from: ``(label, text)``.

    A file that exists is read by :func:`load_config` itself (``text`` is
    None); otherwise ``path`` may name a built-in configuration
    (:func:`builtin_config_names`), whose TOML text is returned with the
    label ``"built-in configuration <name>"``.

    Raises
    ------
    eclipsebench.errors.InputError
        One line when ``path`` is neither a file nor a built-in name, listing
        the built-in names.

    Examples
    --------
    >>> label, text = resolve_config("xo3b-phase-curve")
    >>> label, 'event = "phase-curve"' in text
    ('built-in configuration xo3b-phase-curve', True)
    """
    p = Path(path)
    if p.exists():
        return str(p), None
    names = builtin_config_names()
    name = str(path).strip()
    if name in names:
        text = (resources.files("eclipsebench.data").joinpath(BUILTIN_CONFIG_DIR)
                .joinpath(f"{name}.toml").read_text("utf-8"))
        return f"built-in configuration {name}", text
    raise InputError(f"{path}: no such configuration file or built-in configuration "
                     f"(built-in: {', '.join(names)})")


def load_config(path: str | os.PathLike[str] | None = None, overrides: list[str] | None = None,
                sections: Mapping[str, Mapping[str, Any]] | None = None) -> Config:
    """Read ``path`` (or the defaults), set ``sections``, apply ``--set`` overrides, validate.

    ``path`` is a TOML file or the name of a built-in configuration
    (:func:`resolve_config`; a file of that name wins). ``sections`` holds
    Python values by section (``{"challenge": {"epochs": 2}}``,
    :func:`~eclipsebench.config.base.apply_sections`); the text overrides
    come last.

    Raises
    ------
    eclipsebench.errors.InputError
        With one line naming the file or the dotted key when anything is wrong.

    Examples
    --------
    >>> load_config("xo3b-phase-curve").observation.event
    'phase-curve'
    """
    mapping: dict[str, Any] = {}
    if path is not None:
        label, text = resolve_config(path)
        if text is None:
            mapping = load_toml(path)
        else:
            try:
                mapping = tomllib.loads(text)
            except tomllib.TOMLDecodeError as exc:  # a packaging error, named all the same
                raise InputError(f"{label}: not valid TOML ({exc})") from None
            path = label
    mapping = apply_overrides(apply_sections(mapping, sections or {}), list(overrides or []))
    config = from_mapping(Config, mapping)
    named_by_caller = ("name" in (sections or {}).get("system", {})
                       or any(o.split("=", 1)[0].strip() == "system.name"
                              for o in overrides or []))
    _check_system(config, None if named_by_caller else path)
    return config


def _check_system(config: Config, path: str | os.PathLike[str] | None) -> None:
    """The planet must be in a catalogue (or given by value, ``[system.planet]``): one line
    naming ``system.name``, the catalogues searched and the file that set the name (``path``;
    None when the caller set it)."""
    try:
        system_for(config.system)
    except InputError as exc:
        error = ConfigError("system.name", str(exc))
        if path is not None:
            raise InputError(f"{path}: {error}") from None
        raise error from None
