"""The parts every event's astrophysical model is built from, and their pure helpers.

The planet's phase variation ``p(t)``, one :class:`PhaseTerm` per phase
model, written so that ``p(t_ecl) = D`` (``dt = t - t_ecl``, ``P`` the
period)::

    flat       p = D
    linear     p = D + c1 dt
    quadratic  p = D + c1 dt + c2 dt^2
    sinusoid   p = D + c1 [cos(2 pi dt / P) - 1] + c2 sin(2 pi dt / P)
    harmonic1  p = D + a1 (cos phi - 1) + b1 sin phi,  phi = 2 pi dt / P
    harmonic2  harmonic1 + a2 (cos 2 phi - 1) + b2 sin 2 phi

(the harmonics are :func:`eclipsebench.astro.phase_curves.harmonic_curve`,
a whole phase curve's). The multiplicative detector ramp ``R(t)``, one
:class:`Ramp` per ramp model (``t0`` the first frame)::

    none         R = 1
    linear       R = 1 + r1 (t - t0)
    exponential  R = 1 - a exp(-(t - t0) / tau)

Its constant level is left to the systematics model (every method fits the
flux normalisation). :data:`PHASE_TERMS` and :data:`RAMPS` give each model's
object by its name; the object carries its parameter names, its values for
one parameter vector and for rows of them (the MCMC's batch), and what the
compiled batch kernel needs.

Besides: the parameters' typical magnitudes and the transit's bounds; the
exposure integration (:func:`integration_offsets_d`), the AORs' order
(:func:`aor_order`), the box eclipse (:func:`box_visible_fraction`),
Kipping's (2013) limb-darkening parametrisation (:func:`u_from_q`,
:func:`q_from_u`) and the inclination of an impact parameter.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Any, ClassVar, Protocol

import numpy as np

from ...astro.phase_curves import (
    PHASE_MODELS,
    harmonic_curve,
    harmonic_from_terms,
    harmonic_terms,
)
from ...errors import InputError

__all__ = ["TRANSIT_FREE", "SCALES", "TRANSIT_BOUNDS", "MAX_SUBEXPOSURE_S", "NONNEGATIVE_SCALE",
           "VisibleFraction", "integration_offsets_d", "aor_order", "system_period_days",
           "box_visible_fraction", "half_depth_duration", "u_from_q", "q_from_u",
           "inclination_deg", "PhaseTerm", "Ramp", "PHASE_TERMS", "RAMPS", "known_period"]

#: The transit's optional free parameters, in the order they take in the vector.
TRANSIT_FREE = ("a_rs", "b", "q1", "q2")
#: Typical magnitude of each parameter: sets finite-difference steps (1 % of it)
#: and the size of the initial MCMC ball.
SCALES = {"depth": 1e-4, "t_ecl_bmjd": 1e-3, "c1_per_day": 1e-3, "c2_per_day2": 1e-3,
          "c_cos": 1e-4, "c_sin": 1e-4, "ramp_slope_per_day": 1e-3, "ramp_amplitude": 1e-3,
          "ramp_tau_days": 1e-2, "rp_rs": 1e-3, "t_transit_bmjd": 1e-3, "a_rs": 1e-2,
          "b": 1e-2, "q1": 1e-2, "q2": 1e-2, "phase_a1": 1e-4, "phase_b1": 1e-4,
          "phase_a2": 1e-4, "phase_b2": 1e-4, "aor_offset": 1e-4}
#: Bounds of an eclipse's (and a phase curve's) depth, as a fraction of the star's flux:
#: the fit returns no depth outside them (also the MCMC's uniform prior).
DEPTH_BOUNDS = (-0.1, 0.1)
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



def known_period(period_d: float | None) -> float:
    """``period_d``, or an error if the orbital period is unknown (None)."""
    if period_d is None:
        raise InputError("the orbital period is unknown (give period_d)")
    return period_d


class PhaseTerm:
    """p(t), the planet-to-star flux ratio of one phase model, ``p(t_ecl) = level``.

    ``level`` is the depth (an eclipse or phase curve) or 0 (a transit's
    variation about mid-transit); ``c`` the model's coefficients (its
    :attr:`names`, in order); ``dt = time - t_ecl``.

    Examples
    --------
    >>> quadratic = PHASE_TERMS["quadratic"]
    >>> quadratic.names
    ('c1_per_day', 'c2_per_day2')
    >>> quadratic.value(2e-3, np.array([0.01, -0.1]), np.array([0.0, 0.1]), None).tolist()
    [0.002, 0.002]
    """

    #: The model's name (``phase``).
    kind: ClassVar[str] = ""
    #: Its coefficients' names, in the parameter vector's order.
    names: ClassVar[tuple[str, ...]] = ()
    #: True when p varies in time (every model but "flat").
    varies: ClassVar[bool] = True
    #: True when p needs the orbital period.
    needs_period: ClassVar[bool] = False
    #: The model's code in the compiled eclipse batch (``_astro_rows``); None: numpy's.
    kernel_code: ClassVar[int | None] = None

    def _period(self, period_d: float | None) -> float:
        return known_period(period_d) if self.needs_period else 1.0

    def value(self, level: float, c: np.ndarray, dt: np.ndarray,
              period_d: float | None) -> np.ndarray:
        """p at the times ``dt`` from mid-eclipse of one parameter vector: the model's one
        definition in :mod:`eclipsebench.astro.phase_curves`."""
        return PHASE_MODELS[self.kind](dt, (level, *c), period=self._period(period_d))

    def rows(self, level: np.ndarray, c: np.ndarray, dt: np.ndarray,
             period_d: float | None) -> np.ndarray:
        """p of every row: ``level`` (m, 1), ``c`` (m, len(names)), ``dt`` (m, n); the same
        arithmetic as :meth:`value`, broadcast."""
        columns = tuple(c[:, j:j + 1] for j in range(len(self.names)))
        return PHASE_MODELS[self.kind](dt, (level, *columns), period=self._period(period_d))


class FlatPhase(PhaseTerm):
    """p = D: no phase variation."""

    kind = "flat"
    varies = False
    kernel_code = 0


class LinearPhase(PhaseTerm):
    """p = D + c1 dt."""

    kind = "linear"
    names = ("c1_per_day",)
    kernel_code = 1


class QuadraticPhase(PhaseTerm):
    """p = D + c1 dt + c2 dt^2, evaluated as ``D + dt (c1 + c2 dt)``."""

    kind = "quadratic"
    names = ("c1_per_day", "c2_per_day2")
    kernel_code = 2


class SinusoidPhase(PhaseTerm):
    """p = D + c1 [cos(2 pi dt / P) - 1] + c2 sin(2 pi dt / P)."""

    kind = "sinusoid"
    names = ("c_cos", "c_sin")
    needs_period = True


class FirstHarmonic(PhaseTerm):
    """A whole phase curve's first harmonic (:func:`harmonic_curve` of phi = 2 pi dt / P)."""

    kind = "harmonic1"
    names: ClassVar[tuple[str, ...]] = ("phase_a1", "phase_b1")
    needs_period = True

    def value(self, level, c, dt, period_d):
        return harmonic_curve((2.0 * np.pi / known_period(period_d)) * dt, level, c)

    def terms(self, dt: np.ndarray, period_d: float | None) -> tuple[np.ndarray, ...]:
        """What :meth:`value` weighs by the coefficients (:func:`harmonic_terms`): they
        depend on the eclipse time alone."""
        return harmonic_terms((2.0 * np.pi / known_period(period_d)) * dt, len(self.names) // 2)

    def from_terms(self, level, c, terms: np.ndarray | tuple[np.ndarray, ...]) -> np.ndarray:
        """:meth:`value` from its :meth:`terms` (the same arithmetic)."""
        return harmonic_from_terms(terms, level, c)

    def rows(self, level, c, dt, period_d):
        return np.stack([self.value(level[i, 0], c[i], dt[i], period_d)
                         for i in range(len(dt))])


class SecondHarmonic(FirstHarmonic):
    """The first and second harmonics."""

    kind = "harmonic2"
    names = ("phase_a1", "phase_b1", "phase_a2", "phase_b2")


class Ramp(ABC):
    """R(t), a multiplicative detector ramp; ``r`` its coefficients (:attr:`names` first),
    ``dt = time - t0`` (the first frame).

    Examples
    --------
    >>> linear = RAMPS["linear"]
    >>> linear.names
    ('ramp_slope_per_day',)
    >>> linear.factor(np.array([0.5]), np.array([0.0, 0.2])).tolist()
    [1.0, 1.1]
    """

    #: The model's name (``ramp``).
    kind: ClassVar[str] = ""
    #: Its coefficients' names, in the parameter vector's order.
    names: ClassVar[tuple[str, ...]] = ()

    @abstractmethod
    def factor(self, r: np.ndarray, dt: np.ndarray) -> np.ndarray:
        """R at ``dt`` for one parameter vector."""

    @abstractmethod
    def rows(self, r: np.ndarray, dt: np.ndarray) -> np.ndarray:
        """R of every row of ``r`` (m, >= len(names)): shape (m, len(dt))."""

    def apply(self, flux: np.ndarray, r: np.ndarray, dt: np.ndarray) -> np.ndarray:
        """``flux`` times R (:meth:`factor`), in place."""
        flux *= self.factor(r, dt)
        return flux

    def apply_rows(self, flux: np.ndarray, r: np.ndarray, dt: np.ndarray) -> np.ndarray:
        """Each row of ``flux`` times its R (:meth:`rows`), in place."""
        flux *= self.rows(r, dt)
        return flux

    def kernel_index(self, k: int) -> int | None:
        """The compiled eclipse batch's ``ramp_at`` of a ramp at ``theta[k]``; None: numpy's."""
        return k

    def bound(self, lo: np.ndarray, hi: np.ndarray, k: int, exposure_d: float,
              span_d: float) -> None:
        """Set the bounds of the ramp's parameters at ``k`` (default: unbounded)."""
        return None   # a hook: nothing to do by default

    def start(self, theta: np.ndarray, k: int, span_d: float) -> None:
        """Set the ramp's starting parameters at ``k`` (default: 0, set by the caller)."""
        return None   # a hook: nothing to do by default


class NoRamp(Ramp):
    """R = 1."""

    kind = "none"

    def factor(self, r, dt):
        return np.ones_like(dt)

    def rows(self, r, dt):
        return np.ones((len(r), len(dt)))

    def apply(self, flux, r, dt):
        return flux

    def apply_rows(self, flux, r, dt):
        return flux

    def kernel_index(self, k):
        return -1


class LinearRamp(Ramp):
    """R = 1 + r1 (t - t0)."""

    kind = "linear"
    names = ("ramp_slope_per_day",)

    def factor(self, r, dt):
        return 1.0 + r[0] * dt

    def rows(self, r, dt):
        return 1.0 + r[:, :1] * dt


class ExponentialRamp(Ramp):
    """R = 1 - a exp(-(t - t0) / tau): amplitude in (-0.2, 0.2), tau between one
    frame and the time span (starting at 0.02 d or a quarter of the span)."""

    kind = "exponential"
    names = ("ramp_amplitude", "ramp_tau_days")

    def factor(self, r, dt):
        return 1.0 - r[0] * np.exp(-dt / r[1])

    def rows(self, r, dt):
        return 1.0 - r[:, :1] * np.exp(-dt / r[:, 1:2])

    def kernel_index(self, k):
        return None

    def bound(self, lo, hi, k, exposure_d, span_d):
        lo[k], hi[k] = -0.2, 0.2
        lo[k + 1] = exposure_d
        hi[k + 1] = span_d

    def start(self, theta, k, span_d):
        theta[k + 1] = min(0.02, 0.25 * span_d)


#: Every phase model's term by its name (:data:`~eclipsebench.fit.names.PHASE_MODELS` and
#: :data:`~eclipsebench.fit.names.PHASE_CURVE_MODELS`).
PHASE_TERMS: dict[str, PhaseTerm] = {
    t.kind: t for t in (FlatPhase(), LinearPhase(), QuadraticPhase(), SinusoidPhase(),
                        FirstHarmonic(), SecondHarmonic())}
#: Every ramp by its name (:data:`~eclipsebench.fit.names.RAMP_MODELS`).
RAMPS: dict[str, Ramp] = {r.kind: r for r in (NoRamp(), LinearRamp(), ExponentialRamp())}
