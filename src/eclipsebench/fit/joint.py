"""The joint fit of several epochs with one common depth (``reduce DIR --method M``).

Each epoch keeps its own eclipse time, phase curve and systematics; the
depth is shared. :func:`reduce_joint` returns a :class:`JointResult`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from ..astro.events import event_for
from ..config.reduce import ReduceSection
from ..decorrelate.base import MethodOptions
from ..errors import InputError
from ..io.plain import json_safe
from .leastsq import (
    _covariance,
    _Problem,
    _summarise,
    fit_leastsq,
    has_hyperparameters,
    joint_names,
)
from .model import AstroModel
from .prepare import (
    _DEFAULT_OPTIONS,
    PreparedEpoch,
    _read,
    _resources,
    _source,
    prepare_epoch,
    resolve_method_options,
    resolve_system,
)
from .result import EpochResult, JointResult

__all__ = ["reduce_joint", "start_of"]


@dataclass(frozen=True)
class _Alone:
    """What the joint fit takes from an epoch fitted alone: the least-squares parameters
    (``theta``: astro then systematics, :func:`~eclipsebench.fit.leastsq.joint_names`), the
    depth's Jacobian error (fraction, not yet times beta) and the red-noise factor."""

    theta: np.ndarray
    depth_err: float
    beta_red: float

    @property
    def depth(self) -> float:
        return float(self.theta[0])


def start_of(result: EpochResult | None, prep: PreparedEpoch, astro_model: AstroModel,
             method: str, seed: int) -> _Alone | None:
    """The epoch's fit alone taken from ``result`` (a :func:`reduce_epoch` of it), or None
    when ``result`` is not the fit :func:`reduce_joint` would make.

    It is that fit when it is of the same method, epoch, planet and seed, in the
    controlled profile (the ``[reduce]`` settings as given, no team's choices), with the
    least-squares sampler (so ``params`` are the least-squares solution and
    ``param_errors`` its Jacobian errors: with MCMC they are the posterior's), the same
    method options, phase, ramp and eclipse shape, on the same points, with the same
    parameters (by name). A method that sets maximum-likelihood settings between fits
    (:func:`~eclipsebench.fit.leastsq.has_hyperparameters`: GP's kernel, PLD's bin size,
    SegPoly) is never started from a result: its fit alone leaves those settings on the
    method, the joint fit uses them, and a result does not record them (started without
    them, PLD's joint depth on a two-epoch campaign moved by 125 ppm). The ``[reduce]`` settings a result does
    not record (``max_nfev``, ``beta_bin_minutes``, the limb darkening ...) are the
    caller's to keep equal: give results made with the ``options`` given to
    :func:`reduce_joint`.
    """
    if result is None or has_hyperparameters(prep.systematics):
        return None
    names = joint_names(astro_model, prep.systematics)
    same = (result.method == method and result.epoch == prep.epoch and result.seed == seed
            and result.profile == "controlled" and result.sampler == "leastsq"
            and result.system == str(getattr(prep.system, "name", prep.system))
            and result.options == json_safe(prep.systematics.options.to_dict(),
                                            nonfinite="keep")
            and (result.phase, result.ramp, result.eclipse_shape)
            == (astro_model.phase, astro_model.ramp, astro_model.eclipse_shape)
            and result.n_points == len(prep.systematics.data.time_bmjd)
            # by name: a result read back from its JSON has its keys sorted
            and sorted(result.params) == sorted(names)
            and sorted(result.param_errors) == sorted(names)
            and len(set(names)) == len(names)
            and names[0] == "depth")
    if not same:
        return None
    theta = np.array([result.params[n] for n in names], dtype=float)
    depth_err = float(result.param_errors["depth"])
    if not (np.all(np.isfinite(theta)) and np.isfinite(depth_err) and depth_err > 0):
        return None
    return _Alone(theta=theta, depth_err=depth_err, beta_red=float(result.beta_red))


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
                 seed: int = 0, epochs=None, method_options: MethodOptions | None = None,
                 resources: Mapping[str, Any] | None = None, pmap=None,
                 columns: Mapping[str, str] | None = None, time_column: str | None = None,
                 time_format: str | None = None,
                 time_options: Mapping[str, Any] | None = None, system_section: Any = None,
                 labels: Mapping[str, str] | None = None,
                 starts: Sequence[EpochResult | None] | None = None) -> JointResult:
    """Fit several epochs with one common depth (per-epoch eclipse time, phase, ramp, method).

    Each epoch is first fitted alone (its solution starts the joint fit), then
    all are fitted together by least squares, as the KR/Data and BLISS teams
    did besides their per-epoch fits (paper, App. B.1, B.4). The depth error is
    the Jacobian error times ``max(1, beta_red)``, with ``beta_red`` the mean
    of the epochs' red-noise factors. ``per_epoch`` keeps each epoch's fit
    alone (``depth_alone_ppm``, ``depth_alone_err_ppm``: Jacobian x
    max(1, beta_red)), and ``depth_combined_ppm`` / ``depth_combined_err_ppm``
    their inverse-variance combination, to set beside the joint depth.

    The fit is of one planet: ``system``, else the one every table names
    (``system_section`` and ``labels`` as :func:`~eclipsebench.fit.prepare.prepare_epoch`
    takes them); tables naming two planets are refused before any fit.

    ``starts``, one per table (None where there is none), are the epochs' fits alone
    already made: :func:`~eclipsebench.fit.reduce.reduce_epoch` of the same table with the
    same ``options``, ``method_options``, ``seed`` and epoch, in the controlled profile
    with the least-squares sampler (``campaign`` passes its own reductions). A start is
    used only where :func:`start_of` finds it is the fit this function would make (its
    recorded method, epoch, seed, profile, sampler, method options, models, points and
    parameters); that epoch is then not fitted again, and its least-squares parameters,
    Jacobian depth error and ``beta_red`` are those of the fit alone. Any other epoch is
    fitted alone here. The answer is the same either way: the fit alone is deterministic
    and a result keeps its numbers exactly (JSON floats round-trip).
    """
    tables = list(tables)
    if not tables:
        raise InputError("reduce_joint: no photometry tables given")
    if not event_for(options.event).joint_fit:
        raise InputError(f"reduce_joint: event '{options.event}': joint fits share an eclipse "
                         "depth; fit each transit alone (and each phase curve)")
    epochs = list(epochs) if epochs is not None else [None] * len(tables)
    if len(epochs) != len(tables):
        raise InputError("reduce_joint: give one epoch number per table")
    starts = list(starts) if starts is not None else [None] * len(tables)
    if len(starts) != len(tables):
        raise InputError("reduce_joint: give one start (or None) per table")
    if method_options is None:   # else resolved at the caller's edge, once for all epochs
        method_options = resolve_method_options(method, options)
    hint = dict(labels or {}).get("system", "system=NAME")
    if system is None:
        tables = [_read(table) for table in tables]
        system = _one_planet(tables, system_section, hint)
    problems: list[_Problem] = []
    fits: list[_Alone] = []
    preps: list[PreparedEpoch] = []
    for table, ep, start in zip(tables, epochs, starts, strict=True):
        prep = prepare_epoch(table, method, options=options, system=system, epoch=ep, seed=seed,
                             method_options=method_options,
                             resources=_resources(resources, pmap), columns=columns,
                             time_column=time_column, time_format=time_format,
                             time_options=time_options, system_section=system_section,
                             labels=labels)
        astro_model = prep.astro_model(options)
        alone = start_of(start, prep, astro_model, method, seed)
        if alone is None:   # the fit alone of fit_prepared (epoch_fit.py), made here
            theta0 = astro_model.initial(depth=1e-3, t_event_bmjd=prep.t_event_predicted_bmjd)
            fit = fit_leastsq(prep.systematics, astro_model, theta0, max_nfev=options.max_nfev,
                              beta_bin_minutes=tuple(options.beta_bin_minutes))
            alone = _Alone(theta=fit.theta, depth_err=fit.error("depth"),
                           beta_red=fit.beta_red)
        preps.append(prep)
        fits.append(alone)
        problems.append(_Problem(prep.systematics, astro_model))
    joint = _JointProblem(problems)
    weights = np.array([1.0 / max(f.depth_err, 1e-12) ** 2 for f in fits])
    depth0 = float(np.sum(weights * [f.depth for f in fits]) / np.sum(weights))
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
                          "depth_alone_ppm": fits[i].depth * 1e6,
                          "depth_alone_err_ppm": fits[i].depth_err * 1e6
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


def _one_planet(tables: list, section: Any, hint: str):
    """The planet every table names (:func:`~eclipsebench.fit.prepare.resolve_system`);
    InputError naming the first table that names another."""
    first = resolve_system(None, tables[0].meta, _source(tables[0]), section=section, hint=hint)
    for table in tables[1:]:
        other = resolve_system(None, table.meta, _source(table), section=section, hint=hint)
        if other.name != first.name:
            raise InputError(f"{_source(table)}: names {other.name}, {_source(tables[0])} names "
                             f"{first.name}; a joint fit is of one planet (give {hint})")
    return first
