"""Digital twins of a real observation: its frames simulated again with a known eclipse.

A twin shares with the real observation everything but the noise draw
(``docs/trust.md``):

- the time stamps, channel, readout, cubes and the frames flagged bad;
- the pointing: the measured centroid of each real frame is the twin's
  exposure-mean position, and the simulator's motion within an exposure
  (fractional Brownian jitter, paper Appendix A.1) is added with an rms
  chosen so that the twins' median noise pixels match the real ones
  (:func:`calibrate_motion`);
- the star's aperture flux and the background level in electrons, so the
  photon and read noise are the real ones;
- the detector: the simulator's intra-pixel gain model of the channel
  (``BuiltinPRF``), or, where the user gives an SSC warm pixel map, a gain
  fitted to that map (:func:`map_gain`), rendered through the Fowler
  sampling of paper Appendix A.2-A.3 (:func:`eclipsebench.simulation.render.render_frames`);
- the astrophysics: L(t) given per frame (the real fit's phase model with a
  known depth at the real mid-time).

Frames are rendered in memory and measured by the same photometry as the
real frames (:func:`eclipsebench.photometry.pipeline.measure_aor`); only the
twin's table is written.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from astropy.table import Table

from ..config.photometry import PhotometrySection
from ..instrument.gain_fit import fit_true_phase_gain
from ..instrument.pointing import fbm_segments
from ..instrument.prf import BuiltinPRF, GainPolynomial, load_gainmap_coefficients
from ..photometry.clean import running_median
from ..photometry.measure import measure_stack
from ..photometry.pipeline import AorStack, brightest_of_median, measure_aor
from ..photometry.table import make_table
from ..seeding import rng
from ..simulation.render import FrameModel, render_frames, stamp_origin, tick_moments
from ..simulation.star import StarImager
from .observation import Observation

__all__ = ["TwinRecipe", "make_recipe", "render_frames_of", "twin_table", "calibrate_motion",
           "MOTION_GRID_PX", "gain_model", "map_gain"]

#: Within-exposure motion rms (px) on which the noise pixels are calibrated.
MOTION_GRID_PX = (0.0, 0.02, 0.04, 0.07, 0.1, 0.14, 0.2, 0.28)


def gain_model(channel: int) -> str:
    """What the twins' intra-pixel gain is when no map is given, for the report: the
    simulator's model of the channel, fitted to the SSC pixel map named in
    ``data/gainmap_ch<N>.json``.

    Examples
    --------
    >>> gain_model(2)[:60]
    "the simulator's gain model of channel 2 (BuiltinPRF's intra-"
    """
    source = load_gainmap_coefficients(channel).get("source", "an SSC pixel map")
    return (f"the simulator's gain model of channel {channel} (BuiltinPRF's intra-pixel gain, "
            f"a polynomial fitted to {source}; data/gainmap_ch{channel}.json)")


def map_gain(channel: int, x_grid: np.ndarray, y_grid: np.ndarray, gain: np.ndarray,
             occupancy: np.ndarray, *, source: str, radius_px: float = 3.0
             ) -> tuple[GainPolynomial, str, dict]:
    """The twins' gain from a gridded SSC warm map: what ``BuiltinPRF`` of ``channel``
    needs so that aperture photometry (radius ``radius_px``, the map's 3 px) at the
    measured centroid follows the map (:func:`~eclipsebench.instrument.gain_fit.fit_true_phase_gain`).

    Returns the gain, its description for the report and the fit's diagnostics.
    """
    poly, info = fit_true_phase_gain(BuiltinPRF(gain=False, channel=channel), x_grid, y_grid,
                                     gain, occupancy, radius_px=radius_px)
    text = (f"the SSC pixel map {source} (a degree-6 gain in the true sub-pixel phase fitted "
            f"so that {radius_px:g} px aperture photometry of BuiltinPRF follows the map: "
            f"rms {100 * info['fit_rms']:.3f} % over {info['n_positions']} positions)")
    return poly, text, info


_BACKGROUND_WINDOW = 65   # frames of the running median of the real background (one cube)
_FBM_BETA = 1.0           # the jitter's spectral index (paper Table 5)


@dataclass(frozen=True)
class TwinRecipe:
    """What every twin of one observation shares (computed once, then one call per twin).

    Attributes
    ----------
    obs : Observation
    light_curve : ndarray
        L(t) per frame (1 = the star alone), the twin's astrophysics.
    flux_aperture_e : float
        The star's aperture flux at ``(x_ref_px, y_ref_px)``, electrons per exposure.
    x_ref_px, y_ref_px : float
        Where that flux is defined: the median real position.
    sky_e_per_px : ndarray
        Sky per pixel and exposure under the star, per frame (the real annulus
        background, smoothed over a cube, minus the PRF's own wings).
    motion_rms_px : float
        Rms of the within-exposure motion about each frame's mean position.
    gain : GainPolynomial or None
        The intra-pixel gain in the true phase (:func:`map_gain`); None: the
        simulator's model of the channel.
    """

    obs: Observation
    light_curve: np.ndarray
    flux_aperture_e: float
    x_ref_px: float
    y_ref_px: float
    sky_e_per_px: np.ndarray
    motion_rms_px: float = 0.0
    gain: GainPolynomial | None = None


def _star(obs: Observation, x_ref_px: float, y_ref_px: float, radius_px: float,
          gain: GainPolynomial | None = None) -> StarImager:
    prf = BuiltinPRF(gain=gain is None, channel=obs.channel)
    if gain is not None:
        prf.gain = gain
    return StarImager(prf, x_ref_px=x_ref_px, y_ref_px=y_ref_px, radius_px=radius_px)


def _frame_model(obs: Observation, noise_model: str = "physical") -> FrameModel:
    return FrameModel(mode=obs.mode, noise_model=noise_model, read_noise_e=obs.read_noise_e)


def make_recipe(obs: Observation, light_curve: np.ndarray, *, radius_px: float,
                motion_rms_px: float = 0.0, gain: GainPolynomial | None = None) -> TwinRecipe:
    """The shared part of the twins of ``obs`` with astrophysics ``light_curve``.

    The star's flux is the real median aperture flux divided by the median of
    ``light_curve`` over the good frames, so the twins' flux level is the
    real one whatever the eclipse.
    """
    good = obs.good
    x_ref, y_ref = float(np.median(obs.x_px[good])), float(np.median(obs.y_px[good]))
    flux = float(np.median(obs.flux_e[good]) / np.median(light_curve[good]))
    star = _star(obs, x_ref, y_ref, radius_px, gain)
    level = running_median(obs.background_e_per_px, _BACKGROUND_WINDOW, good)
    wing = star.annulus_per_unit * star.electrons_per_unit(flux)
    return TwinRecipe(obs=obs, light_curve=np.asarray(light_curve, float), flux_aperture_e=flux,
                      x_ref_px=x_ref, y_ref_px=y_ref, sky_e_per_px=np.clip(level - wing, 0, None),
                      motion_rms_px=float(motion_rms_px), gain=gain)


def _motion(model: FrameModel, n_frames: int, rms_px: float, stream: np.random.Generator
            ) -> tuple[np.ndarray, np.ndarray]:
    """Within-exposure offsets (n_frames, grid samples) with zero Fowler-weighted mean per frame
    and overall rms ``rms_px``: fractional Brownian motion, one segment per frame and axis."""
    n_grid = model.grid_samples_per_frame
    if rms_px <= 0:
        return np.zeros((n_frames, n_grid)), np.zeros((n_frames, n_grid))
    z = fbm_segments(stream, 2 * n_frames, n_grid, _FBM_BETA)
    dx, dy = z[:n_frames], z[n_frames:]
    mx, my, _ = tick_moments(dx, dy, model)
    dx, dy = dx - mx[:, None], dy - my[:, None]
    scale = rms_px / max(float(np.sqrt(0.5 * (np.mean(dx**2) + np.mean(dy**2)))), 1e-12)
    return dx * scale, dy * scale


def render_frames_of(recipe: TwinRecipe, rows: np.ndarray, *, seed: int, key: tuple,
                     noise_model: str = "physical", radius_px: float = 2.25,
                     star: StarImager | None = None) -> np.ndarray:
    """The twin's frames (electrons) of the real frames ``rows`` of one cube.

    ``key`` names the random streams (``seed``, ``*key``, ``"motion"``/``"photon"``/
    ``"read"``), one set per cube, so a cube's frames do not depend on the others.
    """
    obs = recipe.obs
    model = _frame_model(obs, noise_model)
    star = star if star is not None else _star(obs, recipe.x_ref_px, recipe.y_ref_px, radius_px,
                                               recipe.gain)
    x_track, y_track = obs.track_px()
    dx, dy = _motion(model, rows.size, recipe.motion_rms_px, rng(seed, *key, "motion"))
    x_off, y_off, moments = tick_moments(dx, dy, model)
    x_f, y_f = x_track[rows] + x_off, y_track[rows] + y_off
    sx0, sy0 = stamp_origin(np.array([x_f.mean()]), np.array([y_f.mean()]), model.stamp_px,
                            model.shape)
    basis = star.taylor_basis(x_f, y_f, int(sx0[0]), int(sy0[0]), model.stamp_px)
    wings = star.image(float(x_f.mean()), float(y_f.mean()), model.shape)
    ticks = model.ticks_per_exposure
    per_tick = star.electrons_per_unit(recipe.flux_aperture_e) / ticks
    frames, _ = render_frames(
        model=model, moments=moments, basis=basis, stamp_x0=int(sx0[0]), stamp_y0=int(sy0[0]),
        wings=wings, star_e_per_tick=per_tick * recipe.light_curve[rows],
        background_e_per_tick=recipe.sky_e_per_px[rows] / ticks,
        rng_photon=rng(seed, *key, "photon"), rng_read=rng(seed, *key, "read"))
    return frames


def _measure_aor(recipe: TwinRecipe, rows: np.ndarray, frames: np.ndarray,
                 options: PhotometrySection) -> dict[str, np.ndarray]:
    obs = recipe.obs
    star = brightest_of_median(frames, obs.frame[rows] != 0)
    star_x, star_y = star if star is not None else (frames.shape[2] // 2, frames.shape[1] // 2)
    stack = AorStack(aorkey=int(obs.aorkey[rows[0]]), frames_e=frames.astype(np.float32),
                     bad_mask=None, time_bmjd=obs.time_bmjd[rows], expid=obs.expid[rows],
                     dce=np.zeros(rows.size, np.int64), frame=obs.frame[rows],
                     first=obs.frame[rows] == 0, x_off=0, y_off=0, star_x=int(star_x),
                     star_y=int(star_y), fowler=obs.mode.fowler, wait=obs.mode.wait,
                     read_noise_e=obs.read_noise_e, files=[])
    return measure_aor(stack, options, stamp_x=int(star_x), stamp_y=int(star_y))


def twin_table(recipe: TwinRecipe, options: PhotometrySection, *, seed: int, twin: int,
               noise_model: str = "physical") -> Table:
    """Simulate and measure twin number ``twin``: its photometry table.

    The real frames' flags are kept (a frame flagged bad in the observation
    is flagged in every twin, beside what the twin's own photometry flags).
    The table's metadata are the real table's, with ``TWIN`` (its number),
    ``SIMULATE`` true and ``EPOCH`` the twin's number.
    """
    obs = recipe.obs
    star = _star(obs, recipe.x_ref_px, recipe.y_ref_px, options.radius_px, recipe.gain)
    parts = []
    for rows in obs.aors():
        frames = np.concatenate([
            render_frames_of(recipe, cube, seed=seed, key=("trust", "twin", twin, int(cube[0])),
                             noise_model=noise_model, star=star)
            for cube in np.split(rows, np.flatnonzero(np.diff(obs.expid[rows]) != 0) + 1)])
        parts.append(_measure_aor(recipe, rows, frames, options))
    columns = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    columns["flag"] = columns["flag"] | obs.flag
    meta = {k: v for k, v in obs.meta.items() if k not in ("FLAGCNT", "FILENAME")}
    meta.update({"TWIN": int(twin), "EPOCH": int(twin), "SIMULATE": True,
                 "TWINMOT": float(recipe.motion_rms_px)})
    return make_table(columns, meta)


def calibrate_motion(recipe: TwinRecipe, options: PhotometrySection, *, n_frames: int = 256,
                     grid_px: tuple[float, ...] = MOTION_GRID_PX) -> tuple[float, dict]:
    """The within-exposure motion rms whose noise-free twins match the real median noise pixels.

    Renders ``n_frames`` frames spread over the good frames, noise-free, for
    each rms of ``grid_px``, measures their median noise pixels and
    interpolates to the real median. Outside the grid's range the nearest end
    is taken and the returned diagnostics say so.

    Returns
    -------
    rms_px : float
    diagnostics : dict
        ``noise_pixels_real``, the grid and the median noise pixels at each.
    """
    obs = recipe.obs
    good = np.flatnonzero(obs.good)
    rows = good[np.linspace(0, good.size - 1, min(n_frames, good.size)).astype(int)]
    target = float(np.median(obs.noise_pixels[obs.good]))
    medians = []
    for rms in grid_px:
        trial = replace(recipe, motion_rms_px=rms)
        frames = render_frames_of(trial, rows, seed=0, key=("trust", "calibrate"),
                                  noise_model="none", radius_px=options.radius_px)
        m = _measure_rows(frames, obs, options)
        medians.append(float(np.median(m)))
    medians_arr = np.maximum.accumulate(np.asarray(medians))
    if target <= medians_arr[0]:
        rms_px, where = float(grid_px[0]), "below"
    elif target >= medians_arr[-1]:
        rms_px, where = float(grid_px[-1]), "above"
    else:
        rms_px, where = float(np.interp(target, medians_arr, grid_px)), "inside"
    return rms_px, {"noise_pixels_real": target, "motion_grid_px": list(grid_px),
                    "noise_pixels_grid": medians, "target_vs_grid": where}


def _measure_rows(frames: np.ndarray, obs: Observation, options: PhotometrySection) -> np.ndarray:
    sx, sy = brightest_of_median(frames, np.ones(len(frames), bool)) or (15, 15)
    m = measure_stack(frames, guess_x=int(sx), guess_y=int(sy), options=options,
                      fowler=obs.mode.fowler, wait=obs.mode.wait, read_noise_e=obs.read_noise_e)
    return m["noise_pixels"]

