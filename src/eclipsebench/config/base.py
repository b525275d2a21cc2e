"""TOML to frozen dataclasses, validated at the edge.

A configuration *section* is a frozen dataclass. :func:`from_mapping` builds
one from a parsed TOML table and rejects unknown keys, wrong types and
out-of-range values with a :class:`~eclipsebench.errors.ConfigError` that
names the dotted key. Range checks live in each section's ``validate`` method
(called after construction) and use :func:`check`.

``--set section.key=value`` overrides are parsed by :func:`parse_override`:
the value is read as a TOML literal (``3``, ``2.5``, ``true``, ``"text"``,
``[1, 2]``); anything that is not a TOML literal is taken as a bare string.
Nothing is ever passed to ``eval``.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import os
import tomllib
import types
import typing
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal, get_args, get_origin, get_type_hints

from ..errors import ConfigError, InputError
from ..io.inputs import read_input_bytes
from ..limits import MAX_TEXT_FILE_BYTES

__all__ = ["from_mapping", "to_mapping", "check", "coerce", "parse_override", "apply_overrides",
           "load_toml", "dump_toml"]


def check(condition: bool, key: str, expected: str) -> None:
    """Raise :class:`ConfigError` for ``key`` unless ``condition`` holds."""
    if not condition:
        raise ConfigError(key, f"expected {expected}")


def _type_name(tp: Any) -> str:
    origin = get_origin(tp)
    if origin is Literal:
        return "one of " + ", ".join(repr(a) for a in get_args(tp))
    if origin in (list, tuple):
        args = get_args(tp)
        inner = _type_name(args[0]) if args else "value"
        return f"a list of {inner}"
    if origin is dict:
        return "a table"
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type_name(a) for a in get_args(tp) if a is not type(None))
    return {int: "an integer", float: "a number", str: "a string", bool: "true or false"}.get(
        tp, getattr(tp, "__name__", str(tp)))


def _coerce(value: Any, tp: Any, key: str) -> Any:
    origin = get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = get_args(tp)
        if value is None and type(None) in args:
            return None
        said = None
        for arg in args:
            if arg is type(None):
                continue
            try:
                return _coerce(value, arg, key)
            except ConfigError as exc:   # a list's own problem (an infinite item) is said
                if get_origin(arg) in (list, tuple) and isinstance(value, (list, tuple)):
                    said = said or exc
                continue
        raise said or ConfigError(key, f"expected {_type_name(tp)}, got {value!r}")
    if origin is Literal:
        if value not in get_args(tp):
            raise ConfigError(key, f"expected {_type_name(tp)}, got {value!r}")
        return value
    if origin is dict:
        if not isinstance(value, Mapping):
            raise ConfigError(key, f"expected a table, got {value!r}")
        _, inner = get_args(tp) or (str, Any)
        return {str(k): _coerce(v, inner, f"{key}.{k}") for k, v in value.items()}
    if origin in (list, tuple):
        if not isinstance(value, (list, tuple)):
            raise ConfigError(key, f"expected {_type_name(tp)}, got {value!r}")
        args = get_args(tp)
        inner = args[0] if args else Any
        items = tuple(_coerce(v, inner, f"{key}[{i}]") for i, v in enumerate(value))
        for i, item in enumerate(items):   # a list's numbers are finite: no inf, no nan
            if isinstance(item, float) and not math.isfinite(item):
                raise ConfigError(key, f"item {i} is {item!r}: expected finite numbers")
        return items
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        if not isinstance(value, Mapping):
            raise ConfigError(key, f"expected a table, got {value!r}")
        return from_mapping(tp, value, prefix=key)
    if tp is Any:
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(key, f"expected true or false, got {value!r}")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(key, f"expected an integer, got {value!r}")
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(key, f"expected a number, got {value!r}")
        return float(value)
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(key, f"expected a string, got {value!r}")
        return value
    raise ConfigError(key, f"unsupported type {tp!r}")


def coerce(value: Any, tp: Any, key: str) -> Any:
    """``value`` as the annotated type ``tp``, as :func:`from_mapping` takes each value.

    A list becomes a tuple, an integer a float where a number is declared;
    anything else of the wrong type, and a list holding an infinite or NaN
    number, is a :class:`ConfigError` naming ``key``.

    Examples
    --------
    >>> coerce([1, 2], tuple[float, ...], "knot_spacing_px")
    (1.0, 2.0)
    """
    return _coerce(value, tp, key)


def from_mapping(cls: type, mapping: Mapping[str, Any], prefix: str = "") -> Any:
    """Build the frozen dataclass ``cls`` from ``mapping``, validating every key.

    Parameters
    ----------
    cls : type
        A dataclass whose fields carry type annotations and defaults.
    mapping : Mapping
        Parsed TOML; missing keys take the field defaults.
    prefix : str
        Dotted path of this section, used in error messages.

    Raises
    ------
    ConfigError
        For an unknown key, a value of the wrong type, or a value that the
        class's ``validate`` method rejects.
    """
    hints = get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    for key in mapping:
        if key not in fields:
            dotted = f"{prefix}.{key}" if prefix else key
            raise ConfigError(dotted, "unknown key (known: " + ", ".join(sorted(fields)) + ")")
    kwargs = {}
    for name in fields:
        if name in mapping:
            dotted = f"{prefix}.{name}" if prefix else name
            kwargs[name] = _coerce(mapping[name], hints[name], dotted)
    obj = cls(**kwargs)
    validate = getattr(obj, "validate", None)
    if callable(validate):
        try:
            validate()
        except ConfigError as exc:
            if prefix and not exc.key.startswith(prefix + "."):
                raise ConfigError(f"{prefix}.{exc.key}", exc.problem) from None
            raise
    return obj


def to_mapping(obj: Any) -> dict[str, Any]:
    """The plain-dict form of a config dataclass (tuples become lists)."""
    def plain(v: Any) -> Any:
        if dataclasses.is_dataclass(v):
            return {f.name: plain(getattr(v, f.name)) for f in dataclasses.fields(v)}
        if isinstance(v, tuple):
            return [plain(x) for x in v]
        if isinstance(v, Mapping):
            return {k: plain(x) for k, x in v.items()}
        return v
    return plain(obj)


def parse_override(text: str) -> tuple[list[str], Any]:
    """Split ``section.key=value`` into the key path and the parsed value.

    Examples
    --------
    >>> parse_override("simulation.noise_model=iracsim2015")
    (['simulation', 'noise_model'], 'iracsim2015')
    >>> parse_override("pointing.x0=15.1")
    (['pointing', 'x0'], 15.1)
    """
    if "=" not in text:
        raise InputError(f"--set {text!r}: expected section.key=value")
    key, raw = text.split("=", 1)
    key = key.strip()
    if not key or any(not part for part in key.split(".")):
        raise InputError(f"--set {text!r}: expected section.key=value")
    raw = raw.strip()
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return key.split("."), value


def apply_overrides(mapping: Mapping[str, Any], overrides: list[str]) -> dict[str, Any]:
    """Return a deep copy of ``mapping`` with each ``--set`` override applied."""
    result = copy.deepcopy(dict(mapping))
    for text in overrides:
        path, value = parse_override(text)
        node = result
        for part in path[:-1]:
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                raise ConfigError(".".join(path), f"'{part}' is not a table")
            node = child
        node[path[-1]] = value
    return result


def _plain(value: Any) -> Any:
    """A Python value as TOML would give it: numpy scalars as Python numbers, tuples and
    arrays as lists, mappings as dicts (recursively)."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items() if v is not None}
    if isinstance(value, (list, tuple)) or (hasattr(value, "tolist") and getattr(
            value, "ndim", 0) > 0):
        return [_plain(v) for v in list(value)]
    item = getattr(value, "item", None)   # a numpy scalar (np.int64, np.float64, np.bool_)
    if callable(item) and getattr(value, "ndim", None) == 0:
        return item()
    return value


def apply_sections(mapping: Mapping[str, Any], sections: Mapping[str, Any]) -> dict[str, Any]:
    """Return a deep copy of ``mapping`` with whole sections' keys set from Python values.

    ``sections`` is ``{"challenge": {"epochs": 2}, ...}``: each key of a
    section replaces the one in ``mapping`` (a nested table such as
    ``system.planet`` as a whole). Values are taken as they are (numpy scalars
    as Python numbers), not through TOML text; :func:`from_mapping` validates
    them.

    Examples
    --------
    >>> import numpy as np
    >>> apply_sections({"challenge": {"seed": 1}}, {"challenge": {"epochs": np.int64(2)}})
    {'challenge': {'seed': 1, 'epochs': 2}}
    """
    result = copy.deepcopy(dict(mapping))
    for section, table in sections.items():
        if not isinstance(table, Mapping):
            raise ConfigError(str(section), f"expected a table (a dict of keys), got "
                                            f"{type(table).__name__}")
        node = result.setdefault(str(section), {})
        if not isinstance(node, dict):
            raise ConfigError(str(section), "is not a table")
        for key, value in table.items():
            node[str(key)] = _plain(value)
    return result


def load_toml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a TOML file, turning any failure into one line naming the file.

    Only a regular file of at most ``MAX_TEXT_FILE_BYTES`` is read
    (:func:`eclipsebench.io.inputs.read_input_bytes`).
    """
    p = Path(path)
    # a regular file within the stated size: not a device (/dev/zero) nor a FIFO
    data = read_input_bytes(p, "configuration file (TOML)", MAX_TEXT_FILE_BYTES)
    for bom, encoding in ((b"\xff\xfe", "UTF-16"), (b"\xfe\xff", "UTF-16"),
                          (b"\xef\xbb\xbf", "UTF-8 with a byte-order mark")):
        if data.startswith(bom):
            raise InputError(f"{p}: the file is {encoding}; expected a UTF-8 TOML file "
                             "without a byte-order mark")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{p}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset "
                         f"{exc.start}); expected a UTF-8 TOML file") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{p}: not valid TOML ({exc})") from None


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} as TOML")


def dump_toml(mapping: Mapping[str, Any]) -> str:
    """Write a mapping of sections (scalars, lists and nested tables) as TOML.

    Empty nested tables are left out.

    Examples
    --------
    >>> print(dump_toml({"reduce": {"phase": "flat", "options": {"bliss": {"k": 1}}}}), end="")
    [reduce]
    phase = "flat"
    <BLANKLINE>
    [reduce.options.bliss]
    k = 1
    """
    lines: list[str] = []

    def write(path: tuple[str, ...], node: Mapping[str, Any]) -> None:
        scalars = [(k, v) for k, v in node.items()
                   if not isinstance(v, Mapping) and v is not None]
        if len(path) == 1 or (path and scalars):
            if lines:
                lines.append("")
            lines.append("[" + ".".join(path) + "]")
        lines.extend(f"{k} = {_toml_value(v)}" for k, v in scalars)
        for k, v in node.items():
            if isinstance(v, Mapping) and (v or not path):
                write(path + (k,), v)

    write((), mapping)
    return "\n".join(lines) + "\n"
