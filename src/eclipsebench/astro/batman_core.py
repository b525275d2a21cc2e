"""batman's two compiled routines, called directly: the package's one use of batman's private API.

:mod:`eclipsebench.astro.eclipse` uses batman's public ``TransitModel`` to
tabulate an event's shape once. The fit's transit model
(:class:`eclipsebench.fit.model.AstroModel`) evaluates the transit
thousands of times per second with the orbit fixed or free, where building a
``TransitModel`` per call (it re-derives the geometry and its integration
settings each time) costs more than the curve itself. It therefore calls the
two C routines that ``TransitModel.light_curve`` calls, ``_rsky`` (the sky
separation of the orbit) and ``_quadratic_ld`` (Mandel & Agol's quadratic
limb darkening), through the two functions below, so that a change of
batman's private API touches this module only; a test checks them against
``batman.TransitModel`` (``tests/fit/test_transit.py``).
"""

from __future__ import annotations

import numpy as np
from batman import _quadratic_ld, _rsky

__all__ = ["sky_separation", "quadratic_transit"]


def sky_separation(time: np.ndarray, t0: float, period_d: float, a_rs: float, inc_rad: float,
                   ecc: float, omega_rad: float) -> np.ndarray:
    """batman's ``rsky``: planet-star separation (stellar radii; 100 behind the star) at ``time``.

    ``t0`` is batman's time of inferior conjunction, in the units of ``time`` and ``period_d``.
    """
    return _rsky._rsky(time, t0, period_d, a_rs, inc_rad, ecc, omega_rad, 1, 1)


def quadratic_transit(separation: np.ndarray, rp_rs: float, u1: float, u2: float) -> np.ndarray:
    """batman's quadratic limb-darkened transit (1 out of transit) at the separations given."""
    return _quadratic_ld._quadratic_ld(separation, rp_rs, u1, u2, 1)
