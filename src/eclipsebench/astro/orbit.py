"""Keplerian orbits: Kepler's equation, anomalies, distances, event times, time scales.

Conventions (the transit-community ones, as in batman):

* ``omega_deg`` is the argument of periastron of the *planet's* orbit; the
  planet is at inferior conjunction (transit) when the true anomaly is
  ``f = pi/2 - omega`` and at superior conjunction (eclipse) when
  ``f = 3 pi/2 - omega``.
* The sky frame has ``z`` pointing towards the observer, so the planet's
  coordinate along the line of sight is ``z = r sin(i) sin(f + omega)``
  (positive in front of the star).
* Times are BMJD_TDB (``BJD_TDB - 2400000.5``) unless a name says ``bjd``.

Light-travel time.  Anything the planet does (block the star, be hidden by
it, glow) reaches the observer ``-z/c`` later than light from the star's
centre, so an event that happens at *geometric* time ``t_g`` is *observed* at
``t = t_g - z(t_g)/c``.  The catalogue's transit time is an observed time;
the eclipse of an eccentric planet therefore arrives ``(r_tr + r_ecl) sin(i)/c``
after the purely geometric prediction (42 s for XO-3b).

Event times.  ``transit_time_bmjd`` and ``eclipse_time_bmjd`` return the
observed time of *mid-event*, the minimum of the sky-projected separation,
which for an inclined eccentric orbit is not the conjunction (for XO-3b the
eclipse centre is 90 s after superior conjunction); pass
``reference="conjunction"`` for the conjunction times.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import minimize_scalar

from .times import BMJD_OFFSET

if TYPE_CHECKING:  # pragma: no cover
    from .catalogue import PlanetSystem

__all__ = [
    "BMJD_OFFSET", "C_RSUN_PER_DAY",
    "bjd_to_bmjd", "bmjd_to_bjd", "jd2455000_to_bmjd",
    "solve_kepler", "mean_anomaly", "eccentric_to_true", "true_anomaly",
    "true_anomaly_at_conjunction", "CONJUNCTION_ANOMALY_RAD", "CONJUNCTION_SIDE",
    "mean_anomaly_from_true",
    "separation", "sky_coordinates", "sky_separation",
    "periastron_angular_velocity",
    "geometric_to_observed", "observed_to_geometric",
    "transit_time_bmjd", "eclipse_time_bmjd", "conjunction_time_bmjd", "orbital_phase",
    "OrbitClock",
]


_C_KM_S = 299792.458
_RSUN_KM = 695700.0  # IAU 2015 nominal solar radius
C_RSUN_PER_DAY = _C_KM_S * 86400.0 / _RSUN_KM
"""Speed of light in solar radii per day (about 37 232)."""


# --------------------------------------------------------------------------- time scales
def bjd_to_bmjd(bjd):
    """BJD_TDB to BMJD_TDB (``bjd - 2400000.5``)."""
    return np.asarray(bjd, dtype=float) - BMJD_OFFSET if np.ndim(bjd) else float(bjd) - BMJD_OFFSET


def bmjd_to_bjd(bmjd):
    """BMJD_TDB to BJD_TDB (``bmjd + 2400000.5``)."""
    return np.asarray(bmjd, dtype=float) + BMJD_OFFSET if np.ndim(bmjd) else float(bmjd) + BMJD_OFFSET


def jd2455000_to_bmjd(value):
    """The paper's tables give JD - 2455000; BMJD = value + 54999.5."""
    return bjd_to_bmjd(np.asarray(value, dtype=float) + 2455000.0) if np.ndim(value) \
        else float(value) + 2455000.0 - BMJD_OFFSET


# --------------------------------------------------------------------------- Kepler
def solve_kepler(mean_anomaly, ecc, *, tol: float = 1e-14, max_iter: int = 50):
    """Solve Kepler's equation ``E - e sin E = M`` for the eccentric anomaly.

    Vectorised Newton iteration from Danby's starting value
    ``E0 = M + 0.85 e sign(sin M)``, which converges for every ``0 <= e < 1``.

    Parameters
    ----------
    mean_anomaly : float or array_like
        Mean anomaly ``M`` in radians (any real value).
    ecc : float or array_like
        Eccentricity, ``0 <= e < 1`` (broadcast against ``mean_anomaly``).

    Returns
    -------
    ndarray or float
        ``E`` in radians, in the same 2 pi branch as ``M``; the residual
        ``|E - e sin E - M|`` is below 1e-12 for ``e <= 0.95``.

    Examples
    --------
    >>> round(float(solve_kepler(1.0, 0.5)), 10)
    1.4987011335
    """
    m = np.asarray(mean_anomaly, dtype=float)
    e = np.asarray(ecc, dtype=float)
    if np.any((e < 0) | (e >= 1)):
        raise ValueError("eccentricity must satisfy 0 <= e < 1")
    m, e = np.broadcast_arrays(m, e)
    two_pi = 2.0 * math.pi
    base = np.floor((m + math.pi) / two_pi) * two_pi
    mr = m - base  # reduced to [-pi, pi)
    big_e = mr + 0.85 * e * np.sign(np.sin(mr))
    for _ in range(max_iter):
        sin_e = np.sin(big_e)
        f = big_e - e * sin_e - mr
        fp = 1.0 - e * np.cos(big_e)
        # Halley's correction, falling back on Newton's where it would misbehave
        fpp = e * sin_e
        newton = f / fp
        denom = fp - 0.5 * newton * fpp
        step = np.where(np.abs(denom) > 0.1 * np.abs(fp), f / denom, newton)
        big_e = big_e - step
        if np.all(np.abs(step) <= tol):
            break
    result = big_e + base
    return float(result) if result.ndim == 0 else result


def eccentric_to_true(ecc_anomaly, ecc):
    """True anomaly from the eccentric anomaly (radians; same branch)."""
    big_e = np.asarray(ecc_anomaly, dtype=float)
    f = 2.0 * np.arctan2(np.sqrt(1.0 + ecc) * np.sin(big_e / 2.0),
                         np.sqrt(1.0 - ecc) * np.cos(big_e / 2.0))
    return float(f) if np.ndim(f) == 0 else f


def mean_anomaly_from_true(true_anom, ecc):
    """Mean anomaly (radians, in (-pi, pi]) of a true anomaly."""
    f = np.asarray(true_anom, dtype=float)
    big_e = 2.0 * np.arctan2(np.sqrt(1.0 - ecc) * np.sin(f / 2.0),
                             np.sqrt(1.0 + ecc) * np.cos(f / 2.0))
    m = big_e - ecc * np.sin(big_e)
    return float(m) if np.ndim(m) == 0 else m


#: Each conjunction's true anomaly plus the argument of periastron: inferior conjunction
#: (``"transit"``, the planet in front of the star) at pi/2, superior (``"eclipse"``) at 3 pi/2.
CONJUNCTION_ANOMALY_RAD = {"transit": math.pi / 2.0, "eclipse": 1.5 * math.pi}

#: The sign of the planet's coordinate towards the observer at each conjunction.
CONJUNCTION_SIDE = {"transit": 1.0, "eclipse": -1.0}


def true_anomaly_at_conjunction(omega_rad: float, which: str) -> float:
    """True anomaly at inferior (``"transit"``) or superior (``"eclipse"``) conjunction
    (:data:`CONJUNCTION_ANOMALY_RAD`; an event passes its ``conjunction``)."""
    if which not in CONJUNCTION_ANOMALY_RAD:
        raise ValueError(f"which must be one of {sorted(CONJUNCTION_ANOMALY_RAD)}, not {which!r}")
    return CONJUNCTION_ANOMALY_RAD[which] - omega_rad


class OrbitClock:
    """The geometric clock of one orbit: time -> anomalies and positions.

    ``t_peri`` is the geometric time of periastron passage (BMJD); all times
    here are geometric (no light-travel time), see
    :func:`geometric_to_observed`.
    """

    def __init__(self, system: PlanetSystem):
        self.system = system
        self.period = system.period_days
        self.ecc = system.ecc
        self.omega = math.radians(system.omega_deg)
        self.inc = math.radians(system.inc_deg)
        self.a_rs = system.a_rs
        self.n = 2.0 * math.pi / self.period
        # geometric time of inferior conjunction from the observed mid-transit time
        t_mid_obs = system.t_transit_bmjd
        f_tr = true_anomaly_at_conjunction(self.omega, "transit")
        m_tr = mean_anomaly_from_true(f_tr, self.ecc)
        # first pass: conjunction = mid-transit, then correct both effects
        t_conj = t_mid_obs
        self.t_peri = t_conj - m_tr / self.n
        for _ in range(3):
            t_mid_geom = self._mid_event_geom(t_conj, "transit")
            t_mid_obs_model = float(geometric_to_observed(t_mid_geom, self))
            t_conj += t_mid_obs - t_mid_obs_model
            self.t_peri = t_conj - m_tr / self.n

    # ------------------------------------------------------------------ positions
    def mean_anomaly(self, t_geom):
        return self.n * (np.asarray(t_geom, dtype=float) - self.t_peri)

    def true_anomaly(self, t_geom):
        big_e = solve_kepler(self.mean_anomaly(t_geom), self.ecc)
        return eccentric_to_true(big_e, self.ecc)

    def radius(self, true_anom):
        """Star-planet distance in stellar radii at true anomaly ``f``."""
        return self.a_rs * (1.0 - self.ecc ** 2) / (1.0 + self.ecc * np.cos(true_anom))

    def sky(self, t_geom):
        """``(x, y, z)`` of the planet relative to the star, stellar radii; z to the observer."""
        f = self.true_anomaly(t_geom)
        r = self.radius(f)
        u = f + self.omega
        x = -r * np.cos(u)
        y = -r * np.sin(u) * math.cos(self.inc)
        z = r * np.sin(u) * math.sin(self.inc)
        return x, y, z

    def conjunction_geom(self, which: str, near: float) -> float:
        """Geometric time of the conjunction nearest ``near``."""
        f = true_anomaly_at_conjunction(self.omega, which)
        t = self.t_peri + mean_anomaly_from_true(f, self.ecc) / self.n
        k = round((near - t) / self.period)
        return t + k * self.period

    def _mid_event_geom(self, t_conj: float, which: str) -> float:
        """Geometric time of minimum projected separation near a conjunction."""

        span = 0.02 * self.period

        def d2(t):
            x, y, z = self.sky(t)
            return float(x * x + y * y)

        res = minimize_scalar(d2, bounds=(t_conj - span, t_conj + span), method="bounded",
                              options={"xatol": 1e-11})
        return float(res.x)


def _clock(system) -> OrbitClock:
    return system if isinstance(system, OrbitClock) else system.clock


def mean_anomaly(time_bmjd, system):
    """Mean anomaly (radians, unwrapped) at geometric time ``time_bmjd``."""
    return _clock(system).mean_anomaly(time_bmjd)


def true_anomaly(time_bmjd, system):
    """True anomaly (radians) at geometric time ``time_bmjd``."""
    return _clock(system).true_anomaly(time_bmjd)


def separation(time_bmjd, system):
    """Star-planet distance in stellar radii at geometric time ``time_bmjd``."""
    clock = _clock(system)
    return clock.radius(clock.true_anomaly(time_bmjd))


def sky_coordinates(time_bmjd, system):
    """Planet position ``(x, y, z)`` relative to the star (stellar radii; z to the observer)."""
    return _clock(system).sky(time_bmjd)


def sky_separation(time_bmjd, system):
    """Sky-projected star-planet separation in stellar radii (batman's ``z``)."""
    x, y, _ = _clock(system).sky(time_bmjd)
    return np.hypot(x, y)


def periastron_angular_velocity(system) -> float:
    """Orbital angular velocity at periastron, rad/day: ``n sqrt(1+e) / (1-e)^1.5``."""
    e = system.ecc
    return 2.0 * math.pi / system.period_days * math.sqrt(1.0 + e) / (1.0 - e) ** 1.5


# --------------------------------------------------------------------------- light-travel time
def _light_delay_days(z_rs, system) -> np.ndarray:
    clock = _clock(system)
    return -np.asarray(z_rs) * clock.system.r_star_rsun / C_RSUN_PER_DAY


def geometric_to_observed(t_geom, system):
    """Observed time of what the planet does at geometric time ``t_geom``: ``t_g - z/c``."""
    clock = _clock(system)
    t = np.asarray(t_geom, dtype=float)
    _, _, z = clock.sky(t)
    out = t + _light_delay_days(z, clock)
    return float(out) if out.ndim == 0 else out


def observed_to_geometric(t_obs, system):
    """Inverse of :func:`geometric_to_observed` (fixed-point iteration; delays are < 1 min)."""
    clock = _clock(system)
    t_obs = np.asarray(t_obs, dtype=float)
    t = t_obs.copy()
    for _ in range(4):
        _, _, z = clock.sky(t)
        t = t_obs - _light_delay_days(z, clock)
    return float(t) if t.ndim == 0 else t


# --------------------------------------------------------------------------- event times
def conjunction_time_bmjd(system, near_bmjd: float, which: str, *,
                          reference: str = "mid") -> float:
    """Observed time (BMJD_TDB) of the transit (``which="transit"``) or secondary eclipse
    (``"eclipse"``) nearest ``near_bmjd``: :func:`transit_time_bmjd` or
    :func:`eclipse_time_bmjd` (an event's ``conjunction``,
    :mod:`eclipsebench.astro.events`, names it)."""
    clock = _clock(system)
    if reference not in ("mid", "conjunction"):
        raise ValueError("reference must be 'mid' or 'conjunction'")
    # first guess in geometric time, then correct for the light delay
    t_conj = clock.conjunction_geom(which, near_bmjd)
    t_geom = t_conj if reference == "conjunction" else clock._mid_event_geom(t_conj, which)
    return float(geometric_to_observed(t_geom, clock))


def transit_time_bmjd(system, near_bmjd: float, *, reference: str = "mid") -> float:
    """Observed time (BMJD_TDB) of the transit nearest ``near_bmjd``.

    ``reference="mid"`` (default): minimum of the sky-projected separation;
    ``"conjunction"``: inferior conjunction.  Both include the light-travel
    time, so with ``"mid"`` the catalogue's transit epochs are returned
    exactly.
    """
    return conjunction_time_bmjd(system, near_bmjd, "transit", reference=reference)


def eclipse_time_bmjd(system, near_bmjd: float, *, reference: str = "mid") -> float:
    """Observed time (BMJD_TDB) of the secondary eclipse nearest ``near_bmjd``.

    Includes the light-travel time across the orbit; see
    :func:`transit_time_bmjd` for ``reference``.
    """
    return conjunction_time_bmjd(system, near_bmjd, "eclipse", reference=reference)


def orbital_phase(time_bmjd, system, *, reference: str = "transit"):
    """Orbital phase in [0, 1): fraction of a period since the observed mid-transit
    (``reference="transit"``) or mid-eclipse (``"eclipse"``)."""
    t = np.asarray(time_bmjd, dtype=float)
    if reference not in CONJUNCTION_ANOMALY_RAD:
        raise ValueError("reference must be 'transit' or 'eclipse'")
    # the reference time's name (mid-transit or mid-eclipse, the caller's choice), not a
    # branch on an observation's event: the one comparison of an event's name outside them
    t_ref = system.t_transit_bmjd if reference == "transit" else \
        eclipse_time_bmjd(system, system.t_transit_bmjd + 0.5 * system.period_days)
    phase = np.mod((t - t_ref) / system.period_days, 1.0)
    return float(phase) if phase.ndim == 0 else phase
