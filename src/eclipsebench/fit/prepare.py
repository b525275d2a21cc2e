"""Preparing a table for a fit: its frames, its system and predicted eclipse, the method built.

:func:`prepare_epoch` turns a photometry table (a file or a table, with the
columns a pipeline names) into a :class:`PreparedEpoch`: the frames a fit
uses (flags, the settling AOR), the system and its predicted event time, and
the systematics model built on them with its options and resources.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from astropy.table import Table

from ..astro.events import event_for
from ..astro.orbit import conjunction_time_bmjd, eclipse_time_bmjd
from ..config.reduce import ReduceSection
from ..decorrelate import get_method
from ..decorrelate.base import MethodOptions, Systematics, parse_method_options, unknown_methods
from ..errors import ConfigError, InputError
from ..io.pmap_files import check_pmap_path
from ..photometry.table import read_table
from .data import check_columns, epoch_data_from_table, standardise_table
from .frames import per_aor_systematics, settling_aor
from .model import PHASE_CURVE_MODELS, AstroModel
from .profiles import centroid_columns, paper_profile
from .target import system_of_table

__all__ = ["prepare_epoch", "PreparedEpoch", "resolve_system", "predicted_event_bmjd",
           "resolve_method_options", "configured_method_options", "table_epoch"]

#: The ``[reduce]`` defaults (a frozen dataclass, so one shared instance is safe).
_DEFAULT_OPTIONS = ReduceSection()


def _read(table):
    """An astropy Table from a Table or a path (FITS, ECSV or CSV: :func:`read_table`)."""
    if isinstance(table, (str, os.PathLike)):
        path = os.fspath(table)
        if not os.path.exists(path):
            raise InputError(f"{path}: no such photometry table")
        table = read_table(path)
        table.meta.setdefault("FILENAME", path)
    elif not isinstance(table, Table):
        raise InputError("table: expected an astropy Table or the path of a photometry table")
    return table


def _as_table(table, *, columns: Mapping[str, str] | None = None, time_column: str | None = None,
              time_format: str | None = None, time_options: Mapping[str, Any] | None = None,
              target=None, radius_px: float | None = None,
              labels: Mapping[str, str] | None = None):
    """An astropy Table with the package's column names from a Table or a path.

    A path is read as FITS, ECSV or CSV (:func:`read_table`); ``columns``,
    ``time_column``, ``time_format`` and ``time_options`` (``time_scale``,
    ``time_at``, ``observer``, ``frame_time_s``) map another pipeline's names
    and times, converted with ``target``'s coordinates
    (:func:`~eclipsebench.fit.data.standardise_table`). A table still without
    the columns a fit needs is refused in one line naming the likely
    candidates (:func:`~eclipsebench.fit.data.check_columns`, ``labels``: how
    it names the arguments), whichever door it came in by.
    """
    out = standardise_table(_read(table), columns=columns, time_column=time_column,
                            time_format=time_format, target=target, labels=labels,
                            **dict(time_options or {}))
    check_columns(out, _source(out), radius_px=radius_px, labels=labels)
    return out


def _source(table) -> str:
    """The table as errors name it: its file, else "the photometry table"."""
    return str((table.meta or {}).get("FILENAME", "the photometry table"))


def resolve_system(system: Any, meta: Mapping[str, Any] | None = None,
                   source: str = "the photometry table", *, section: Any = None,
                   hint: str = "system=NAME"):
    """A PlanetSystem from a name, a mapping of the planet's values (with ``name``) or a
    PlanetSystem; None: the one a configuration's ``[system]`` ``section`` names, else the
    planet the table's metadata name (``SYSTEM``, ``OBJECT``, also in ``section``'s
    catalogue: :func:`~eclipsebench.fit.target.system_of_table`), never the challenge's
    by default; ``hint`` is how the caller gives a planet."""
    return system_of_table(meta or {}, system=system, section=section, source=source,
                           hint=hint)


def predicted_event_bmjd(system, time_bmjd: np.ndarray, source: str = "the data",
                         event: str = "eclipse") -> float:
    """The catalogue ephemeris's time of ``event`` nearest the data (its conjunction: the
    eclipse, or the transit); InputError if it is outside them.

    A whole phase curve (``event="phase-curve"``): the first eclipse whose
    centre lies in the data, else (no eclipse centre inside) the one nearest
    their middle; the others follow from the period.
    """
    t0, t1 = float(np.min(time_bmjd)), float(np.max(time_bmjd))
    facts = event_for(event)
    if facts.whole_orbit:
        period = float(system.period_days)
        first = float(eclipse_time_bmjd(system, t0))
        first += period * np.ceil((t0 - first) / period - 1e-12)   # first at or after t0
        return first if first <= t1 else float(eclipse_time_bmjd(system, 0.5 * (t0 + t1)))
    t_event = float(conjunction_time_bmjd(system, 0.5 * (t0 + t1), facts.conjunction))
    if not t0 <= t_event <= t1:
        name = getattr(system, "name", "the system")
        raise InputError(f"{source}: the {name} {event} nearest the data is at "
                         f"{t_event:.5f} BMJD, outside the time span {t0:.5f}-{t1:.5f} "
                         f"(wrong system, or no {event} in these frames)")
    return t_event


def table_epoch(table, epoch: int | None = None) -> int | None:
    """The epoch a fit of ``table`` records: ``epoch`` when given, else the table's ``EPOCH``
    metadata (None when it has none)."""
    if epoch is not None:
        return int(epoch)
    value = (getattr(table, "meta", {}) or {}).get("EPOCH")
    try:
        return int(value) if value is not None else None
    except (TypeError, ValueError):
        return None


@dataclass
class PreparedEpoch:
    """One epoch ready to fit: the method built on the data, and the predicted time of its
    event (``t_event_predicted_bmjd``: the mid-eclipse, or the mid-transit when ``[reduce]
    event`` is a transit)."""

    table: Any
    systematics: Systematics
    system: Any
    epoch: int | None
    t_event_predicted_bmjd: float
    source: str
    n_frames_dropped: dict[str, int]
    #: The centroid columns the method regresses on when a profile chose them ("" otherwise).
    centroid: str = ""

    @property
    def n_frames(self) -> int:
        """Frames the method fits (after every drop)."""
        return self.systematics.n_frames

    def astro_model(self, options: ReduceSection, *, phase: str | None = None) -> AstroModel:
        """The shared astrophysical model at the method's data times, with its event's own
        settings read from ``options`` (:mod:`eclipsebench.fit.model.settings`)."""
        data = self.systematics.data
        model = AstroModel.event_class(options.event)
        if event_for(options.event).whole_orbit:
            # a whole phase curve: its own phase models, the physical eclipse repeated each
            # orbit, an offset per AOR unless each AOR has its own systematics
            phase = phase if phase in PHASE_CURVE_MODELS else options.phase_curve_model
        return model(data.time_bmjd, self.system, phase=phase or options.phase,
                     ramp=options.ramp, eclipse_shape=options.eclipse_shape,
                     settings=model.settings_class.from_options(options, data.aorkey))


def configured_method_options(options: ReduceSection) -> dict[str, MethodOptions]:
    """Every ``[reduce.options.<method>]`` table parsed into its method's options, once.

    Called at the edge, before any work (the reduce command, the runner's
    planner, trust), so that a typo in a configuration file is one line naming
    the dotted key; the caller keeps the result and gives it to
    :func:`resolve_method_options` (``configured=``).

    Raises
    ------
    ConfigError
        ``reduce.options.<name>`` for an unknown method, or
        ``reduce.options.<name>.<key>`` for an unknown or ill-typed option.

    Examples
    --------
    >>> from dataclasses import replace
    >>> configured_method_options(replace(_DEFAULT_OPTIONS, options={"kr-data": {"k": 20}}))
    {'kr-data': KrDataOptions(k=20, use_noise_pixels=False)}
    """
    parsed: dict[str, MethodOptions] = {}
    for name, table in options.options.items():
        if problem := unknown_methods([name]):
            raise ConfigError(f"reduce.options.{name}", problem)
        parsed[name] = parse_method_options(get_method(name), table,
                                            prefix=f"reduce.options.{name}")
    return parsed


def resolve_method_options(method: str, options: ReduceSection = _DEFAULT_OPTIONS,
                           method_options: Mapping[str, Any] | MethodOptions | None = None, *,
                           profile: str = "controlled",
                           configured: Mapping[str, MethodOptions] | None = None,
                           ) -> MethodOptions:
    """The options ``method`` runs with, parsed once into its options dataclass.

    ``[reduce.options.<method>]`` (``configured[method]`` when the caller parsed
    the tables already, :func:`configured_method_options`), overlaid in the
    paper profile (``profile="paper"``) by the options of the method's team
    (its record's ``PaperProfile.method_options``), overlaid by
    ``method_options``. An options instance is the whole answer: it is
    returned as it is.

    Raises
    ------
    InputError
        An unknown method; an unknown or ill-typed option, naming the
        configuration key (``reduce.options.<method>.<key>``) or the option.

    Examples
    --------
    >>> resolve_method_options("kr-data", method_options={"k": 20}).k
    20
    >>> resolve_method_options("gp", profile="paper").bin_seconds   # the team's 30 s bins
    30.0
    """
    cls = get_method(method)
    if isinstance(method_options, MethodOptions):
        return parse_method_options(cls, method_options)   # its class checked, nothing parsed
    base = (configured or {}).get(method)
    if base is None:
        base = parse_method_options(cls, options.options.get(method, {}),
                                    prefix=f"reduce.options.{method}")
    team = paper_profile(method) if profile == "paper" else None
    given = {**(team.method_options if team is not None else {}), **dict(method_options or {})}
    return parse_method_options(cls, given, base=base)


def prepare_epoch(table, method: str, *, options: ReduceSection = _DEFAULT_OPTIONS, system=None,
                  epoch=None, seed: int = 0, method_options: MethodOptions | None = None,
                  resources: Mapping[str, Any] | None = None,
                  columns: Mapping[str, str] | None = None, time_column: str | None = None,
                  time_format: str | None = None,
                  time_options: Mapping[str, Any] | None = None,
                  centroid: str | None = None, system_section: Any = None,
                  labels: Mapping[str, str] | None = None) -> PreparedEpoch:
    """Read the table, keep the good frames, build the method and predict the eclipse time.

    The method gets its options, ``method_options``: the instance of its options
    dataclass that the caller's edge resolved once (:func:`resolve_method_options`),
    as it is; None gives ``[reduce.options.<method>]`` over the defaults; and a
    :class:`~eclipsebench.decorrelate.base.MethodContext` with the run seed,
    the epoch and the resources it declares, loaded by its ``load_resources``
    from ``resources`` (paths or loaded objects). ``centroid`` ("col",
    "gauss", "gauss-fixed") makes those columns the method's ``x``/``y``
    (the paper profile); None keeps the table's ``x``/``y``. ``time_options``:
    the times' ``time_scale``, ``time_at``, ``observer`` and ``frame_time_s``
    (:func:`~eclipsebench.fit.data.standardise_table`); times at the observer
    (``time_format`` jd or mjd) are converted with the planet's coordinates,
    so the planet is then found before the columns are read. ``system_section``
    (a configuration's ``[system]``) and ``labels`` (how errors name the table's
    arguments and ``system``: :data:`eclipsebench.fit.data.check_columns`'s keys and
    ``"system"``) are as :func:`resolve_system` and :func:`_as_table` take them.
    """
    labels = dict(labels or {})
    hint = labels.get("system", "system=NAME")
    target = None
    if time_format in ("jd", "mjd"):
        table = _read(table)
        system = target = resolve_system(system, table.meta, _source(table),
                                         section=system_section, hint=hint)
    table = _as_table(table, columns=columns, time_column=time_column, time_format=time_format,
                      time_options=time_options, target=target,
                      radius_px=options.radius_px or None, labels=labels)
    source = _source(table)
    centroid_note = ""
    if centroid is not None:
        (cx, cy), centroid_note = centroid_columns(table.colnames, centroid)
        if (cx, cy) != ("x", "y"):
            table = table.copy(copy_data=False)
            table["x"], table["y"] = table[cx], table[cy]
        centroid_note = f"{cx}/{cy}" + (f" ({centroid_note})" if centroid_note else "")
    cls = get_method(method)
    method_opts = (method_options if method_options is not None
                   else resolve_method_options(method, options))
    data = epoch_data_from_table(table, radius_px=options.radius_px or None, stamp=options.stamp)
    dropped = {"flagged": int(data.meta.get("n_frames_flagged", 0)),
               "nonfinite": int(data.meta.get("n_frames_nonfinite", 0)), "settling_aor": 0}
    if options.settling_aor == "drop":
        settling = settling_aor(data.time_bmjd, data.aorkey)
        if settling.any():
            dropped["settling_aor"] = int(settling.sum())
            data = data.subset(~settling)
    system = resolve_system(system, table.meta, source, section=system_section, hint=hint)
    _check_resources(cls, resources, table.meta, source, labels)
    t_pred = predicted_event_bmjd(system, data.time_bmjd, source, options.event)
    # What the ephemeris predicts (never the truth): a method may use it to find the
    # eclipse's signature in its own decomposition (ICA's eclipse component).
    data = replace(data, meta={**data.meta, "t_ecl_predicted_bmjd": t_pred})
    epoch_number = table_epoch(table, epoch)

    def build(frames):
        return cls.build(frames, method_opts, seed=seed, epoch=epoch_number or 0,
                         resources=resources)

    if options.systematics_per_aor:   # a whole phase curve: one method per AOR
        systematics = per_aor_systematics(data, build)
    else:
        systematics = build(data)
    dropped.update({k: int(v) for k, v in systematics.dropped_frames().items()})
    return PreparedEpoch(table=table, systematics=systematics, system=system,
                         epoch=epoch_number, t_event_predicted_bmjd=t_pred,
                         source=source, n_frames_dropped=dropped, centroid=centroid_note)


#: How :func:`_check_resources` names the method and its pixel map by default (the API's words).
_RESOURCE_LABELS = {"method": "method", "pmap": 'a pmap as resources={"pmap": PATH}'}


def _check_resources(cls: type[Systematics], resources: Mapping[str, Any] | None,
                     meta: Mapping[str, Any] | None, source: str,
                     labels: Mapping[str, str]) -> None:
    """Before any fit: a pixel map given as a path must be a regular file or a folder, and a
    method that needs one (``kr-pmap``) needs it given or a simulated table's ``SIMDIR``
    to find it in; one line naming how to give it (``labels``: ``"method"``, ``"pmap"``)."""
    words = {**_RESOURCE_LABELS, **labels}
    pmap = dict(resources or {}).get("pmap")
    if isinstance(pmap, (str, os.PathLike)):   # a device or a FIFO is refused here
        check_pmap_path(pmap)
    if "pmap" not in cls.resources or pmap is not None:
        return
    if not ((meta or {}).get("SIMDIR") or (meta or {}).get("simdir")):
        raise InputError(f"{words['method']} {cls.name}: needs {words['pmap']} (a "
                         "calibration-star table, the SSC pmap, or a folder of its versions); "
                         f"{source} names no simulation folder (SIMDIR) to find one in")


def _resources(resources: Mapping[str, Any] | None, pmap) -> dict[str, Any]:
    out = dict(resources or {})
    if pmap is not None:
        out["pmap"] = pmap
    return out
