"""The twins' astrophysics and shared recipe, from the real table and its first fit.

The twins' L(t) is the reduction's own astrophysical model
(:class:`eclipsebench.fit.astro_model.AstroModel`, the physical eclipse
shape of the planet) evaluated at every real frame with the first method's
fitted mid-time and phase-curve coefficients and a known depth: by default
that fit's depth, or the one asked for. No ramp: a ramp is the detector's,
and the twins' detector is the simulator's.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..config.base import from_mapping
from ..config.photometry import PhotometrySection
from ..errors import InputError
from ..fit.astro_model import AstroModel
from ..instrument.prf import GainPolynomial
from ..io.atomic import atomic_path, write_json
from ..io.pmap_files import GriddedPmap, find_pmap_path, load_pmap
from ..photometry.table import read_table
from .observation import Observation, observation_from_table
from .twin import TwinRecipe, calibrate_motion, gain_model, make_recipe, map_gain

__all__ = ["twin_light_curve", "build_recipe", "twin_map", "twin_gain", "write_recipe", "read_recipe", "EVENTS"]

#: The events a twin can carry (a whole phase curve is several AORs of its own kind).
EVENTS = ("eclipse", "transit")


def twin_light_curve(time_bmjd: np.ndarray, system: Any, fit: Mapping[str, Any],
                     depth_ppm: float, event: str = "eclipse") -> np.ndarray:
    """L(t) of the real fit ``fit`` (a result's ``to_dict()``) with the depth ``depth_ppm``.

    Examples
    --------
    >>> from eclipsebench.astro.catalogue import get_system
    >>> t = np.linspace(56241.75, 56242.10, 500)
    >>> lc = twin_light_curve(t, get_system("XO-3b"), {"phase": "flat",
    ...                       "t_ecl_bmjd": 56241.955}, 1500.0)
    >>> round(float(lc.max() - lc.min()) * 1e6)
    1500
    """
    if event not in EVENTS:
        raise InputError(f"event {event!r}: twins carry an eclipse or a transit "
                         f"({', '.join(EVENTS)})")
    model = AstroModel.build(time_bmjd, system, phase=str(fit.get("phase", "flat")), event=event)
    when = "t_transit_bmjd" if event == "transit" else "t_ecl_bmjd"
    size = np.sqrt(depth_ppm * 1e-6) if event == "transit" else depth_ppm * 1e-6
    theta = model.initial(t_ecl_bmjd=float(fit[when]))
    theta[0] = size
    for i, name in enumerate(model.names[2:], start=2):
        value = fit.get(name)
        if isinstance(value, (int, float)) and np.isfinite(value):
            theta[i] = float(value)
    return np.asarray(model(theta), dtype=float)


def twin_map(obs: Observation, pmap: str | None) -> tuple[Path, GriddedPmap | None] | None:
    """The map ``pmap`` names for ``obs`` (a folder of versions: the one in force at the
    observation's date), loaded: ``(path, map)``, the map None for a calibration-star
    table; None without ``pmap``. Raises InputError/DataError in one line for a path
    that holds no readable map."""
    if pmap is None or str(pmap) == "":
        return None
    path = find_pmap_path(pmap, {"CHANNEL": obs.channel}, float(obs.time_bmjd[0]))
    found = load_pmap(path)
    return path, (found if isinstance(found, GriddedPmap) else None)


def twin_gain(obs: Observation, pmap: str | None) -> tuple[GainPolynomial | None, str, dict]:
    """The twins' intra-pixel gain: fitted to the gridded SSC map ``pmap`` (:func:`twin_map`),
    else the simulator's model.

    Returns the gain (None: the simulator's), its description and the map fit's
    diagnostics. A calibration-star table is not a gridded map: the twins keep the
    simulator's model and the description says so.
    """
    chosen = twin_map(obs, pmap)
    if chosen is None:
        return None, gain_model(obs.channel), {}
    path, found = chosen
    if found is None:
        return None, (gain_model(obs.channel) + f"; {path.name} is a calibration-star table, "
                      "not a gridded map of the gain, so the twins keep the simulator's model"), {}
    poly, text, info = map_gain(obs.channel, found.x_grid, found.y_grid, found.gain,
                                found.occupancy, source=path.name)
    return poly, text, {"path": str(path), **info}


def _gain_dict(gain: GainPolynomial | None) -> dict[str, Any] | None:
    if gain is None:
        return None
    return {"powers": [list(p) for p in gain.powers], "coeffs": list(gain.coeffs),
            "box": None if gain.box is None else [list(gain.box[0]), list(gain.box[1])]}


def build_recipe(table_path: str, system: Any, fit: Mapping[str, Any], depth_ppm: float,
                 event: str = "eclipse", pmap: str | None = None
                 ) -> tuple[TwinRecipe, dict[str, Any]]:
    """The recipe of the twins of the table at ``table_path`` and what it is made of.

    ``pmap``: an SSC warm map (file or folder of versions) whose gain the
    twins carry (:func:`twin_gain`); None: the simulator's gain model.
    """
    table = read_table(table_path)
    obs = observation_from_table(table, table_path)
    options = photometry_options(obs)
    gain, gain_text, gain_fit = twin_gain(obs, pmap)
    lc = twin_light_curve(obs.time_bmjd, system, fit, depth_ppm, event)
    recipe = make_recipe(obs, lc, radius_px=options.radius_px, gain=gain)
    if np.isfinite(obs.noise_pixels[obs.good]).any():
        peak, calibration = calibrate_motion(recipe, options)
    else:   # another pipeline's table without noise pixels: nothing to calibrate on
        peak, calibration = 0.0, {"noise_pixels_real": None, "rms_per_peak": 0.0,
                                  "target_vs_grid": "no noise pixels in the table"}
    recipe = make_recipe(obs, lc, radius_px=options.radius_px, motion_peak_px=peak, gain=gain)
    info = {"depth_ppm": float(depth_ppm), "event": event, "phase": fit.get("phase"),
            "t_event_bmjd": float(fit["t_transit_bmjd" if event == "transit" else "t_ecl_bmjd"]),
            "from_method": fit.get("method"), "system": getattr(system, "name", str(system)),
            "flux_aperture_e": recipe.flux_aperture_e, "x_ref_px": recipe.x_ref_px,
            "y_ref_px": recipe.y_ref_px, "motion_peak_px": peak,
            "motion_rms_px": peak * calibration["rms_per_peak"], "calibration": calibration,
            "gain_model": gain_text, "gain": _gain_dict(gain), "gain_fit": gain_fit,
            "n_frames": obs.n_frames, "n_good": int(obs.good.sum())}
    return recipe, info


def photometry_options(obs: Observation) -> PhotometrySection:
    """The photometry settings the real table was measured with (its ``OPTIONS``)."""
    stored = obs.meta.get("OPTIONS")
    if isinstance(stored, str):
        stored = json.loads(stored)
    if not isinstance(stored, Mapping):
        return PhotometrySection()
    return from_mapping(PhotometrySection, dict(stored), prefix="photometry")


def write_recipe(recipe: TwinRecipe, info: Mapping[str, Any], npz_path: Path,
                 json_path: Path) -> None:
    """The description (JSON), then the per-frame arrays (``.npz``, written last)."""
    write_json(json_path, dict(info))
    with atomic_path(npz_path) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, light_curve=recipe.light_curve, sky_e_per_px=recipe.sky_e_per_px)


def read_recipe(table_path: str, npz_path: Path, json_path: Path
                ) -> tuple[TwinRecipe, dict[str, Any]]:
    """The recipe written by :func:`write_recipe` for the table at ``table_path``."""
    info = json.loads(Path(json_path).read_text())
    obs = observation_from_table(read_table(table_path), table_path)
    with np.load(npz_path) as arrays:
        recipe = TwinRecipe(obs=obs, light_curve=arrays["light_curve"],
                            flux_aperture_e=float(info["flux_aperture_e"]),
                            x_ref_px=float(info["x_ref_px"]), y_ref_px=float(info["y_ref_px"]),
                            sky_e_per_px=arrays["sky_e_per_px"],
                            motion_peak_px=float(info["motion_peak_px"]),
                            gain=(None if info.get("gain") is None
                                  else GainPolynomial.from_dict(info["gain"])))
    return recipe, info
