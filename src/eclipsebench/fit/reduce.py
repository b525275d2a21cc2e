"""From a photometry table and a method name to an eclipse depth.

:func:`reduce_epoch` fits one epoch, :func:`reduce_joint` fits several epochs
with one common depth, and :func:`select_phase_model` fits every phase-curve
model and reports BIC and AIC for each so that a user can bracket the choice
(paper Section 4.2). All three share one astrophysical model
(:class:`~eclipsebench.fit.astro_model.AstroModel`); methods differ only in
their systematics model.

The reported depth uncertainty is the largest of the estimates available,
as Wong et al. (2014) did: the least-squares (Jacobian) error multiplied by
``max(1, beta_red)``, the prayer-bead spread, and the MCMC posterior width.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from astropy.table import Table
from scipy.optimize import least_squares

from ..astro.orbit import eclipse_time_bmjd, transit_time_bmjd
from ..config.reduce import ReduceSection
from ..decorrelate import available_methods, get_method
from ..decorrelate.base import MethodOptions, Systematics, parse_method_options
from ..errors import ConfigError, InputError
from ..photometry.table import read_table
from .astro_model import PHASE_CURVE_MODELS, PHASE_MODELS, AstroModel
from .data import epoch_data_from_table, median_cadence_s, standardise_table
from .display import html_repr, text_repr
from .error_rule import largest_estimate, reported_depth_error
from .frames import per_aor_systematics, settling_aor
from .leastsq import (
    FitResult,
    _covariance,
    _Problem,
    _summarise,
    fit_leastsq,
    has_own_likelihood,
    prayer_bead,
)
from .mcmc import McmcResult, run_mcmc
from .profiles import PROFILES, PaperProfile, centroid_columns, paper_profile
from .result import (
    EpochResult,
    joint_extra_keys,
    joint_fields_shown,
    jsonable,
    lightcurve_errors,
)
from .target import system_of_table

__all__ = ["EpochResult", "JointResult", "PhaseSelection", "reduce_epoch", "reduce_joint",
           "select_phase_model", "prepare_epoch", "PreparedEpoch", "fit_prepared",
           "resolve_system", "predicted_eclipse_bmjd", "resolve_method_options",
           "check_method_options", "resolve_profile", "phase_curve_detail"]

#: The ``[reduce]`` defaults (a frozen dataclass, so one shared instance is safe).
_DEFAULT_OPTIONS = ReduceSection()


# --------------------------------------------------------------------------- inputs
def _as_table(table, *, columns: Mapping[str, str] | None = None, time_column: str | None = None,
              time_format: str | None = None):
    """An astropy Table with the package's column names from a Table or a path.

    A path is read as FITS, ECSV or CSV (:func:`read_table`); ``columns``,
    ``time_column`` and ``time_format`` map another pipeline's names and time
    format (:func:`~eclipsebench.fit.data.standardise_table`).
    """
    if isinstance(table, (str, os.PathLike)):
        path = os.fspath(table)
        if not os.path.exists(path):
            raise InputError(f"{path}: no such photometry table")
        table = read_table(path)
        table.meta.setdefault("FILENAME", path)
    elif not isinstance(table, Table):
        raise InputError("table: expected an astropy Table or the path of a photometry table")
    return standardise_table(table, columns=columns, time_column=time_column,
                             time_format=time_format)


def resolve_system(system: Any, meta: Mapping[str, Any] | None = None,
                   source: str = "the photometry table"):
    """A PlanetSystem from a name, a mapping of the planet's values (with ``name``) or a
    PlanetSystem; None: the planet the table's metadata name (``SYSTEM``, ``OBJECT``:
    :func:`~eclipsebench.fit.target.system_of_table`), never the challenge's by default."""
    return system_of_table(meta or {}, system=system, source=source,
                           hint="system=NAME")


def predicted_eclipse_bmjd(system, time_bmjd: np.ndarray, source: str = "the data",
                           event: str = "eclipse") -> float:
    """The catalogue ephemeris's eclipse (or transit) nearest the data; InputError if it is
    outside them.

    A whole phase curve (``event="phase-curve"``): the first eclipse whose
    centre lies in the data, else (no eclipse centre inside) the one nearest
    their middle; the others follow from the period.
    """
    t0, t1 = float(np.min(time_bmjd)), float(np.max(time_bmjd))
    if event == "phase-curve":
        period = float(system.period_days)
        first = float(eclipse_time_bmjd(system, t0))
        first += period * np.ceil((t0 - first) / period - 1e-12)   # first at or after t0
        return first if first <= t1 else float(eclipse_time_bmjd(system, 0.5 * (t0 + t1)))
    when = transit_time_bmjd if event == "transit" else eclipse_time_bmjd
    t_ecl = float(when(system, 0.5 * (t0 + t1)))
    if not t0 <= t_ecl <= t1:
        name = getattr(system, "name", "the system")
        raise InputError(f"{source}: the {name} {event} nearest the data is at "
                         f"{t_ecl:.5f} BMJD, outside the time span {t0:.5f}-{t1:.5f} "
                         f"(wrong system, or no {event} in these frames)")
    return t_ecl


def _epoch_number(table, epoch):
    if epoch is not None:
        return int(epoch)
    value = (getattr(table, "meta", {}) or {}).get("EPOCH")
    try:
        return int(value) if value is not None else None
    except (TypeError, ValueError):
        return None


@dataclass
class PreparedEpoch:
    """One epoch ready to fit: the method built on the data, and the predicted eclipse
    (``t_ecl_predicted_bmjd``: the predicted mid-transit when ``[reduce] event`` is a transit)."""

    table: Any
    systematics: Systematics
    system: Any
    epoch: int | None
    t_ecl_predicted_bmjd: float
    source: str
    n_frames_dropped: dict[str, int]
    #: The centroid columns the method regresses on when a profile chose them ("" otherwise).
    centroid: str = ""

    @property
    def n_frames(self) -> int:
        """Frames the method fits (after every drop)."""
        return self.systematics.n_frames

    def astro_model(self, options: ReduceSection, *, phase: str | None = None) -> AstroModel:
        """The shared astrophysical model at the method's data times."""
        shape = options.eclipse_shape
        if options.event == "phase-curve":
            # a whole phase curve: its own phase models, the physical eclipse repeated each
            # orbit, an offset per AOR unless each AOR has its own systematics
            data = self.systematics.data
            return AstroModel(
                data.time_bmjd, self.system, event="phase-curve",
                phase=phase if phase in PHASE_CURVE_MODELS else options.phase_curve_model,
                ramp=options.ramp, eclipse_shape=shape,
                limb_darkening_q=options.limb_darkening_q,
                aorkey=(data.aorkey if options.aor_offsets and not options.systematics_per_aor
                        else None),
                exposure_s=options.exposure_s or None,
                nonnegative_planet=options.nonnegative_planet)
        return AstroModel(self.systematics.data.time_bmjd, self.system,
                          phase=phase or options.phase, ramp=options.ramp, eclipse_shape=shape,
                          event=options.event, transit_free=options.transit_free,
                          transit_priors=options.transit_priors,
                          limb_darkening_q=options.limb_darkening_q)


def resolve_method_options(method: str, options: ReduceSection = _DEFAULT_OPTIONS,
                           method_options: Mapping[str, Any] | MethodOptions | None = None,
                           ) -> MethodOptions:
    """The effective options of ``method``: ``[reduce.options.<method>]`` overlaid by
    ``method_options``, checked against the method's options dataclass.

    Raises
    ------
    InputError
        An unknown method; an unknown or ill-typed option, naming the
        configuration key (``reduce.options.<method>.<key>``) or the option.

    Examples
    --------
    >>> resolve_method_options("kr-data", method_options={"k": 20}).k
    20
    """
    cls = get_method(method)
    configured = options.options.get(method, {})
    base = parse_method_options(cls, configured, prefix=f"reduce.options.{method}")
    if method_options is None:
        return base
    if isinstance(method_options, MethodOptions):
        return parse_method_options(cls, method_options)
    return parse_method_options(cls, {**base.to_dict(), **dict(method_options)})


def check_method_options(options: ReduceSection) -> None:
    """Every ``[reduce.options.<method>]`` table names a registered method and its options.

    Called before any work (the runner's planner, the reduce command), so that
    a typo in a configuration file is one line naming the dotted key.

    Raises
    ------
    ConfigError
        ``reduce.options.<name>`` for an unknown method, or
        ``reduce.options.<name>.<key>`` for an unknown or ill-typed option.
    """
    known = available_methods()
    for name, table in options.options.items():
        if name not in known:
            raise ConfigError(f"reduce.options.{name}",
                              f"unknown method (known: {', '.join(known)})")
        parse_method_options(get_method(name), table, prefix=f"reduce.options.{name}")


def prepare_epoch(table, method: str, *, options: ReduceSection = _DEFAULT_OPTIONS, system=None,
                  epoch=None, seed: int = 0, method_options=None,
                  resources: Mapping[str, Any] | None = None,
                  columns: Mapping[str, str] | None = None, time_column: str | None = None,
                  time_format: str | None = None,
                  centroid: str | None = None) -> PreparedEpoch:
    """Read the table, keep the good frames, build the method and predict the eclipse time.

    The method gets its options (:func:`resolve_method_options`) and a
    :class:`~eclipsebench.decorrelate.base.MethodContext` with the run seed,
    the epoch and the resources it declares, loaded by its ``load_resources``
    from ``resources`` (paths or loaded objects). ``centroid`` ("col",
    "gauss", "gauss-fixed") makes those columns the method's ``x``/``y``
    (the paper profile); None keeps the table's ``x``/``y``.
    """
    table = _as_table(table, columns=columns, time_column=time_column, time_format=time_format)
    source = str((table.meta or {}).get("FILENAME", "the photometry table"))
    centroid_note = ""
    if centroid is not None:
        (cx, cy), centroid_note = centroid_columns(table.colnames, centroid)
        if (cx, cy) != ("x", "y"):
            table = table.copy(copy_data=False)
            table["x"], table["y"] = table[cx], table[cy]
        centroid_note = f"{cx}/{cy}" + (f" ({centroid_note})" if centroid_note else "")
    cls = get_method(method)
    method_opts = resolve_method_options(method, options, method_options)
    data = epoch_data_from_table(table, radius_px=options.radius_px or None, stamp=options.stamp)
    dropped = {"flagged": int(data.meta.get("n_frames_flagged", 0)),
               "nonfinite": int(data.meta.get("n_frames_nonfinite", 0)), "settling_aor": 0}
    if options.settling_aor == "drop":
        settling = settling_aor(data.time_bmjd, data.aorkey)
        if settling.any():
            dropped["settling_aor"] = int(settling.sum())
            data = data.subset(~settling)
    system = resolve_system(system, table.meta, source)
    t_pred = predicted_eclipse_bmjd(system, data.time_bmjd, source, options.event)
    # What the ephemeris predicts (never the truth): a method may use it to find the
    # eclipse's signature in its own decomposition (ICA's eclipse component).
    data = replace(data, meta={**data.meta, "t_ecl_predicted_bmjd": t_pred})
    epoch_number = _epoch_number(table, epoch)

    def build(frames):
        return cls.build(frames, method_opts, seed=seed, epoch=epoch_number or 0,
                         resources=resources)

    if options.systematics_per_aor:   # a whole phase curve: one method per AOR
        systematics = per_aor_systematics(data, build)
    else:
        systematics = build(data)
    dropped.update({k: int(v) for k, v in systematics.dropped_frames().items()})
    return PreparedEpoch(table=table, systematics=systematics, system=system,
                         epoch=epoch_number, t_ecl_predicted_bmjd=t_pred,
                         source=source, n_frames_dropped=dropped, centroid=centroid_note)


# --------------------------------------------------------------------------- one epoch
def _mcmc_noise_scale(systematics: Systematics, fit: FitResult) -> float:
    """Flux-error scale of the MCMC likelihood: ``sqrt(chi2_red) max(1, beta_red)``.

    With the white-noise likelihood the reported flux errors are rescaled so
    that the residuals have chi2_red = 1 (the Jacobian covariance is scaled the
    same way), then multiplied by the red-noise factor as Winn et al. (2008)
    and Gillon et al. (2010) do in their chains, so that the posterior carries
    the correlated noise the white-noise likelihood cannot see. A method with
    its own likelihood (GP) models its noise: 1.
    """
    if has_own_likelihood(systematics):
        return 1.0
    beta = fit.beta_red if np.isfinite(fit.beta_red) else 1.0
    return float(np.sqrt(max(fit.chi2_red, 1e-12)) * max(1.0, beta))


def _depth_derivative(astro_model: AstroModel, fit: FitResult) -> tuple[np.ndarray, np.ndarray]:
    """The best-fitting astrophysical curve and its derivative with respect to the depth
    (the event's size parameter ``names[0]``: a transit's Rp/R*)."""
    theta = fit.theta_astro.copy()
    astro = astro_model(theta)
    h = 1e-6
    theta[0] += h
    return astro, (astro_model(theta) - astro) / h


def _extra_depth_variance(systematics: Systematics, astro: np.ndarray,
                          dastro: np.ndarray) -> float:
    """The method's extra depth variance (ICA's component separation), fraction squared."""
    value = float(systematics.extra_depth_variance(astro, dastro))
    return value if np.isfinite(value) and value > 0 else 0.0


def reduce_epoch(table, method: str, *, options: ReduceSection = _DEFAULT_OPTIONS, system=None,
                 seed: int = 0, epoch: int | None = None, method_options=None,
                 resources: Mapping[str, Any] | None = None, pmap=None,
                 columns: Mapping[str, str] | None = None, time_column: str | None = None,
                 time_format: str | None = None, profile: str | None = None) -> EpochResult:
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
        The planet (default: the configured system, the 2015 challenge's XO-3b; give
        "XO-3b" for real data).
    seed : int
        Run seed; every stream of the fit and of the method is
        ``rng(seed, "reduce", epoch, method, ...)`` (the MCMC's ends in ``"mcmc"``).
    epoch : int or None
        Epoch number (default: the table's ``EPOCH`` metadata).
    method_options : Mapping or MethodOptions, optional
        The method's options, over those of ``options.options[method]``
        (``[reduce.options.<method>]``).
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
        Its format (default ``"bmjd"``); every format is taken as BJD_TDB-based
        (no time-scale or barycentric conversion is made).
    profile : {"controlled", "paper"}, optional
        Default ``options.profile``. ``controlled``: the ``[reduce]`` settings
        for every method. ``paper``: the method's team's centroid, phase and
        ramp models (by BIC where the team chose by BIC), eclipse shape,
        sampler, options and reported error (:mod:`eclipsebench.fit.profiles`).

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
    if team is not None and not isinstance(method_options, MethodOptions):
        method_options = {**team.method_options, **dict(method_options or {})}
    prep = prepare_epoch(table, method, options=options, system=system, epoch=epoch, seed=seed,
                         method_options=method_options, resources=_resources(resources, pmap),
                         columns=columns, time_column=time_column, time_format=time_format,
                         centroid=None if team is None else team.centroid)
    options, bic = _phase_curve_choice(prep, method, options, seed)
    if team is None:
        result = replace(fit_prepared(prep, method, options=options, seed=seed),
                         profile=requested)
        if requested == "paper":
            result = replace(result, profile_detail={"team": None, "settings": "controlled"})
    else:
        result = _fit_paper_profile(prep, method, team, options=options, seed=seed)
    if bic:
        result = replace(result, event_detail={**result.event_detail, "phase_curve_bic": bic})
    return result


def _phase_curve_choice(prep: PreparedEpoch, method: str, options: ReduceSection,
                        seed: int) -> tuple[ReduceSection, dict[str, float]]:
    """A whole phase curve with ``phase_curve_model = "bic"``: the harmonic order of least BIC.

    Both orders are fitted by least squares (no errors) and the options come
    back with the chosen one; the BIC of each is returned for the result.
    Any other event or model: the options unchanged and no BIC.
    """
    if options.event != "phase-curve" or options.phase_curve_model != "bic":
        return options, {}
    bic: dict[str, float] = {phase: float(fit_prepared(prep, method, options=options, seed=seed,
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
                       options: ReduceSection, seed: int) -> EpochResult:
    """The team's fit: its phase and ramp (least BIC among its candidates), its error."""
    bic: dict[str, float] = {}
    if len(team.phases) * len(team.ramps) > 1:
        candidates = {f"{phase}/{ramp}": (phase, ramp)
                      for ramp in team.ramps for phase in team.phases}
        for key, (phase, ramp) in candidates.items():
            trial = fit_prepared(prep, method, options=replace(options, ramp=ramp),
                                 seed=seed, phase=phase, errors=False)
            bic[key] = float(trial.bic)
        phase, ramp = candidates[min(bic, key=lambda k: bic[k])]
        options = replace(options, phase=phase, ramp=ramp)
    result = fit_prepared(prep, method, options=options, seed=seed,
                          reported=team.reported_error)
    return replace(result, profile="paper",
                   profile_detail={"team": team.team, "centroid": prep.centroid,
                                   "reported_error": list(team.reported_error),
                                   "bic": bic})


def _resources(resources: Mapping[str, Any] | None, pmap) -> dict[str, Any]:
    out = dict(resources or {})
    if pmap is not None:
        out["pmap"] = pmap
    return out


def fit_prepared(prep: PreparedEpoch, method: str, *, options: ReduceSection,
                 seed: int = 0, phase: str | None = None, errors: bool = True,
                 reported: tuple[str, ...] | None = None) -> EpochResult:
    """Fit a :class:`PreparedEpoch` (used by :func:`reduce_epoch` and the phase comparison).

    ``reported`` names the depth errors to report, the largest of them (the
    paper profile's team rule); None applies ``options.error_rule``.

    The errors are those of the event's size parameter ``astro_model.names[0]``
    (the depth, or a transit's Rp/R*) and time ``names[1]``; the ``depth_*``
    fields hold them as the event's depth (:meth:`AstroModel.depth_ppm`), and
    a transit's ``event_detail`` has Rp/R* and its error as fitted.
    """
    systematics = prep.systematics
    astro_model = prep.astro_model(options, phase=phase)
    size, when = astro_model.names[:2]   # ("depth", "t_ecl_bmjd") or ("rp_rs", "t_transit_bmjd")
    theta0 = astro_model.initial(t_ecl_bmjd=prep.t_ecl_predicted_bmjd)
    fit = fit_leastsq(systematics, astro_model, theta0, max_nfev=options.max_nfev,
                      beta_bin_minutes=tuple(options.beta_bin_minutes))
    inflate = max(1.0, fit.beta_red) if np.isfinite(fit.beta_red) else 1.0
    jac_depth = fit.error(size)
    jac_tecl = fit.error(when)

    # Noise-free residuals (a synthetic exact model) leave no posterior width to sample.
    sample = errors and options.resolved_sampler() == "mcmc" and fit.rms_ppm > 1e-6
    # The prayer bead is computed where a rule can report it: not beside a posterior
    # that the default rule reports (error_rule = "largest" or "leastsq" bring it back).
    bead_wanted = ("prayer_bead" in reported if reported is not None
                   else not (sample and options.error_rule == "posterior"))
    pb_depth = pb_tecl = None
    if (errors and options.prayer_bead_shifts > 0 and systematics.policy.use_prayer_bead
            and bead_wanted):
        if options.prayer_bead_mode == "all":
            beads = prayer_bead(systematics, astro_model, fit, n_shifts=None,
                                stride=options.prayer_bead_stride, max_nfev=options.max_nfev)
        else:
            beads = prayer_bead(systematics, astro_model, fit, n_shifts=options.prayer_bead_shifts)
        pb_depth = float(np.std(beads[:, 0], ddof=1))
        pb_tecl = float(np.std(beads[:, 1], ddof=1))

    mc: McmcResult | None = None
    mcmc_info = None
    if sample:
        stream = systematics.context.stream("mcmc")   # rng(seed, "reduce", epoch, method, "mcmc")
        mc = run_mcmc(systematics, astro_model, fit.theta, fit.errors, names=fit.names,
                      rng=stream, n_walkers=options.mcmc_walkers, max_steps=options.mcmc_steps,
                      block_steps=options.mcmc_block_steps, tau_factor=options.mcmc_tau_factor,
                      noise_scale=_mcmc_noise_scale(systematics, fit), cov_start=fit.cov)
        i = fit.names.index(size)
        mcmc_info = {"move": mc.move, "walkers": mc.n_walkers, "steps": mc.n_steps,
                     "burn_in": mc.burn_in, "tau_max": float(np.max(mc.tau)),
                     "n_over_tau": float(mc.n_over_tau),
                     "acceptance": mc.acceptance, "converged": mc.converged,
                     "noise_scale": _mcmc_noise_scale(systematics, fit),
                     "depth_median_ppm": astro_model.depth_ppm(mc.median[i]),
                     "depth_err_lo_ppm": astro_model.depth_difference_ppm(mc.p16[i],
                                                                          mc.median[i]),
                     "depth_err_hi_ppm": astro_model.depth_difference_ppm(mc.median[i],
                                                                          mc.p84[i])}

    astro_fit, dastro = _depth_derivative(astro_model, fit)
    # the methods' hooks see the derivative per unit of the event's depth and give depth
    # errors; `scale` (d size / d depth: 1 for an eclipse) turns them into errors of the size
    scale = astro_model.size_per_depth(fit.theta[0])
    dastro = dastro * scale
    separation_var = _extra_depth_variance(systematics, astro_fit, dastro) * scale ** 2
    shared = {"jacobian_beta": jac_depth * inflate, "prayer_bead": pb_depth,
              "mcmc": mc.error(size) if mc is not None else None}
    own = {name: float(v) * scale for name, v in systematics.depth_error_estimates(
        astro_fit, dastro, fit.theta[fit.n_astro:] if len(systematics.param_names) else None
    ).items()} if errors else {}
    team = paper_profile(method)   # the errors the method's authors reported, if known
    depth_err, err_method = reported_depth_error(
        shared, error_rule=options.error_rule, jacobian=jac_depth, own=own, reported=reported,
        authors=team.reported_error if team is not None else None, sampled=mc is not None,
        errors=errors, separation_var=separation_var, method=method)
    t_err, _ = largest_estimate({"jacobian_beta": jac_tecl * inflate, "prayer_bead": pb_tecl,
                         "mcmc": mc.error(when) if mc is not None else None})
    if mc is not None and err_method.split("+")[0] == "mcmc":
        t_err = mc.error(when)
    # The reported parameters: the paper profile's MCMC teams quoted posterior medians; the
    # controlled profile quotes every method's least-squares best fit (one estimator for all,
    # sampled or not), with the posterior's width as its error (docs/fitting.md).
    theta_report = mc.median if mc is not None and options.profile == "paper" else fit.theta
    astro = astro_model(theta_report[:fit.n_astro])
    theta_s = theta_report[fit.n_astro:] if len(systematics.param_names) else None
    corrected = systematics.correct(astro, theta_s)
    lightcurve = {"time_bmjd": np.asarray(systematics.data.time_bmjd, dtype=float),
                  "flux_corrected": corrected, "astro_model": astro,
                  "residual": corrected - astro,
                  **lightcurve_errors(systematics.data.flux, systematics.data.flux_err, corrected)}
    params = {n: float(v) for n, v in zip(fit.names, theta_report, strict=True)}
    param_err = {n: float(e) for n, e in zip(fit.names, fit.errors, strict=True)}
    if mc is not None:
        param_err = {n: max(param_err[n], mc.error(n)) for n in fit.names}
    converged = bool(fit.success and (mc.converged if mc is not None else True))
    value = params[size]

    def ppm(err):   # an error of the size parameter as a depth error (ppm)
        return astro_model.depth_error_ppm(value, err)

    detail = {} if astro_model.event != "transit" else {
        "event": astro_model.event, "rp_rs": value, "rp_rs_err": depth_err,
        "transit_depth_ppm": astro_model.depth_ppm(value), "transit_depth_err_ppm": ppm(depth_err),
        "transit_depth_definition": "rp_rs^2 (geometric)", "t_transit_bmjd": params[when],
        "t_transit_err_d": t_err, "t_transit_predicted_bmjd": prep.t_ecl_predicted_bmjd,
        "transit_model": astro_model.describe()}
    if astro_model.event == "phase-curve":
        detail = phase_curve_detail(astro_model, fit, mc, inflate)
    return EpochResult(
        method=method, epoch=prep.epoch,
        depth_ppm=astro_model.depth_ppm(value), depth_err_ppm=ppm(depth_err),
        depth_err_method=err_method, depth_leastsq_ppm=astro_model.depth_ppm(fit.value(size)),
        depth_err_jacobian_ppm=ppm(jac_depth),
        depth_err_prayer_bead_ppm=None if pb_depth is None else ppm(pb_depth),
        depth_err_mcmc_ppm=None if mc is None else ppm(mc.error(size)),
        depth_err_separation_ppm=ppm(float(np.sqrt(separation_var))),
        t_ecl_bmjd=params[when], t_ecl_err_d=t_err,
        t_ecl_predicted_bmjd=prep.t_ecl_predicted_bmjd,
        bic=fit.bic, aic=fit.aic, k=fit.k, log_likelihood=fit.log_likelihood,
        chi2_red=fit.chi2_red, rms_ppm=fit.rms_ppm, beta_red=fit.beta_red,
        cadence_s=median_cadence_s(prep.table["time_bmjd"]),
        n_frames=prep.n_frames, n_frames_dropped=dict(prep.n_frames_dropped),
        n_points=len(systematics.data.time_bmjd), bic_n_points=fit.n_data,
        phase=astro_model.phase, ramp=astro_model.ramp, eclipse_shape=astro_model.eclipse_shape,
        sampler="mcmc" if mc is not None else "leastsq", converged=converged,
        params=params, param_errors=param_err,
        mcmc=mcmc_info, system=str(getattr(prep.system, "name", prep.system)), seed=int(seed),
        options=systematics.options.to_dict(), diagnostics=jsonable(systematics.diagnostics()),
        depth_err_own_ppm={k: ppm(v) for k, v in own.items()}, lightcurve=lightcurve,
        chain=None if mc is None else {"names": np.asarray(mc.names),
                                       "samples": np.asarray(mc.samples)},
        event_detail=detail)


def _wrap_deg(angle):
    """Angles (deg) into [-180, 180)."""
    return (np.asarray(angle, dtype=float) + 180.0) % 360.0 - 180.0


def phase_curve_detail(astro_model: AstroModel, fit: FitResult, mc: McmcResult | None,
                       inflate: float = 1.0) -> dict[str, Any]:
    """A whole phase curve's result keys: amplitude, hotspot offset, night side, Rp/R*, offsets.

    The summary is :meth:`AstroModel.phase_summary` (the lead's
    :func:`~eclipsebench.astro.phase_curves.harmonic_summary`) of the reported
    parameters. Errors (``phase_errors_from``): with MCMC samples, the 16-84 %
    half-width of the summary of every sample (the offset's differences from
    the median wrapped into +-180 deg); otherwise the delta method, ``g^T C g``
    with ``g`` the central-difference gradient of each summary value and ``C``
    the least-squares covariance times ``max(1, beta_red)^2`` (the depth's
    Jacobian rule). ``planet_flux_negative`` flags a minimum below zero.
    """
    names = astro_model.names
    n_astro = len(names)
    theta = np.asarray(mc.median if mc is not None else fit.theta, dtype=float)[:n_astro]
    keys = ("phase_amplitude", "phase_offset_deg", "nightside_flux", "planet_flux_min")
    best = astro_model.phase_summary(theta)
    errors: dict[str, float] = {}
    if mc is not None:
        samples = np.asarray(mc.samples, dtype=float)[:, :n_astro]
        if len(samples) > 4000:   # a thinned, evenly spaced subset keeps the summary quick
            samples = samples[np.linspace(0, len(samples) - 1, 4000).astype(int)]
        rows = [astro_model.phase_summary(t) for t in samples]
        for key in keys:
            vals = np.array([r[key] for r in rows])
            if key == "phase_offset_deg":
                vals = _wrap_deg(vals - best[key])
            lo, hi = np.percentile(vals, [16.0, 84.0])
            errors[key] = float(0.5 * (hi - lo))
        source = "mcmc samples (16-84 % half-width)"
    else:
        free = [i for i, n in enumerate(names) if n == "depth" or n.startswith("phase_")]
        cov = np.asarray(fit.cov, dtype=float)[np.ix_(free, free)] * inflate ** 2
        grads = np.zeros((len(keys), len(free)))
        for j, i in enumerate(free):
            h = 1e-3 * astro_model.scales[i]
            up, down = theta.copy(), theta.copy()
            up[i] += h
            down[i] -= h
            s_up, s_down = astro_model.phase_summary(up), astro_model.phase_summary(down)
            for k, key in enumerate(keys):
                diff = s_up[key] - s_down[key]
                if key == "phase_offset_deg":
                    diff = float(_wrap_deg(diff))
                grads[k, j] = diff / (2.0 * h)
        for k, key in enumerate(keys):
            errors[key] = float(np.sqrt(max(grads[k] @ cov @ grads[k], 0.0)))
        source = "delta method (least-squares covariance x max(1, beta_red)^2)"

    def err(name):
        i = names.index(name)
        if mc is not None:
            return float(mc.error(name))
        return float(fit.errors[i] * inflate)

    offsets = [{"aorkey": key, "offset": 0.0, "offset_err": 0.0, "reference": True}
               for key in astro_model.aor_keys[:1]]
    for k, key in enumerate(astro_model.aor_keys[1:], start=1):
        offsets.append({"aorkey": key, "offset": float(theta[names.index(f"aor_offset_{k}")]),
                        "offset_err": err(f"aor_offset_{k}"), "reference": False})
    return {
        "event": "phase-curve",
        "phase_amplitude_ppm": best["phase_amplitude"] * 1e6,
        "phase_amplitude_err_ppm": errors["phase_amplitude"] * 1e6,
        "phase_offset_deg": best["phase_offset_deg"],
        "phase_offset_err_deg": errors["phase_offset_deg"],
        "phase_offset_convention": "hotspot offset: minus the orbital phase of the maximum "
                                   "from mid-eclipse; east of the substellar point positive",
        "nightside_flux_ppm": best["nightside_flux"] * 1e6,
        "nightside_flux_err_ppm": errors["nightside_flux"] * 1e6,
        "planet_flux_min_ppm": best["planet_flux_min"] * 1e6,
        "planet_flux_min_err_ppm": errors["planet_flux_min"] * 1e6,
        "planet_flux_negative": bool(best["planet_flux_min"] < 0.0),
        "rp_rs": float(theta[names.index("rp_rs")]), "rp_rs_err": err("rp_rs"),
        "aor_offsets": offsets,
        "phase_errors_from": source,
        "phase_curve_model": astro_model.describe(),
    }


# --------------------------------------------------------------------------- phase models
@dataclass(frozen=True)
class PhaseSelection:
    """Every phase-curve model fitted to one epoch, with BIC and AIC for each.

    ``rows`` has one dict per model (``phase``, ``k``, ``depth_ppm``,
    ``depth_err_ppm``, ``bic``, ``aic``, ``delta_bic``, ``delta_aic``,
    ``chi2_red``); ``best_bic`` and ``best_aic`` name the preferred models and
    ``bracket`` lists the models from the BIC choice to the AIC choice in order
    of size (Dziak et al. 2012, paper Section 4.2).
    """

    method: str
    epoch: int | None
    rows: tuple[dict[str, Any], ...]
    best_bic: str
    best_aic: str
    bracket: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        return {"method": self.method, "epoch": self.epoch, "models": list(self.rows),
                "best_bic": self.best_bic, "best_aic": self.best_aic,
                "bracket": list(self.bracket)}


def select_phase_model(table, method: str, *, options: ReduceSection = _DEFAULT_OPTIONS,
                       system=None, seed: int = 0, epoch: int | None = None, method_options=None,
                       resources: Mapping[str, Any] | None = None, pmap=None,
                       phases: tuple[str, ...] = PHASE_MODELS,
                       columns: Mapping[str, str] | None = None, time_column: str | None = None,
                       time_format: str | None = None) -> PhaseSelection:
    """Fit each phase model by least squares and report BIC and AIC for each.

    The method is built once and reused; each model's depth error is the
    Jacobian error times ``max(1, beta_red)`` (no prayer bead or MCMC, to keep
    the comparison fast).
    """
    prep = prepare_epoch(table, method, options=options, system=system, epoch=epoch, seed=seed,
                         method_options=method_options, resources=_resources(resources, pmap),
                         columns=columns, time_column=time_column, time_format=time_format)
    if options.event == "phase-curve" and phases == PHASE_MODELS:
        phases = PHASE_CURVE_MODELS
    rows: list[dict[str, Any]] = []
    for phase in phases:
        res = fit_prepared(prep, method, options=options, seed=seed, phase=phase, errors=False)
        rows.append({"phase": phase, "k": res.k, "depth_ppm": res.depth_ppm,
                     "depth_err_ppm": res.depth_err_ppm, "bic": res.bic, "aic": res.aic,
                     "chi2_red": res.chi2_red, "beta_red": res.beta_red})
    min_bic = min(r["bic"] for r in rows)
    min_aic = min(r["aic"] for r in rows)
    for r in rows:
        r["delta_bic"] = r["bic"] - min_bic
        r["delta_aic"] = r["aic"] - min_aic
    best_bic = min(rows, key=lambda r: r["bic"])
    best_aic = min(rows, key=lambda r: r["aic"])
    chosen = (best_bic["phase"], best_aic["phase"])
    lo, hi = sorted((best_bic["k"], best_aic["k"]))
    bracket = tuple(r["phase"] for r in sorted(rows, key=lambda r: r["k"])
                    if lo < r["k"] < hi or r["phase"] in chosen)
    return PhaseSelection(method=method, epoch=prep.epoch, rows=tuple(rows),
                          best_bic=best_bic["phase"], best_aic=best_aic["phase"], bracket=bracket)


# --------------------------------------------------------------------------- joint fit
@dataclass(frozen=True)
class JointResult:
    """One depth common to several epochs; every other parameter per epoch."""

    method: str
    epochs: tuple[int | None, ...]
    depth_ppm: float
    depth_err_ppm: float
    depth_err_jacobian_ppm: float
    beta_red: float
    chi2_red: float
    bic: float
    aic: float
    k: int
    n_points: int
    phase: str
    converged: bool
    t_ecl_bmjd: tuple[float, ...]
    per_epoch: tuple[dict[str, Any], ...]

    @property
    def depth_combined_ppm(self) -> float:
        """Inverse-variance mean of the epochs' depths fitted alone."""
        w = 1.0 / np.array([e["depth_alone_err_ppm"] for e in self.per_epoch]) ** 2
        return float(np.sum(w * [e["depth_alone_ppm"] for e in self.per_epoch]) / np.sum(w))

    @property
    def depth_combined_err_ppm(self) -> float:
        """``1 / sqrt(sum 1 / sigma_i^2)`` of the epochs' errors fitted alone."""
        w = 1.0 / np.array([e["depth_alone_err_ppm"] for e in self.per_epoch]) ** 2
        return float(1.0 / np.sqrt(np.sum(w)))

    def to_dict(self) -> dict[str, Any]:
        return {"method": self.method, "joint": True, "epochs": list(self.epochs),
                "depth_ppm": self.depth_ppm,
                "depth_combined_ppm": self.depth_combined_ppm,
                "depth_combined_err_ppm": self.depth_combined_err_ppm,
                "depth_err_ppm": self.depth_err_ppm,
                "depth_err_jacobian_ppm": self.depth_err_jacobian_ppm,
                "beta_red": self.beta_red, "chi2_red": self.chi2_red, "bic": self.bic,
                "aic": self.aic, "k": self.k, "n_points": self.n_points, "phase": self.phase,
                "converged": self.converged, "t_ecl_bmjd": list(self.t_ecl_bmjd),
                "per_epoch": list(self.per_epoch), **joint_extra_keys(self)}

    def __repr__(self) -> str:
        return text_repr("JointResult", joint_fields_shown(self))

    def _repr_html_(self) -> str:
        return html_repr("JointResult", joint_fields_shown(self))


class _JointProblem:
    """Residuals of several epochs with the depth (parameter 0) shared."""

    def __init__(self, problems: list[_Problem]):
        self.problems = problems
        self.sizes = [len(p.astro) + p.n_sys - 1 for p in problems]
        self.offsets = np.concatenate([[1], 1 + np.cumsum(self.sizes)]).astype(int)
        self.lower = np.concatenate([[problems[0].lower[0]]] + [p.lower[1:] for p in problems])
        self.upper = np.concatenate([[problems[0].upper[0]]] + [p.upper[1:] for p in problems])

    def epoch_theta(self, theta: np.ndarray, i: int) -> np.ndarray:
        return np.concatenate([[theta[0]], theta[self.offsets[i]:self.offsets[i + 1]]])

    def scales(self, theta: np.ndarray) -> np.ndarray:
        parts = [self.problems[0].astro.scales[:1]]
        for i, p in enumerate(self.problems):
            parts.append(p.scales(self.epoch_theta(theta, i))[1:])
        return np.concatenate(parts)

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        return np.concatenate([p.residuals(self.epoch_theta(theta, i))
                               for i, p in enumerate(self.problems)])

    def jacobian(self, theta: np.ndarray, *, central: bool = False) -> np.ndarray:
        """Block-structured finite differences: each epoch's block touches only its rows.

        An epoch's rows are its residuals (bins, for a method that fits bins).
        """
        blocks = [p.jacobian(self.epoch_theta(theta, i), central=central)
                  for i, p in enumerate(self.problems)]
        jac = np.zeros((sum(len(b) for b in blocks), len(theta)))
        row = 0
        for i, block in enumerate(blocks):
            rows = slice(row, row + len(block))
            jac[rows, 0] = block[:, 0]
            jac[rows, self.offsets[i]:self.offsets[i + 1]] = block[:, 1:]
            row += len(block)
        return jac


def reduce_joint(tables, method: str, *, options: ReduceSection = _DEFAULT_OPTIONS, system=None,
                 seed: int = 0, epochs=None, method_options=None,
                 resources: Mapping[str, Any] | None = None, pmap=None,
                 columns: Mapping[str, str] | None = None, time_column: str | None = None,
                 time_format: str | None = None) -> JointResult:
    """Fit several epochs with one common depth (per-epoch eclipse time, phase, ramp, method).

    Each epoch is first fitted alone (its solution starts the joint fit), then
    all are fitted together by least squares, as the KR/Data and BLISS teams
    did besides their per-epoch fits (paper, App. B.1, B.4). The depth error is
    the Jacobian error times ``max(1, beta_red)``, with ``beta_red`` the mean
    of the epochs' red-noise factors. ``per_epoch`` keeps each epoch's fit
    alone (``depth_alone_ppm``, ``depth_alone_err_ppm``: Jacobian x
    max(1, beta_red)), and ``depth_combined_ppm`` / ``depth_combined_err_ppm``
    their inverse-variance combination, to set beside the joint depth.
    """
    tables = list(tables)
    if not tables:
        raise InputError("reduce_joint: no photometry tables given")
    if options.event != "eclipse":
        raise InputError(f"reduce_joint: event '{options.event}': joint fits share an eclipse "
                         "depth; fit each transit alone (and each phase curve)")
    epochs = list(epochs) if epochs is not None else [None] * len(tables)
    if len(epochs) != len(tables):
        raise InputError("reduce_joint: give one epoch number per table")
    problems, fits, preps = [], [], []
    for table, ep in zip(tables, epochs, strict=True):
        prep = prepare_epoch(table, method, options=options, system=system, epoch=ep, seed=seed,
                             method_options=method_options,
                             resources=_resources(resources, pmap), columns=columns,
                             time_column=time_column, time_format=time_format)
        astro_model = prep.astro_model(options)
        theta0 = astro_model.initial(depth=1e-3, t_ecl_bmjd=prep.t_ecl_predicted_bmjd)
        fit = fit_leastsq(prep.systematics, astro_model, theta0, max_nfev=options.max_nfev,
                          beta_bin_minutes=tuple(options.beta_bin_minutes))
        preps.append(prep)
        fits.append(fit)
        problems.append(_Problem(prep.systematics, astro_model))
    joint = _JointProblem(problems)
    weights = np.array([1.0 / max(f.error("depth"), 1e-12) ** 2 for f in fits])
    depth0 = float(np.sum(weights * [f.value("depth") for f in fits]) / np.sum(weights))
    theta0 = np.concatenate([[depth0]] + [f.theta[1:] for f in fits])
    theta0 = np.clip(theta0, joint.lower, joint.upper)
    sol = least_squares(joint.residuals, theta0, jac=lambda th: joint.jacobian(th),
                        bounds=(joint.lower, joint.upper), x_scale=joint.scales(theta0),
                        method="trf", max_nfev=options.max_nfev, xtol=1e-10, ftol=1e-10,
                        gtol=1e-10)
    theta = sol.x
    per_epoch: list[dict[str, Any]] = []
    betas, loglike, chi2, k, n = [], 0.0, 0.0, 1, 0
    for i, (p, prep) in enumerate(zip(problems, preps, strict=True)):
        s = _summarise(p, joint.epoch_theta(theta, i), sol.nfev, bool(sol.success),
                       str(sol.message), tuple(options.beta_bin_minutes))
        betas.append(s.beta_red)
        loglike += s.log_likelihood
        chi2 += s.chi2
        k += s.k - 1
        n += s.n_data
        per_epoch.append({"epoch": prep.epoch, "t_ecl_bmjd": s.value("t_ecl_bmjd"),
                          "rms_ppm": s.rms_ppm, "beta_red": s.beta_red, "chi2_red": s.chi2_red,
                          "n_points": s.n_data,
                          "depth_alone_ppm": fits[i].value("depth") * 1e6,
                          "depth_alone_err_ppm": fits[i].error("depth") * 1e6
                          * (max(1.0, fits[i].beta_red) if np.isfinite(fits[i].beta_red)
                             else 1.0)})
    chi2_red = chi2 / (n - k)
    jac = joint.jacobian(theta, central=True)
    cov = _covariance(jac, chi2_red)
    err_depth = float(np.sqrt(max(cov[0, 0], 0.0)))
    finite_betas = [b for b in betas if np.isfinite(b)]
    beta = float(np.mean(finite_betas)) if finite_betas else float("nan")
    inflate = max(1.0, beta) if np.isfinite(beta) else 1.0
    bic = -2.0 * loglike + k * np.log(n)
    aic = -2.0 * loglike + 2.0 * k
    return JointResult(method=method, epochs=tuple(p.epoch for p in preps),
                       depth_ppm=float(theta[0] * 1e6), depth_err_ppm=err_depth * inflate * 1e6,
                       depth_err_jacobian_ppm=err_depth * 1e6, beta_red=beta, chi2_red=chi2_red,
                       bic=float(bic), aic=float(aic), k=k, n_points=n,
                       phase=problems[0].astro.phase, converged=bool(sol.success),
                       t_ecl_bmjd=tuple(e["t_ecl_bmjd"] for e in per_epoch),
                       per_epoch=tuple(per_epoch))

