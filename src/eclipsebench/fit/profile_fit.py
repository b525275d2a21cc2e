"""One epoch in a profile: the controlled settings, or the team's pipeline (paper profile).

:func:`reduce_epoch` prepares the table, picks a whole phase curve's
harmonic order by BIC, and fits it with the ``[reduce]`` settings
(``controlled``) or with the team's choices of the method's record
(``paper``: :func:`resolve_profile`, phase and ramp by BIC among the team's
candidates, the team's reported error).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from ..astro.events import event_for
from ..config.reduce import ReduceSection
from ..decorrelate.base import MethodOptions
from ..errors import InputError
from .epoch_fit import fit_prepared
from .model import PHASE_CURVE_MODELS
from .prepare import (
    _DEFAULT_OPTIONS,
    PreparedEpoch,
    _resources,
    prepare_epoch,
    resolve_method_options,
)
from .profiles import PROFILES, PaperProfile, paper_profile
from .result import EpochResult

__all__ = ["reduce_epoch", "resolve_profile"]


def reduce_epoch(table, method: str, *, options: ReduceSection = _DEFAULT_OPTIONS, system=None,
                 seed: int = 0, epoch: int | None = None,
                 method_options: MethodOptions | None = None,
                 resources: Mapping[str, Any] | None = None, pmap=None,
                 columns: Mapping[str, str] | None = None, time_column: str | None = None,
                 time_format: str | None = None, profile: str | None = None,
                 time_options: Mapping[str, Any] | None = None, system_section: Any = None,
                 labels: Mapping[str, str] | None = None) -> EpochResult:
    """Fit one epoch with one method and estimate the depth and its uncertainty.

    Parameters
    ----------
    table : astropy.table.Table or path
        One epoch's photometry table (``docs/contracts.md``).
    method : str
        A registered method name (``eclipsebench.decorrelate.available_methods()``).
    options : ReduceSection
        Phase and ramp model, sampler, error settings (``[reduce]``).
    system : str, PlanetSystem or None
        The planet (default: the one the table names, a simulation's ``SYSTEM`` or the
        archive's ``OBJECT`` through the catalogue; InputError when it names none).
    seed : int
        Run seed, carried from here by the method's context (``MethodContext.seed``,
        also what the result records); every stream of the fit and of the method is
        ``rng(seed, "reduce", epoch, method, ...)`` (the MCMC's ends in ``"mcmc"``).
    epoch : int or None
        Epoch number (default: the table's ``EPOCH`` metadata).
    method_options : MethodOptions, optional
        The method's options: the instance of its options dataclass that the
        caller's edge resolved once
        (:func:`~eclipsebench.fit.prepare.resolve_method_options`, with the
        profile), used as it is; None gives ``options.options[method]``
        (``[reduce.options.<method>]``) and, in the paper profile, the team's.
    resources : Mapping, optional
        Inputs a method declares in its ``resources`` (``{"pmap": path or
        loaded map}`` for ``kr-pmap``), loaded by the method's ``load_resources``.
    pmap : path, CalibrationSet or GriddedPmap, optional
        Shorthand for ``resources={"pmap": pmap}``.
    columns : Mapping, optional
        The package's column name -> the table's, for photometry from another
        pipeline (``{"flux": "FLUX", "noise_pixels": "NPIX"}``; docs/photometry.md).
    time_column : str, optional
        The table's time column (default ``time_bmjd``).
    time_format : {"bmjd", "bjd", "mjd", "jd"}, optional
        Its format (default ``"bmjd"``): ``b`` for barycentric, else times at the
        observer (converted: :mod:`eclipsebench.astro.timescales`).
    time_options : Mapping, optional
        ``time_scale``, ``time_at``, ``observer``, ``frame_time_s`` of the times
        (:func:`~eclipsebench.fit.data.standardise_table`).
    profile : {"controlled", "paper"}, optional
        Default ``options.profile``. ``controlled``: the ``[reduce]`` settings
        for every method. ``paper``: the method's team's centroid, phase and
        ramp models (by BIC where the team chose by BIC), eclipse shape,
        sampler, options and reported error (:mod:`eclipsebench.fit.profiles`).
    system_section : SystemSection, optional
        A configuration's ``[system]``: its planet when it names one, its
        catalogue searched for the table's ``OBJECT``.
    labels : Mapping, optional
        How errors name the table's arguments and the planet (the command line
        passes its options: ``{"columns": "--columns", "system": "--system NAME", ...}``).

    Returns
    -------
    EpochResult

    Raises
    ------
    InputError
        Missing columns, all frames flagged, an eclipse outside the time span,
        an unknown method, option or profile.
    """
    requested = options.profile if profile is None else profile
    options, team = resolve_profile(method, options, profile)
    if method_options is None:
        method_options = resolve_method_options(method, options, profile=requested)
    prep = prepare_epoch(table, method, options=options, system=system, epoch=epoch, seed=seed,
                         method_options=method_options, resources=_resources(resources, pmap),
                         columns=columns, time_column=time_column, time_format=time_format,
                         time_options=time_options,
                         centroid=None if team is None else team.centroid,
                         system_section=system_section, labels=labels)
    options, bic = _phase_curve_choice(prep, method, options)
    if team is None:
        result = replace(fit_prepared(prep, method, options=options), profile=requested)
        if requested == "paper":
            result = replace(result, profile_detail={"team": None, "settings": "controlled"})
    else:
        result = _fit_paper_profile(prep, method, team, options=options)
    if bic:
        result = replace(result, event_detail={**result.event_detail, "phase_curve_bic": bic})
    return result


def _phase_curve_choice(prep: PreparedEpoch, method: str, options: ReduceSection,
                        ) -> tuple[ReduceSection, dict[str, float]]:
    """A whole phase curve with ``phase_curve_model = "bic"``: the harmonic order of least BIC.

    Both orders are fitted by least squares (no errors) and the options come
    back with the chosen one; the BIC of each is returned for the result.
    Any other event or model: the options unchanged and no BIC.
    """
    if not event_for(options.event).whole_orbit or options.phase_curve_model != "bic":
        return options, {}
    bic: dict[str, float] = {phase: float(fit_prepared(prep, method, options=options,
                                                       phase=phase, errors=False).bic)
                             for phase in PHASE_CURVE_MODELS}
    best = min(PHASE_CURVE_MODELS, key=lambda phase: bic[phase])
    return replace(options, phase_curve_model=best), bic


def resolve_profile(method: str, options: ReduceSection = _DEFAULT_OPTIONS,
                    profile: str | None = None) -> tuple[ReduceSection, PaperProfile | None]:
    """The ``[reduce]`` settings a profile gives ``method``, and its team's entry (paper only).

    A method whose record has no paper profile gets the controlled settings
    in the paper profile too (and no entry).

    Examples
    --------
    >>> opts, team = resolve_profile("kr-pmap", profile="paper")
    >>> opts.phase, opts.sampler, team.reported_error
    ('flat', 'leastsq', ('jacobian',))
    >>> resolve_profile("kr-pmap", profile="controlled")[1] is None
    True
    """
    profile = options.profile if profile is None else profile
    if profile not in PROFILES:
        raise InputError(f"profile {profile!r}: expected one of {', '.join(PROFILES)}")
    if profile == "controlled":
        return options, None
    team = paper_profile(method)
    if team is None:   # no team's pipeline (a plugin): the controlled settings
        return replace(options, profile="controlled"), None
    return replace(options, phase=team.phases[0], ramp=team.ramps[0],
                   eclipse_shape=team.eclipse_shape, sampler=team.sampler,
                   prayer_bead_mode="all", profile="paper"), team


def _fit_paper_profile(prep: PreparedEpoch, method: str, team: PaperProfile, *,
                       options: ReduceSection) -> EpochResult:
    """The team's fit: its phase and ramp (least BIC among its candidates), its error."""
    bic: dict[str, float] = {}
    if len(team.phases) * len(team.ramps) > 1:
        candidates = {f"{phase}/{ramp}": (phase, ramp)
                      for ramp in team.ramps for phase in team.phases}
        for key, (phase, ramp) in candidates.items():
            trial = fit_prepared(prep, method, options=replace(options, ramp=ramp),
                                 phase=phase, errors=False)
            bic[key] = float(trial.bic)
        phase, ramp = candidates[min(bic, key=lambda k: bic[k])]
        options = replace(options, phase=phase, ramp=ramp)
    result = fit_prepared(prep, method, options=options, reported=team.reported_error)
    return replace(result, profile="paper",
                   profile_detail={"team": team.team, "centroid": prep.centroid,
                                   "reported_error": list(team.reported_error),
                                   "bic": bic})
