"""Digital twins of a real observation: its frames simulated again with a known eclipse.

A twin shares with the real observation everything but the noise draw
(``docs/trust.md``):

- the time stamps, channel, readout, cubes and the frames flagged bad;
- the pointing: the measured centroid of each real frame is the twin's
  exposure-mean position, and the simulator's motion within an exposure
  (its fractional Brownian jitter, paper Appendix A.1, drawn as the
  challenge simulator draws it: :class:`ExposureMotion`) is added;
- the PSF's width: the builtin PRF's blur (:func:`builtin_prf`) and the
  jitter's amplitude are fitted together so that the twins' noise pixels
  have the real median and the real spread over cubes (:func:`calibrate_motion`);
- the star's aperture flux and the background level in electrons, so the
  photon and read noise are the real ones, and the share of the real
  background's frame-to-frame deviations that the twins' own noise leaves
  out (:func:`background_scatter_share`);
- the detector: the simulator's intra-pixel gain model of the channel
  refitted for the PSF (:func:`builtin_gain`), or, where the user gives an
  SSC warm pixel map, a gain fitted to that map (:func:`map_gain`), rendered
  through the Fowler sampling of paper Appendix A.2-A.3
  (:func:`eclipsebench.simulation.render.render_frames`), each pixel's photon
  and read noise one Gaussian draw of that model's mean and variance
  (:data:`GAUSSIAN_SKEW`);
- the astrophysics: L(t) given per frame (the real fit's phase model with a
  known depth at the real mid-time);
- the real correlated noise that the twins lack, added to each twin's
  photometry cyclically shifted (:mod:`eclipsebench.trust.noise`).

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
    fbm_scale,
    frame_windows,
)
from ..instrument.prf import (
    BuiltinPRF,
    GainPolynomial,
    load_gainmap_coefficients,
    warm_rescaling,
)
from ..photometry.clean import running_median
from ..photometry.measure import measure_noise_pixels, measure_stack, read_radius_px
from ..photometry.pipeline import AorStack, brightest_of_median, measure_aor
from ..photometry.table import make_table
from ..seeding import rng
from ..simulation.plan import SECONDS_PER_DAY
from ..simulation.render import (
    FrameModel,
    centred_tick_moments,
    render_cube,
    tick_means,
    tick_moments,
)
from ..simulation.star import StarImager
from .noise import add_correlated
from .observation import Observation

__all__ = ["TwinRecipe", "ExposureMotion", "make_recipe", "render_frames_of", "twin_table",
           "calibrate_motion", "gentler_motions", "motion_rms_per_peak", "blur_spanning",
           "photometry_window", "twin_star", "MOTION_GRID_PX", "BLUR_GRID_PX", "TWIN_MODEL",
           "GAUSSIAN_SKEW",
           "gain_model", "map_gain", "builtin_prf", "builtin_gain", "background_scatter_share"]

#: How twins are made (recorded with a trust run's settings, so a folder of twins made
#: otherwise is refused rather than mixed): 6 since each pixel's photon and read noise are
#: one Gaussian draw of the same mean and variance where the skewness lost is small
#: (:data:`GAUSSIAN_SKEW`; issue 40; the recipe's calibration keeps the exact draws, so its
#: recipes are 5's); 5 since a table without noise pixels gets the
#: most motion within an exposure whose pilot twin is no redder than the real residuals
#: (:func:`~eclipsebench.trust.recipe.bounded_recipe`; a table with them is made as in 4);
#: 4 since the motion within an exposure is bounded by the real photometry (a pilot twin no
#: redder than the real residuals, the same function); 3 since the PSF's blur is fitted with
#: the motion, the real background scatter and correlated noise are added (issue 36), and
#: only the part of the subarray the photometry reads is rendered (:func:`photometry_window`);
#: 2 since the motion within an exposure is the simulator's block-scaled jitter
#: (:class:`ExposureMotion`), 1 before (one rms throughout).
TWIN_MODEL = 6

#: The twins' photon noise: a pixel's photon and read noise are drawn as one Gaussian of the
#: physical model's mean and variance wherever the skewness that drops is at most this
#: (``FrameModel.gaussian_skew``, :mod:`eclipsebench.simulation.render`'s notes); with warm
#: channel 2's read noise it is at most 0.082 at any charge, so every pixel is drawn once.
GAUSSIAN_SKEW = 0.1

#: Peak amplitudes (px) of the jitter (Table 5's ``A_fbm``; the challenge's is 0.4) on which
#: the noise pixels are calibrated; for ``sub_2s`` frames they give 0 to about 0.28 px rms
#: within an exposure.
MOTION_GRID_PX = (0.0, 0.1, 0.2, 0.3, 0.45, 0.6, 0.9, 1.25)

#: Gaussian blurs (px) of the builtin PRF's optics among which the twins' PSF is chosen
#: (:func:`calibrate_motion`); the committed one of channel 2 is 0.294 px.
BLUR_GRID_PX = (0.0, 0.08, 0.15, 0.22, 0.3, 0.38, 0.46)


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
             occupancy: np.ndarray, *, source: str, radius_px: float = 3.0,
             blur_px: float | None = None) -> tuple[GainPolynomial, str, dict]:
    """The twins' gain from a gridded SSC warm map: what ``BuiltinPRF`` of ``channel``
    (its optics blurred by ``blur_px``, :func:`builtin_prf`) needs so that aperture
    photometry (radius ``radius_px``, the map's 3 px) at the measured centroid follows
    the map (:func:`~eclipsebench.instrument.gain_fit.fit_true_phase_gain`).

    Returns the gain, its description for the report and the fit's diagnostics.
    """
    poly, info = fit_true_phase_gain(builtin_prf(channel, blur_px, gain=False), x_grid, y_grid,
                                     gain, occupancy, radius_px=radius_px)
    text = (f"the SSC pixel map {source} (a degree-6 gain in the true sub-pixel phase fitted "
            f"so that {radius_px:g} px aperture photometry of BuiltinPRF follows the map: "
            f"rms {100 * info['fit_rms']:.3f} % over {info['n_positions']} positions)")
    return poly, text, info


def builtin_gain(channel: int, blur_px: float) -> tuple[GainPolynomial, str]:
    """The simulator's gain model of ``channel`` refitted for the builtin PRF blurred by
    ``blur_px``: the gain that makes aperture photometry of that PSF at its centroid follow
    the committed polynomial of the channel's SSC map (:func:`~eclipsebench.instrument.prf.
    warm_rescaling`, paper Appendix A.2), as the committed gain does for the committed blur.

    Returns the gain and its description for the report.
    """
    source = load_gainmap_coefficients(channel).get("source", "an SSC pixel map")
    gain = warm_rescaling(builtin_prf(channel, blur_px, gain=False), channel=channel)
    return gain, (f"the simulator's gain model of channel {channel} refitted for the twins' PSF "
                  f"(blur {blur_px:.3f} px): aperture photometry follows the polynomial fitted "
                  f"to {source} (data/gainmap_ch{channel}.json)")


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
        Sky per pixel and exposure under the star, per frame: the real annulus
        background's running median over a cube plus ``sky_scatter`` times its
        deviation from it, minus the PRF's own wings.
    motion_peak_px : float
        Peak of the jitter's fractional Brownian motion in each block of the
        simulator (Table 5's ``A_fbm``), which sets the motion within an
        exposure (:class:`ExposureMotion`).
    gain : GainPolynomial or None
        The intra-pixel gain in the true phase (:func:`map_gain`,
        :func:`builtin_gain`); None: the simulator's model of the channel.
    blur_px : float or None
        The Gaussian blur (px) of the builtin PRF's optics (:func:`builtin_prf`),
        fitted to the real noise pixels by :func:`calibrate_motion`; None: the
        committed one.
    sky_scatter : float
        The share (0-1) of the real background's frame-to-frame deviations
        from its running median that ``sky_e_per_px`` carries
        (:func:`background_scatter_share`).
    correlated : ndarray or None
        The real observation's correlated noise (relative flux per frame,
        :func:`eclipsebench.trust.noise.correlated_component`), added to each
        twin's photometry cyclically shifted; None: none.
    """

    obs: Observation
    light_curve: np.ndarray
    flux_aperture_e: float
    x_ref_px: float
    y_ref_px: float
    sky_e_per_px: np.ndarray
    motion_peak_px: float = 0.0
    gain: GainPolynomial | None = None
    blur_px: float | None = None
    sky_scatter: float = 0.0
    correlated: np.ndarray | None = None


def builtin_prf(channel: int, blur_px: float | None = None, *, gain: bool = True) -> BuiltinPRF:
    """``BuiltinPRF`` of ``channel`` with its optics blurred by ``blur_px`` (px; None: the
    committed blur of ``data/gainmap_ch<N>.json``), with or without the committed gain.

    Examples
    --------
    >>> builtin_prf(2, 0.1, gain=False).coefficients["blur_px"]
    0.1
    """
    coefficients = None
    if blur_px is not None:
        coefficients = {**load_gainmap_coefficients(channel)["builtin"], "blur_px": float(blur_px)}
    return BuiltinPRF(gain=gain, channel=channel, coefficients=coefficients)


def _star(obs: Observation, x_ref_px: float, y_ref_px: float, radius_px: float,
          gain: GainPolynomial | None = None, blur_px: float | None = None,
          kind: type[StarImager] = StarImager) -> StarImager:
    prf = builtin_prf(obs.channel, blur_px, gain=gain is None)
    if gain is not None:
        prf.gain = gain
    return kind(prf, x_ref_px=x_ref_px, y_ref_px=y_ref_px, radius_px=radius_px)


#: The most bytes of Taylor bases a :class:`_KeptBasisStar` keeps (real epoch 1's 244 cubes
#: of 64 frames take 127 MB: 8 KB a frame); the cubes beyond it are rendered as before.
KEPT_BASIS_BYTES = 256 * 2**20


class _KeptBasisStar(StarImager):
    """A :class:`~eclipsebench.simulation.star.StarImager` that keeps the Taylor bases and the
    wings it made (read-only, so no caller changes what it shares), keyed by the positions'
    bytes, up to :data:`KEPT_BASIS_BYTES`: the calibration renders the same frames at every
    peak of the motion, and every twin of a recipe the same cubes, whose positions (the track
    plus the motion's Fowler-weighted mean offset, zero to rounding) are the same floats; the
    basis is most of the rendering (issue 40). A position that differs in its last bit is
    another key: its basis is made anew."""

    _kept: dict[tuple, np.ndarray] | None = None
    _kept_wings: dict[tuple, np.ndarray] | None = None
    _kept_bytes: int = 0

    def taylor_basis(self, x_px: np.ndarray, y_px: np.ndarray, sx0: int, sy0: int, size: int
                     ) -> np.ndarray:
        key = (np.asarray(x_px, float).tobytes(), np.asarray(y_px, float).tobytes(), int(sx0),
               int(sy0), int(size))
        if self._kept is None:
            self._kept = {}
        basis = self._kept.get(key)
        if basis is None:
            basis = super().taylor_basis(x_px, y_px, sx0, sy0, size)
            basis.setflags(write=False)
            if self._kept_bytes + basis.nbytes <= KEPT_BASIS_BYTES:
                self._kept[key] = basis
                self._kept_bytes += basis.nbytes
        return basis

    def image(self, x_px: float, y_px: float, shape: tuple[int, int]) -> np.ndarray:
        key = (float(x_px), float(y_px), int(shape[0]), int(shape[1]))
        if self._kept_wings is None:
            self._kept_wings = {}
        wings = self._kept_wings.get(key)
        if wings is None:
            wings = super().image(x_px, y_px, shape)
            wings.setflags(write=False)
            if len(self._kept_wings) < 4096:
                self._kept_wings[key] = wings
        return wings


def _frame_model(obs: Observation, noise_model: str = "physical",
                 gaussian_skew: float = GAUSSIAN_SKEW) -> FrameModel:
    skew = gaussian_skew if noise_model == "physical" else 0.0
    return FrameModel(mode=obs.mode, noise_model=noise_model, read_noise_e=obs.read_noise_e,
                      gaussian_skew=skew)


def make_recipe(obs: Observation, light_curve: np.ndarray, *, radius_px: float,
                motion_peak_px: float = 0.0, gain: GainPolynomial | None = None,
                blur_px: float | None = None, sky_scatter: float = 0.0,
                correlated: np.ndarray | None = None) -> TwinRecipe:
    """The shared part of the twins of ``obs`` with astrophysics ``light_curve``.

    The star's flux is the real median aperture flux divided by the median of
    ``light_curve`` over the good frames, so the twins' flux level is the
    real one whatever the eclipse. The sky is the real background's running
    median over a cube plus ``sky_scatter`` of each frame's deviation from it
    (frames without a finite background: the running median), less the PRF's
    wings in the annulus.
    """
    good = obs.good
    x_ref, y_ref = float(np.median(obs.x_px[good])), float(np.median(obs.y_px[good]))
    flux = float(np.median(obs.flux_e[good]) / np.median(light_curve[good]))
    star = _star(obs, x_ref, y_ref, radius_px, gain, blur_px)
    level = running_median(obs.background_e_per_px, _BACKGROUND_WINDOW, good)
    deviation = np.where(np.isfinite(obs.background_e_per_px),
                         obs.background_e_per_px - level, 0.0)
    wing = star.annulus_per_unit * star.electrons_per_unit(flux)
    sky = level + float(sky_scatter) * deviation - wing
    return TwinRecipe(obs=obs, light_curve=np.asarray(light_curve, float), flux_aperture_e=flux,
                      x_ref_px=x_ref, y_ref_px=y_ref, sky_e_per_px=np.clip(sky, 0, None),
                      motion_peak_px=float(motion_peak_px), gain=gain, blur_px=blur_px,
                      sky_scatter=float(sky_scatter), correlated=correlated)


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
        mx, my = tick_means(dx, dy, self.model)
        return dx - mx[:, None], dy - my[:, None]

    def moments(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The tick moments of :meth:`offsets` of frames ``rows`` (what
        :func:`~eclipsebench.simulation.render.render_cube` takes), computed from the
        jitter's samples in one pass (:func:`~eclipsebench.simulation.render.
        centred_tick_moments`) rather than cut out, centred and summed frame by frame."""
        n_grid = self.model.grid_samples_per_frame
        n_max = self.model.mode.n_max
        if not self.peak_px > 0:
            still = np.zeros((rows.size, n_max, 6))
            still[:, :, 0] = 1.0
            return np.zeros(rows.size), np.zeros(rows.size), still
        starts = self.start_index[rows]
        block = starts // (FBM_SEGMENT * FBM_BLOCK_SEGMENTS)
        x_mean, y_mean = np.empty(rows.size), np.empty(rows.size)
        tick = np.empty((rows.size, n_max, 6))
        for b in np.unique(block):
            sel = np.flatnonzero(block == b)
            first = int(starts[sel].min())
            gx, gy = self._pointing.fbm_samples(first, int(starts[sel].max()) - first + n_grid)
            x_mean[sel], y_mean[sel], tick[sel] = centred_tick_moments(
                gx, gy, starts[sel] - first, self.model)
        return x_mean, y_mean, tick


class _AnyPeakMotion:
    """One draw of :class:`ExposureMotion` at frames ``rows``, for any peak: ``offsets(peak)``
    is ``ExposureMotion(obs, model, peak, stream).offsets(rows)`` byte for byte, the jitter's
    blocks drawn once (each block is one unscaled draw times ``A_fbm`` over its peak,
    :meth:`~eclipsebench.instrument.pointing.PointingModel.fbm_block_unscaled`; the unscaled
    values are single precision, so they are kept as such). The calibration's draw is asked at
    the unit peak and at each candidate recipe's (issue 40)."""

    def __init__(self, obs: Observation, model: FrameModel, stream: np.random.Generator,
                 rows: np.ndarray):
        motion = ExposureMotion(obs, model, 1.0, stream)
        self.model = model
        n_grid = model.grid_samples_per_frame
        block_len = FBM_SEGMENT * FBM_BLOCK_SEGMENTS
        starts = motion.start_index[rows]
        # each frame's samples: its first block's from `at`, the next block's after `split`
        self._first = starts // block_len
        at = starts % block_len
        self._split = np.minimum(block_len - at, n_grid)
        self._raw = np.empty((2, rows.size, n_grid), np.float32)
        self._peaks: dict[int, np.ndarray] = {}
        crossing = np.flatnonzero(self._split < n_grid)
        for b in np.unique(np.concatenate([self._first, self._first[crossing] + 1])):
            z, self._peaks[int(b)] = motion._pointing.fbm_block_unscaled(int(b))
            for i in np.flatnonzero(self._first == b):
                k = self._split[i]
                self._raw[:, i, :k] = z[:, at[i]:at[i] + k]
            for i in crossing[self._first[crossing] == b - 1]:
                k = self._split[i]
                self._raw[:, i, k:] = z[:, :n_grid - k]

    def offsets(self, peak_px: float) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`ExposureMotion.offsets` of the rows with peak ``peak_px``."""
        peak = float(peak_px)
        n_rows, n_grid = self._raw.shape[1:]
        dx, dy = np.zeros((n_rows, n_grid)), np.zeros((n_rows, n_grid))
        if peak > 0:
            scale = {b: fbm_scale(peak, p)[:, 0] for b, p in self._peaks.items()}
            first = np.array([scale[int(b)] for b in self._first])
            second = np.array([scale.get(int(b) + 1, scale[int(b)]) for b in self._first])
            in_first = np.arange(n_grid)[None, :] < self._split[:, None]
            for axis, out in enumerate((dx, dy)):
                factor = np.where(in_first, first[:, axis, None], second[:, axis, None])
                np.multiply(self._raw[axis].astype(float), factor, out=out)
        mx, my = tick_means(dx, dy, self.model)
        return dx - mx[:, None], dy - my[:, None]


#: The calibration's draw of the motion last made in this process (:func:`_calibration_motion`).
_CALIBRATION_MOTION: list[tuple[Observation, tuple, _AnyPeakMotion]] = []


def _calibration_motion(obs: Observation, rows: np.ndarray, model: FrameModel
                        ) -> _AnyPeakMotion:
    """The calibration's one draw of :class:`ExposureMotion` (stream ``("trust",
    "calibrate")``) at ``rows`` of ``obs``, made once for the noise pixels' unit motion, the
    blurs spanned and each candidate's background share (issue 40)."""
    key = (rows.tobytes(), model.mode, model.subsamples, model.subsamples_per_tick)
    if _CALIBRATION_MOTION and _CALIBRATION_MOTION[0][0] is obs \
            and _CALIBRATION_MOTION[0][1] == key:
        return _CALIBRATION_MOTION[0][2]
    motion = _AnyPeakMotion(obs, model, rng(0, "trust", "calibrate"), rows)
    _CALIBRATION_MOTION[:] = [(obs, key, motion)]
    return motion


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
                     window: tuple[int, int, int, int] | None = None,
                     moments: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
                     gaussian_skew: float = GAUSSIAN_SKEW,
                     track: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """The twin's frames (electrons) of the real frames ``rows`` of one cube.

    ``motion``: the offsets within each exposure about the measured centroid
    (:meth:`ExposureMotion.offsets` of ``rows``); None: none. ``key`` names
    the noise's random streams (``seed``, ``*key``, ``"photon"``/``"read"``),
    one set per cube, so a cube's frames do not depend on the others.
    ``moments``: the motion's tick moments instead (:meth:`ExposureMotion.moments`).
    ``window``: ``(x0, y0, nx, ny)``, render only that part of the subarray
    (:func:`photometry_window`; the PRF depends on the sub-pixel phase only,
    so the pixels are the whole frame's); None: the whole subarray.
    ``gaussian_skew``: where the photon noise is drawn as a Gaussian (:data:`GAUSSIAN_SKEW`;
    0: exact Poisson draws everywhere, the challenge simulator's). ``track``: the
    observation's :meth:`~eclipsebench.trust.observation.Observation.track_px`, when the
    caller renders it cube by cube (None: taken here).
    """
    obs = recipe.obs
    model = _frame_model(obs, noise_model, gaussian_skew)
    x0, y0 = 0, 0
    if window is not None:
        x0, y0 = int(window[0]), int(window[1])
        model = dataclasses.replace(model, shape=(int(window[3]), int(window[2])))
    star = star if star is not None else _star(obs, recipe.x_ref_px, recipe.y_ref_px, radius_px,
                                               recipe.gain, recipe.blur_px)
    x_track, y_track = track if track is not None else obs.track_px()
    dx: np.ndarray | None
    dy: np.ndarray | None
    if moments is not None:
        dx = dy = None
    elif motion is None:
        dx = dy = np.zeros((rows.size, model.grid_samples_per_frame))
    else:
        dx, dy = motion
    ticks = model.ticks_per_exposure
    per_tick = star.electrons_per_unit(recipe.flux_aperture_e) / ticks
    frames, _, _, _ = render_cube(
        model=model, star=star, x_px=x_track[rows] - x0, y_px=y_track[rows] - y0, dx=dx, dy=dy,
        star_e_per_tick=per_tick * recipe.light_curve[rows],
        background_e_per_tick=recipe.sky_e_per_px[rows] / ticks,
        rng_photon=rng(seed, *key, "photon"), rng_read=rng(seed, *key, "read"),
        moments=moments)
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
    once and shared by the twins of a batch, which keeps each cube's Taylor basis and wings
    for the next twin (:class:`_KeptBasisStar`)."""
    return _star(recipe.obs, recipe.x_ref_px, recipe.y_ref_px, options.radius_px, recipe.gain,
                 recipe.blur_px, kind=_KeptBasisStar)


def twin_table(recipe: TwinRecipe, options: PhotometrySection, *, seed: int, twin: int,
               noise_model: str = "physical", star: StarImager | None = None,
               whole_frame: bool = False, gaussian_skew: float = GAUSSIAN_SKEW) -> Table:
    """Simulate and measure twin number ``twin``: its photometry table.

    The real frames' flags are kept (a frame flagged bad in the observation
    is flagged in every twin, beside what the twin's own photometry flags).
    The table's metadata are the real table's, with ``TWIN`` (its number),
    ``SIMULATE`` true and ``EPOCH`` the twin's number.

    Only the part of the subarray that the photometry reads is rendered
    (:func:`photometry_window`, per AOR); ``whole_frame`` renders all of it
    (the same photometry without noise, the same statistics with it; slower).
    ``star``: the twins' :class:`StarImager` (:func:`twin_star`), when several
    twins share it. ``gaussian_skew``: as :func:`render_frames_of` (0: the exact
    Poisson draws of twins before ``TWIN_MODEL`` 6, the same statistics; slower).
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
                             moments=motion.moments(cube) if motion.peak_px > 0 else None,
                             noise_model=noise_model, star=star, window=window,
                             gaussian_skew=gaussian_skew, track=(x_track, y_track))
            for cube in np.split(rows, np.flatnonzero(np.diff(obs.expid[rows]) != 0) + 1)])
        parts.append(_measure_aor(recipe, rows, frames, options, window))
    columns = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    columns["flag"] = columns["flag"] | obs.flag
    meta = {k: v for k, v in obs.meta.items() if k not in ("FLAGCNT", "FILENAME")}
    meta.update({"TWIN": int(twin), "EPOCH": int(twin), "SIMULATE": True,
                 "TWINMOT": float(recipe.motion_peak_px)})
    return add_correlated(make_table(columns, meta), recipe.correlated, seed=seed, twin=twin)


def _calibration_rows(obs: Observation, frames_per_cube: int, max_frames: int
                      ) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """Up to ``frames_per_cube`` good frames spread over each cube of at least 2 good frames
    (:meth:`~eclipsebench.trust.observation.Observation.calibration_cubes`; fewer per cube
    when the observation has more than ``max_frames / frames_per_cube`` cubes, at least 2):
    the rows, the index of each row's cube among the cubes kept, and every good row of each
    kept cube."""
    cubes = obs.calibration_cubes()
    k = int(np.clip(max_frames // max(len(cubes), 1), 2, frames_per_cube))
    picked = [c[np.unique(np.linspace(0, c.size - 1, min(k, c.size)).astype(int))]
              for c in cubes]
    rows = np.concatenate(picked)
    cube_of = np.concatenate([np.full(p.size, i) for i, p in enumerate(picked)])
    return rows, cube_of, cubes


def _cube_median_sd(values: np.ndarray, cube_of: np.ndarray) -> float:
    """Sample SD over cubes of each cube's median of ``values``.

    The cubes of one size are stacked and their medians taken along the rows (the same
    partition and mean as one cube's median, so the same floats; issue 40: the calibration
    asks for 72 such spreads of 244 cubes)."""
    cubes, counts = np.unique(cube_of, return_counts=True)
    grouped = np.asarray(values)[np.argsort(cube_of, kind="stable")]
    starts = np.cumsum(counts) - counts
    medians = np.empty(cubes.size)
    for n in np.unique(counts):
        same = np.flatnonzero(counts == n)
        medians[same] = np.median(grouped[starts[same][:, None] + np.arange(n)], axis=1)
    return float(np.std(medians, ddof=1)) if cubes.size > 1 else float("nan")


def _solve_on_curve(target: float, values: np.ndarray, grid: tuple[float, ...]
                    ) -> float | None:
    """The grid point (interpolated) where the non-decreasing envelope of ``values`` reaches
    ``target``; None outside its range."""
    env = np.maximum.accumulate(np.asarray(values, float))
    if not env[0] <= target <= env[-1]:
        return None
    return float(np.interp(target, env, grid))


def _noise_pixel_curves(recipe: TwinRecipe, options: PhotometrySection, frames_per_cube: int,
                        max_frames: int, grid_px: tuple[float, ...]):
    """What :func:`calibrate_motion` and :func:`gentler_motions` compare: the real median noise
    pixels and their SD over cubes, the function giving for a blur the twins' median and SD at
    each peak of ``grid_px`` (noise-free frames spread over the cubes, one draw of
    :class:`ExposureMotion`), the motion's rms per px of peak, the rows and the cubes."""
    obs = recipe.obs
    rows, cube_of, cubes = _calibration_rows(obs, frames_per_cube, max_frames)
    target = float(np.median(obs.noise_pixels[obs.good]))
    real_cube = np.concatenate([np.full(c.size, i) for i, c in enumerate(cubes)])
    target_sd = _cube_median_sd(obs.noise_pixels[np.concatenate(cubes)], real_cube)
    unit_x, unit_y, rms_per_peak = _unit_motion(obs, rows)
    model = _frame_model(obs, "none")
    # only the part of the subarray the photometry reads (the whole frame's noise pixels on
    # noise-free frames, to an ulp: the wings are rendered at the frames' mean position in
    # offset coordinates), the motion's tick moments once per peak (they do not depend on the
    # blur) and the star's Taylor basis once per blur (issue 40)
    x_track, y_track = obs.track_px()
    window = photometry_window(x_track[rows], y_track[rows], options, model.shape)
    moments_at: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def moments(peak: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if peak not in moments_at:
            moments_at[peak] = tick_moments(peak * unit_x, peak * unit_y, model)
        return moments_at[peak]

    def curves(blur: float | None) -> tuple[np.ndarray, np.ndarray]:
        star = _star(obs, recipe.x_ref_px, recipe.y_ref_px, options.radius_px, None, blur,
                     kind=_KeptBasisStar)
        medians, spreads = [], []
        for peak in grid_px:
            frames = render_frames_of(recipe, rows, seed=0, key=("trust", "calibrate"),
                                      moments=moments(peak), noise_model="none", star=star,
                                      window=window)
            npx = _measure_rows(frames, options)
            medians.append(float(np.median(npx)))
            spreads.append(_cube_median_sd(npx, cube_of))
        return np.asarray(medians), np.asarray(spreads)

    return target, target_sd, curves, rms_per_peak, rows, cubes


def _unit_motion(obs: Observation, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """One draw of :class:`ExposureMotion` of 1 px peak at ``rows`` (the calibration's): its
    offsets in x and y and its rms (px) per px of peak."""
    unit_x, unit_y = _calibration_motion(obs, rows, _frame_model(obs, "none")).offsets(1.0)
    return unit_x, unit_y, float(np.sqrt(0.5 * (np.mean(unit_x**2) + np.mean(unit_y**2))))


def motion_rms_per_peak(obs: Observation, *, frames_per_cube: int = 8,
                        max_frames: int = 2048) -> float:
    """The rms (px) of :class:`ExposureMotion` within an exposure per px of its peak, over
    the frames :func:`calibrate_motion` renders (for a table without noise pixels, whose
    motion is set by :func:`~eclipsebench.trust.recipe.bounded_recipe` alone)."""
    rows, _, _ = _calibration_rows(obs, frames_per_cube, max_frames)
    return _unit_motion(obs, rows)[2]


def calibrate_motion(recipe: TwinRecipe, options: PhotometrySection, *,
                     frames_per_cube: int = 8, max_frames: int = 2048,
                     blur_grid_px: tuple[float, ...] = BLUR_GRID_PX,
                     grid_px: tuple[float, ...] = MOTION_GRID_PX
                     ) -> tuple[float | None, float, dict]:
    """The PSF's blur and the jitter's amplitude whose twins match the real noise pixels.

    Frames spread over every cube (``frames_per_cube``, at most ``max_frames``
    in all) are rendered noise-free along the real track with one draw of
    :class:`ExposureMotion` scaled to each peak of ``grid_px``. With the
    committed PSF, where its noise pixels without motion are no larger than
    the real median, the peak that gives the real median is interpolated and
    the PSF kept (the simulator's own: a simulated epoch's twins are made as
    it was). Where the committed PSF is too broad even without motion (real
    epoch 1: 4.25 against 3.98), the blur is fitted as well, on a second
    number: the standard deviation over cubes of each cube's median noise
    pixels (how the image's size follows the pointing from cube to cube: a
    sharper PSF changes more with the sub-pixel position, and the jitter's
    block-to-block scaling adds its own; paper Appendix A.1-A.2). For each
    blur of ``blur_grid_px`` the peak that gives the real median is
    interpolated, then the blur where the spread at that peak equals the
    real one (the crossing nearest the committed blur, else the closest),
    and the peak again at that blur. Noise adds about 0.005 to a cube's
    median over 63 frames (real epoch 1), negligible beside the spread of
    0.06 it is compared with.

    Returns
    -------
    blur_px : float or None
        The builtin PRF's blur (:func:`builtin_prf`); None: the committed one.
    peak_px : float
        ``A_fbm`` for :class:`ExposureMotion`.
    diagnostics : dict
        The real targets (``noise_pixels_real``, ``noise_pixels_cube_sd_real``),
        the grids and what each gave, the twins' values at the solution
        (``noise_pixels_twins``, ``noise_pixels_cube_sd_twins``, interpolated on
        the motion grid at the chosen blur), ``blur_px`` and ``blur_fitted``,
        ``target_vs_grid`` (``"inside"``: matched; ``"spread_outside"``: the
        median matched, the spread only as near as the grid allows;
        ``"below"``/``"above"``: even the sharpest PSF without motion is broader
        than the real image / the broadest with the most motion narrower),
        ``blur_px_builtin`` and ``rms_per_peak``: the rms of the motion within
        an exposure per px of peak.
    """
    obs = recipe.obs
    target, target_sd, curves, rms_per_peak, rows, cubes = _noise_pixel_curves(
        recipe, options, frames_per_cube, max_frames, grid_px)
    builtin_blur = float(load_gainmap_coefficients(obs.channel)["builtin"]["blur_px"])
    # the committed PSF where it is not too broad: the motion alone on the median
    med, sd = curves(builtin_blur)
    peak_builtin = _solve_on_curve(target, med, grid_px)
    if peak_builtin is not None:
        return None, peak_builtin, {
            "noise_pixels_real": target, "noise_pixels_cube_sd_real": target_sd,
            "noise_pixels_twins": float(np.interp(peak_builtin, grid_px, med)),
            "noise_pixels_cube_sd_twins": float(np.interp(peak_builtin, grid_px, sd)),
            "blur_px": builtin_blur, "blur_px_builtin": builtin_blur, "blur_fitted": False,
            "motion_peak_px": peak_builtin, "target_vs_grid": "inside",
            "rms_per_peak": rms_per_peak, "frames_calibrated": int(rows.size),
            "cubes_calibrated": len(cubes), "motion_grid_px": list(grid_px),
            "noise_pixels_grid": [med.tolist()], "noise_pixels_cube_sd_grid": [sd.tolist()],
            "blur_grid_px": [builtin_blur]}
    grid_medians, grid_spreads, on_curve = [], [], []
    for blur in blur_grid_px:
        med, sd = curves(blur)
        grid_medians.append(med.tolist())
        grid_spreads.append(sd.tolist())
        peak = _solve_on_curve(target, med, grid_px)
        if peak is not None:
            on_curve.append((float(blur), peak, float(np.interp(peak, grid_px, sd))))
    if on_curve:
        blurs = np.array([b for b, _, _ in on_curve])
        excess = np.array([sd for _, _, sd in on_curve]) - target_sd
        crossings = [(b0 + (b1 - b0) * e0 / (e0 - e1))
                     for b0, b1, e0, e1 in zip(blurs[:-1], blurs[1:], excess[:-1], excess[1:],
                                               strict=True)
                     if e0 == 0 or e0 * e1 < 0]
        if crossings:
            blur = float(min(crossings, key=lambda b: abs(b - builtin_blur)))
            where = "inside"
        else:
            blur, where = float(blurs[int(np.argmin(np.abs(excess)))]), "spread_outside"
        med, sd = curves(blur)
        peak_solved = _solve_on_curve(target, med, grid_px)
        peak = float(peak_solved) if peak_solved is not None else \
            float(grid_px[int(np.argmin(np.abs(med - target)))])
    else:
        # no blur reaches the real median: the sharpest PSF without motion, or the broadest
        # with the most, whichever side the target is on
        zero = np.array([m[0] for m in grid_medians])
        if target < zero.min():
            blur, peak, where = float(blur_grid_px[int(np.argmin(zero))]), 0.0, "below"
        else:
            top = np.array([max(m) for m in grid_medians])
            blur, peak, where = float(blur_grid_px[int(np.argmax(top))]), float(grid_px[-1]), \
                "above"
        med, sd = curves(blur)
    return blur, peak, {
        "noise_pixels_real": target, "noise_pixels_cube_sd_real": target_sd,
        "noise_pixels_twins": float(np.interp(peak, grid_px, med)),
        "noise_pixels_cube_sd_twins": float(np.interp(peak, grid_px, sd)),
        "blur_px": blur, "blur_px_builtin": builtin_blur, "blur_fitted": True,
        "motion_peak_px": peak, "target_vs_grid": where, "rms_per_peak": rms_per_peak,
        "frames_calibrated": int(rows.size), "cubes_calibrated": len(cubes),
        "blur_grid_px": list(blur_grid_px), "motion_grid_px": list(grid_px),
        "noise_pixels_grid": grid_medians, "noise_pixels_cube_sd_grid": grid_spreads}


def blur_spanning(recipe: TwinRecipe, options: PhotometrySection, calibration: dict, *,
                  frames_per_cube: int = 8, max_frames: int = 2048,
                  blur_grid_px: tuple[float, ...] = BLUR_GRID_PX) -> dict:
    """``calibration`` with its noise pixels on a grid of several blurs: itself where its
    grid spans them (it fitted the blur), else a copy with the calibration's frames rendered
    at each of ``blur_grid_px`` (where the committed PSF was kept), made once for all the
    calls of :func:`gentler_motions` that follow."""
    if len(calibration["blur_grid_px"]) > 1:
        return calibration
    grid_px = tuple(float(g) for g in calibration["motion_grid_px"])
    *_, curves, _, _, _ = _noise_pixel_curves(recipe, options, frames_per_cube, max_frames,
                                              grid_px)
    both = [curves(float(b)) for b in blur_grid_px]
    return {**calibration, "blur_grid_px": list(blur_grid_px),
            "noise_pixels_grid": [m.tolist() for m, _ in both],
            "noise_pixels_cube_sd_grid": [sd.tolist() for _, sd in both]}


def gentler_motions(recipe: TwinRecipe, options: PhotometrySection, calibration: dict, *,
                    frames_per_cube: int = 8, max_frames: int = 2048,
                    blur_grid_px: tuple[float, ...] = BLUR_GRID_PX,
                    peaks_px: tuple[float, ...] | None = None) -> list[dict]:
    """The PSFs with less motion within an exposure than :func:`calibrate_motion`'s that still
    give the twins the real median noise pixels, the most motion first.

    The median alone does not separate the PSF's width from the motion (a
    sharper PSF with more motion is as large); the spread over cubes chose
    between them, but what else makes the real image's size vary from cube
    to cube (the spread is then an upper bound on the motion's share) the
    twins give to the motion, and its block-to-block scaling then moves the
    flux through the gain's curvature. Where a pilot twin's residuals come
    out redder than the real ones, :func:`~eclipsebench.trust.recipe.bounded_recipe`
    takes these in turn. For each peak of the calibration's motion grid
    below its ``motion_peak_px``, the blur at which that motion gives the
    real median (interpolated over ``blur_grid_px``; peaks no blur of the
    grid reaches are left out). The calibration's own grid is used where it
    spans the blurs; otherwise (the committed PSF was kept) the same frames
    are rendered at each blur. ``peaks_px``: these peaks instead of the grid's
    below the calibrated one (each blur's median and spread linear between
    the grid's peaks).

    Returns
    -------
    list of dict
        ``blur_px``, ``motion_peak_px``, and the twins' ``noise_pixels_twins``
        and ``noise_pixels_cube_sd_twins`` there (interpolated over the blurs).
    """
    grid_px = tuple(float(g) for g in calibration["motion_grid_px"])
    spanning = blur_spanning(recipe, options, calibration, frames_per_cube=frames_per_cube,
                             max_frames=max_frames, blur_grid_px=blur_grid_px)
    blurs = np.asarray(spanning["blur_grid_px"], float)
    medians = np.asarray(spanning["noise_pixels_grid"], float)
    spreads = np.asarray(spanning["noise_pixels_cube_sd_grid"], float)
    target = float(calibration["noise_pixels_real"])
    asked = sorted((g for g in grid_px if g < float(calibration["motion_peak_px"])), reverse=True) \
        if peaks_px is None else list(peaks_px)
    out = []
    for peak in asked:
        # each blur's median and spread at this peak, linear between the grid's peaks
        med = np.array([np.interp(peak, grid_px, row) for row in medians])
        sd = np.array([np.interp(peak, grid_px, row) for row in spreads])
        blur = _solve_on_curve(target, med, tuple(blurs))
        if blur is None:
            continue
        out.append({"blur_px": blur, "motion_peak_px": float(peak),
                    "noise_pixels_twins": float(np.interp(blur, blurs, med)),
                    "noise_pixels_cube_sd_twins": float(np.interp(blur, blurs, sd))})
    return out


def background_scatter_share(recipe: TwinRecipe, options: PhotometrySection, *,
                             frames_per_cube: int = 8, max_frames: int = 2048
                             ) -> tuple[float, dict]:
    """The share of the real background's deviations the twins' sky must carry so that their
    measured background scatters as much as the real one, and no more.

    A twin's measured background already scatters by its photon and read
    noise; the real one scatters more (on real epoch 1 about 3 e/px rms about
    its running median, against 1 e/px of noise). Frames spread over the
    cubes are rendered with noise on the smooth sky of ``recipe`` (its
    ``sky_scatter`` 0); with ``v_twin`` the variance of their measured
    background about the real running median and ``v_real`` the real
    frames', the share is ``sqrt(1 - v_twin / v_real)`` (0 when the twins
    already scatter as much): the real deviations, scaled so that they and
    the twin's own noise add up to the real variance (robust variances:
    1.4826 MAD squared).

    Returns
    -------
    share : float
    diagnostics : dict
        ``background_sd_real``, ``background_sd_twin_noise`` (e/px) and ``share``.
    """
    obs = recipe.obs
    rows, _, _ = _calibration_rows(obs, frames_per_cube, max_frames)
    level = running_median(obs.background_e_per_px, _BACKGROUND_WINDOW, obs.good)
    model = _frame_model(obs, "physical")
    motion = _calibration_motion(obs, rows, model).offsets(recipe.motion_peak_px)
    # the exact Poisson draws, as the pilot twin's (trust/recipe.py::pilot_twin): a calibration
    frames = render_frames_of(recipe, rows, seed=0, key=("trust", "calibrate", "background"),
                              motion=motion, radius_px=options.radius_px,
                              gaussian_skew=0.0)
    sx, sy = brightest_of_median(frames, np.ones(len(frames), bool)) or (15, 15)
    measured = measure_stack(frames, guess_x=int(sx), guess_y=int(sy), options=options,
                             fowler=obs.mode.fowler, wait=obs.mode.wait,
                             read_noise_e=obs.read_noise_e)["background"]

    def robust_var(x: np.ndarray) -> float:
        x = x[np.isfinite(x)]
        return float((1.4826 * np.median(np.abs(x - np.median(x)))) ** 2) if x.size else 0.0

    v_real = robust_var(obs.background_e_per_px[rows] - level[rows])
    v_twin = robust_var(np.asarray(measured, float) - level[rows])
    share = float(np.sqrt(max(0.0, 1.0 - v_twin / v_real))) if v_real > 0 else 0.0
    return share, {"background_sd_real": float(np.sqrt(v_real)),
                   "background_sd_twin_noise": float(np.sqrt(v_twin)), "share": share}


def _measure_rows(frames: np.ndarray, options: PhotometrySection) -> np.ndarray:
    """The noise pixels of ``frames`` as the twins' photometry measures them
    (:func:`~eclipsebench.photometry.measure.measure_noise_pixels`: the same floats as
    :func:`~eclipsebench.photometry.measure.measure_stack`, without the rest)."""
    sx, sy = brightest_of_median(frames, np.ones(len(frames), bool)) or (15, 15)
    return measure_noise_pixels(frames, guess_x=int(sx), guess_y=int(sy), options=options)

