"""A result's files: their paths, the one writer, the one reader and the resume rule.

A reduction writes ``RESULT.lc.ecsv`` (its light curve), then ``RESULT.json``
(:func:`write_result`), or a refusal (:func:`write_failure`);
:func:`result_ok` is the resume rule of every runner and :func:`read_result`
gives an :class:`~.epoch.EpochResult` or a :class:`~.joint.JointResult` back.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Table

from ... import __version__
from ...errors import InputError
from ...io.atomic import write_json, write_text
from ...io.ecsv import ecsv_text
from .epoch import EpochResult
from .joint import JointResult

__all__ = ["lightcurve_path", "chain_path", "write_result", "write_failure", "result_ok",
           "read_result"]


def lightcurve_path(result_path: str | os.PathLike) -> Path:
    """``RESULT.json`` -> ``RESULT.lc.ecsv`` (the decorrelated light curve beside it).

    Examples
    --------
    >>> lightcurve_path("results/pld/epoch_01.json").as_posix()
    'results/pld/epoch_01.lc.ecsv'
    """
    p = Path(result_path)
    stem = p.name[:-len(p.suffix)] if p.suffix else p.name
    return p.with_name(stem + ".lc.ecsv")


def chain_path(result_path: str | os.PathLike) -> Path:
    """``RESULT.json`` -> ``RESULT.chain.npz`` (the posterior samples).

    Examples
    --------
    >>> chain_path("r.json").as_posix()
    'r.chain.npz'
    """
    lc = lightcurve_path(result_path)
    return lc.with_name(lc.name.replace(".lc.ecsv", ".chain.npz"))


def write_result(result: EpochResult, path: str | os.PathLike) -> None:
    """Write one reduction's files: ``RESULT.lc.ecsv`` first, then ``RESULT.json`` (``path``).

    The one result writer of every runner (``run``, ``trust``, ``campaign``): the
    JSON is written last, so a result whose JSON exists has its light curve
    (:func:`result_ok`).
    """
    write_text(lightcurve_path(path), ecsv_text(result.lightcurve_table()))
    write_json(Path(path), result.to_dict())


def write_failure(path: str | os.PathLike, method: str, epoch: int | None, error: str,
                  **extra: Any) -> None:
    """Record at ``path`` that ``method`` refused epoch ``epoch`` (an InputError's message).

    A refusal is an outcome, not a crash: the JSON has ``failed``, the ``error``
    and null depths, and :func:`result_ok` accepts it, so a rerun does not retry it.
    ``extra`` keys (the profile) are added.
    """
    write_json(Path(path), {"method": method, "epoch": epoch, "failed": True, "error": error,
                            "depth_ppm": None, "depth_err_ppm": None, **extra,
                            "eclipsebench_version": __version__})


def _number_or_none(v: Any) -> bool:
    return v is None or (isinstance(v, (int, float)) and not isinstance(v, bool))


def result_ok(method: str, epoch: int | None, path: str | os.PathLike) -> bool:
    """The one resume rule of a reduction (``run``, ``trust``'s real and twin reductions,
    ``campaign``): the result JSON parses and matches its schema for (method, epoch).

    A result has ``method``, ``epoch`` (None for a table without an epoch number:
    trust's real table may have none), ``depth_ppm`` and ``depth_err_ppm`` (numbers,
    or null with ``failed`` and an ``error`` message); a finished one also has its
    decorrelated light curve beside it (:func:`lightcurve_path`).

    Examples
    --------
    >>> import json, tempfile
    >>> path = Path(tempfile.mkdtemp()) / "epoch_01.json"
    >>> _ = path.write_text(json.dumps({"method": "pld", "epoch": 1, "failed": True,
    ...                                 "error": "no stamps", "depth_ppm": None,
    ...                                 "depth_err_ppm": None}))
    >>> result_ok("pld", 1, path), result_ok("bliss", 1, path), result_ok("pld", 2, path)
    (True, False, False)
    """
    res = json.loads(Path(path).read_text())
    if not (isinstance(res, dict) and res.get("method") == method and "epoch" in res
            and res["epoch"] == epoch
            and _number_or_none(res.get("depth_ppm"))
            and _number_or_none(res.get("depth_err_ppm"))):
        return False
    if res.get("failed"):
        return isinstance(res.get("error"), str)
    return lightcurve_path(path).is_file()


def read_result(path: str | os.PathLike):
    """The result written to ``path`` (a RESULT.json), with its light curve and chain.

    ``RESULT.lc.ecsv`` and ``RESULT.chain.npz`` beside it are read when present
    (else the result has no light curve, or no chain). A joint fit's JSON gives
    a ``JointResult``. Every field ``to_dict`` writes comes back equal.

    Raises
    ------
    InputError
        Naming the file: missing, unreadable, not JSON, not a result, a failed
        reduction, or written by an older eclipsebench (no ``params``).
    """
    path = Path(path)
    data = _read_json(path)
    if data.get("joint"):
        return JointResult.from_dict(data, path)
    lc_file, chain_file = lightcurve_path(path), chain_path(path)
    lightcurve = _read_lightcurve(lc_file) if lc_file.is_file() else {}
    chain = _read_chain(chain_file) if chain_file.is_file() else None
    try:
        return EpochResult.from_dict(data, lightcurve, chain)
    except (KeyError, TypeError) as exc:
        raise InputError(f"{path}: not a result of this eclipsebench ({__version__}): "
                         f"{type(exc).__name__} {exc} (written by an older version? "
                         "reduce again)") from None


def _read_json(path: Path) -> dict[str, Any]:
    """A result file's dict; InputError naming the file when it is not one."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"{path}: no such result file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read the result file "
                         f"({type(exc).__name__}: {exc})") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: not a result file (invalid JSON: {exc.msg}, line "
                         f"{exc.lineno})") from None
    if not isinstance(data, dict) or "method" not in data or "depth_ppm" not in data:
        raise InputError(f"{path}: not a result file (no 'method' and 'depth_ppm')")
    if data.get("failed"):
        raise InputError(f"{path}: a failed reduction, no result: {data.get('error')}")
    return data


def _read_lightcurve(path: Path) -> dict[str, np.ndarray]:
    try:
        table = Table.read(path, format="ascii.ecsv")
    except Exception as exc:
        raise InputError(f"{path}: not a readable light curve "
                         f"({type(exc).__name__}: {exc})") from None
    return {name: np.asarray(table[name], dtype=float) for name in table.colnames}


def _read_chain(path: Path) -> dict[str, np.ndarray]:
    try:
        with np.load(path, allow_pickle=False) as npz:
            return {"names": npz["names"], "samples": npz["samples"]}
    except Exception as exc:
        raise InputError(f"{path}: not a readable chain ({type(exc).__name__}: {exc})") \
            from None
