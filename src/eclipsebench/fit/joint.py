"""The joint fit of several epochs with one common depth (``reduce DIR --method M``).

Each epoch keeps its own eclipse time, phase curve and systematics; the
depth is shared. :func:`reduce_joint` returns a :class:`JointResult`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from ..astro.events import event_for
from ..config.reduce import ReduceSection
from ..errors import InputError
from .leastsq import (
    _covariance,
    _Problem,
    _summarise,
    fit_leastsq,
)
from .prepare import (
    _DEFAULT_OPTIONS,
    _read,
    _resources,
    _source,
    prepare_epoch,
    resolve_method_options,
    resolve_system,
)
from .result import JointResult

__all__ = ["reduce_joint"]


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
                 time_format: str | None = None,
                 time_options: Mapping[str, Any] | None = None, system_section: Any = None,
                 labels: Mapping[str, str] | None = None) -> JointResult:
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
    method_options = resolve_method_options(method, options, method_options)  # once, for all
    hint = dict(labels or {}).get("system", "system=NAME")
    if system is None:
        tables = [_read(table) for table in tables]
        system = _one_planet(tables, system_section, hint)
    problems, fits, preps = [], [], []
    for table, ep in zip(tables, epochs, strict=True):
        prep = prepare_epoch(table, method, options=options, system=system, epoch=ep, seed=seed,
                             method_options=method_options,
                             resources=_resources(resources, pmap), columns=columns,
                             time_column=time_column, time_format=time_format,
                             time_options=time_options, system_section=system_section,
                             labels=labels)
        astro_model = prep.astro_model(options)
        theta0 = astro_model.initial(depth=1e-3, t_event_bmjd=prep.t_event_predicted_bmjd)
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
