"""From a photometry table and a method name to an eclipse depth: the public entry points.

:func:`reduce_epoch` fits one epoch, :func:`reduce_joint` fits several epochs
with one common depth, and :func:`select_phase_model` fits every phase-curve
model and reports BIC and AIC for each so that a user can bracket the choice
(paper Section 4.2). All three share one astrophysical model
(:class:`~eclipsebench.fit.model.AstroModel`); methods differ only in
their systematics model.

The fit is split by concern, one module each: preparing a table
(:mod:`.prepare`), the joint fit of one epoch (:mod:`.epoch_fit`), the error
rule (:mod:`.error_rule`), the profiles (:mod:`.profile_fit`), phase-model
selection (:mod:`.phase_select`), the multi-epoch fit (:mod:`.joint`) and the
result (:mod:`.result`). This module keeps their public names in one place.
"""

from __future__ import annotations

from .epoch_fit import fit_prepared, phase_curve_detail
from .joint import reduce_joint
from .phase_select import PhaseSelection, select_phase_model
from .prepare import (
    PreparedEpoch,
    configured_method_options,
    predicted_event_bmjd,
    prepare_epoch,
    resolve_method_options,
    resolve_system,
)
from .profile_fit import reduce_epoch, resolve_profile
from .result import EpochResult, JointResult

__all__ = ["EpochResult", "JointResult", "PhaseSelection", "reduce_epoch", "reduce_joint",
           "select_phase_model", "prepare_epoch", "PreparedEpoch", "fit_prepared",
           "resolve_system", "predicted_event_bmjd", "resolve_method_options",
           "configured_method_options", "resolve_profile", "phase_curve_detail"]
