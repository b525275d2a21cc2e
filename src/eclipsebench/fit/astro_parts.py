"""The parts every event's astrophysical model is built from, and their pure helpers.

The parameter names' typical magnitudes and the transit's bounds; the
exposure integration (:func:`integration_offsets_d`), the AORs' order
(:func:`aor_order`), the box eclipse (:func:`box_visible_fraction`),
Kipping's (2013) limb-darkening parametrisation (:func:`u_from_q`,
:func:`q_from_u`) and the inclination of an impact parameter. The models
themselves are in :mod:`.astro_eclipse`, :mod:`.astro_transit` and
:mod:`.astro_phase_curve` (:class:`~eclipsebench.fit.astro_model.AstroModel`
picks one).
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np

from ..errors import InputError

__all__ = ["TRANSIT_FREE", "SCALES", "TRANSIT_BOUNDS", "MAX_SUBEXPOSURE_S", "NONNEGATIVE_SCALE",
           "VisibleFraction", "integration_offsets_d", "aor_order", "system_period_days",
           "box_visible_fraction", "half_depth_duration", "u_from_q", "q_from_u",
           "inclination_deg"]

#: The transit's optional free parameters, in the order they take in the vector.
TRANSIT_FREE = ("a_rs", "b", "q1", "q2")
#: Typical magnitude of each parameter: sets finite-difference steps (1 % of it)
#: and the size of the initial MCMC ball.
SCALES = {"depth": 1e-4, "t_ecl_bmjd": 1e-3, "c1_per_day": 1e-3, "c2_per_day2": 1e-3,
          "c_cos": 1e-4, "c_sin": 1e-4, "ramp_slope_per_day": 1e-3, "ramp_amplitude": 1e-3,
          "ramp_tau_days": 1e-2, "rp_rs": 1e-3, "t_transit_bmjd": 1e-3, "a_rs": 1e-2,
          "b": 1e-2, "q1": 1e-2, "q2": 1e-2, "phase_a1": 1e-4, "phase_b1": 1e-4,
          "phase_a2": 1e-4, "phase_b2": 1e-4, "aor_offset": 1e-4}
#: Bounds of the transit's parameters (also the MCMC's uniform prior): q1, q2 in
#: [0, 1] is Kipping's (2013) physically allowed triangle.
TRANSIT_BOUNDS = {"rp_rs": (0.0, 0.5), "a_rs": (1.5, 200.0), "b": (0.0, 1.5),
                  "q1": (0.0, 1.0), "q2": (0.0, 1.0)}
#: Longest sub-exposure (s) over which a row's model is averaged (:func:`integration_offsets_d`).
MAX_SUBEXPOSURE_S = 10.0
#: Scale (planet-to-star flux ratio) of the least-squares penalty residual that keeps a
#: phase curve's minimum non-negative (``nonnegative_planet``): -1 ppm adds 1 to chi2.
NONNEGATIVE_SCALE = 1e-6


def integration_offsets_d(exposure_s: float,
                          max_step_s: float = MAX_SUBEXPOSURE_S) -> np.ndarray:
    """Offsets (days) from a row's mid-time at which its model is averaged over the exposure.

    The midpoint rule with ``n = ceil(exposure_s / max_step_s)`` equal
    sub-exposures: the numerical resampling ("supersampling") of Kipping (2010,
    MNRAS 408, 1758) for long integrations (one row per 64-frame cube). A 2 s
    frame is one sample at its mid-time (offset 0).

    Examples
    --------
    >>> integration_offsets_d(2.0).tolist()
    [0.0]
    >>> (integration_offsets_d(30.0) * 86400.0).round(6).tolist()
    [-10.0, 0.0, 10.0]
    """
    if not (math.isfinite(exposure_s) and exposure_s >= 0):
        raise InputError(f"exposure_s {exposure_s!r}: expected a non-negative exposure in s")
    n = max(1, int(math.ceil(exposure_s / max_step_s - 1e-9)))
    return ((np.arange(n) + 0.5) / n - 0.5) * (exposure_s / 86400.0)


def aor_order(time_bmjd: np.ndarray, aorkey: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The AORs in the order of their first frame, and each frame's rank in that order.

    Examples
    --------
    >>> keys, rank = aor_order(np.array([3.0, 1.0, 2.0, 4.0]), np.array([7, 9, 9, 7]))
    >>> keys.tolist(), rank.tolist()
    ([9, 7], [1, 0, 0, 1])
    """
    keys, inverse = np.unique(np.asarray(aorkey), return_inverse=True)
    first = np.full(len(keys), np.inf)
    np.minimum.at(first, inverse.ravel(), np.asarray(time_bmjd, dtype=float))
    order = np.argsort(first, kind="stable")
    rank = np.empty(len(order), dtype=np.int64)
    rank[order] = np.arange(len(order))
    return keys[order], rank[inverse.ravel()]


class VisibleFraction(Protocol):
    """Anything with ``visible_fraction(t_ecl_bmjd) -> ndarray`` (the astro API)."""

    def visible_fraction(self, t_ecl_bmjd: float) -> np.ndarray: ...


def system_period_days(system: Any) -> float | None:
    """The orbital period of ``system`` in days, or None if it does not say."""
    for name in ("period_days", "period_d", "period"):
        value = getattr(system, name, None)
        if value is not None:
            return float(value)
    return None


def box_visible_fraction(time_bmjd: np.ndarray, t_ecl_bmjd: float | np.ndarray, duration_d: float,
                         exposure_d: float) -> np.ndarray:
    """A box eclipse averaged over each exposure.

    The planet is invisible for ``|t - t_ecl| < duration_d / 2``; a frame of
    length ``exposure_d`` that straddles a contact sees the fraction of its
    exposure outside the box, which keeps the model continuous in ``t_ecl``
    (a fitter can move the box by less than a frame).
    """
    edge = (np.abs(np.asarray(time_bmjd) - t_ecl_bmjd) - 0.5 * duration_d) / exposure_d + 0.5
    return np.clip(edge, 0.0, 1.0)


def half_depth_duration(time_bmjd: np.ndarray, visible: np.ndarray) -> float | None:
    """Time between the v = 0.5 crossings of ingress and egress, or None."""
    below = np.flatnonzero(visible < 0.5)
    if len(below) == 0 or below[0] == 0 or below[-1] == len(visible) - 1:
        return None
    i, j = below[0], below[-1]
    t_in = np.interp(0.5, [visible[i], visible[i - 1]], [time_bmjd[i], time_bmjd[i - 1]])
    t_out = np.interp(0.5, [visible[j], visible[j + 1]], [time_bmjd[j], time_bmjd[j + 1]])
    return float(t_out - t_in)


def u_from_q(q1: float, q2: float) -> tuple[float, float]:
    """Quadratic limb-darkening coefficients from Kipping's (2013) q1, q2 (his Eqs. 15-16).

    Examples
    --------
    >>> u_from_q(0.25, 0.25)
    (0.25, 0.25)
    """
    root = math.sqrt(q1)
    return 2.0 * root * q2, root * (1.0 - 2.0 * q2)


def q_from_u(u1: float, u2: float) -> tuple[float, float]:
    """Kipping's (2013) q1, q2 of quadratic coefficients u1, u2 (his Eqs. 17-18).

    ``q2`` is 0 when ``u1 + u2 = 0`` (a uniform disc, where it is undefined).

    Examples
    --------
    >>> q_from_u(0.25, 0.25)
    (0.25, 0.25)
    """
    total = u1 + u2
    return total * total, (u1 / (2.0 * total) if total != 0 else 0.0)


def inclination_deg(a_rs: float, b: float, ecc: float, omega_deg: float) -> float:
    """Inclination (deg) of impact parameter ``b`` (Winn 2010, Eq. 7, inverted).

    ``b = a cos i (1 - e^2) / (1 + e sin omega)``, the form of
    :attr:`eclipsebench.astro.catalogue.PlanetSystem.impact_parameter`; cos i
    is kept in [0, 1] (a ``b`` that ``a_rs`` cannot reach gives i = 0).
    """
    w = math.radians(omega_deg)
    cos_i = b * (1.0 + ecc * math.sin(w)) / (a_rs * (1.0 - ecc * ecc))
    return math.degrees(math.acos(min(max(cos_i, 0.0), 1.0)))

