"""The one astrophysical model that every decorrelation method shares.

``AstroModel(time_bmjd, system, event=..., phase=..., ramp=..., ...)`` builds
the model of the event fitted, normalised so that 1 is the star alone::

    eclipse      A(t) = R(t) [1 + v(t) p(t)]                   EclipseModel
    transit      A(t) = R(t) [T(t) + p(t)]                     TransitModel
    phase-curve  A(t) = R(t) O(t) [T(t) + v(t) p(t)]           PhaseCurveModel

``v(t)`` is the planet's visible fraction, ``T(t)`` the star's flux in
transit, ``p(t)`` the planet-to-star flux ratio (a phase term, ``p(t_ecl) =
D``), ``R(t)`` the detector ramp and ``O(t)`` a phase curve's AOR offsets.
The parameter vector starts with the event's size (the eclipse depth, or
Rp/R*) and its time, then the event's shape parameters, the phase
coefficients and the ramp's (a phase curve's AOR offsets last).

The model is one class per event, composed with a phase term and a ramp
instead of one class switching on their names:

- :mod:`.base`: :class:`AstroModel`, the base with what every event
  shares. It is also the one constructor: ``AstroModel(...)`` returns the
  subclass of its ``event`` (its ``__new__`` picks it), so
  ``isinstance(m, AstroModel)`` holds for every model and callers need not
  know the subclasses; each subclass may also be called directly.
- :mod:`.eclipse`: :class:`EclipseModel` (physical or box shape, the
  compiled batch); :mod:`.transit`: :class:`TransitModel` (batman's
  transit, free a_rs, b, q1, q2 and their priors); :mod:`.phase_curve`:
  :class:`PhaseCurveModel` (harmonics, exposure integration, AOR offsets).
  Each module gives its event's equations.
- :mod:`.parts`: the phase terms and ramps (:data:`~.parts.PHASE_TERMS`,
  :data:`~.parts.RAMPS`, with their equations) and the pure helpers;
  :mod:`.kernels`: the eclipse batch's numba kernels.
- :mod:`.settings`: each event's own settings (:class:`TransitSettings`,
  :class:`PhaseCurveSettings`, :class:`EclipseSettings`), one object given as
  ``settings=`` instead of keywords that only one event reads.

This module imports every event's model (so that ``AstroModel`` knows them
all) and keeps the public names: import from here.

Examples
--------
>>> import numpy as np
>>> from eclipsebench.astro.catalogue import get_system
>>> time_bmjd = np.linspace(57215.3, 57215.5, 5)
>>> m = AstroModel(time_bmjd, get_system("XO-3b"), phase="linear", ramp="linear")
>>> isinstance(m, EclipseModel), m.names
(True, ('depth', 't_ecl_bmjd', 'c1_per_day', 'ramp_slope_per_day'))
>>> type(AstroModel(time_bmjd, get_system("XO-3b"), event="transit")).__name__
'TransitModel'
"""

from __future__ import annotations

from ..names import ECLIPSE_SHAPES, EVENTS, PHASE_CURVE_MODELS, PHASE_MODELS, RAMP_MODELS
from .base import AstroModel
from .eclipse import EclipseModel
from .parts import (
    TRANSIT_FREE,
    aor_order,
    box_visible_fraction,
    integration_offsets_d,
    q_from_u,
    system_period_days,
    u_from_q,
)
from .phase_curve import PhaseCurveModel
from .settings import EclipseSettings, PhaseCurveSettings, TransitSettings
from .transit import TransitModel

__all__ = ["AstroModel", "PHASE_MODELS", "PHASE_CURVE_MODELS", "RAMP_MODELS", "ECLIPSE_SHAPES",
           "EVENTS", "TRANSIT_FREE", "box_visible_fraction", "system_period_days", "q_from_u",
           "u_from_q", "integration_offsets_d", "aor_order", "EclipseModel", "TransitModel",
           "PhaseCurveModel", "depth_limit_ppm", "EclipseSettings", "TransitSettings",
           "PhaseCurveSettings"]


def depth_limit_ppm(event: str) -> float:
    """The deepest event (ppm) a fit can return: the upper bound of its size parameter.

    An eclipse's or a phase curve's depth lies below ``DEPTH_BOUNDS[1]`` (0.1 of
    the star's flux: 100,000 ppm); a transit's Rp/R* below
    ``TRANSIT_BOUNDS["rp_rs"][1]`` (0.5: a geometric depth of 250,000 ppm). A
    depth at or above it cannot be measured: the fit stops on the bound.

    Examples
    --------
    >>> depth_limit_ppm("eclipse"), depth_limit_ppm("transit")
    (100000.0, 250000.0)
    """
    return AstroModel.event_class(event).depth_limit_ppm()
