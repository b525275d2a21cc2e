"""The joint fit of one prepared epoch: least squares, prayer bead, MCMC, the result.

:func:`fit_prepared` fits the astrophysical model times the method's
systematics, estimates the depth errors (Jacobian x beta_red, prayer bead,
posterior) and reports one by the error rule (:mod:`.error_rule`); a whole
phase curve's summary (amplitude, offset, night side) is
:func:`phase_curve_detail`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..config.reduce import ReduceSection
from ..decorrelate.base import Systematics
from ..io.plain import json_safe
from .data import median_cadence_s
from .error_rule import largest_estimate, reported_depth_error
from .leastsq import (
    FitResult,
    fit_leastsq,
    has_own_likelihood,
    prayer_bead,
)
from .mcmc import McmcResult, run_mcmc
from .model import AstroModel
from .prepare import PreparedEpoch
from .profiles import paper_profile
from .result import EpochResult, lightcurve_errors

__all__ = ["fit_prepared", "phase_curve_detail"]


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


def _prayer_bead_errors(systematics: Systematics, astro_model: AstroModel, fit: FitResult,
                        options: ReduceSection) -> tuple[float, float]:
    """The prayer bead's spread of the size and time parameters (``[reduce] prayer_bead_*``)."""
    if options.prayer_bead_mode == "all":
        beads = prayer_bead(systematics, astro_model, fit, n_shifts=None,
                            stride=options.prayer_bead_stride, max_nfev=options.max_nfev)
    else:
        beads = prayer_bead(systematics, astro_model, fit, n_shifts=options.prayer_bead_shifts)
    return float(np.std(beads[:, 0], ddof=1)), float(np.std(beads[:, 1], ddof=1))


def _sample_posterior(systematics: Systematics, astro_model: AstroModel, fit: FitResult,
                      options: ReduceSection, size: str) -> tuple[McmcResult, dict[str, Any]]:
    """The MCMC from the least-squares solution, and its summary for the result's ``mcmc``."""
    stream = systematics.context.stream("mcmc")   # rng(seed, "reduce", epoch, method, "mcmc")
    mc = run_mcmc(systematics, astro_model, fit.theta, fit.errors, names=fit.names,
                  rng=stream, n_walkers=options.mcmc_walkers, max_steps=options.mcmc_steps,
                  block_steps=options.mcmc_block_steps, tau_factor=options.mcmc_tau_factor,
                  noise_scale=_mcmc_noise_scale(systematics, fit), cov_start=fit.cov)
    i = fit.names.index(size)
    info = {"move": mc.move, "walkers": mc.n_walkers, "steps": mc.n_steps,
            "burn_in": mc.burn_in, "tau_max": float(np.max(mc.tau)),
            "n_over_tau": float(mc.n_over_tau),
            "acceptance": mc.acceptance, "converged": mc.converged,
            "noise_scale": _mcmc_noise_scale(systematics, fit),
            "depth_median_ppm": astro_model.depth_ppm(mc.median[i]),
            "depth_err_lo_ppm": astro_model.depth_difference_ppm(mc.p16[i], mc.median[i]),
            "depth_err_hi_ppm": astro_model.depth_difference_ppm(mc.median[i], mc.p84[i])}
    return mc, info


def _corrected_lightcurve(systematics: Systematics, astro_model: AstroModel,
                          theta: np.ndarray, n_astro: int) -> dict[str, np.ndarray]:
    """The decorrelated light curve at ``theta`` (``RESULT.lc.ecsv``)."""
    astro = astro_model(theta[:n_astro])
    theta_s = theta[n_astro:] if len(systematics.param_names) else None
    corrected = systematics.correct(astro, theta_s)
    return {"time_bmjd": np.asarray(systematics.data.time_bmjd, dtype=float),
            "flux_corrected": corrected, "astro_model": astro, "residual": corrected - astro,
            **lightcurve_errors(systematics.data.flux, systematics.data.flux_err, corrected)}


def _method_error_estimates(systematics, astro_model, fit, errors: bool
                            ) -> tuple[dict[str, float], float]:
    """The method's own depth errors and its separation variance, in the event's size parameter.

    The methods' hooks see the derivative per unit of the event's depth and give
    depth errors; ``scale`` (d size / d depth: 1 for an eclipse) turns them into
    errors of the size.
    """
    astro_fit, dastro = _depth_derivative(astro_model, fit)
    scale = astro_model.size_per_depth(fit.theta[0])
    dastro = dastro * scale
    separation_var = _extra_depth_variance(systematics, astro_fit, dastro) * scale ** 2
    own = {name: float(v) * scale for name, v in systematics.depth_error_estimates(
        astro_fit, dastro, fit.theta[fit.n_astro:] if len(systematics.param_names) else None
    ).items()} if errors else {}
    return own, separation_var


def fit_prepared(prep: PreparedEpoch, method: str, *, options: ReduceSection,
                 phase: str | None = None, errors: bool = True,
                 reported: tuple[str, ...] | None = None) -> EpochResult:
    """Fit a :class:`PreparedEpoch` (used by :func:`reduce_epoch` and the phase comparison).

    ``reported`` names the depth errors to report, the largest of them (the
    paper profile's team rule); None applies ``options.error_rule``.

    The errors are those of the event's size parameter ``astro_model.names[0]``
    (the depth, or a transit's Rp/R*) and time ``names[1]``; the ``depth_*``
    fields hold them as the event's depth (:meth:`AstroModel.depth_ppm`), and
    a transit's ``event_detail`` has Rp/R* and its error as fitted.

    The run seed is the method's (``prep.systematics.context.seed``): the one
    that seeded its streams and the MCMC's, and the one the result records.
    """
    systematics = prep.systematics
    astro_model = prep.astro_model(options, phase=phase)
    size, when = astro_model.names[:2]   # ("depth", "t_ecl_bmjd") or ("rp_rs", "t_transit_bmjd")
    theta0 = astro_model.initial(t_event_bmjd=prep.t_event_predicted_bmjd)
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
        pb_depth, pb_tecl = _prayer_bead_errors(systematics, astro_model, fit, options)
    mc, mcmc_info = (_sample_posterior(systematics, astro_model, fit, options, size) if sample
                     else (None, None))

    # the method's own depth-error estimates (size units) and its separation variance
    own, separation_var = _method_error_estimates(systematics, astro_model, fit, errors)
    shared = {"jacobian_beta": jac_depth * inflate, "prayer_bead": pb_depth,
              "mcmc": mc.error(size) if mc is not None else None}
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
    lightcurve = _corrected_lightcurve(systematics, astro_model, theta_report, fit.n_astro)
    params = {n: float(v) for n, v in zip(fit.names, theta_report, strict=True)}
    param_err = {n: float(e) for n, e in zip(fit.names, fit.errors, strict=True)}
    if mc is not None:
        param_err = {n: max(param_err[n], mc.error(n)) for n in fit.names}
    converged = bool(fit.success and (mc.converged if mc is not None else True))
    value = params[size]

    def ppm(err):   # an error of the size parameter as a depth error (ppm)
        return astro_model.depth_error_ppm(value, err)

    detail = (phase_curve_detail(astro_model, fit, mc, inflate) if astro_model.whole_orbit
              else astro_model.event_detail(value, depth_err, params[when], t_err,
                                            prep.t_event_predicted_bmjd))
    return EpochResult(
        method=method, epoch=prep.epoch,
        depth_ppm=astro_model.depth_ppm(value), depth_err_ppm=ppm(depth_err),
        depth_err_method=err_method, depth_leastsq_ppm=astro_model.depth_ppm(fit.value(size)),
        depth_err_jacobian_ppm=ppm(jac_depth),
        depth_err_prayer_bead_ppm=None if pb_depth is None else ppm(pb_depth),
        depth_err_mcmc_ppm=None if mc is None else ppm(mc.error(size)),
        depth_err_separation_ppm=ppm(float(np.sqrt(separation_var))),
        t_event_bmjd=params[when], t_event_err_d=t_err,
        t_event_predicted_bmjd=prep.t_event_predicted_bmjd,
        bic=fit.bic, aic=fit.aic, k=fit.k, log_likelihood=fit.log_likelihood,
        chi2_red=fit.chi2_red, rms_ppm=fit.rms_ppm, beta_red=fit.beta_red,
        cadence_s=median_cadence_s(prep.table["time_bmjd"]),
        n_frames=prep.n_frames, n_frames_dropped=dict(prep.n_frames_dropped),
        n_points=len(systematics.data.time_bmjd), bic_n_points=fit.n_data,
        phase=astro_model.phase, ramp=astro_model.ramp, eclipse_shape=astro_model.eclipse_shape,
        sampler="mcmc" if mc is not None else "leastsq", converged=converged,
        params=params, param_errors=param_err,
        mcmc=mcmc_info, system=str(getattr(prep.system, "name", prep.system)),
        seed=systematics.context.seed,
        options=systematics.options.to_dict(), diagnostics=json_safe(systematics.diagnostics(), nonfinite="keep"),
        depth_err_own_ppm={k: ppm(v) for k, v in own.items()}, lightcurve=lightcurve,
        chain=None if mc is None else {"names": np.asarray(mc.names),
                                       "samples": np.asarray(mc.samples)},
        event_detail=detail, time_conversion=(prep.table.meta or {}).get("TIMECONV"))


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
