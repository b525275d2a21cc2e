"""Digital twins of a real observation: its frames simulated again with a known eclipse.

A twin shares with the real observation everything but the noise draw
(``docs/trust.md``):

- the time stamps, channel, readout, cubes and the frames flagged bad;
- the pointing: the measured centroid of each real frame is the twin's
  exposure-mean position, and the simulator's motion within an exposure
  (its fractional Brownian jitter, paper Appendix A.1, drawn as the
  challenge simulator draws it: :class:`ExposureMotion`) is added with an
  amplitude chosen so that the twins' median noise pixels match the real
  ones (:func:`calibrate_motion`);
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

import dataclasses
from dataclasses import dataclass

import numpy as np
from astropy.table import Table

from ..config.photometry import PhotometrySection
from ..instrument.gain_fit import fit_true_phase_gain
from ..instrument.pointing import (
    FBM_BLOCK_SEGMENTS,
    FBM_SEGMENT,
    PointingModel,
    PointingParams,
    frame_windows,
)
from ..instrument.prf import BuiltinPRF, GainPolynomial, load_gainmap_coefficients
from ..photometry.clean import running_median
from ..photometry.measure import measure_stack, read_radius_px
from ..photometry.pipeline import AorStack, brightest_of_median, measure_aor
from ..photometry.table import make_table
from ..seeding import rng
from ..simulation.plan import SECONDS_PER_DAY
from ..simulation.render import FrameModel, render_frames, stamp_origin, tick_moments
from ..simulation.star import StarImager
from .observation import Observation

__all__ = ["TwinRecipe", "ExposureMotion", "make_recipe", "render_frames_of", "twin_table",
           "calibrate_motion", "photometry_window", "twin_star", "MOTION_GRID_PX", "TWIN_MODEL",
           "gain_model", "map_gain"]

#: How twins are made (recorded with a trust run's settings, so a folder of twins made
#: otherwise is refused rather than mixed): 3 since only the part of the subarray the
#: photometry reads is rendered (:func:`photometry_window`: the same photometry, other noise
#: draws); 2 since the motion within an exposure is the simulator's block-scaled jitter
#: (:class:`ExposureMotion`), 1 before (one rms throughout).
TWIN_MODEL = 3

#: Peak amplitudes (px) of the jitter (Table 5's ``A_fbm``; the challenge's is 0.4) on which
#: the noise pixels are calibrated; for ``sub_2s`` frames they give 0 to about 0.28 px rms
#: within an exposure.
MOTION_GRID_PX = (0.0, 0.1, 0.2, 0.3, 0.45, 0.6, 0.9, 1.25)


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
    motion_peak_px : float
        Peak of the jitter's fractional Brownian motion in each block of the
        simulator (Table 5's ``A_fbm``), which sets the motion within an
        exposure (:class:`ExposureMotion`).
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
    motion_peak_px: float = 0.0
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
                motion_peak_px: float = 0.0, gain: GainPolynomial | None = None) -> TwinRecipe:
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
                      motion_peak_px=float(motion_peak_px), gain=gain)


class ExposureMotion:
    """The simulator's jitter within each exposure of one observation's frames.

    The fractional Brownian motion of :class:`~eclipsebench.instrument.pointing.PointingModel`
    exactly as the challenge simulator draws it (paper Appendix A.1, Table 5:
    ``beta = 1``; segments of 2048 samples at ``dt = SAMPTIME / subsamples``,
    each block of 64 segments, 131 s, scaled so that its peak ``|FBM|`` is
    ``peak_px`` on each axis, as IRACSIM scaled each cube), sampled at the
    real frames' times, less each frame's Fowler-weighted mean, which the
    measured centroid already holds. Where the segments and blocks begin
    among the frames is drawn (uniform over one block): the simulator counts
    them from its epoch's start, which a real table does not give. The peak
    scaling makes the motion's rms change from block to block (for
    ``sub_2s`` frames its variance by about 6 % rms), and with it the flux
    through the curvature of the gain, as in the simulator.

    Parameters
    ----------
    obs : Observation
    model : FrameModel
    peak_px : float
        ``A_fbm``.
    stream : numpy.random.Generator
        The motion's randomness (the grid's start and one seed are drawn
        from it; blocks derive their own streams, so a frame's motion does
        not depend on which frames are asked for with it).

    Examples
    --------
    >>> import numpy as np
    >>> from eclipsebench.trust.observation import Observation
    >>> from eclipsebench.detector.constants import SUB_2S
    >>> from eclipsebench.simulation.render import FrameModel
    >>> n = 128
    >>> obs = Observation(time_bmjd=57000.0 + np.arange(n) * 2.02 / 86400, aorkey=np.ones(n, int),
    ...                   expid=np.arange(n) // 64, frame=np.arange(n) % 64, x_px=np.full(n, 15.0),
    ...                   y_px=np.full(n, 15.0), flux_e=np.ones(n), background_e_per_px=np.ones(n),
    ...                   noise_pixels=np.ones(n), flag=np.zeros(n, int), channel=2, mode=SUB_2S,
    ...                   read_noise_e=9.4)
    >>> motion = ExposureMotion(obs, FrameModel(mode=SUB_2S), 0.4, np.random.default_rng(1))
    >>> dx, dy = motion.offsets(np.arange(64))
    >>> dx.shape
    (64, 2001)
    """

    def __init__(self, obs: Observation, model: FrameModel, peak_px: float,
                 stream: np.random.Generator):
        self.model = model
        self.peak_px = float(peak_px)
        self.dt_s = obs.mode.sample_time_s / model.subsamples
        # where the segments and blocks fall among the frames: the table does not say, so each
        # twin draws it (a grid shared by all twins would give them a common error pattern)
        offset = int(stream.integers(0, FBM_SEGMENT * FBM_BLOCK_SEGMENTS))
        elapsed_s = (obs.time_bmjd - np.min(obs.time_bmjd)) * SECONDS_PER_DAY
        self.start_index = offset + np.rint(elapsed_s / self.dt_s).astype(np.int64)
        duration_s = (float(self.start_index.max()) + model.grid_samples_per_frame + 1) * self.dt_s
        jitter_only = PointingParams(a_j_px=0.0, a_fbm_px=self.peak_px, beta_fbm=1.0, a_w_px=0.0,
                                     da_w_max_px=0.0, dp_w_max_s=0.0, a_sd_px=0.0,
                                     a_ld_arcsec_per_hr=0.0)
        self._pointing = PointingModel(jitter_only, duration_s=duration_s, dt_s=self.dt_s,
                                       rng=stream)

    def offsets(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Offsets (px) of frames ``rows`` at their grid samples, shape (rows.size, grid
        samples per frame), each frame's Fowler-weighted mean zero."""
        n_grid = self.model.grid_samples_per_frame
        dx, dy = np.zeros((rows.size, n_grid)), np.zeros((rows.size, n_grid))
        if self.peak_px > 0:
            starts = self.start_index[rows]
            block = starts // (FBM_SEGMENT * FBM_BLOCK_SEGMENTS)
            # the frames starting in one block: one span of at most a block and a frame
            for b in np.unique(block):
                sel = np.flatnonzero(block == b)
                dx[sel], dy[sel] = frame_windows(self._pointing.fbm_samples, starts[sel], n_grid)
        mx, my, _ = tick_moments(dx, dy, self.model)
        return dx - mx[:, None], dy - my[:, None]


def photometry_window(x_px: np.ndarray, y_px: np.ndarray, options: PhotometrySection,
                      shape: tuple[int, int]) -> tuple[int, int, int, int]:
    """``(x0, y0, nx, ny)``: the part of frames of ``shape`` that the photometry with
    ``options`` reads when the star is at ``(x_px, y_px)`` (one AOR's track).

    Every pixel within :func:`~eclipsebench.photometry.measure.read_radius_px` of
    the star's brightest pixel (within one pixel of the nearest pixel centre
    of each position) or of its centroid, with one more pixel of margin; clipped
    to the frame. The cosmic-ray rejection of the pixels outside it cannot
    reach the measurements (it is per pixel), and no twin frame is a fault
    (:func:`~eclipsebench.photometry.clean.frame_faults`), so rendering only
    this part gives the photometry the whole frame would
    (``tests/trust/test_trust.py`` checks it byte for byte on noise-free twins).

    Examples
    --------
    >>> photometry_window(np.array([15.1, 15.3]), np.array([14.9]), PhotometrySection(),
    ...                   (32, 32))
    (5, 5, 21, 21)
    """
    reach = int(np.ceil(read_radius_px(options))) + 2
    ny, nx = shape
    x_lo = max(int(np.rint(np.min(x_px))) - reach, 0)
    x_hi = min(int(np.rint(np.max(x_px))) + reach + 1, nx)
    y_lo = max(int(np.rint(np.min(y_px))) - reach, 0)
    y_hi = min(int(np.rint(np.max(y_px))) + reach + 1, ny)
    return x_lo, y_lo, x_hi - x_lo, y_hi - y_lo


def render_frames_of(recipe: TwinRecipe, rows: np.ndarray, *, seed: int, key: tuple,
                     motion: tuple[np.ndarray, np.ndarray] | None = None,
                     noise_model: str = "physical", radius_px: float = 2.25,
                     star: StarImager | None = None,
                     window: tuple[int, int, int, int] | None = None) -> np.ndarray:
    """The twin's frames (electrons) of the real frames ``rows`` of one cube.

    ``motion``: the offsets within each exposure about the measured centroid
    (:meth:`ExposureMotion.offsets` of ``rows``); None: none. ``key`` names
    the noise's random streams (``seed``, ``*key``, ``"photon"``/``"read"``),
    one set per cube, so a cube's frames do not depend on the others.
    ``window``: ``(x0, y0, nx, ny)``, render only that part of the subarray
    (:func:`photometry_window`; the PRF depends on the sub-pixel phase only,
    so the pixels are the whole frame's); None: the whole subarray.
    """
    obs = recipe.obs
    model = _frame_model(obs, noise_model)
    x0, y0 = 0, 0
    if window is not None:
        x0, y0 = int(window[0]), int(window[1])
        model = dataclasses.replace(model, shape=(int(window[3]), int(window[2])))
    star = star if star is not None else _star(obs, recipe.x_ref_px, recipe.y_ref_px, radius_px,
                                               recipe.gain)
    x_track, y_track = obs.track_px()
    if motion is None:
        dx = dy = np.zeros((rows.size, model.grid_samples_per_frame))
    else:
        dx, dy = motion
    x_off, y_off, moments = tick_moments(dx, dy, model)
    x_f, y_f = x_track[rows] - x0 + x_off, y_track[rows] - y0 + y_off
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
                 options: PhotometrySection, window: tuple[int, int, int, int] | None = None
                 ) -> dict[str, np.ndarray]:
    obs = recipe.obs
    x_off, y_off = (0, 0) if window is None else (int(window[0]), int(window[1]))
    star = brightest_of_median(frames, obs.frame[rows] != 0)
    star_x, star_y = star if star is not None else (frames.shape[2] // 2, frames.shape[1] // 2)
    stack = AorStack(aorkey=int(obs.aorkey[rows[0]]), frames_e=frames.astype(np.float32),
                     bad_mask=None, time_bmjd=obs.time_bmjd[rows], expid=obs.expid[rows],
                     dce=np.zeros(rows.size, np.int64), frame=obs.frame[rows],
                     first=obs.frame[rows] == 0, x_off=x_off, y_off=y_off, star_x=int(star_x),
                     star_y=int(star_y), fowler=obs.mode.fowler, wait=obs.mode.wait,
                     read_noise_e=obs.read_noise_e, files=[])
    return measure_aor(stack, options, stamp_x=int(star_x), stamp_y=int(star_y))


def twin_star(recipe: TwinRecipe, options: PhotometrySection) -> StarImager:
    """The star every twin of ``recipe`` is rendered with (its PRF tables and gain), built
    once and shared by the twins of a batch."""
    return _star(recipe.obs, recipe.x_ref_px, recipe.y_ref_px, options.radius_px, recipe.gain)


def twin_table(recipe: TwinRecipe, options: PhotometrySection, *, seed: int, twin: int,
               noise_model: str = "physical", star: StarImager | None = None,
               whole_frame: bool = False) -> Table:
    """Simulate and measure twin number ``twin``: its photometry table.

    The real frames' flags are kept (a frame flagged bad in the observation
    is flagged in every twin, beside what the twin's own photometry flags).
    The table's metadata are the real table's, with ``TWIN`` (its number),
    ``SIMULATE`` true and ``EPOCH`` the twin's number.

    Only the part of the subarray that the photometry reads is rendered
    (:func:`photometry_window`, per AOR); ``whole_frame`` renders all of it
    (the same photometry without noise, the same statistics with it; slower).
    ``star``: the twins' :class:`StarImager` (:func:`twin_star`), when several
    twins share it.
    """
    obs = recipe.obs
    star = star if star is not None else twin_star(recipe, options)
    model = _frame_model(obs, noise_model)
    motion = ExposureMotion(obs, model, recipe.motion_peak_px,
                            rng(seed, "trust", "twin", twin, "motion"))
    x_track, y_track = obs.track_px()
    parts = []
    for rows in obs.aors():
        window = None if whole_frame else photometry_window(x_track[rows], y_track[rows],
                                                            options, model.shape)
        # no jitter (A_fbm 0): no offsets to draw, and no moments to take of zeros
        frames = np.concatenate([
            render_frames_of(recipe, cube, seed=seed, key=("trust", "twin", twin, int(cube[0])),
                             motion=motion.offsets(cube) if motion.peak_px > 0 else None,
                             noise_model=noise_model, star=star, window=window)
            for cube in np.split(rows, np.flatnonzero(np.diff(obs.expid[rows]) != 0) + 1)])
        parts.append(_measure_aor(recipe, rows, frames, options, window))
    columns = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    columns["flag"] = columns["flag"] | obs.flag
    meta = {k: v for k, v in obs.meta.items() if k not in ("FLAGCNT", "FILENAME")}
    meta.update({"TWIN": int(twin), "EPOCH": int(twin), "SIMULATE": True,
                 "TWINMOT": float(recipe.motion_peak_px)})
    return make_table(columns, meta)


def calibrate_motion(recipe: TwinRecipe, options: PhotometrySection, *, n_frames: int = 256,
                     grid_px: tuple[float, ...] = MOTION_GRID_PX) -> tuple[float, dict]:
    """The jitter amplitude whose noise-free twins match the real median noise pixels.

    Renders ``n_frames`` frames spread over the good frames, noise-free, with
    one draw of :class:`ExposureMotion` scaled to each peak amplitude of
    ``grid_px``, measures their median noise pixels and interpolates to the
    real median. Outside the grid's range the nearest end is taken and the
    returned diagnostics say so.

    Returns
    -------
    peak_px : float
        ``A_fbm`` for :class:`ExposureMotion`.
    diagnostics : dict
        ``noise_pixels_real``, the grid, the median noise pixels at each, and
        ``rms_per_peak``: the rms of the motion within an exposure per px of peak.
    """
    obs = recipe.obs
    good = np.flatnonzero(obs.good)
    rows = good[np.linspace(0, good.size - 1, min(n_frames, good.size)).astype(int)]
    target = float(np.median(obs.noise_pixels[obs.good]))
    model = _frame_model(obs, "none")
    unit_x, unit_y = ExposureMotion(obs, model, 1.0, rng(0, "trust", "calibrate")).offsets(rows)
    medians = []
    for peak in grid_px:
        frames = render_frames_of(recipe, rows, seed=0, key=("trust", "calibrate"),
                                  motion=(peak * unit_x, peak * unit_y), noise_model="none",
                                  radius_px=options.radius_px)
        medians.append(float(np.median(_measure_rows(frames, obs, options))))
    medians_arr = np.maximum.accumulate(np.asarray(medians))
    if target <= medians_arr[0]:
        peak_px, where = float(grid_px[0]), "below"
    elif target >= medians_arr[-1]:
        peak_px, where = float(grid_px[-1]), "above"
    else:
        peak_px, where = float(np.interp(target, medians_arr, grid_px)), "inside"
    rms_per_peak = float(np.sqrt(0.5 * (np.mean(unit_x**2) + np.mean(unit_y**2))))
    return peak_px, {"noise_pixels_real": target, "motion_grid_px": list(grid_px),
                     "noise_pixels_grid": medians, "target_vs_grid": where,
                     "rms_per_peak": rms_per_peak}


def _measure_rows(frames: np.ndarray, obs: Observation, options: PhotometrySection) -> np.ndarray:
    sx, sy = brightest_of_median(frames, np.ones(len(frames), bool)) or (15, 15)
    m = measure_stack(frames, guess_x=int(sx), guess_y=int(sy), options=options,
                      fowler=obs.mode.fowler, wait=obs.mode.wait, read_noise_e=obs.read_noise_e)
    return m["noise_pixels"]

