"""The light curve L(t) of a star and its planet: thermal phase curve, eclipses, transits.

``L(t) = S(t) + F(t) V(t)`` in units of the star's flux, where ``S`` is the
stellar flux (1 except in transit, quadratic limb darkening), ``F`` the
planet-to-star flux ratio of the thermal phase curve
(:mod:`eclipsebench.astro.thermal`) and ``V`` the visible fraction of the
planet's disk (0 in eclipse).  In eclipse ``L = 1``, so the eclipse depth of
the paper's Eq. (eclipse_depth), ``D = F_out/F_in - 1``, is ``F`` at
mid-eclipse (``F_out`` interpolated to the centre of the occultation).

Everything that does not depend on the times asked for (the periodic
steady-state phase curve over one orbit, the eclipse and transit shapes on
fine grids of offsets) is computed once when the light curve is built;
calling it interpolates one table of ``L`` over a period (the union of those
grids), about 30 ms per million samples.

Examples
--------
>>> from eclipsebench.astro.catalogue import get_system
>>> lc = light_curve_function(get_system("XO-3b"))
>>> round(lc.depth_ppm, 6)
1875.0
>>> t = lc.eclipse_times_bmjd(57234.3, 57235.0)[0]
>>> float(lc(np.array([t]))[0])
1.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import cast

import numpy as np

from ..errors import InputError
from .catalogue import PlanetSystem, system_for
from .eclipse import EclipseShape, TransitShape
from .orbit import eclipse_time_bmjd, geometric_to_observed, transit_time_bmjd
from .thermal import ThermalModel, band_for

__all__ = ["LightCurve", "light_curve_function", "light_curve_from_config", "cached_light_curve",
           "FLUX_RATIO_MODELS"]

FLUX_RATIO_MODELS = ("monochromatic", "tophat")


@dataclass
class LightCurve:
    """``L(t)``, normalised so that the star alone is 1; call it with BMJD times.

    Attributes
    ----------
    system : PlanetSystem
    depth_ppm : float
        Eclipse depth of this light curve (the fixed depth when
        ``fix_depth_ppm`` was given, otherwise the model's).
    model_depth_ppm : float
        The thermal model's own depth, before any fixing.
    planet_scale : float
        Factor applied to the model's planet flux (``depth_ppm / model_depth_ppm``).
    t_transit_bmjd, t_eclipse_bmjd : float
        A reference observed mid-transit and the mid-eclipse that follows it.
    options : dict
        The phase-curve options the light curve was computed with.
    """

    system: PlanetSystem
    depth_ppm: float
    model_depth_ppm: float
    planet_scale: float
    t_transit_bmjd: float
    t_eclipse_bmjd: float
    options: dict
    _t_obs: np.ndarray = field(repr=False)
    _ratio: np.ndarray = field(repr=False)
    _eclipse: EclipseShape = field(repr=False)
    _transit: TransitShape = field(repr=False)
    _grid: np.ndarray = field(init=False, repr=False)   # set in __post_init__
    _table: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        # one table of L over one period (the union of the phase-curve samples and the
        # fine eclipse and transit grids), so a call is one mod and one interp
        p = self.system.period_days
        t0 = self._t_obs[0]
        parts = [self._t_obs - t0, [0.0, p]]
        for shape, t_event in ((self._eclipse, self.t_eclipse_bmjd),
                               (self._transit, self.t_transit_bmjd)):
            parts.append(np.mod(t_event + shape._offset - t0, p))
        grid = np.unique(np.concatenate(parts))
        t = t0 + grid
        self._grid = grid / p  # in orbital phase from t0: cheaper to wrap than np.mod
        self._table = self.stellar_flux(t) + self.planet_flux(t) * self.visible_fraction(t)

    # ------------------------------------------------------------------ evaluation
    def _wrap(self, time_bmjd: np.ndarray) -> np.ndarray:
        p = self.system.period_days
        return self._t_obs[0] + np.mod(time_bmjd - self._t_obs[0], p)

    def planet_flux(self, time_bmjd) -> np.ndarray:
        """Planet-to-star flux ratio ``F(t)`` (scaled if the depth is fixed), no eclipse."""
        t = np.asarray(time_bmjd, dtype=float)
        return self.planet_scale * np.interp(self._wrap(t), self._t_obs, self._ratio)

    def visible_fraction(self, time_bmjd) -> np.ndarray:
        """``V(t)``: visible fraction of the planet's disk (0 in eclipse)."""
        return self._eclipse.at(np.asarray(time_bmjd, dtype=float), self.t_eclipse_bmjd)

    def stellar_flux(self, time_bmjd) -> np.ndarray:
        """``S(t)``: stellar flux (1 out of transit)."""
        return self._transit.at(np.asarray(time_bmjd, dtype=float), self.t_transit_bmjd)

    def __call__(self, time_bmjd) -> np.ndarray:
        """``L(t)`` at BMJD times (1 = the star alone)."""
        phase = (np.asarray(time_bmjd, dtype=float) - self._t_obs[0]) * (
            1.0 / self.system.period_days)
        phase -= np.floor(phase)
        # (numpy's stub picks its scalar overload for an array of unknown shape)
        return cast(np.ndarray, np.interp(phase, self._grid, self._table))

    # ------------------------------------------------------------------ events
    def _events(self, t_ref: float, start: float, stop: float) -> list[float]:
        p = self.system.period_days
        k0 = math.ceil((start - t_ref) / p)
        k1 = math.floor((stop - t_ref) / p)
        return [t_ref + k * p for k in range(k0, k1 + 1)]

    def eclipse_times_bmjd(self, start: float, stop: float) -> list[float]:
        """Observed mid-eclipse times (BMJD) with ``start <= t <= stop``."""
        return self._events(self.t_eclipse_bmjd, start, stop)

    def transit_times_bmjd(self, start: float, stop: float) -> list[float]:
        """Observed mid-transit times (BMJD) with ``start <= t <= stop``."""
        return self._events(self.t_transit_bmjd, start, stop)

    def describe(self) -> dict:
        """Numbers for reports and ``--json``."""
        return {"system": self.system.name,
                "eclipse_depth_ppm": self.depth_ppm,
                "model_depth_ppm": self.model_depth_ppm,
                "depth_fixed": self.options["fix_depth_ppm"] > 0,
                "planet_scale": self.planet_scale,
                "t_transit_bmjd": self.t_transit_bmjd,
                "t_eclipse_bmjd": self.t_eclipse_bmjd,
                "options": dict(self.options)}


def light_curve_function(system: PlanetSystem, *, albedo: float = 0.0,
                         tau_rad_days: float = 1.0, omega_rot: float = 1.0,
                         flux_ratio_model: str = "monochromatic",
                         wavelength_um: float = 4.5095,
                         fix_depth_ppm: float = 1875.0,
                         limb_dark: str = "quadratic", limb_dark_u=None,
                         quadrature: str = "gauss", n_lat: int = 12, n_lon: int = 48,
                         n_time: int = 1024) -> LightCurve:
    """Build the light curve of ``system``; the defaults are the 2015 challenge's.

    Parameters
    ----------
    system : PlanetSystem
    albedo, tau_rad_days, omega_rot : float
        Cowan & Agol (2011) parameters: Bond albedo, radiative time (days) and
        gas angular velocity in units of the periastron orbital angular
        velocity (see :class:`~eclipsebench.astro.thermal.ThermalModel`).
    flux_ratio_model : {"monochromatic", "tophat"}
        Ratio of blackbodies at ``wavelength_um`` (IRACSIM's choice) or
        averaged over a top-hat 4.0-5.0 um band.
    wavelength_um : float
    fix_depth_ppm : float
        When > 0, scale the planet's flux so that the eclipse depth is exactly
        this value (the phase curve keeps its shape); 0 keeps the model depth.
    limb_dark, limb_dark_u
        Transit limb darkening (batman law and coefficients); default the
        system's quadratic coefficients.
    quadrature, n_lat, n_lon, n_time
        Surface quadrature and resolution of the thermal model (see
        :class:`~eclipsebench.astro.thermal.ThermalModel`; ``"iracsim2015"``
        reproduces the 2015 challenge's surface sum).
    """
    if flux_ratio_model not in FLUX_RATIO_MODELS:
        raise InputError(f"flux_ratio_model: expected one of {', '.join(FLUX_RATIO_MODELS)}, "
                         f"got {flux_ratio_model!r}")
    if not 0.0 <= albedo < 1.0:
        raise InputError(f"albedo: expected 0 <= A < 1, got {albedo}")
    if tau_rad_days < 0:
        raise InputError(f"tau_rad_days: expected a number >= 0, got {tau_rad_days}")
    if wavelength_um <= 0:
        raise InputError(f"wavelength_um: expected a positive wavelength, got {wavelength_um}")
    if quadrature not in ("gauss", "iracsim2015"):
        raise InputError(f"quadrature: expected gauss or iracsim2015, got {quadrature!r}")
    if fix_depth_ppm < 0:
        raise InputError(f"fix_depth_ppm: expected 0 (not fixed) or a depth > 0, "
                         f"got {fix_depth_ppm}")
    model = ThermalModel(system, albedo=albedo, tau_rad_days=tau_rad_days, omega_rot=omega_rot,
                         band=band_for(flux_ratio_model, wavelength_um),
                         n_lat=n_lat, n_lon=n_lon, n_time=n_time, quadrature=quadrature)
    table = model.flux_table()
    t_obs = geometric_to_observed(table.t_geom, system)
    # close the period so that interpolation wraps smoothly
    t_obs = np.append(t_obs, t_obs[0] + system.period_days)
    ratio = np.append(table.ratio, table.ratio[0])
    t_tr = transit_time_bmjd(system, system.t_transit_bmjd)
    t_ecl = eclipse_time_bmjd(system, t_tr + 0.5 * system.period_days)
    empty = np.empty(0)
    eclipse = EclipseShape(empty, system)
    transit = TransitShape(empty, system, limb_dark=limb_dark, u=limb_dark_u)
    wrapped = t_obs[0] + np.mod(t_ecl - t_obs[0], system.period_days)
    model_depth = float(np.interp(wrapped, t_obs, ratio)) * 1e6
    scale = fix_depth_ppm / model_depth if fix_depth_ppm > 0 else 1.0
    options = {"albedo": float(albedo), "tau_rad_days": float(tau_rad_days),
               "omega_rot": float(omega_rot), "flux_ratio_model": flux_ratio_model,
               "wavelength_um": float(wavelength_um), "band": model.band.name,
               "fix_depth_ppm": float(fix_depth_ppm), "quadrature": quadrature,
               "limb_dark": transit.limb_dark,
               "limb_dark_u": list(transit.u), "t0_periastron_k": model.t0_k}
    return LightCurve(system=system, depth_ppm=model_depth * scale, model_depth_ppm=model_depth,
                      planet_scale=scale, t_transit_bmjd=t_tr, t_eclipse_bmjd=t_ecl,
                      options=options, _t_obs=t_obs, _ratio=ratio, _eclipse=eclipse,
                      _transit=transit)


def light_curve_from_config(section, **overrides) -> LightCurve:
    """The light curve described by a ``[system]`` configuration section (``SystemSection``)."""
    system = system_for(section)
    kwargs = dict(albedo=section.albedo, tau_rad_days=section.tau_rad_days,
                  omega_rot=section.omega_rot, flux_ratio_model=section.flux_ratio_model,
                  wavelength_um=section.wavelength_um, fix_depth_ppm=section.fix_depth_ppm,
                  quadrature=getattr(section, "quadrature", "gauss"))
    kwargs.update(overrides)
    return light_curve_function(system, **kwargs)


@lru_cache(maxsize=4)
def cached_light_curve(section) -> LightCurve:
    """:func:`light_curve_from_config` of a ``[system]`` section, built once per process.

    The one cache of L(t) (building it takes seconds): the simulation's AOR
    tasks, its truth tables and anything else that needs the light curve of
    a configuration call this. ``section`` is the frozen (hashable)
    ``SystemSection``; the returned object is shared, do not modify it.
    """
    return light_curve_from_config(section)
