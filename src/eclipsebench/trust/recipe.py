"""The twins' astrophysics and shared recipe, from the real table and its first fit.

The twins' L(t) is the reduction's own astrophysical model
(:class:`eclipsebench.fit.model.AstroModel`, the physical eclipse
shape of the planet) evaluated at every real frame with the first method's
fitted mid-time and phase-curve coefficients and a known depth: by default
that fit's depth, or the one asked for. No ramp: a ramp is the detector's,
and the twins' detector is the simulator's. A whole phase curve's L(t) is
``T(t) + v(t) p(t)`` (:mod:`eclipsebench.fit.model.phase_curve`) with the
fit's ``rp_rs`` and harmonics and no AOR offsets (the repointing's steps are
the detector's too); its injected amplitude and peak offset are that
model's :func:`~eclipsebench.astro.phase_curves.harmonic_summary`
(:func:`phase_truth`).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..config.base import from_mapping
from ..config.photometry import PhotometrySection
from ..errors import InputError
from ..fit.model import AstroModel
from ..fit.names import EVENTS as MODEL_EVENTS
from ..instrument.prf import GainPolynomial
from ..io.atomic import atomic_path, write_json
from ..io.pmap_files import GriddedPmap, find_pmap_path, load_pmap
from ..photometry.table import read_table
from .noise import correlated_component
from .observation import Observation, observation_from_table
from .twin import (
    MOTION_GRID_PX,
    TwinRecipe,
    background_scatter_share,
    blur_spanning,
    builtin_gain,
    calibrate_motion,
    gain_model,
    gentler_motions,
    make_recipe,
    map_gain,
    motion_rms_per_peak,
    twin_table,
)

__all__ = ["twin_light_curve", "twin_truth", "phase_truth", "build_recipe", "twin_map",
           "twin_gain", "write_recipe", "read_recipe", "EVENTS", "PILOT_TWIN", "pilot_twin",
           "with_real_noise", "bounded_recipe"]

#: The events a twin can carry: one eclipse or transit observation, or a whole phase curve
#: of several AORs (the models of :mod:`eclipsebench.fit.model`).
EVENTS = MODEL_EVENTS


def twin_truth(time_bmjd: np.ndarray, system: Any, fit: Mapping[str, Any], depth_ppm: float,
               event: str = "eclipse") -> tuple[AstroModel, np.ndarray]:
    """The twins' astrophysical model at ``time_bmjd`` and its parameters: the real fit
    ``fit`` (a result's ``to_dict()``) with the depth ``depth_ppm``.

    The event's time, shape (a phase curve's ``rp_rs``) and phase coefficients are the
    fit's; no ramp and, for a whole phase curve, no AOR offsets: they are the detector's
    (the simulator makes the twins' systematics).
    """
    if event not in EVENTS:
        raise InputError(f"event {event!r}: twins carry an eclipse, a transit or a whole "
                         f"phase curve ({', '.join(EVENTS)})")
    model = AstroModel.build(time_bmjd, system, phase=str(fit.get("phase", "flat")), event=event)
    theta = model.initial(t_event_bmjd=float(fit[model.facts.time_key]))
    theta[0] = model.facts.size_from_depth(depth_ppm)
    for i, name in enumerate(model.names[2:], start=2):
        value = fit.get(name)
        if isinstance(value, (int, float)) and np.isfinite(value):
            theta[i] = float(value)
    return model, theta


def twin_light_curve(time_bmjd: np.ndarray, system: Any, fit: Mapping[str, Any],
                     depth_ppm: float, event: str = "eclipse") -> np.ndarray:
    """L(t) of the real fit ``fit`` (a result's ``to_dict()``) with the depth ``depth_ppm``
    (:func:`twin_truth`).

    Examples
    --------
    >>> from eclipsebench.astro.catalogue import get_system
    >>> t = np.linspace(56241.75, 56242.10, 500)
    >>> lc = twin_light_curve(t, get_system("XO-3b"), {"phase": "flat",
    ...                       "t_ecl_bmjd": 56241.955}, 1500.0)
    >>> round(float(lc.max() - lc.min()) * 1e6)
    1500
    """
    model, theta = twin_truth(time_bmjd, system, fit, depth_ppm, event)
    return np.asarray(model(theta), dtype=float)


def phase_truth(model: AstroModel, theta: np.ndarray) -> dict[str, float]:
    """A whole phase curve's injected amplitude and peak offset, as its fits report them
    (:meth:`~eclipsebench.fit.model.phase_curve.PhaseCurveModel.phase_summary`, that is
    :func:`~eclipsebench.astro.phase_curves.harmonic_summary`); empty for an event that is
    not a whole orbit.

    Examples
    --------
    >>> from eclipsebench.astro.catalogue import get_system
    >>> xo3 = get_system("XO-3b (2015 challenge)")
    >>> t = np.linspace(57205.7, 57208.8, 2000)
    >>> fit = {"phase": "harmonic1", "t_ecl_bmjd": 57205.80, "rp_rs": 0.09,
    ...        "phase_a1": 2e-4, "phase_b1": 2e-4}
    >>> truth = phase_truth(*twin_truth(t, xo3, fit, 1800.0, "phase-curve"))
    >>> round(truth["phase_amplitude_ppm"], 3), round(truth["phase_offset_deg"], 3)
    (282.843, -45.0)
    """
    if not model.whole_orbit:
        return {}
    summary = model.phase_summary(theta)
    return {"phase_amplitude_ppm": 1e6 * float(summary["phase_amplitude"]),
            "phase_offset_deg": float(summary["phase_offset_deg"])}


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


def twin_gain(obs: Observation, pmap: str | None, blur_px: float | None = None
              ) -> tuple[GainPolynomial | None, str, dict]:
    """The twins' intra-pixel gain for the builtin PRF blurred by ``blur_px`` (None: the
    committed blur): fitted to the gridded SSC map ``pmap`` (:func:`twin_map`), else the
    simulator's model (refitted for the blur, :func:`~eclipsebench.trust.twin.builtin_gain`).

    Returns the gain (None: the simulator's as committed), its description and the map
    fit's diagnostics. A calibration-star table is not a gridded map: the twins keep the
    simulator's model and the description says so.
    """
    chosen = twin_map(obs, pmap)
    if chosen is None or chosen[1] is None:
        if blur_px is None:
            poly, text = None, gain_model(obs.channel)
        else:
            poly, text = builtin_gain(obs.channel, blur_px)
        if chosen is not None:
            text += (f"; {chosen[0].name} is a calibration-star table, not a gridded map of the "
                     "gain, so the twins keep the simulator's model")
        return poly, text, {}
    path, found = chosen
    assert found is not None   # a gridded map (a calibration-star table returned above)
    poly, text, info = map_gain(obs.channel, found.x_grid, found.y_grid, found.gain,
                                found.occupancy, source=path.name, blur_px=blur_px)
    return poly, text, {"path": str(path), **info}


def _gain_dict(gain: GainPolynomial | None) -> dict[str, Any] | None:
    if gain is None:
        return None
    return {"powers": [list(p) for p in gain.powers], "coeffs": list(gain.coeffs),
            "box": None if gain.box is None else [list(gain.box[0]), list(gain.box[1])]}


def _recipe_with(obs: Observation, lc: np.ndarray, options: PhotometrySection,
                 blur: float | None, peak: float, pmap: str | None
                 ) -> tuple[TwinRecipe, dict[str, Any]]:
    """The recipe for the PSF of ``blur`` and the jitter of ``peak``: the gain for that PSF
    (:func:`twin_gain`), then the share of the real background's scatter the twins' sky
    carries; and what these are, for the recipe's description."""
    gain, gain_text, gain_fit = twin_gain(obs, pmap, blur)
    recipe = make_recipe(obs, lc, radius_px=options.radius_px, motion_peak_px=peak, gain=gain,
                         blur_px=blur)
    share, background = background_scatter_share(recipe, options)
    recipe = make_recipe(obs, lc, radius_px=options.radius_px, motion_peak_px=peak, gain=gain,
                         blur_px=blur, sky_scatter=share)
    return recipe, {"sky_scatter": share, "background": background, "gain_model": gain_text,
                    "gain": _gain_dict(gain), "gain_fit": gain_fit}


def build_recipe(table_path: str, system: Any, fit: Mapping[str, Any], depth_ppm: float,
                 event: str = "eclipse", pmap: str | None = None
                 ) -> tuple[TwinRecipe, dict[str, Any]]:
    """The recipe of the twins of the table at ``table_path`` and what it is made of.

    ``pmap``: an SSC warm map (file or folder of versions) whose gain the
    twins carry (:func:`twin_gain`); None: the simulator's gain model.

    The PSF's blur and the motion within an exposure are fitted to the real
    noise pixels (:func:`~eclipsebench.trust.twin.calibrate_motion`), then the
    gain for that PSF, then the share of the real background's scatter the
    twins' sky carries (:func:`~eclipsebench.trust.twin.background_scatter_share`).
    The real correlated noise is added by :func:`with_real_noise`.
    """
    table = read_table(table_path)
    obs = observation_from_table(table, table_path)
    options = photometry_options(obs)
    model, theta = twin_truth(obs.time_bmjd, system, fit, depth_ppm, event)
    lc = np.asarray(model(theta), dtype=float)
    if np.isfinite(obs.noise_pixels[obs.good]).any():
        blur, peak, calibration = calibrate_motion(
            make_recipe(obs, lc, radius_px=options.radius_px), options)
    else:   # another pipeline's table without noise pixels: the photometry bounds the motion
        blur, peak, calibration = None, 0.0, {
            "noise_pixels_real": None, "rms_per_peak": motion_rms_per_peak(obs),
            "target_vs_grid": "no noise pixels in the table"}
    recipe, made = _recipe_with(obs, lc, options, blur, peak, pmap)
    info = {"depth_ppm": float(depth_ppm), "event": event, "phase": fit.get("phase"),
            "t_event_bmjd": float(fit[model.facts.time_key]),
            "from_method": fit.get("method"), "system": getattr(system, "name", str(system)),
            "flux_aperture_e": recipe.flux_aperture_e, "x_ref_px": recipe.x_ref_px,
            "y_ref_px": recipe.y_ref_px, "motion_peak_px": peak,
            "motion_rms_px": peak * calibration["rms_per_peak"], "calibration": calibration,
            "blur_px": blur, **made, "correlated_noise": None,
            "n_frames": obs.n_frames, "n_good": int(obs.good.sum()),
            **phase_truth(model, theta)}
    return recipe, info


#: Halvings of the interval between the last grid peak whose pilot twin is redder than the real
#: residuals and the first that is not (:func:`bounded_recipe`): 0.04 px for real epoch 1's.
REFINE_STEPS = 2

#: The pilot twin's number: made and reduced like the others to measure how red a twin's
#: residuals are before the real correlated noise is added (:func:`with_real_noise`), never
#: scored (the scored twins are numbered from 1).
PILOT_TWIN = 0


def pilot_twin(recipe: TwinRecipe, *, seed: int) -> Any:
    """The pilot twin's photometry table (:data:`PILOT_TWIN`), without correlated noise.

    Its photon noise keeps the exact Poisson draws (``gaussian_skew=0``): the recipe
    is calibrated once per run, where the twins' Gaussian draws
    (:data:`~eclipsebench.trust.twin.GAUSSIAN_SKEW`) would save a second, and the
    motion's bound this pilot decides is then the one of twin model 5 (issue 40).
    """
    return twin_table(dataclasses.replace(recipe, correlated=None), photometry_options(recipe.obs),
                      seed=seed, twin=PILOT_TWIN, gaussian_skew=0.0)


def with_real_noise(recipe: TwinRecipe, info: Mapping[str, Any],
                    real: tuple[np.ndarray, np.ndarray], pilot: tuple[np.ndarray, np.ndarray]
                    ) -> tuple[TwinRecipe, dict[str, Any]]:
    """``recipe`` with the real correlated noise its twins lack, and ``info`` saying what it is.

    ``real`` and ``pilot``: ``(time_bmjd, residual)`` of the first method's fit
    of the real table and of :func:`pilot_twin`
    (:func:`eclipsebench.trust.noise.correlated_component`).
    """
    correlated, noise = correlated_component(recipe.obs.time_bmjd, real, pilot)
    if noise["bins_in_excess"] == 0:   # as red as a twin already: nothing to add
        return recipe, {**info, "correlated_noise": noise}
    return dataclasses.replace(recipe, correlated=correlated), \
        {**info, "correlated_noise": noise}


def bounded_recipe(recipe: TwinRecipe, info: Mapping[str, Any], pmap: str | None,
                   real: tuple[np.ndarray, np.ndarray],
                   pilot_residuals: Callable[[TwinRecipe], tuple[np.ndarray, np.ndarray]]
                   ) -> tuple[TwinRecipe, dict[str, Any]]:
    """``recipe`` with the real correlated noise (:func:`with_real_noise`), its motion within
    an exposure bounded by the real photometry.

    The noise pixels calibrate the motion (:func:`~eclipsebench.trust.twin.calibrate_motion`);
    the real residuals bound it: where the pilot twin's residuals
    (``pilot_residuals(recipe)``, the first method's fit of :func:`pilot_twin`) are
    significantly redder than ``real`` in any frequency bin (the F test of
    :func:`~eclipsebench.trust.noise.correlated_component`), the motion the
    noise pixels gave makes more pointing noise than the real frames hold, and
    the PSFs with less motion that keep the real median noise pixels
    (:func:`~eclipsebench.trust.twin.gentler_motions`) are taken in turn until
    a pilot is not, and the interval between that peak and the last redder one
    is halved :data:`REFINE_STEPS` times (the grid is coarse); the most motion
    whose pilot is no redder is kept, or, where none is, the fewest such bins
    (the most motion among equals).

    A table without noise pixels (another pipeline's) has nothing to calibrate
    on, so the same rule sets its motion alone: where its pilot without motion is
    nowhere redder than ``real``, the committed PSF with each peak of
    :data:`~eclipsebench.trust.twin.MOTION_GRID_PX`, the most first, until a
    pilot is no redder, then the halvings (docs/trust.md, "the motion's bound").

    Nothing of a twin's truth enters: the test compares residuals.
    ``info["motion_bound"]`` lists the steps.
    """
    options = photometry_options(recipe.obs)
    calibration = info["calibration"]
    made = [with_real_noise(recipe, info, real, pilot_residuals(recipe))]

    def step(extra: Mapping[str, Any]) -> dict[str, Any]:
        noise = made[-1][1]["correlated_noise"]
        return {"blur_px": made[-1][1]["blur_px"], "motion_peak_px": made[-1][1]["motion_peak_px"],
                "bins_twin_in_excess": noise["bins_twin_in_excess"],
                "periods_twin_in_excess_min": noise["periods_twin_in_excess_min"], **extra}

    steps = [step({})]

    def passes(candidate: Mapping[str, Any]) -> bool:
        """Make and reduce the pilot of ``candidate``'s PSF; whether it is no redder."""
        blur = None if candidate["blur_px"] is None else float(candidate["blur_px"])
        peak = float(candidate["motion_peak_px"])
        twin_recipe, parts = _recipe_with(recipe.obs, recipe.light_curve, options, blur, peak,
                                          pmap)
        at = {**info, **parts, "blur_px": blur, "motion_peak_px": peak,
              "motion_rms_px": peak * calibration["rms_per_peak"]}
        made.append(with_real_noise(twin_recipe, at, real, pilot_residuals(twin_recipe)))
        steps.append(step({k: candidate[k] for k in ("noise_pixels_twins",
                                                     "noise_pixels_cube_sd_twins")}))
        return steps[-1]["bins_twin_in_excess"] == 0

    photometry_only = calibration.get("noise_pixels_real") is None
    redder: float | None = None
    if photometry_only:
        def at_peaks(peaks: tuple[float, ...]) -> list[dict[str, Any]]:
            return [{"blur_px": None, "motion_peak_px": float(p), "noise_pixels_twins": None,
                     "noise_pixels_cube_sd_twins": None} for p in peaks]
        ladder = (at_peaks(tuple(sorted((p for p in MOTION_GRID_PX if p > 0), reverse=True)))
                  if steps[0]["bins_twin_in_excess"] == 0 else [])
    elif steps[0]["bins_twin_in_excess"] > 0 and "motion_grid_px" in calibration:
        redder = float(calibration["motion_peak_px"])
        grid = blur_spanning(recipe, options, calibration)   # rendered once, if at all

        def at_peaks(peaks: tuple[float, ...]) -> list[dict[str, Any]]:
            return gentler_motions(recipe, options, grid, peaks_px=peaks)
        ladder = gentler_motions(recipe, options, grid)
    else:
        ladder = []
    for candidate in ladder:
        if passes(candidate):
            # the grid is coarse: halve the interval between the last redder peak and this
            # one, REFINE_STEPS times
            calm = float(candidate["motion_peak_px"])
            for _ in range(REFINE_STEPS):
                if redder is None:   # the most motion of the grid is no redder
                    break
                mid = at_peaks((0.5 * (calm + redder),))
                if not mid:
                    break
                if passes(mid[0]):
                    calm = float(mid[0]["motion_peak_px"])
                else:
                    redder = float(mid[0]["motion_peak_px"])
            break
        redder = float(candidate["motion_peak_px"])
    # the most motion among the pilots no redder (or, where none is, with the fewest bins)
    chosen = min(range(len(steps)), key=lambda i: (steps[i]["bins_twin_in_excess"],
                                                   -steps[i]["motion_peak_px"]))
    twin_recipe, out = made[chosen]
    psfs = ("the committed PSF (the table has no noise pixels)" if photometry_only
            else "the PSFs with the real median noise pixels")
    bound = {"rule": f"the most motion within an exposure, among {psfs}, whose pilot twin is "
                     "nowhere significantly redder than the real residuals", "steps": steps,
             "chosen": chosen, "bounded": chosen > 0 and not photometry_only,
             "photometry_only": photometry_only}
    if chosen > 0 and photometry_only:
        out["calibration"] = {**calibration, "motion_peak_px": steps[chosen]["motion_peak_px"],
                              "target_vs_grid": "no noise pixels in the table: the motion "
                                                "from the real residuals alone"}
    elif chosen > 0:   # the chosen PSF and its noise pixels; the noise pixels' own fit beside
        keys = ("blur_px", "motion_peak_px", "noise_pixels_twins", "noise_pixels_cube_sd_twins")
        out["calibration"] = {**calibration, **{k: steps[chosen][k] for k in keys},
                              "noise_pixels_only": {k: calibration[k] for k in keys}}
    return twin_recipe, {**out, "motion_bound": bound}


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
    arrays: dict[str, Any] = {"light_curve": recipe.light_curve,
                              "sky_e_per_px": recipe.sky_e_per_px}
    if recipe.correlated is not None:
        arrays["correlated"] = recipe.correlated
    with atomic_path(npz_path) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **arrays)


def read_recipe(table_path: str, npz_path: Path, json_path: Path
                ) -> tuple[TwinRecipe, dict[str, Any]]:
    """The recipe written by :func:`write_recipe` for the table at ``table_path``."""
    info = json.loads(Path(json_path).read_text())
    obs = observation_from_table(read_table(table_path), table_path)
    blur = info.get("blur_px")
    with np.load(npz_path) as arrays:
        recipe = TwinRecipe(obs=obs, light_curve=arrays["light_curve"],
                            flux_aperture_e=float(info["flux_aperture_e"]),
                            x_ref_px=float(info["x_ref_px"]), y_ref_px=float(info["y_ref_px"]),
                            sky_e_per_px=arrays["sky_e_per_px"],
                            motion_peak_px=float(info["motion_peak_px"]),
                            gain=(None if info.get("gain") is None
                                  else GainPolynomial.from_dict(info["gain"])),
                            blur_px=None if blur is None else float(blur),
                            sky_scatter=float(info.get("sky_scatter", 0.0)),
                            correlated=(arrays["correlated"] if "correlated" in arrays.files
                                        else None))
    return recipe, info
