"""Thermal phase curves: the Cowan & Agol (2011, ApJ 726, 82) model for any eccentricity.

The model
---------
Each patch of the planet (latitude ``theta``, longitude ``phi`` in a frame
that rotates with the gas at ``Omega_p = omega_rot * omega_peri``, where
``omega_peri`` is the orbital angular velocity at periastron; zero obliquity)
absorbs the stellar flux falling on it and re-radiates as a blackbody with a
radiative time ``tau_rad``::

    dT~/dt = [ (r_p / r(t))^2 max(cos alpha, 0) - T~^4 ] / tau_rad

with ``T = T0 T~``, ``T0 = T* (1 - A)^(1/4) sqrt(R* / r_p)`` the sub-stellar
equilibrium temperature at periastron distance ``r_p = a (1 - e)``, and
``cos alpha = cos(theta) cos(lambda - lambda_*)`` the cosine of the stellar
zenith angle (``lambda`` the patch's inertial longitude, ``lambda_* = f + pi``
the sub-stellar one).  ``tau_rad`` is the radiative time at ``T0``, the
hottest the gas can be: like ``Omega_rot``, it is referred to periastron.
``tau_rad = 0`` is instantaneous re-radiation, ``T~^4 = forcing``.

Each patch is an independent periodic ODE; the periodic steady state is found
by Newton's method on the one-orbit map (RK4 steps carrying the variational
equation), so no spin-up orbits are needed and the result is periodic to
1e-10.  The planet's flux towards the observer is the sum over the visible
hemisphere of ``B(T) cos(gamma)`` (isotropic emission; ``gamma`` the angle
between the patch normal and the line of sight), on a Gauss-Legendre grid in
``sin(theta)`` by a uniform grid in longitude.

Flux ratios
-----------
``monochromatic`` (IRACSIM's exoplanet wrapper): ratio of Planck functions at
one wavelength, 4.5095 um by default.  ``tophat``: photon-weighted band
average (``integral lambda B_lambda``) over a top-hat 4.0-5.0 um band.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .orbit import eccentric_to_true, periastron_angular_velocity, solve_kepler

__all__ = ["planck_lambda", "Band", "band_for", "ThermalModel", "PlanetFluxTable"]

_HC_OVER_K_UM_K = 14387.7688  # h c / k in um K


def planck_lambda(wavelength_um, temperature_k):
    """Planck function up to a constant: ``lambda^-5 / (exp(hc / lambda k T) - 1)``.

    Only ratios are used, so the constant ``2 h c^2`` is dropped.  Zero at
    ``T = 0``.
    """
    lam = np.asarray(wavelength_um, dtype=float)
    t = np.asarray(temperature_k, dtype=float)
    with np.errstate(divide="ignore", over="ignore"):
        x = _HC_OVER_K_UM_K / (lam * t)
        out = np.where(t > 0, lam ** -5.0 / np.expm1(np.minimum(x, 700.0)), 0.0)
    return out


@dataclass(frozen=True)
class Band:
    """A spectral response: wavelengths (um) and photon-counting weights.

    A single wavelength is the monochromatic case.
    """

    name: str
    wavelength_um: tuple[float, ...]
    weight: tuple[float, ...]

    def radiance(self, temperature_k) -> np.ndarray:
        """Band-averaged ``B_lambda`` (photon weighted), same arbitrary units for every T."""
        t = np.asarray(temperature_k, dtype=float)
        lam = np.asarray(self.wavelength_um)
        if lam.size == 1:
            return planck_lambda(lam[0], t)
        w = np.asarray(self.weight) * lam  # photon counting: lambda B_lambda R(lambda)
        w = w / w.sum()
        return planck_lambda(lam[:, None], t.reshape(1, -1)).T @ w if t.ndim else \
            float(planck_lambda(lam, t) @ w)


def band_for(flux_ratio_model: str, wavelength_um: float = 4.5095) -> Band:
    """The :class:`Band` for a ``[system] flux_ratio_model``."""
    if flux_ratio_model == "monochromatic":
        return Band(f"monochromatic {wavelength_um:g} um", (float(wavelength_um),), (1.0,))
    if flux_ratio_model == "tophat":
        # Simpson-weighted samples of a flat response between 4.0 and 5.0 um
        lam = np.linspace(4.0, 5.0, 201)
        w = np.ones_like(lam)
        w[1:-1:2], w[2:-1:2] = 4.0, 2.0
        return Band("top-hat 4.0-5.0 um", tuple(lam), tuple(w))
    raise ValueError(f"unknown flux_ratio_model {flux_ratio_model!r} "
                     "(expected 'monochromatic' or 'tophat')")


@dataclass(frozen=True)
class PlanetFluxTable:
    """Planet-to-star flux ratio over one orbit, sampled in geometric time.

    ``t_geom`` runs over one period from periastron; ``ratio`` is ``F_p/F_*``
    (1 = the star's flux), ``temperature_max_k`` the hottest patch at each time.
    """

    t_geom: np.ndarray
    ratio: np.ndarray
    temperature_max_k: np.ndarray
    t0_k: float


class ThermalModel:
    """Cowan & Agol (2011) thermal phase curve of one planet.

    Parameters
    ----------
    system : PlanetSystem
    albedo : float
        Bond albedo A, ``0 <= A < 1``.
    tau_rad_days : float
        Radiative time at the periastron sub-stellar temperature (days); 0 is
        instantaneous re-radiation.
    omega_rot : float
        Angular velocity of the gas (planet rotation plus winds) in the
        inertial frame, in units of the orbital angular velocity at
        periastron; 1 with ``e = 0`` is a tidally locked, windless planet.
    band : Band
        Spectral response of the flux ratio.
    n_lat, n_lon : int
        Patches per hemisphere in latitude (Gauss-Legendre in ``sin theta``)
        and in longitude.
    n_time : int
        Output samples per orbit (also the minimum number of RK4 steps).
    """

    def __init__(self, system, *, albedo: float = 0.0, tau_rad_days: float = 1.0,
                 omega_rot: float = 1.0, band: Band | None = None, n_lat: int = 24,
                 n_lon: int = 96, n_time: int = 2048):
        if not 0.0 <= albedo < 1.0:
            raise ValueError("albedo must satisfy 0 <= A < 1")
        if tau_rad_days < 0:
            raise ValueError("tau_rad_days must be >= 0")
        self.system = system
        self.albedo = float(albedo)
        self.tau_rad_days = float(tau_rad_days)
        self.omega_rot = float(omega_rot)
        self.band = band or band_for("monochromatic")
        self.n_lat, self.n_lon, self.n_time = int(n_lat), int(n_lon), int(n_time)
        e = system.ecc
        self.r_peri = system.a_rs * (1.0 - e)
        self.t0_k = system.teff_star_k * (1.0 - self.albedo) ** 0.25 * math.sqrt(1.0 / self.r_peri)
        self.omega_planet = self.omega_rot * periastron_angular_velocity(system)  # rad/day
        # grid: Gauss-Legendre in mu = sin(theta) on (0, 1), northern hemisphere
        x, w = np.polynomial.legendre.leggauss(self.n_lat)
        self.mu = 0.5 * (x + 1.0)
        self.w_mu = 0.5 * w
        self.phi = (np.arange(self.n_lon) + 0.5) * (2.0 * math.pi / self.n_lon)
        self.cos_lat = np.sqrt(1.0 - self.mu ** 2)[:, None]  # (n_lat, 1)

    # ------------------------------------------------------------------ orbit helpers
    def _orbit(self, t_from_peri: np.ndarray):
        s = self.system
        m = 2.0 * math.pi * t_from_peri / s.period_days
        f = eccentric_to_true(solve_kepler(m, s.ecc), s.ecc)
        r = s.a_rs * (1.0 - s.ecc ** 2) / (1.0 + s.ecc * np.cos(f))
        return f, r

    def _forcing(self, t_from_peri: float | np.ndarray, f, r) -> np.ndarray:
        """``(r_p/r)^2 max(cos alpha, 0)`` on the grid at one time (n_lat, n_lon)."""
        lam = self.phi[None, :] + self.omega_planet * t_from_peri
        cos_a = self.cos_lat * np.cos(lam - f - math.pi)
        return (self.r_peri / r) ** 2 * np.maximum(cos_a, 0.0)

    # ------------------------------------------------------------------ energy balance
    _MAX_STEPS = 1 << 16

    def _steps(self) -> int:
        """RK4 steps per orbit (a multiple of ``n_time``); 0 means treat as instantaneous.

        Stability and accuracy need ``dt * 4 T~^3 / tau <= 0.5`` with ``T~ <= 1``.
        When that takes more than 65 536 steps per orbit (``tau_rad`` below
        1.2e-4 of the period) the lag of the temperatures behind the forcing is
        negligible and instantaneous re-radiation is used.
        """
        if self.tau_rad_days == 0.0:
            return 0
        n = self.n_time
        n_needed = int(math.ceil(self.system.period_days * 8.0 / self.tau_rad_days))
        n *= max(1, math.ceil(n_needed / n))
        return 0 if n > self._MAX_STEPS else n

    def temperature_history(self):
        """Periodic steady-state dimensionless temperatures at the output times.

        Returns ``(t_from_peri, T~)`` with ``T~`` of shape (n_time, n_lat, n_lon).
        """
        s = self.system
        n_out = self.n_time
        t_out = np.arange(n_out) * (s.period_days / n_out)
        n_steps = self._steps()
        if n_steps == 0:
            f, r = self._orbit(t_out)
            temps = np.empty((n_out, self.n_lat, self.n_lon))
            for k in range(n_out):
                temps[k] = self._forcing(t_out[k], f[k], r[k]) ** 0.25
            return t_out, temps
        sub = n_steps // n_out
        dt = s.period_days / n_steps
        t_half = np.arange(2 * n_steps + 1) * (0.5 * dt)
        f_half, r_half = self._orbit(t_half)
        inv_tau = 1.0 / self.tau_rad_days

        def get(j):
            return self._forcing(t_half[j], f_half[j], r_half[j])

        def one_orbit(x0, record):
            x = x0.copy()
            d = np.ones_like(x)
            fc = None
            out = np.empty((n_out, self.n_lat, self.n_lon)) if record else None
            for i in range(n_steps):
                if record and i % sub == 0:
                    out[i // sub] = x
                fa = fc if i else get(0)
                fb, fc = get(2 * i + 1), get(2 * i + 2)
                k1 = (fa - x ** 4) * inv_tau
                g1 = -4.0 * x ** 3 * inv_tau
                x2 = x + 0.5 * dt * k1
                k2 = (fb - x2 ** 4) * inv_tau
                g2 = -4.0 * x2 ** 3 * inv_tau
                x3 = x + 0.5 * dt * k2
                k3 = (fb - x3 ** 4) * inv_tau
                g3 = -4.0 * x3 ** 3 * inv_tau
                x4 = x + dt * k3
                k4 = (fc - x4 ** 4) * inv_tau
                g4 = -4.0 * x4 ** 3 * inv_tau
                # variational equation d' = g d along the same stages
                d1 = g1 * d
                d2 = g2 * (d + 0.5 * dt * d1)
                d3 = g3 * (d + 0.5 * dt * d2)
                d4 = g4 * (d + dt * d3)
                x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
                d = d + dt / 6.0 * (d1 + 2 * d2 + 2 * d3 + d4)
            return x, d, out

        # start from the orbit-mean forcing^(1/4), a good guess on the night side too
        x = np.full((self.n_lat, self.n_lon), 0.5) * self.cos_lat ** 0.25 + 0.05
        for _ in range(30):
            x_end, d_end, _ = one_orbit(x, False)
            resid = x_end - x
            x_new = x - resid / (d_end - 1.0)
            x = np.where(x_new > 0, x_new, 0.5 * x)
            if np.max(np.abs(resid)) < 1e-11:
                break
        _, _, temps = one_orbit(x, True)
        return t_out, temps

    # ------------------------------------------------------------------ flux
    def flux_table(self) -> PlanetFluxTable:
        """The planet-to-star flux ratio at ``n_time`` times over one orbit."""
        s = self.system
        t_out, temps = self.temperature_history()
        inc = math.radians(s.inc_deg)
        w = math.radians(s.omega_deg)
        # band radiance of the planet, interpolated on a temperature table
        t_k = temps * self.t0_k
        tmax = float(t_k.max()) * 1.001 + 1.0
        grid = np.linspace(0.0, tmax, 4001)
        rad_grid = self.band.radiance(grid)
        star = float(self.band.radiance(s.teff_star_k))
        ratio = np.empty(len(t_out))
        sin_lat = self.mu[:, None]
        for k, t in enumerate(t_out):
            lam = self.phi[None, :] + self.omega_planet * t
            horiz = self.cos_lat * math.sin(inc) * np.sin(lam + w)
            vert = sin_lat * math.cos(inc)
            rad = np.interp(t_k[k], grid, rad_grid)
            # north (theta > 0) and south (theta < 0) share temperatures
            vis = np.maximum(horiz + vert, 0.0) + np.maximum(horiz - vert, 0.0)
            integral = float(np.sum(self.w_mu[:, None] * rad * vis)) * (2 * math.pi / self.n_lon)
            ratio[k] = s.rp_rs ** 2 * integral / (math.pi * star)
        return PlanetFluxTable(t_geom=s.clock.t_peri + t_out, ratio=ratio,
                               temperature_max_k=t_k.reshape(len(t_out), -1).max(axis=1),
                               t0_k=self.t0_k)
