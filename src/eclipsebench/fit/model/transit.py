"""The transit's astrophysical model (``event="transit"``): :class:`TransitModel`.

Transits share the eclipse's phase and ramp models::

    A(t) = R(t) * [T(t) + p(t)]

- ``T(t)`` is the stellar flux in transit (1 outside): batman's quadratic
  limb-darkening law (Mandel & Agol 2002; Kreidberg 2015) with Kipping's
  (2013, MNRAS 435, 2152, Eqs. 15-16) ``u1 = 2 sqrt(q1) q2``,
  ``u2 = sqrt(q1) (1 - 2 q2)``, on the orbit of the system (period,
  eccentricity, argument of periastron; ``a_rs`` and the impact parameter
  ``b`` from the catalogue unless free).
- ``p(t)`` is the planet's phase variation about mid-transit, the eclipse's
  phase curve without its constant: 0 (flat), ``c1 (t - t_tr)`` (linear),
  ``+ c2 (t - t_tr)^2`` (quadratic), ``c1 [cos(2 pi (t - t_tr) / P) - 1] +
  c2 sin(...)`` (sinusoid). The planet's own flux at mid-transit is taken
  into the normalisation that every method fits, so the transit is diluted
  by ``1 / (1 + F_p(t_tr))`` (F_p: the planet-to-star flux ratio then; 1119
  ppm on the simulated 2015-challenge XO-3b's night side, so Rp/R* comes out
  low by a fraction F_p / 2 = 5.6e-4, 5e-5 in Rp/R*).

The transit's parameter vector is ``[rp_rs, t_transit_bmjd, a_rs?, b?, q1?,
q2?, phase coefficients..., ramp coefficients...]`` (the ``?`` ones when free):
the first parameter is always the event's size (the eclipse depth, or Rp/R*)
and the second its mid-time, so that code reading ``names[0]`` and
``names[1]`` handles both events; :meth:`TransitModel.depth_ppm` turns the size
into the event's depth (the transit's is ``rp_rs^2``, geometric: not the
limb-darkened flux drop at mid-transit).

:class:`TransitGeometry` (the transit's fixed values, free parameters and
limb darkening) is shared with the whole phase curve
(:mod:`.phase_curve`), whose transits are this model's ``T(t)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ...astro.batman_core import quadratic_transit, sky_separation
from ...errors import InputError
from .base import AstroModel, EventSettings
from .parts import (
    TRANSIT_BOUNDS,
    TRANSIT_FREE,
    inclination_deg,
    q_from_u,
    system_period_days,
    u_from_q,
)
from .settings import TransitSettings

__all__ = ["TransitModel", "TransitGeometry"]

#: Sky separation (stellar radii) that batman's rsky gives when the planet is behind the
#: star; also the value outside the tabulated transit window (no overlap for rp_rs <= 0.5).
_FAR = 100.0


class _TransitCurve:
    """T(t): the limb-darkened transit of one orbit at fixed times, batman's routines.

    The observed mid-transit ``t_tr`` (minimum sky separation, light travel
    included: :func:`eclipsebench.astro.orbit.transit_time_bmjd`) is
    ``offset_d`` after batman's ``t0`` (the inferior conjunction, 138 s for the
    2015 challenge's XO-3b with e = 0.29), computed once on the catalogue
    orbit. With ``a_rs`` and ``b`` fixed the sky separation of the planet is
    tabulated once against the time from conjunction (batman's rsky on a 0.25 s
    grid where it is below 2 stellar radii) and interpolated at each call;
    with either free batman's rsky is evaluated at the data times. The flux
    is batman's quadratic law (Mandel & Agol 2002) on those separations, the
    same two compiled routines that ``batman.TransitModel.light_curve`` calls
    (a test checks that they agree).
    """

    def __init__(self, time_bmjd: np.ndarray, system: Any, *, fixed_orbit: bool,
                 grid_step_s: float = 0.25) -> None:
        self.time_bmjd = time_bmjd
        self.period_d = float(system.period_days)
        self.ecc = float(system.ecc)
        self.omega_deg = float(system.omega_deg)
        clock = system.clock
        t_conj = clock.conjunction_geom("transit", system.t_transit_bmjd)
        # conjunction minus mid-transit (both geometric: the light delay is common)
        self.offset_d = float(t_conj - clock._mid_event_geom(t_conj, "transit"))
        self.fixed_orbit = fixed_orbit
        # the separation table of a fixed orbit (_tabulate); unused otherwise
        self._tau, self._sep = np.empty(0), np.empty(0)
        if fixed_orbit:
            self._tabulate(float(system.a_rs), float(system.inc_deg), grid_step_s)

    def separation(self, t0_bmjd: float, a_rs: float, inc_deg: float) -> np.ndarray:
        """batman's rsky (stellar radii; 100 behind the star) at the data times."""
        return sky_separation(self.time_bmjd, t0_bmjd, self.period_d, a_rs,
                              math.radians(inc_deg), self.ecc, math.radians(self.omega_deg))

    def _tabulate(self, a_rs: float, inc_deg: float, grid_step_s: float) -> None:
        coarse = np.linspace(-0.25, 0.25, 20001) * self.period_d
        sep = sky_separation(coarse, 0.0, self.period_d, a_rs, math.radians(inc_deg), self.ecc,
                             math.radians(self.omega_deg))
        near = np.flatnonzero(sep < 2.0)
        if len(near) == 0:   # no transit at all: T = 1 everywhere
            self._tau, self._sep = np.array([-1.0, 1.0]), np.full(2, _FAR)
            return
        lo, hi = coarse[max(near[0] - 1, 0)], coarse[min(near[-1] + 1, len(coarse) - 1)]
        n = max(int(math.ceil((hi - lo) * 86400.0 / grid_step_s)) + 1, 3)
        self._tau = np.linspace(lo, hi, n)
        self._sep = sky_separation(self._tau, 0.0, self.period_d, a_rs, math.radians(inc_deg),
                                   self.ecc, math.radians(self.omega_deg))

    def __call__(self, rp_rs: float, t_transit_bmjd: float, a_rs: float, inc_deg: float,
                 u1: float, u2: float) -> np.ndarray:
        t0 = t_transit_bmjd + self.offset_d
        if self.fixed_orbit:
            tau = self.time_bmjd - t0
            half = 0.5 * self.period_d
            if tau.min() < -half or tau.max() >= half:   # data a period away: fold
                tau = tau - self.period_d * np.floor(tau / self.period_d + 0.5)
            sep = np.interp(tau, self._tau, self._sep, left=_FAR, right=_FAR)
        else:
            sep = self.separation(t0, a_rs, inc_deg)
        return quadratic_transit(sep, abs(rp_rs), u1, u2)


def _transit_fixed_values(system: Any, q: Sequence[float] | None) -> dict[str, float]:
    """The transit's a_rs, b (catalogue) and Kipping's q1, q2 (given, else the catalogue's)."""
    if q is None or len(q) == 0:
        q = q_from_u(*(float(u) for u in system.ld_quadratic))
    if len(q) != 2 or not all(0.0 <= float(v) <= 1.0 for v in q):
        raise InputError(f"limb_darkening_q {list(q)!r}: expected [q1, q2], each in [0, 1]")
    return {"a_rs": float(system.a_rs), "b": float(system.impact_parameter),
            "q1": float(q[0]), "q2": float(q[1])}


class TransitGeometry:
    """The transit's geometry: fixed values, free parameters, orbit and limb darkening.

    A mixin of the models that have transits (:class:`TransitModel`,
    :class:`~.phase_curve.PhaseCurveModel`): ``transit_free`` (the free
    ones among a_rs, b, q1, q2, which follow the size and the time in the
    parameter vector) is set by the model before :meth:`transit_values` is
    called.
    """

    transit_free: tuple[str, ...]

    def _set_transit_geometry(self, system: Any, q: Sequence[float] | None) -> None:
        """The transit's fixed values (a_rs, b, q1, q2), the catalogue's Rp/R* and orbit."""
        #: The transit's values when fixed (and the start when free).
        self.transit_fixed = _transit_fixed_values(system, q)
        self.rp_rs_catalogue = float(system.rp_rs)
        self.ecc = float(system.ecc)
        self.omega_deg = float(system.omega_deg)
        self._inc_fixed_deg = float(system.inc_deg)

    def transit_values(self, theta) -> dict[str, float]:
        """The transit's a_rs, b, q1, q2 (free from ``theta``, fixed otherwise), inclination
        and quadratic coefficients u1, u2."""
        values = dict(self.transit_fixed)
        for i, name in enumerate(self.transit_free):
            values[name] = float(theta[2 + i])
        if {"a_rs", "b"} & set(self.transit_free):
            values["inc_deg"] = inclination_deg(values["a_rs"], values["b"], self.ecc,
                                                self.omega_deg)
        else:
            values["inc_deg"] = self._inc_fixed_deg
        values["u1"], values["u2"] = u_from_q(values["q1"], values["q2"])
        return values


class TransitModel(TransitGeometry, AstroModel):
    """The transit, phase-variation and ramp model at fixed times: ``A = R [T + p]``.

    ``AstroModel(time, system, event="transit", ...)`` builds one; the
    parameters are :class:`AstroModel`'s (its own ``settings`` a
    :class:`~.settings.TransitSettings`: free parameters, priors, limb
    darkening; ``eclipse_shape``,
    ``shape`` and ``box_duration_d`` are ignored).

    Examples
    --------
    >>> import numpy as np
    >>> from eclipsebench.astro.catalogue import get_system
    >>> xo3 = get_system("XO-3b (2015 challenge)")
    >>> t = xo3.t_transit_bmjd + np.linspace(-0.1, 0.1, 5)
    >>> tr = TransitModel(t, xo3, phase="flat", settings=TransitSettings(free=("q1", "q2")))
    >>> tr.event, tr.names
    ('transit', ('rp_rs', 't_transit_bmjd', 'q1', 'q2'))
    >>> tr(tr.initial()).round(5).tolist()
    [1.0, 0.99487, 0.99167, 0.99488, 1.0]
    """

    event = "transit"
    settings_class = TransitSettings

    def _setup(self, system: Any, settings: EventSettings) -> None:
        """The transit's fixed values, free parameters, priors and precomputed curve."""
        self.period_d = (settings.period_d if settings.period_d is not None
                         else system_period_days(system))
        if system is None:
            raise InputError("event 'transit': give the planetary system (its orbit)")
        if self.phase_term.needs_period and not self.period_d:
            raise InputError("--phase sinusoid: the orbital period is unknown (give period_d)")
        free = settings.own.free
        unknown = [n for n in free if n not in TRANSIT_FREE]
        if unknown or len(set(free)) != len(tuple(free)):
            raise InputError(f"transit_free {list(free)!r}: expected distinct names among "
                             f"{', '.join(TRANSIT_FREE)}")
        self.transit_free = tuple(n for n in TRANSIT_FREE if n in free)
        self.n_shape = len(self.transit_free)
        self._set_transit_geometry(system, settings.own.limb_darkening_q)
        self._set_priors(settings.own.priors)
        self._transit = _TransitCurve(self.time_bmjd, system,
                                      fixed_orbit=not {"a_rs", "b"} & set(self.transit_free))
        self.names = ("rp_rs", "t_transit_bmjd") + self.transit_free \
            + self.phase_term.names + self.ramp_term.names

    def _set_priors(self, priors: Mapping[str, Sequence[float]] | None) -> None:
        """The Gaussian priors ``{name: (mean, sigma)}`` of free parameters."""
        for name, pair in dict(priors or {}).items():
            if name not in self.transit_free:
                raise InputError(f"transit_priors.{name}: a prior needs a free parameter "
                                 f"(transit_free: {', '.join(self.transit_free) or 'none'})")
            pair = tuple(float(v) for v in pair)
            if len(pair) != 2 or not (math.isfinite(pair[0]) and pair[1] > 0):
                raise InputError(f"transit_priors.{name}: expected [mean, sigma > 0]")
            self.priors[name] = pair
        self.n_priors = len(self.priors)

    def _bound_event(self, lo: np.ndarray, hi: np.ndarray) -> None:
        """Rp/R* in [0, 0.5], a/R* in [1.5, 200], b in [0, 1.5], q1, q2 in [0, 1]."""
        for i, name in enumerate(self.names[:2 + self.n_shape]):
            if name in TRANSIT_BOUNDS:
                lo[i], hi[i] = TRANSIT_BOUNDS[name]

    def _start_event(self, theta: np.ndarray, *, depth: float | None,
                     rp_rs: float | None) -> None:
        """``rp_rs`` (default the catalogue's); free a_rs, b, q1, q2 at their prior means or
        else their fixed values."""
        theta[0] = self.rp_rs_catalogue if rp_rs is None else rp_rs
        for i, name in enumerate(self.transit_free):
            theta[2 + i] = self.priors.get(name, (self.transit_fixed[name],))[0]

    @classmethod
    def depth_limit_ppm(cls) -> float:
        """The geometric depth (ppm) of Rp/R*'s upper bound ``TRANSIT_BOUNDS["rp_rs"][1]``."""
        return float(TRANSIT_BOUNDS["rp_rs"][1] ** 2 * 1e6)

    def event_detail(self, size: float, size_err: float, t_bmjd: float, t_err_d: float,
                     t_predicted_bmjd: float) -> dict[str, Any]:
        """A transit's ``event_detail``: Rp/R* and its error as fitted, the depth, the time
        (under the transit's own keys, which replace the result's ``t_ecl_*``)."""
        return {"event": self.event, "rp_rs": size, "rp_rs_err": size_err,
                "transit_depth_ppm": self.depth_ppm(size),
                "transit_depth_err_ppm": self.depth_error_ppm(size, size_err),
                "transit_depth_definition": "rp_rs^2 (geometric)", "t_transit_bmjd": t_bmjd,
                "t_transit_err_d": t_err_d, "t_transit_predicted_bmjd": t_predicted_bmjd,
                "transit_model": self.describe()}

    def visible_fraction(self, t_event_bmjd: float) -> np.ndarray:
        """v(t): 1 throughout a transit (the planet is never hidden)."""
        return np.ones_like(self.time_bmjd)

    def _planet_level(self, theta: np.ndarray) -> float:
        """p at mid-transit: 0 (the planet's flux then is in the normalisation)."""
        return 0.0

    def stellar_flux(self, theta) -> np.ndarray:
        """T(t), the star's flux in transit (1 outside)."""
        v = self.transit_values(theta)
        return self._transit(float(theta[0]), float(theta[1]), v["a_rs"], v["inc_deg"],
                             v["u1"], v["u2"])

    def _model(self, theta: np.ndarray) -> np.ndarray:
        """A(t) = R(t) [T(t) + p(t)]."""
        flux = self.stellar_flux(theta)
        if self.phase_term.varies:
            flux = flux + self.planet(theta)
        return self._with_ramp(flux, theta)

    def depth_ppm(self, size: float) -> float:
        """The transit's geometric depth ``rp_rs^2 * 1e6`` (ppm) of Rp/R* ``size``."""
        return float(size * size * 1e6)

    def depth_error_ppm(self, size: float, error: float) -> float:
        """An error of Rp/R* as an error of the depth (ppm), to first order."""
        return float(2.0 * abs(size) * error * 1e6)

    def size_per_depth(self, size: float) -> float:
        """d rp_rs / d depth at ``size``: ``1 / (2 rp_rs)``."""
        return 1.0 / (2.0 * max(abs(float(size)), 1e-12))

    def depth_difference_ppm(self, lower: float, upper: float) -> float:
        """``depth(upper) - depth(lower)`` in ppm (a posterior interval's side)."""
        return float((upper * upper - lower * lower) * 1e6)

    def describe(self) -> dict[str, Any]:
        """The model's settings, for results and logs.

        A transit adds ``event``, its free parameters, their priors, the fixed
        (or starting) a_rs, b, q1, q2 and the conjunction's offset from
        mid-transit.
        """
        out = super().describe()
        out.update({"event": "transit", "eclipse_shape": None,
                    "transit_free": list(self.transit_free),
                    "transit_priors": {k: list(v) for k, v in self.priors.items()},
                    "transit_fixed": dict(self.transit_fixed),
                    "conjunction_minus_mid_transit_s": self._transit.offset_d * 86400.0})
        return out
