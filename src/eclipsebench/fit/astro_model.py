"""The one astrophysical model that every decorrelation method shares.

The model of the stellar-system flux, normalised so that 1 is the star alone
(the flux during total eclipse), is::

    A(t) = R(t) * [1 + v(t) * p(t)]

- ``v(t)`` is the visible fraction of the planet (1 outside eclipse, 0 during
  totality): the physical shape of :class:`eclipsebench.astro.eclipse.EclipseShape`
  or a box of the same duration.
- ``p(t)`` is the planet-to-star flux ratio, a phase curve written so that
  ``p(t_ecl) = D`` exactly for every phase model; then ``F_out = 1 + D`` at the
  centre of occultation and ``F_in = 1``, so ``D`` is the paper's depth
  (Eq. ``eclipse_depth``: ``D = (F_out - F_in) / F_in``)::

      flat       p = D
      linear     p = D + c1 (t - t_ecl)
      quadratic  p = D + c1 (t - t_ecl) + c2 (t - t_ecl)^2
      sinusoid   p = D + c1 [cos(2 pi (t - t_ecl) / P) - 1] + c2 sin(2 pi (t - t_ecl) / P)

- ``R(t)`` is a multiplicative detector ramp: 1 (none), ``1 + r1 (t - t0)``
  (linear) or ``1 - a exp(-(t - t0) / tau)`` (exponential), ``t0`` the first
  frame. Its constant level is left to the systematics model (every method
  fits the flux normalisation).

The parameter vector is ``[depth, t_ecl_bmjd, phase coefficients..., ramp
coefficients...]`` (depth as a fraction, not ppm).

Transits (``event="transit"``) share the phase and ramp models::

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
``names[1]`` handles both events; :meth:`AstroModel.depth_ppm` turns the size
into the event's depth (the transit's is ``rp_rs^2``, geometric: not the
limb-darkened flux drop at mid-transit).

Whole phase curves (``event="phase-curve"``) put both events and the
planet's phase variation in one model over several AORs::

    A(t) = R(t) O(t) [T(t) + v(t) p(t)]

- ``T(t)`` is the transit's stellar flux as above (``rp_rs`` free; a_rs, b
  and limb darkening fixed), its mid-transit at ``t_ecl`` plus the catalogue
  orbit's transit-minus-eclipse time; ``v(t)`` the eclipse's physical shape,
  which repeats every period;
- ``p(t)`` the harmonic phase curve of :func:`eclipsebench.astro.phase_curves.harmonic_curve`
  (``harmonic1``: ``D + a1 (cos phi - 1) + b1 sin phi``; ``harmonic2`` adds
  ``a2 (cos 2 phi - 1) + b2 sin 2 phi``; ``phi = 2 pi (t - t_ecl) / P``), the
  first and second harmonic of SPCA (Bell et al. 2021, MNRAS 504, 3316);
- ``O(t)`` a flux offset ``1 + o_k`` for each AOR after the first (the step
  at each repointing, as SPCA fits it), from the table's ``aorkey``.

Its parameter vector is ``[depth, t_ecl_bmjd, rp_rs, phase_a1, phase_b1,
(phase_a2, phase_b2), ramp..., aor_offset_1, ...]``; each row is averaged
over its exposure (binned tables; :func:`integration_offsets_d`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..astro.batman_core import quadratic_transit, sky_separation
from ..astro.eclipse import EclipseShape
from ..astro.orbit import eclipse_time_bmjd, transit_time_bmjd
from ..astro.phase_curves import harmonic_summary
from ..errors import InputError
from .astro_kernels import _NO_TABLE, _astro_rows, _interp_table, _search_table
from .astro_parts import (
    NONNEGATIVE_SCALE,
    PHASE_TERMS,
    RAMPS,
    SCALES,
    TRANSIT_BOUNDS,
    TRANSIT_FREE,
    VisibleFraction,
    aor_order,
    box_visible_fraction,
    half_depth_duration,
    inclination_deg,
    integration_offsets_d,
    q_from_u,
    system_period_days,
    u_from_q,
)
from .names import ECLIPSE_SHAPES, EVENTS, PHASE_CURVE_MODELS, PHASE_MODELS, RAMP_MODELS

__all__ = ["AstroModel", "PHASE_MODELS", "PHASE_CURVE_MODELS", "RAMP_MODELS", "ECLIPSE_SHAPES",
           "EVENTS", "TRANSIT_FREE", "box_visible_fraction", "system_period_days", "q_from_u",
           "u_from_q", "integration_offsets_d", "aor_order"]


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


class AstroModel:
    """The eclipse, phase-curve and ramp model at fixed times.

    Parameters
    ----------
    time_bmjd : array_like, shape (n,)
        Times at which the model is evaluated (the method's data times).
    system : PlanetSystem or None
        The planetary system (:func:`eclipsebench.astro.catalogue.get_system`);
        gives the eclipse geometry and the period for the sinusoid. May be None
        when ``shape`` (and, for the sinusoid, ``period_d``) are given.
    phase : {"flat", "linear", "quadratic", "sinusoid"}
        Phase-curve model (Section 4.2 of the paper).
    ramp : {"none", "linear", "exponential"}
        Multiplicative detector ramp.
    eclipse_shape : {"physical", "box"}
        The orbit's eclipse shape, or a box of the same duration (measured
        between the half-depth points of ingress and egress, so the box removes
        the same planet flux as the physical eclipse).
    shape : object with ``visible_fraction(t_ecl_bmjd)``, optional
        Precomputed geometry at ``time_bmjd``; default
        ``EclipseShape(time_bmjd, system)``.
    period_d : float, optional
        Orbital period for the sinusoid (default: the system's).
    box_duration_d : float, optional
        Duration of the box eclipse (default: measured from the physical shape).
    event : {"eclipse", "transit", "phase-curve"}
        The event fitted. A transit needs ``system`` (its orbit) and ignores
        ``eclipse_shape``, ``shape`` and ``box_duration_d``. A whole phase
        curve (``phase`` "harmonic1" or "harmonic2") needs ``system`` and the
        physical eclipse shape.
    transit_free : sequence of {"a_rs", "b", "q1", "q2"}
        The transit's parameters fitted besides ``rp_rs`` and
        ``t_transit_bmjd``; the others stay at the catalogue's ``a_rs``, impact
        parameter and limb darkening (or ``limb_darkening_q``).
    transit_priors : mapping, optional
        ``{name: (mean, sigma)}``: a Gaussian prior on a free transit
        parameter (added to the least-squares residuals and the MCMC's
        log-probability); a free parameter without one has a uniform prior
        within its bounds.
    limb_darkening_q : (float, float), optional
        Kipping's q1, q2 (fixed values, or the start of free ones); default
        those of the catalogue's quadratic coefficients (:func:`q_from_u`).
    aorkey : array_like, shape (n,), optional
        A phase curve's AOR of each frame: every AOR after the first gets a
        flux offset ``aor_offset_<k>`` (a phase curve only).
    exposure_s : float, optional
        A phase curve's integration time of one row (default: the median
        cadence); rows longer than 10 s are averaged over sub-exposures
        (:func:`integration_offsets_d`).
    nonnegative_planet : bool
        A phase curve's prior ``p(t) >= 0`` over the orbit (a penalty residual
        for least squares, ``-inf`` log-prior for the MCMC).

    Examples
    --------
    >>> import numpy as np
    >>> class Flat:  # a planet that is always fully visible
    ...     def visible_fraction(self, t_ecl_bmjd):
    ...         return np.ones(3)
    >>> m = AstroModel(np.array([0.0, 0.1, 0.2]), None, phase="flat", shape=Flat())
    >>> m.names
    ('depth', 't_ecl_bmjd')
    >>> m(np.array([0.002, 0.1]))
    array([1.002, 1.002, 1.002])

    A transit of the 2015 challenge's XO-3b, limb darkening free:

    >>> from eclipsebench.astro.catalogue import get_system
    >>> xo3 = get_system("XO-3b (2015 challenge)")
    >>> t = xo3.t_transit_bmjd + np.linspace(-0.1, 0.1, 5)
    >>> tr = AstroModel(t, xo3, phase="flat", event="transit", transit_free=("q1", "q2"))
    >>> tr.names
    ('rp_rs', 't_transit_bmjd', 'q1', 'q2')
    >>> tr(tr.initial()).round(5).tolist()
    [1.0, 0.99487, 0.99167, 0.99488, 1.0]
    >>> round(tr.depth_ppm(0.0906), 2)
    8208.36
    """

    def __init__(self, time_bmjd, system: Any = None, *, phase: str = "quadratic",
                 ramp: str = "none", eclipse_shape: str = "physical",
                 shape: VisibleFraction | None = None, period_d: float | None = None,
                 box_duration_d: float | None = None, event: str = "eclipse",
                 transit_free: Sequence[str] = (),
                 transit_priors: Mapping[str, Sequence[float]] | None = None,
                 limb_darkening_q: Sequence[float] | None = None, aorkey=None,
                 exposure_s: float | None = None, nonnegative_planet: bool = False) -> None:
        if event not in EVENTS:
            raise InputError(f"--event {event!r}: expected one of {', '.join(EVENTS)}")
        phases = PHASE_CURVE_MODELS if event == "phase-curve" else PHASE_MODELS
        if phase not in phases:
            raise InputError(f"--phase {phase!r}: expected one of {', '.join(phases)} "
                             f"(event '{event}')")
        if ramp not in RAMP_MODELS:
            raise InputError(f"--ramp {ramp!r}: expected one of {', '.join(RAMP_MODELS)}")
        if event != "phase-curve" and (aorkey is not None or exposure_s is not None
                                       or nonnegative_planet):
            raise InputError("aorkey, exposure_s, nonnegative_planet: apply to event "
                             "'phase-curve' only")
        if eclipse_shape not in ECLIPSE_SHAPES:
            raise InputError(f"eclipse_shape {eclipse_shape!r}: expected one of "
                             f"{', '.join(ECLIPSE_SHAPES)}")
        self.time_bmjd = np.ascontiguousarray(time_bmjd, dtype=float)
        if self.time_bmjd.ndim != 1 or len(self.time_bmjd) < 2:
            raise InputError("time_bmjd: expected at least two times")
        self.system = system
        self.phase = phase
        self.ramp = ramp
        #: The phase model's p(t) and the ramp's R(t) (:mod:`.astro_parts`).
        self.phase_term = PHASE_TERMS[phase]
        self.ramp_term = RAMPS[ramp]
        self.eclipse_shape = eclipse_shape
        self.t_start_bmjd = float(self.time_bmjd.min())
        self.t_stop_bmjd = float(self.time_bmjd.max())
        #: Time since the first frame, the ramp's argument.
        self._since_start = self.time_bmjd - self.t_start_bmjd
        self.event = event
        self.n_shape = 0          # the transit's free a_rs, b, q1, q2
        self.priors: dict[str, tuple[float, float]] = {}
        self.n_priors = 0
        self.n_aor = 0            # a phase curve's AOR offsets
        self.exposure_d = float(np.median(np.diff(np.sort(self.time_bmjd))))
        if not self.exposure_d > 0:
            raise InputError("time_bmjd: the frames do not advance in time")
        self.box_duration_d: float | None = None
        self.period_d: float | None = None
        self.shape: VisibleFraction | None = None
        self.names: tuple[str, ...] = ()
        if event == "phase-curve":
            if transit_free or transit_priors:
                raise InputError("transit_free, transit_priors: apply to event 'transit' only "
                                 "(a phase curve fits Rp/R* with a/R*, b and limb darkening "
                                 "fixed)")
            self._setup_phase_curve(system, shape, period_d, limb_darkening_q, aorkey,
                                    exposure_s, nonnegative_planet)
            return
        if event == "transit":
            self.shape = None
            self.period_d = period_d if period_d is not None else system_period_days(system)
            self._setup_transit(system, transit_free, transit_priors, limb_darkening_q)
            self.names = ("rp_rs", "t_transit_bmjd") + self.transit_free \
                + self.phase_term.names + self.ramp_term.names
            self.n_phase = len(self.phase_term.names)
            self.n_ramp = len(self.ramp_term.names)
            return
        if transit_free or transit_priors:
            raise InputError("transit_free, transit_priors: apply to event 'transit' only")
        if shape is None:
            if system is None:
                raise InputError("AstroModel: give a planetary system or a precomputed shape")
            shape = EclipseShape(self.time_bmjd, system)
        self.shape = shape
        self.period_d = period_d if period_d is not None else system_period_days(system)
        if self.phase_term.needs_period and not self.period_d:
            raise InputError("--phase sinusoid: the orbital period is unknown (give period_d)")
        if eclipse_shape == "box":
            if box_duration_d is None:
                box_duration_d = self._measure_box_duration(system, shape)
                if box_duration_d is None:
                    raise InputError("eclipse_shape 'box': the data do not cover a whole eclipse "
                                     "centred in the time span, so its duration cannot be "
                                     "measured (give box_duration_d)")
            if not box_duration_d > 0:
                raise InputError("box_duration_d: expected a positive duration in days")
            self.box_duration_d = float(box_duration_d)
        self.names = ("depth", "t_ecl_bmjd") + self.phase_term.names + self.ramp_term.names
        self.n_phase = len(self.phase_term.names)
        self.n_ramp = len(self.ramp_term.names)

    def _setup_transit(self, system: Any, free: Sequence[str],
                       priors: Mapping[str, Sequence[float]] | None,
                       q: Sequence[float] | None) -> None:
        """The transit's fixed values, free parameters, priors and precomputed curve."""
        if system is None:
            raise InputError("event 'transit': give the planetary system (its orbit)")
        if self.phase_term.needs_period and not self.period_d:
            raise InputError("--phase sinusoid: the orbital period is unknown (give period_d)")
        unknown = [n for n in free if n not in TRANSIT_FREE]
        if unknown or len(set(free)) != len(tuple(free)):
            raise InputError(f"transit_free {list(free)!r}: expected distinct names among "
                             f"{', '.join(TRANSIT_FREE)}")
        self.transit_free = tuple(n for n in TRANSIT_FREE if n in free)
        self.n_shape = len(self.transit_free)
        #: The transit's values when fixed (and the start when free).
        self.transit_fixed = _transit_fixed_values(system, q)
        for name, pair in dict(priors or {}).items():
            if name not in self.transit_free:
                raise InputError(f"transit_priors.{name}: a prior needs a free parameter "
                                 f"(transit_free: {', '.join(self.transit_free) or 'none'})")
            pair = tuple(float(v) for v in pair)
            if len(pair) != 2 or not (math.isfinite(pair[0]) and pair[1] > 0):
                raise InputError(f"transit_priors.{name}: expected [mean, sigma > 0]")
            self.priors[name] = pair
        self.n_priors = len(self.priors)
        self.rp_rs_catalogue = float(system.rp_rs)
        self.ecc = float(system.ecc)
        self.omega_deg = float(system.omega_deg)
        self._transit = _TransitCurve(self.time_bmjd, system,
                                      fixed_orbit=not {"a_rs", "b"} & set(self.transit_free))
        self._inc_fixed_deg = float(system.inc_deg)

    def _setup_phase_curve(self, system: Any, shape: VisibleFraction | None,
                           period_d: float | None, q: Sequence[float] | None, aorkey,
                           exposure_s: float | None, nonnegative: bool) -> None:
        """A whole phase curve: T(t) as the transit's, v(t) as the eclipse's, p(t) harmonic,
        and the AOR offsets O(t)."""
        if system is None:
            raise InputError("event 'phase-curve': give the planetary system (its orbit)")
        if self.eclipse_shape != "physical":
            raise InputError(f"eclipse_shape {self.eclipse_shape!r}: a phase curve's eclipses "
                             "repeat every orbit; use 'physical'")
        period = period_d if period_d is not None else system_period_days(system)
        self.period_d = float(period) if period is not None else float("nan")
        if not self.period_d > 0:
            raise InputError("event 'phase-curve': the orbital period is unknown (give period_d)")
        # the transit exactly as event "transit" makes it, with Rp/R* free and a/R*, b and
        # the limb darkening fixed (their defaults there)
        self.transit_free = ()
        self.transit_fixed = _transit_fixed_values(system, q)
        self.rp_rs_catalogue = float(system.rp_rs)
        self.ecc = float(system.ecc)
        self.omega_deg = float(system.omega_deg)
        self._inc_fixed_deg = float(system.inc_deg)
        # integration over each row's exposure (binned tables: one row per 64-frame cube)
        self.exposure_s = float(self.exposure_d * 86400.0 if exposure_s is None else exposure_s)
        self._sub_offsets_d = integration_offsets_d(self.exposure_s)
        n_sub = len(self._sub_offsets_d)
        self._sub_time = (self.time_bmjd if n_sub == 1 else
                          (self.time_bmjd[:, None] + self._sub_offsets_d[None, :]).ravel())
        if shape is not None and n_sub > 1:
            raise InputError("shape: a precomputed eclipse shape cannot be integrated over "
                             f"{self.exposure_s:g} s exposures (leave it out)")
        self.shape = shape if shape is not None else EclipseShape(self._sub_time, system)
        self._transit = _TransitCurve(self._sub_time, system, fixed_orbit=True)
        # the catalogue orbit's mid-transit minus mid-eclipse (observed, light travel included);
        # the fitted eclipse time carries every transit with it (one orbit, period fixed)
        t_e = eclipse_time_bmjd(system, self.t_start_bmjd)
        self.transit_minus_eclipse_d = float(transit_time_bmjd(system, t_e - 0.5 * self.period_d)
                                             - t_e)
        self.transit_phase_rad = 2.0 * math.pi * self.transit_minus_eclipse_d / self.period_d
        # one flux offset (1 + o_k) per AOR after the first (Bell et al. 2021, SPCA)
        self.aor_keys: tuple = ()
        self._aor_rank = None
        if aorkey is not None:
            aorkey = np.asarray(aorkey)
            if aorkey.shape != self.time_bmjd.shape:
                raise InputError(f"aorkey: expected {len(self.time_bmjd)} values, got "
                                 f"{aorkey.shape}")
            keys, self._aor_rank = aor_order(self.time_bmjd, aorkey)
            self.aor_keys = tuple(k.item() if hasattr(k, "item") else k for k in keys)
        self.n_aor = max(len(self.aor_keys) - 1, 0)
        self.nonnegative_planet = bool(nonnegative)
        self.n_priors = 1 if self.nonnegative_planet else 0
        self.n_shape = 1   # rp_rs
        self.n_phase = len(self.phase_term.names)
        self.n_ramp = len(self.ramp_term.names)
        self.names = ("depth", "t_ecl_bmjd", "rp_rs") + self.phase_term.names \
            + self.ramp_term.names + tuple(f"aor_offset_{k}" for k in range(1, self.n_aor + 1))

    def _measure_box_duration(self, system: Any, shape: VisibleFraction) -> float | None:
        """Half-depth duration of the physical eclipse.

        With a system: on a fine grid (half a period wide, 20,001 points)
        around one of its eclipses. Without one: on the data times, with the
        eclipse placed at the middle of the data.
        """
        if system is not None and self.period_d:
            mid = 0.5 * (self.t_start_bmjd + self.t_stop_bmjd)
            grid = mid + np.linspace(-0.25, 0.25, 20001) * self.period_d
            return half_depth_duration(grid, EclipseShape(grid, system).visible_fraction(mid))
        mid = 0.5 * (self.t_start_bmjd + self.t_stop_bmjd)
        return half_depth_duration(self.time_bmjd, np.asarray(shape.visible_fraction(mid)))

    def __len__(self) -> int:
        return len(self.names)

    def _period(self) -> float:
        """The orbital period (days); the events and phase models that use it require it."""
        if self.period_d is None:
            raise InputError("the orbital period is unknown (give period_d)")
        return self.period_d

    def _shape(self) -> VisibleFraction:
        """The eclipse's visible fraction (an eclipse or a phase curve has one)."""
        if self.shape is None:
            raise InputError(f"event {self.event!r}: no eclipse shape")
        return self.shape

    def _box_duration(self) -> float:
        """The box eclipse's duration (days), set with ``eclipse_shape = 'box'``."""
        if self.box_duration_d is None:
            raise InputError("eclipse_shape 'box': no box duration")
        return self.box_duration_d

    @property
    def scales(self) -> np.ndarray:
        """Typical magnitude of each parameter (finite-difference steps, MCMC ball)."""
        return np.array([SCALES["aor_offset" if n.startswith("aor_offset_") else n]
                         for n in self.names])

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds (also the MCMC's uniform prior).

        The depth lies in (-0.1, 0.1); the eclipse centre inside the time span
        of the data; an exponential ramp has amplitude in (-0.2, 0.2) and a
        timescale between one frame and the time span. A transit's Rp/R* lies
        in [0, 0.5], its mid-time inside the data, a/R* in [1.5, 200], b in
        [0, 1.5] and q1, q2 in [0, 1]. A phase curve's eclipse time lies
        within half a period of the data (its first eclipse may precede them),
        its Rp/R* in [0, 0.5] and each AOR offset in (-0.5, 0.5).
        """
        lo = np.full(len(self.names), -np.inf)
        hi = np.full(len(self.names), np.inf)
        lo[0], hi[0] = -0.1, 0.1
        lo[1], hi[1] = self.t_start_bmjd, self.t_stop_bmjd
        if self.event == "phase-curve":
            lo[1] -= 0.5 * self._period()
            hi[1] += 0.5 * self._period()
            lo[2], hi[2] = TRANSIT_BOUNDS["rp_rs"]
            if self.n_aor:
                lo[-self.n_aor:], hi[-self.n_aor:] = -0.5, 0.5
        if self.event == "transit":
            for i, name in enumerate(self.names[:2 + self.n_shape]):
                if name in TRANSIT_BOUNDS:
                    lo[i], hi[i] = TRANSIT_BOUNDS[name]
        self.ramp_term.bound(lo, hi, 2 + self.n_shape + self.n_phase, self.exposure_d,
                             self.t_stop_bmjd - self.t_start_bmjd)
        return lo, hi

    def initial(self, *, depth: float | None = None, t_ecl_bmjd: float | None = None,
                rp_rs: float | None = None) -> np.ndarray:
        """Starting parameters: no phase variation or ramp, and

        - an eclipse: ``depth`` (default 1e-3) at ``t_ecl_bmjd``;
        - a transit: ``rp_rs`` (default the catalogue's) at ``t_ecl_bmjd`` (the
          event's time: mid-transit), free a_rs, b, q1, q2 at their prior
          means or else their fixed values;
        - a phase curve: ``depth`` at ``t_ecl_bmjd`` (an eclipse within half a
          period of the data), the catalogue's ``rp_rs``, no phase variation,
          AOR offsets 0.

        The time defaults to the middle of the data.
        """
        if t_ecl_bmjd is None:
            t_ecl_bmjd = 0.5 * (self.t_start_bmjd + self.t_stop_bmjd)
        lo, hi = self.bounds
        if self.event == "phase-curve" and not lo[1] <= t_ecl_bmjd <= hi[1]:
            raise InputError(f"eclipse time {t_ecl_bmjd:.5f} BMJD lies more than half a period "
                             f"from the data ({self.t_start_bmjd:.5f}-{self.t_stop_bmjd:.5f})")
        if self.event != "phase-curve" and not self.t_start_bmjd <= t_ecl_bmjd <= self.t_stop_bmjd:
            raise InputError(f"{self.event} time {t_ecl_bmjd:.5f} BMJD lies outside the data "
                             f"({self.t_start_bmjd:.5f}-{self.t_stop_bmjd:.5f})")
        theta = np.zeros(len(self.names))
        if self.event == "transit":
            theta[0] = self.rp_rs_catalogue if rp_rs is None else rp_rs
            for i, name in enumerate(self.transit_free):
                theta[2 + i] = self.priors.get(name, (self.transit_fixed[name],))[0]
        else:
            theta[0] = 1e-3 if depth is None else depth
        if self.event == "phase-curve":
            theta[2] = self.rp_rs_catalogue if rp_rs is None else rp_rs
        theta[1] = t_ecl_bmjd
        self.ramp_term.start(theta, 2 + self.n_shape + self.n_phase,
                             self.t_stop_bmjd - self.t_start_bmjd)
        return theta

    def visible_fraction(self, t_ecl_bmjd: float) -> np.ndarray:
        """v(t): 1 = planet fully visible, 0 = fully eclipsed (1 throughout a transit).

        A phase curve's is averaged over each row's exposure.
        """
        if self.event == "transit":
            return np.ones_like(self.time_bmjd)
        if self.event == "phase-curve":
            return self._integrated(np.asarray(self._shape().visible_fraction(t_ecl_bmjd),
                                               dtype=float))
        if self.eclipse_shape == "box":
            return box_visible_fraction(self.time_bmjd, t_ecl_bmjd, self._box_duration(),
                                        self.exposure_d)
        return np.asarray(self._shape().visible_fraction(t_ecl_bmjd), dtype=float)

    def planet(self, theta) -> np.ndarray:
        """p(t), the planet-to-star flux ratio; p(t_ecl) = depth for every phase model.

        For a transit, the phase variation about mid-transit (0 there). For a
        phase curve, :func:`~eclipsebench.astro.phase_curves.harmonic_curve` at
        the rows' mid-times.
        """
        theta = np.asarray(theta, dtype=float)
        depth, t_ecl = theta[0], theta[1]
        if self.event == "phase-curve":
            return self._harmonic(theta, self.time_bmjd)
        if self.event == "transit":
            depth = 0.0
        k = 2 + self.n_shape
        c = theta[k:k + self.n_phase]
        dt = self.time_bmjd - t_ecl
        return self.phase_term.value(depth, c, dt, self.period_d)

    def ramp_factor(self, theta) -> np.ndarray:
        """R(t), the multiplicative ramp (1 when ``ramp="none"``)."""
        r = np.asarray(theta, dtype=float)[2 + self.n_shape + self.n_phase:]
        return self.ramp_term.factor(r, self._since_start)

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

    def stellar_flux(self, theta) -> np.ndarray:
        """T(t), the star's flux in transit (1 outside; a transit or a phase curve).

        A phase curve's transits follow its eclipse time (``t_ecl +
        transit_minus_eclipse_d``, modulo the period), averaged over each row's
        exposure.
        """
        if self.event == "eclipse":
            raise InputError("stellar_flux: the model is of an eclipse, not a transit")
        if self.event == "phase-curve":
            return self._integrated(self._stellar_sub(theta))
        v = self.transit_values(theta)
        return self._transit(float(theta[0]), float(theta[1]), v["a_rs"], v["inc_deg"],
                             v["u1"], v["u2"])

    # ------------------------------------------------------------------ whole phase curves
    def _integrated(self, values: np.ndarray) -> np.ndarray:
        """The mean over each row's sub-exposures of values at ``_sub_time`` (a phase curve)."""
        n_sub = len(self._sub_offsets_d)
        return values if n_sub == 1 else values.reshape(-1, n_sub).mean(axis=1)

    def _harmonic(self, theta: np.ndarray, time: np.ndarray) -> np.ndarray:
        """p(t) of a phase curve at ``time``: the lead's harmonic curve, phi = 2 pi (t - t_ecl) / P."""
        k = 2 + self.n_shape
        return self.phase_term.value(theta[0], theta[k:k + self.n_phase], time - theta[1],
                                     self._period())

    def _stellar_sub(self, theta: np.ndarray) -> np.ndarray:
        """T(t) of a phase curve at the sub-exposure times (Rp/R* is ``theta[2]``)."""
        v = self.transit_values(theta)
        return self._transit(float(theta[2]), float(theta[1]) + self.transit_minus_eclipse_d,
                             v["a_rs"], v["inc_deg"], v["u1"], v["u2"])

    def aor_factor(self, theta) -> np.ndarray:
        """O(t): ``1`` in the first AOR, ``1 + aor_offset_k`` in the k-th after it."""
        if not self.n_aor:
            return np.ones_like(self.time_bmjd)
        theta = np.asarray(theta, dtype=float)
        levels = np.concatenate([[1.0], 1.0 + theta[len(self.names) - self.n_aor:]])
        return levels[self._aor_rank]

    def phase_summary(self, theta) -> dict[str, float]:
        """What the literature reports of the fitted phase curve (a phase curve only).

        :func:`~eclipsebench.astro.phase_curves.harmonic_summary` of the depth and
        harmonics, the night side at this orbit's mid-transit phase: keys
        ``phase_amplitude``, ``phase_offset_deg`` (east positive),
        ``nightside_flux``, ``planet_flux_min`` (fractions of the star's flux).
        """
        if self.event != "phase-curve":
            raise InputError("phase_summary: the model is not a whole phase curve")
        theta = np.asarray(theta, dtype=float)
        k = 2 + self.n_shape
        return harmonic_summary(float(theta[0]), theta[k:k + self.n_phase],
                                transit_phase_rad=self.transit_phase_rad)

    def _phase_curve(self, theta: np.ndarray) -> np.ndarray:
        """A(t) = R(t) O(t) [T(t) + v(t) p(t)], T, v and p averaged over each exposure."""
        v = np.asarray(self._shape().visible_fraction(theta[1]), dtype=float)
        flux = self._integrated(self._stellar_sub(theta) + v * self._harmonic(theta,
                                                                              self._sub_time))
        flux = self.ramp_term.apply(flux, theta[2 + self.n_shape + self.n_phase:],
                                    self._since_start)
        if self.n_aor:
            flux *= self.aor_factor(theta)
        return flux

    def __call__(self, theta) -> np.ndarray:
        """A(t) = R(t) [1 + v(t) p(t)], normalised to 1 = the star alone.

        A transit: A(t) = R(t) [T(t) + p(t)]. A phase curve: A(t) = R(t) O(t)
        [T(t) + v(t) p(t)].
        """
        theta = np.asarray(theta, dtype=float)
        if len(theta) != len(self.names):
            raise ValueError(f"expected {len(self.names)} parameters {self.names}, "
                             f"got {len(theta)}")
        if self.event == "phase-curve":
            return self._phase_curve(theta)
        if self.event == "transit":
            flux = self.stellar_flux(theta)
            if self.phase_term.varies:
                flux = flux + self.planet(theta)
        else:
            flux = 1.0 + self.visible_fraction(theta[1]) * self.planet(theta)
        return self.ramp_term.apply(flux, theta[2 + self.n_shape + self.n_phase:],
                                    self._since_start)

    # ------------------------------------------------------------------ the event's depth
    def depth_ppm(self, size: float) -> float:
        """The event's depth (ppm) of its size parameter ``names[0]``.

        An eclipse's size is its depth (``size * 1e6``); a transit's is Rp/R*,
        whose depth is the geometric ``rp_rs^2 * 1e6`` (the limb-darkened flux
        drop at mid-transit is deeper).
        """
        return float(size * size * 1e6) if self.event == "transit" else float(size * 1e6)

    def depth_error_ppm(self, size: float, error: float) -> float:
        """An error of the size parameter as an error of the depth (ppm), to first order."""
        if self.event == "transit":
            return float(2.0 * abs(size) * error * 1e6)
        return float(error * 1e6)

    def size_per_depth(self, size: float) -> float:
        """d size / d depth at ``size``: 1 for an eclipse, ``1 / (2 rp_rs)`` for a transit."""
        if self.event == "transit":
            return 1.0 / (2.0 * max(abs(float(size)), 1e-12))
        return 1.0

    def depth_difference_ppm(self, lower: float, upper: float) -> float:
        """``depth(upper) - depth(lower)`` in ppm (a posterior interval's side)."""
        if self.event == "transit":
            return float((upper * upper - lower * lower) * 1e6)
        return float((upper - lower) * 1e6)

    # ------------------------------------------------------------------ priors
    def prior_residuals(self, theta) -> np.ndarray:
        """``(value - mean) / sigma`` of each Gaussian prior (empty without priors).

        A phase curve with ``nonnegative_planet``: one penalty residual,
        ``min(p_min, 0) / NONNEGATIVE_SCALE`` (0 while the planet's flux stays
        non-negative over the orbit).
        """
        theta = np.asarray(theta, dtype=float)
        if self.event == "phase-curve":
            if not self.nonnegative_planet:
                return np.zeros(0)
            p_min = self.phase_summary(theta)["planet_flux_min"]
            return np.array([min(p_min, 0.0) / NONNEGATIVE_SCALE])
        return np.array([(theta[self.names.index(n)] - mu) / sigma
                         for n, (mu, sigma) in self.priors.items()])

    def log_prior_batch(self, thetas) -> np.ndarray:
        """``-0.5 sum(prior residuals^2)`` of every row (0 without priors).

        A phase curve with ``nonnegative_planet``: ``-inf`` where the planet's
        flux goes negative somewhere in the orbit, else 0.
        """
        thetas = np.atleast_2d(np.asarray(thetas, dtype=float))
        out = np.zeros(len(thetas))
        if self.event == "phase-curve":
            if self.nonnegative_planet:
                p_min = np.array([self.phase_summary(t)["planet_flux_min"] for t in thetas])
                out[p_min < 0.0] = -np.inf
            return out
        for n, (mu, sigma) in self.priors.items():
            out -= 0.5 * ((thetas[:, self.names.index(n)] - mu) / sigma) ** 2
        return out

    def batch(self, thetas) -> np.ndarray:
        """The model of every row of ``thetas`` at once: shape (m, n) (the MCMC's call).

        Each row equals ``self(theta)``: the same arithmetic, element by
        element. Flat, linear and quadratic phase curves with no or a linear
        ramp are computed in one compiled pass over the frames (no temporary
        arrays), the physical eclipse with :func:`numpy.interp`'s formula on
        the shape's table but an O(1) search; the sinusoid and the exponential
        ramp are broadcast with numpy (their ``sin``, ``cos``, ``exp`` stay
        numpy's). A transit or a phase curve is evaluated row by row (:meth:`__call__`).

        Parameters
        ----------
        thetas : array_like, shape (m, len(names))

        Examples
        --------
        >>> import numpy as np
        >>> class Flat:
        ...     def visible_fraction(self, t_ecl_bmjd):
        ...         return np.ones(3)
        >>> m = AstroModel(np.array([0.0, 0.1, 0.2]), None, phase="linear", shape=Flat())
        >>> m.batch([[0.002, 0.1, 0.0], [0.001, 0.1, 0.01]])
        array([[1.002, 1.002, 1.002],
               [1.   , 1.001, 1.002]])
        """
        thetas = np.atleast_2d(np.asarray(thetas, dtype=float))
        if thetas.ndim != 2 or thetas.shape[1] != len(self.names):
            raise ValueError(f"expected rows of {len(self.names)} parameters {self.names}, "
                             f"got shape {thetas.shape}")
        if self.event != "eclipse":   # batman's routines per row: each row is self(theta)
            return np.stack([self(theta) for theta in thetas])
        fused = self._fused_arguments(thetas)
        if fused is not None:
            return _astro_rows(self.time_bmjd, np.ascontiguousarray(thetas), *fused)
        t_ecl = thetas[:, 1]
        dt = self.time_bmjd - t_ecl[:, None]
        planet = self._planet_batch(thetas, dt)
        cols, visible = self._visible_fraction_batch(t_ecl)
        if cols is None:
            flux = 1.0 + visible * planet
        else:   # v = 1 outside cols: 1 + 1 * p is 1 + p exactly
            flux = 1.0 + planet
            flux[:, cols] = 1.0 + visible * planet[:, cols]
        return self.ramp_term.apply_rows(flux, thetas[:, 2 + self.n_shape + self.n_phase:],
                                         self._since_start)

    def _fused_arguments(self, thetas: np.ndarray) -> tuple | None:
        """The arguments of :func:`_astro_rows` after the times and thetas, or None.

        None (numpy broadcasting instead) for the sinusoid, the exponential
        ramp, a shape other than :class:`EclipseShape`'s table at these times,
        or eclipse times so far from the data that the shape would fold the
        offsets by a period.
        """
        phase_code = self.phase_term.kernel_code
        ramp_at = self.ramp_term.kernel_index(2 + self.n_phase)
        if phase_code is None or ramp_at is None:
            return None
        if self.eclipse_shape == "box":
            return (phase_code, ramp_at, self.t_start_bmjd, True, 0.5 * self._box_duration(),
                    self.exposure_d, *_NO_TABLE)
        shape = self.shape
        if not (isinstance(shape, EclipseShape) and shape.time_bmjd.shape == self.time_bmjd.shape
                and np.array_equal(shape.time_bmjd, self.time_bmjd)):
            return None
        table = self._shape_table(shape)
        half = 0.5 * shape.period
        t_ecl = thetas[:, 1]
        if (table is None or self.t_start_bmjd - t_ecl.max() < -half
                or self.t_stop_bmjd - t_ecl.min() >= half):
            return None
        return (phase_code, ramp_at, self.t_start_bmjd, False, 0.0, 1.0, *table[:3], *table[3:])

    def _planet_batch(self, thetas: np.ndarray, dt: np.ndarray) -> np.ndarray:
        """:meth:`planet` of every row (``dt = time - t_ecl`` of each row)."""
        c = thetas[:, 2 + self.n_shape:2 + self.n_shape + self.n_phase]
        return self.phase_term.rows(thetas[:, :1], c, dt, self.period_d)

    def _visible_fraction_batch(self, t_ecl: np.ndarray) -> tuple[np.ndarray | None, np.ndarray]:
        """:meth:`visible_fraction` of every eclipse time in ``t_ecl``.

        Returns ``(cols, v)``: ``v`` (m, len(cols)) at the frames ``cols``, the
        planet being wholly visible (v = 1) at every other frame; or ``(None,
        v)`` with ``v`` (m, n) at every frame.
        """
        if self.eclipse_shape == "box":
            return None, box_visible_fraction(self.time_bmjd, t_ecl[:, None],
                                              self._box_duration(), self.exposure_d)
        shape = self.shape
        if not isinstance(shape, EclipseShape):
            return None, np.stack([self.visible_fraction(t) for t in t_ecl])
        table = self._shape_table(shape)
        times = shape.time_bmjd
        half = 0.5 * shape.period
        lo, hi = float(times.min() - t_ecl.max()), float(times.max() - t_ecl.min())
        if table is None or lo < -half or hi >= half:
            # no table to bound, or times a period apart: the shape's own fold and interpolation
            dt = times - t_ecl[:, None]
            return None, shape.at(dt.ravel(), 0.0).reshape(dt.shape)
        xp = table[0]
        cols = np.flatnonzero((times > t_ecl.min() + xp[0]) & (times < t_ecl.max() + xp[-1]))
        dt = times[cols] - t_ecl[:, None]
        return cols, _interp_table(dt, table)

    def _shape_table(self, shape: EclipseShape):
        """The eclipse shape's table and an O(1) search index for :func:`_interp_table` (cached).

        The shape interpolates a table of v against the offset from
        mid-eclipse (``EclipseShape.at``, :func:`numpy.interp` with v = 1
        beyond both ends); this reads it once. None if the shape keeps no
        such table (then the batch calls ``shape.at``).
        """
        cached = getattr(self, "_table_cache", None)
        if cached is not None and cached[0] is shape:
            return cached[1]
        xp = np.asarray(getattr(shape, "_offset", []), dtype=float)
        fp = np.asarray(getattr(shape, "_shape", []), dtype=float)
        table = None
        if xp.ndim == 1 and xp.shape == fp.shape and len(xp) >= 3 and np.all(np.diff(xp) > 0):
            table = _search_table(xp, fp)
        self._table_cache = (shape, table)
        return table

    def describe(self) -> dict[str, Any]:
        """The model's settings, for results and logs.

        A transit adds ``event``, its free parameters, their priors, the fixed
        (or starting) a_rs, b, q1, q2 and the conjunction's offset from
        mid-transit.
        """
        out: dict[str, Any] = {"phase": self.phase, "ramp": self.ramp,
                               "eclipse_shape": self.eclipse_shape,
               "box_duration_d": self.box_duration_d, "period_d": self.period_d}
        if self.event == "transit":
            out.update({"event": "transit", "eclipse_shape": None,
                        "transit_free": list(self.transit_free),
                        "transit_priors": {k: list(v) for k, v in self.priors.items()},
                        "transit_fixed": dict(self.transit_fixed),
                        "conjunction_minus_mid_transit_s": self._transit.offset_d * 86400.0})
        if self.event == "phase-curve":
            out.update({"event": "phase-curve", "transit_fixed": dict(self.transit_fixed),
                        "transit_minus_eclipse_d": self.transit_minus_eclipse_d,
                        "transit_phase_deg": math.degrees(self.transit_phase_rad),
                        "exposure_s": self.exposure_s,
                        "n_subexposures": len(self._sub_offsets_d),
                        "aorkeys": list(self.aor_keys),
                        "nonnegative_planet": self.nonnegative_planet})
        return out


