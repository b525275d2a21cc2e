"""``[system]``: which planet, and how its light curve is made."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal

from ..astro.catalogue import system_from_mapping
from ..errors import ConfigError, InputError
from .base import check

CHALLENGE_SYSTEM = "XO-3b (2015 challenge)"
"""The built-in challenge's planet: XO-3b with the 2015 challenge's orbital elements."""


@dataclass(frozen=True)
class SystemSection:
    """The planetary system and the thermal phase-curve model.

    The defaults are the 2015 data challenge's choices (Section 2.3 of the
    paper): XO-3b with the challenge's orbital elements (the catalogue row
    ``"XO-3b (2015 challenge)"``: e = 0.2884, omega = 346 deg, Winn et al.
    2008; the row ``"XO-3b"`` keeps Wong et al. 2014), Bond albedo 0,
    radiative time 1 day, rotation rate 1 (in units of the orbital angular
    velocity at periastron), a monochromatic 4.5095 um ratio of blackbodies,
    and the eclipse depth fixed to 1875 ppm.

    The planet is ``name`` looked up in ``catalogue`` (a user TOML file,
    searched first) and the built-in catalogue, or, when the ``planet``
    table is given (``[system.planet]``, or ``--planet KEY=VALUE`` on the
    command line), a planet in no catalogue: ``name`` with these values,
    checked as a catalogue row (``eclipsebench.astro.catalogue.system_for``).
    """

    name: str = CHALLENGE_SYSTEM
    catalogue: str = ""  # optional TOML file of user systems; empty: the built-in catalogue
    # the planet's own values (the keys of a catalogue row: period_days, t_transit_bjd, ecc,
    # omega_deg, inc_deg, a_rs, rp_rs, teff_star_k, ...); empty: look `name` up. Not hashed
    # (a dict), so equal sections differing in it share a hash but not equality.
    planet: dict[str, Any] = field(default_factory=dict, hash=False)
    albedo: float = 0.0
    tau_rad_days: float = 1.0
    omega_rot: float = 1.0
    # "monochromatic": Planck ratio at wavelength_um (IRACSIM's exoplanet wrapper);
    # "tophat": photon-weighted average over a flat 4.0-5.0 um band
    flux_ratio_model: Literal["monochromatic", "tophat"] = "monochromatic"
    wavelength_um: float = 4.5095
    fix_depth_ppm: float = 1875.0  # 0 leaves the depth to the phase-curve model
    # surface sum of the thermal model: "gauss" (converged) or "iracsim2015" (the wrapper's
    # 20 x 40 rectangle sum, about 6% high; reproduces the paper's 1875 ppm without fixing)
    quadrature: Literal["gauss", "iracsim2015"] = "gauss"

    def validate(self) -> None:
        check(bool(self.name.strip()), "name", "a planet name")
        if self.planet:
            try:
                system_from_mapping(self.name, dict(self.planet))
            except InputError as exc:
                raise ConfigError("planet", str(exc)) from None
        check(0.0 <= self.albedo < 1.0, "albedo", "0 <= albedo < 1")
        check(self.tau_rad_days >= 0.0, "tau_rad_days", "a non-negative number of days")
        check(self.wavelength_um > 0.0, "wavelength_um", "a positive wavelength in micron")
        check(self.fix_depth_ppm >= 0.0, "fix_depth_ppm", "0 (not fixed) or a positive depth in ppm")
        check(math.isfinite(self.omega_rot) and abs(self.omega_rot) < 1e3, "omega_rot",
              "a finite rotation rate in units of the periastron orbital angular velocity")
