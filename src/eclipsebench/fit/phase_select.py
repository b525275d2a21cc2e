"""Phase-model selection: every phase model of an epoch fitted, BIC and AIC for each.

The paper (Section 4.2) found the choice of phase model to move the depth;
:func:`select_phase_model` fits every model so that a user can bracket it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ..config.reduce import ReduceSection
from ..decorrelate.base import MethodOptions
from .epoch_fit import fit_prepared
from .model import PHASE_MODELS, AstroModel
from .prepare import _DEFAULT_OPTIONS, _resources, prepare_epoch

__all__ = ["PhaseSelection", "select_phase_model"]


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
                       system=None, seed: int = 0, epoch: int | None = None,
                       method_options: MethodOptions | None = None,
                       resources: Mapping[str, Any] | None = None, pmap=None,
                       phases: tuple[str, ...] = PHASE_MODELS,
                       columns: Mapping[str, str] | None = None, time_column: str | None = None,
                       time_format: str | None = None,
                       time_options: Mapping[str, Any] | None = None, system_section: Any = None,
                       labels: Mapping[str, str] | None = None) -> PhaseSelection:
    """Fit each phase model by least squares and report BIC and AIC for each.

    The method is built once and reused; each model's depth error is the
    Jacobian error times ``max(1, beta_red)`` (no prayer bead or MCMC, to keep
    the comparison fast). ``system_section`` and ``labels`` are as
    :func:`~eclipsebench.fit.prepare.prepare_epoch` takes them.
    """
    prep = prepare_epoch(table, method, options=options, system=system, epoch=epoch, seed=seed,
                         method_options=method_options, resources=_resources(resources, pmap),
                         columns=columns, time_column=time_column, time_format=time_format,
                         time_options=time_options, system_section=system_section,
                         labels=labels)
    if phases == PHASE_MODELS:   # the default: the event's own models (a phase curve's)
        phases = AstroModel.event_class(options.event).phase_models
    rows: list[dict[str, Any]] = []
    for phase in phases:
        res = fit_prepared(prep, method, options=options, phase=phase, errors=False)
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
