"""Render Fowler-sampled frames (subarray or full array) of a moving point source (paper Appendix A.2-A.3).

Pure kernels on arrays: the orchestration (plans, files) lives in
:mod:`eclipsebench.simulation.aor` (one AOR) and :mod:`eclipsebench.simulation.stage` (the tasks).

How a frame is made
-------------------
The pointing model is sampled every ``delta t = Delta t / n`` (1 ms for the
subarray, ``n = 10`` sub-samples per Fowler tick). Rendering the PRF at every
sub-sample (2,000 PRFs per frame) is avoided with a second-order Taylor
expansion about the frame's mean position ``p_f`` (the Fowler-weighted mean of
the sub-sample positions, written as ``XYMEANnn``)::

    PRF(p_f + d) ~ V + G . d + 1/2 d^T H d

so the mean charge of tick ``k`` in pixel ``i`` is
``q_ki = r_f [V_i m0_k + Gx_i mx_k + Gy_i my_k + 1/2 Hxx_i mxx_k + Hxy_i mxy_k
+ 1/2 Hyy_i myy_k] + b``, where ``m.._k`` are the tick's mean sub-sample moments
of ``d`` (``m0 = 1``), ``r_f`` the star's electrons per tick times ``L(t_f)``,
and ``b`` the background per tick. The ``iracsim2015`` model averages ``n + 1``
sub-samples per tick, as IRACSIM's inclusive loop bound did (the boundary
sub-sample is shared with the next tick); it changes the smear, not the light:
the 2015 frames show the aperture flux the paper measured on them (see
``docs/simulate.md``). The sub-sample spread of the fractional Brownian jitter
(rms ~0.09 px within a frame) is what the second moments carry; higher orders
are below 1e-3 of the pixel values.

Only a stamp (13 x 13 by default) around the star gets this per-tick
treatment. Outside it the star's wings change little within a cube: they are
rendered once per cube at the cube's mean position and, with the background,
give each pixel a constant rate over the frame.

Noise (physical model)
    Stamp pixels: :func:`eclipsebench.detector.fowler.fowler_sample_grouped`
    (FN Poisson draws per pixel, exact). Constant-rate pixels: the same
    distribution with two Poisson draws per pixel (:func:`fowler_uniform`).
    Read noise: one Gaussian per pixel, ``sigma_rn sqrt(2 / FN)``, from its
    own stream. ``iracsim2015``: the per-tick charges of every pixel go
    through :func:`eclipsebench.detector.fowler.fowler_sample_iracsim2015`.
    ``none``: the frames are their noise-free expectation (the physical
    model's Fowler sum, no photon, read or background noise); nothing is
    drawn, so every seed gives the same frames for the same pointing.

Gaussian photon noise (``FrameModel.gaussian_skew``, the trust twins only)
    A pixel's photon and read noise drawn together as one Gaussian of the
    physical model's mean and variance (``sum_j j^2 G_j / FN^2 + 2 sigma_rn^2
    / FN``, the read noise's draw scaled), where the skewness that drops is
    small: the photon part's third cumulant ``sum_j j^3 G_j / FN^3`` is at
    most its variance ``v``, so the pixel's skewness is at most ``v / (v +
    2 sigma_rn^2 / FN)^1.5``; pixels where that bound exceeds
    ``gaussian_skew`` keep the exact draws. With warm channel 2's read noise
    (9.4 e, FN = 8) the bound never exceeds 0.082 whatever the charge (its
    largest at ``v = 44`` e), so every pixel is drawn once; the mean and the
    variance of every pixel, and so of any sum of pixels, are the physical
    model's exactly (docs/trust.md, "How twins are made").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit

from ..detector.constants import READ_NOISE_E, ReadoutMode
from ..detector.fowler import fowler_sample_grouped, fowler_sample_iracsim2015, fowler_weights
from ..errors import InputError

__all__ = ["FrameModel", "tick_moments", "centred_tick_moments", "weight_groups", "read_intervals",
           "star_group_charges", "fowler_uniform",
           "expected_fowler", "render_frames", "render_cube", "stamp_origin", "N_MOMENTS",
           "NOISE_MODELS"]

N_MOMENTS = 6  # 1, dx, dy, dx^2, dx dy, dy^2
#: ``simulation.noise_model`` values the renderer knows
NOISE_MODELS = ("physical", "iracsim2015", "none")
SMALL_COUNT = 32  # ramp electrons per pixel up to which each gets its own weight draw


@dataclass(frozen=True)
class FrameModel:
    """Detector and noise settings shared by all frames of a simulation.

    Parameters
    ----------
    mode : ReadoutMode
        Fowler sampling (FN, WT, tick time).
    noise_model : {"physical", "iracsim2015", "none"}
    read_noise_e : float
        Gaussian read noise per read (electrons).
    noise_factor : float
        IRACSIM's ``NOISE_FACTOR`` on the Poisson deviates and the read noise
        (``iracsim2015`` only; 1 leaves the noise as drawn).
    subsamples : int
        Pointing sub-samples per tick ``n``.
    stamp_px : int
        Side of the square stamp that gets the per-tick treatment (odd).
    shape : tuple of int
        Image shape (ny, nx).
    gaussian_skew : float
        ``physical`` only: the largest bound on a pixel's skewness for which its
        photon noise is drawn with its read noise as one Gaussian of the same
        mean and variance (module notes, "Gaussian photon noise"); 0 (the
        challenge simulator's): exact Poisson draws everywhere.
    """

    mode: ReadoutMode
    noise_model: str = "physical"
    read_noise_e: float = READ_NOISE_E
    noise_factor: float = 1.0
    subsamples: int = 10
    stamp_px: int = 13
    shape: tuple[int, int] = (32, 32)
    gaussian_skew: float = 0.0

    def __post_init__(self):
        if self.noise_factor != 1.0 and self.noise_model != "iracsim2015":
            raise InputError(f"noise_factor: IRACSIM's NOISE_FACTOR applies to noise_model "
                             f"'iracsim2015' only, got {self.noise_factor} with {self.noise_model!r}")
        if not self.gaussian_skew >= 0 or (self.gaussian_skew > 0
                                           and self.noise_model != "physical"):
            raise InputError(f"gaussian_skew: expected a number >= 0, and 0 unless noise_model "
                             f"is 'physical', got {self.gaussian_skew} with {self.noise_model!r}")

    @property
    def subsamples_per_tick(self) -> int:
        """Sub-samples summed into one tick (``n + 1`` for ``iracsim2015``)."""
        return self.subsamples + (1 if self.noise_model == "iracsim2015" else 0)

    @property
    def grid_samples_per_frame(self) -> int:
        """Pointing-grid samples a frame needs (one more than ``n_max n`` for the extra one)."""
        return self.mode.n_max * self.subsamples + 1

    @property
    def ticks_per_exposure(self) -> int:
        """``FN + WT``: ticks between a pedestal and its signal read."""
        return self.mode.fowler + self.mode.wait


def tick_moments(dx: np.ndarray, dy: np.ndarray, model: FrameModel
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean position and per-tick moments of the sub-sample offsets of each frame.

    Parameters
    ----------
    dx, dy : ndarray, shape (n_frames, n_max * n + 1)
        Pointing offsets (px) at the frame's sub-samples ``t_start + s delta t``.
    model : FrameModel

    Returns
    -------
    x_mean, y_mean : ndarray, shape (n_frames,)
        Fowler-weighted mean offset of each frame (what the frame "sees").
    moments : ndarray, shape (n_frames, n_max, 6)
        Per tick: ``[m0, <d_x>, <d_y>, <d_x^2>, <d_x d_y>, <d_y^2>]``, the means
        over the tick's sub-samples (``n``, or ``n + 1`` for ``iracsim2015``),
        so ``m0`` is 1, with ``d`` relative to the frame mean.
    """
    nf = dx.shape[0]
    n_max = model.mode.n_max
    sx, sy, span = _tick_samples(dx, dy, model)
    # power sums per tick, then shifted to the frame mean (offsets are < 2 px,
    # so the shift loses nothing in float64)
    s1x = sx.sum(axis=2)
    s1y = sy.sum(axis=2)
    sxx = np.einsum("ftk,ftk->ft", sx, sx)
    sxy = np.einsum("ftk,ftk->ft", sx, sy)
    syy = np.einsum("ftk,ftk->ft", sy, sy)
    x_mean, y_mean = _weighted_means(s1x, s1y, model, span)
    mx = x_mean[:, None]
    my = y_mean[:, None]
    moments = np.empty((nf, n_max, N_MOMENTS))
    # means over the tick's sub-samples: IRACSIM's (n + 1)-th sub-sample widens
    # the smear but adds no light (the 2015 frames show the paper's flux)
    moments[:, :, 0] = 1.0
    moments[:, :, 1] = (s1x - span * mx) / span
    moments[:, :, 2] = (s1y - span * my) / span
    moments[:, :, 3] = (sxx - 2 * mx * s1x + span * mx * mx) / span
    moments[:, :, 4] = (sxy - mx * s1y - my * s1x + span * mx * my) / span
    moments[:, :, 5] = (syy - 2 * my * s1y + span * my * my) / span
    return x_mean, y_mean, moments


def tick_means(dx: np.ndarray, dy: np.ndarray, model: FrameModel
               ) -> tuple[np.ndarray, np.ndarray]:
    """The mean positions of :func:`tick_moments` (the same values) without its moments:
    what removing each exposure's mean offset needs (issue 40: the twins' motion)."""
    sx, sy, span = _tick_samples(dx, dy, model)
    return _weighted_means(sx.sum(axis=2), sy.sum(axis=2), model, span)


def centred_tick_moments(gx: np.ndarray, gy: np.ndarray, at: np.ndarray, model: FrameModel
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`tick_moments` of each frame's offsets less their Fowler-weighted mean, read from
    one span of samples.

    Frame ``f``'s grid samples are ``gx[at[f] : at[f] + model.grid_samples_per_frame]``
    (and ``gy``): what :func:`~eclipsebench.instrument.pointing.frame_windows` cuts out
    and :meth:`~eclipsebench.trust.twin.ExposureMotion.offsets` centres. The same
    values (to rounding: the sums run in another order) without cutting, centring and
    summing each frame's window in separate passes over memory (issue 40: the twins'
    motion).

    Returns
    -------
    x_mean, y_mean : ndarray, shape (n_frames,)
        The Fowler-weighted mean of the centred offsets (zero to rounding).
    moments : ndarray, shape (n_frames, n_max, 6)
        As :func:`tick_moments`.
    """
    w = fowler_weights(model.mode).astype(float)
    return _centred_moments_kernel(np.ascontiguousarray(gx, dtype=float),
                                   np.ascontiguousarray(gy, dtype=float),
                                   np.asarray(at, np.int64), w, model.subsamples,
                                   model.subsamples_per_tick)


@njit(cache=True)
def _centred_moments_kernel(gx, gy, at, w, n, span):
    nf = at.size
    n_max = w.size
    w_sum = 0.0
    for t in range(n_max):
        w_sum += w[t]
    x_out = np.empty(nf)
    y_out = np.empty(nf)
    moments = np.empty((nf, n_max, 6))
    s1x = np.empty(n_max)
    s1y = np.empty(n_max)
    sxx = np.empty(n_max)
    sxy = np.empty(n_max)
    syy = np.empty(n_max)
    for f in range(nf):
        a = at[f]
        # the frame's Fowler-weighted mean (tick_means)
        wx = 0.0
        wy = 0.0
        for t in range(n_max):
            bx = 0.0
            by = 0.0
            for k in range(span):
                bx += gx[a + t * n + k]
                by += gy[a + t * n + k]
            wx += bx * w[t]
            wy += by * w[t]
        mx0 = wx / (span * w_sum)
        my0 = wy / (span * w_sum)
        # the centred offsets' power sums per tick and their weighted mean (tick_moments)
        wx = 0.0
        wy = 0.0
        for t in range(n_max):
            a1 = 0.0
            a2 = 0.0
            axx = 0.0
            axy = 0.0
            ayy = 0.0
            for k in range(span):
                u = gx[a + t * n + k] - mx0
                v = gy[a + t * n + k] - my0
                a1 += u
                a2 += v
                axx += u * u
                axy += u * v
                ayy += v * v
            s1x[t] = a1
            s1y[t] = a2
            sxx[t] = axx
            sxy[t] = axy
            syy[t] = ayy
            wx += a1 * w[t]
            wy += a2 * w[t]
        mx = wx / (span * w_sum)
        my = wy / (span * w_sum)
        x_out[f] = mx
        y_out[f] = my
        for t in range(n_max):
            moments[f, t, 0] = 1.0
            moments[f, t, 1] = (s1x[t] - span * mx) / span
            moments[f, t, 2] = (s1y[t] - span * my) / span
            moments[f, t, 3] = (sxx[t] - 2 * mx * s1x[t] + span * mx * mx) / span
            moments[f, t, 4] = (sxy[t] - mx * s1y[t] - my * s1x[t] + span * mx * my) / span
            moments[f, t, 5] = (syy[t] - 2 * my * s1y[t] + span * my * my) / span
    return x_out, y_out, moments


def _tick_samples(dx: np.ndarray, dy: np.ndarray, model: FrameModel
                  ) -> tuple[np.ndarray, np.ndarray, int]:
    """The offsets of each tick's sub-samples, shape (n_frames, n_max, span), and span."""
    mode, n = model.mode, model.subsamples
    nf = dx.shape[0]
    n_max = mode.n_max
    span = model.subsamples_per_tick
    if span == n:
        sx = dx[:, :n_max * n].reshape(nf, n_max, n)
        sy = dy[:, :n_max * n].reshape(nf, n_max, n)
    else:  # sub-sample s of tick k is grid sample k n + s, s = 0 .. span - 1
        idx = (np.arange(n_max)[:, None] * n + np.arange(span)[None, :]).ravel()
        sx = dx[:, idx].reshape(nf, n_max, span)
        sy = dy[:, idx].reshape(nf, n_max, span)
    return sx, sy, span


def _weighted_means(s1x: np.ndarray, s1y: np.ndarray, model: FrameModel, span: int
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Fowler-weighted frame means from the per-tick sums ``s1x``, ``s1y`` (n_frames, n_max)."""
    w = fowler_weights(model.mode).astype(float)
    return (s1x @ w) / (span * w.sum()), (s1y @ w) / (span * w.sum())


def weight_groups(mode: ReadoutMode) -> np.ndarray:
    """Indicator matrix (n_max, FN): tick ``k`` belongs to the group of Fowler weight ``j``.

    Row sums are 1 except for the first tick (weight 0), whose charge never
    enters the frame.
    """
    w = fowler_weights(mode)
    return (w[:, None] == np.arange(1, mode.fowler + 1)[None, :]).astype(float)


def read_intervals(mode: ReadoutMode) -> np.ndarray:
    """Indicator matrix (n_max, 2 FN): tick ``k`` is collected before read ``r`` and after read ``r - 1``.

    Reads are ``P_1 .. P_FN, S_1 .. S_FN`` (ticks ``1..FN`` and
    ``FN + WT + 1 .. 2 FN + WT``); ticks after the last read are not collected.
    """
    fn, wt = mode.fowler, mode.wait
    read_tick = np.concatenate([np.arange(1, fn + 1), fn + wt + np.arange(1, fn + 1)])
    k = np.arange(1, mode.n_max + 1)
    interval = np.searchsorted(read_tick, k, side="left")
    out = np.zeros((mode.n_max, 2 * fn))
    ok = interval < 2 * fn
    out[np.flatnonzero(ok), interval[ok]] = 1.0
    return out


def star_group_charges(basis: np.ndarray, group_moments: np.ndarray,
                       rate_e_per_tick: np.ndarray) -> np.ndarray:
    """Mean star charge per tick group and stamp pixel from the Taylor basis.

    Parameters
    ----------
    basis : ndarray, shape (n_frames, 6, n_pix)
        ``[V, Gx, Gy, Hxx/2, Hxy, Hyy/2]`` of the PRF at each frame's mean
        position, per stamp pixel (PRF units).
    group_moments : ndarray, shape (n_frames, n_groups, 6)
        :func:`tick_moments` summed over the ticks of each group.
    rate_e_per_tick : ndarray, shape (n_frames,)
        Electrons per tick per PRF unit (flux scale times L(t)).

    Returns
    -------
    ndarray, shape (n_groups, n_frames, n_pix)
        Group-major, as the :mod:`eclipsebench.detector.fowler` kernels want.
    """
    q = np.einsum("fgm,fmp->gfp", group_moments, basis, optimize=True)
    q *= rate_e_per_tick[None, :, None]
    np.clip(q, 0.0, None, out=q)
    return q


def fowler_uniform(rate_e_per_tick: np.ndarray, mode: ReadoutMode,
                   rng: np.random.Generator) -> np.ndarray:
    """Physical Fowler sampling of pixels whose rate is constant over the frame (no read noise).

    The same distribution as
    :func:`~eclipsebench.detector.fowler.fowler_sample_grouped` for equal
    tick charges ``r``: the ``WT + 1`` ticks of weight FN give
    ``Poisson((WT + 1) r)``; the ``2 (FN - 1)`` ramp ticks (weights
    ``1 .. FN-1``, two ticks each) give ``Poisson(2 (FN - 1) r)`` electrons in
    total, each landing in a ramp tick chosen uniformly (splitting a Poisson
    count multinomially gives independent Poisson counts), so the frame value
    ``[FN N_wait + sum_e w_e] / FN`` needs two Poisson draws per pixel (plus
    one small integer per ramp electron, or one multinomial draw for pixels
    with more than 32 ramp electrons).

    Parameters
    ----------
    rate_e_per_tick : ndarray
        Mean charge per tick (e), any shape, >= 0.
    mode : ReadoutMode
    rng : numpy.random.Generator

    Returns
    -------
    ndarray
        ``sum_i (S_i - P_i) / FN`` (e), same shape.
    """
    r = np.asarray(rate_e_per_tick, dtype=float)
    fn, wt = mode.fowler, mode.wait
    n_wait = rng.poisson((wt + 1) * r)
    total = fn * n_wait.astype(float)
    if fn == 2:
        total += rng.poisson(2 * r)
    elif fn > 2:
        n_ramp = rng.poisson(2 * (fn - 1) * r).ravel()
        small = n_ramp <= SMALL_COUNT
        # few electrons: one uniform weight each; many: a multinomial split
        n_small = np.where(small, n_ramp, 0)
        n_e = int(n_small.sum())
        extra = np.zeros(n_ramp.size)
        if n_e:
            owner = np.repeat(np.arange(n_ramp.size), n_small)
            weight = rng.integers(1, fn, size=n_e).astype(float)
            extra += np.bincount(owner, weights=weight, minlength=n_ramp.size)
        big = np.flatnonzero(~small)
        if big.size:
            counts = rng.multinomial(n_ramp[big], np.full(fn - 1, 1.0 / (fn - 1)))
            extra[big] += counts @ np.arange(1, fn, dtype=float)
        total += extra.reshape(r.shape)
    return total / fn


def expected_fowler(q_ticks: np.ndarray, mode: ReadoutMode) -> np.ndarray:
    """Noise-free frame value ``sum_k w_k q_k / FN`` of tick charges ``(n_max, ...)``."""
    w = fowler_weights(mode).astype(float)
    return np.tensordot(w, q_ticks, axes=(0, 0)) / mode.fowler


def stamp_origin(x: np.ndarray, y: np.ndarray, size: int, shape: tuple[int, int]
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Lower-left pixel (x0, y0) of the ``size`` stamp centred on (x, y), kept on the array."""
    half = size // 2
    x0 = np.clip(np.rint(x).astype(int) - half, 0, shape[1] - size)
    y0 = np.clip(np.rint(y).astype(int) - half, 0, shape[0] - size)
    return x0, y0


def render_frames(*, model: FrameModel, moments: np.ndarray, basis: np.ndarray, stamp_x0: int, stamp_y0: int,
                  wings: np.ndarray, star_e_per_tick: np.ndarray, background_e_per_tick:
                  np.ndarray, rng_photon: np.random.Generator, rng_read: np.random.Generator
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Fowler-sampled frames (electrons per exposure) and their noise-free expectation.

    Parameters
    ----------
    model : FrameModel
    moments : ndarray, shape (n_frames, n_max, 6)
        :func:`tick_moments`.
    basis : ndarray, shape (n_frames, 6, s*s)
        Taylor basis of the PRF in the stamp whose lower-left pixel is
        ``(stamp_x0, stamp_y0)`` (the same for all frames of the call).
    wings : ndarray, shape (ny, nx)
        The star (PRF units) over the whole array at the chunk's mean
        position; used outside the stamp.
    star_e_per_tick : ndarray, shape (n_frames,)
        Electrons per tick per PRF unit, including ``L(t)``.
    background_e_per_tick : ndarray, shape (n_frames,)
        Background electrons per tick and pixel.
    rng_photon, rng_read : numpy.random.Generator
        Streams for photon noise and read noise; draw counts and order do not
        depend on the pointing or the gain map, so systematics-free twins
        draw from the same streams in the same order (``none`` draws nothing).

    Returns
    -------
    frames_e, expected_e : ndarray, shape (n_frames, ny, nx)
    """
    mode = model.mode
    ny, nx = model.shape
    s = model.stamp_px
    nf = moments.shape[0]
    if model.noise_model not in NOISE_MODELS:
        raise InputError(f"noise_model: expected one of {', '.join(NOISE_MODELS)}, "
                         f"got {model.noise_model!r}")
    if basis.shape != (nf, N_MOMENTS, s * s):
        raise ValueError(f"basis: expected shape {(nf, N_MOMENTS, s * s)}, got {basis.shape}")
    in_stamp = np.zeros((ny, nx), dtype=bool)
    in_stamp[stamp_y0:stamp_y0 + s, stamp_x0:stamp_x0 + s] = True
    outside = ~in_stamp.ravel()

    m0 = moments[:, :, 0]                                                # (nf, n_max)
    rate_out = (star_e_per_tick[:, None] * wings.ravel()[outside][None, :]
                + background_e_per_tick[:, None])                       # (nf, n_out) per tick
    np.clip(rate_out, 0.0, None, out=rate_out)
    frames = np.empty((nf, ny * nx))
    expected = np.empty((nf, ny * nx))
    stamp_cols = np.flatnonzero(in_stamp.ravel())
    out_cols = np.flatnonzero(outside)
    if model.noise_model in ("physical", "none"):
        member = weight_groups(mode)                                     # (n_max, FN)
        gm = np.matmul(member.T, moments)                                # (nf, FN, 6)
        groups = star_group_charges(basis, gm, star_e_per_tick)          # (FN, nf, s*s)
        groups += (gm[:, :, 0] * background_e_per_tick[:, None]).T[:, :, None]
        j = np.arange(1, mode.fowler + 1, dtype=float)
        expected[:, stamp_cols] = np.tensordot(j, groups, axes=(0, 0)) / mode.fowler
        if model.noise_model == "physical" and not model.gaussian_skew > 0:
            frames[:, stamp_cols] = fowler_sample_grouped(groups, mode, rng_photon, 0.0)
            frames[:, out_cols] = fowler_uniform(rate_out, mode, rng_photon)
    else:
        member = read_intervals(mode)                                    # (n_max, 2FN)
        im = np.matmul(member.T, moments)                                # (nf, 2FN, 6)
        inc = star_group_charges(basis, im, star_e_per_tick)             # (2FN, nf, s*s)
        inc += (im[:, :, 0] * background_e_per_tick[:, None]).T[:, :, None]
        reads = np.cumsum(inc, axis=0)
        frames[:, stamp_cols] = fowler_sample_iracsim2015(reads, mode, rng_photon, 0.0,
                                                          noise_factor=model.noise_factor)
        reads_out = np.cumsum(im[:, :, 0].T, axis=0)[:, :, None] * rate_out[None, :, :]
        frames[:, out_cols] = fowler_sample_iracsim2015(reads_out, mode, rng_photon, 0.0,
                                                        noise_factor=model.noise_factor)
        fn = mode.fowler
        expected[:, stamp_cols] = (reads[fn:] - reads[:fn]).sum(axis=0) / fn
    w_sum = (fowler_weights(mode)[None, :] * m0).sum(axis=1) / mode.fowler
    expected[:, out_cols] = rate_out * w_sum[:, None]
    if model.gaussian_skew > 0:
        return _gaussian_frames(model, groups, rate_out, m0, expected, stamp_cols, out_cols,
                                rng_photon, rng_read)
    if model.noise_model == "none":
        frames[:] = expected
        return frames.reshape(nf, ny, nx), expected.reshape(nf, ny, nx)
    # Read noise: 2 FN reads per pixel; their sum in sum_i (S_i - P_i) / FN is one Gaussian.
    read_sd = model.read_noise_e * model.noise_factor
    frames += rng_read.standard_normal(size=frames.shape) * (read_sd * np.sqrt(2.0 / mode.fowler))
    return frames.reshape(nf, ny, nx), expected.reshape(nf, ny, nx)


def _gaussian_frames(model: FrameModel, groups: np.ndarray, rate_out: np.ndarray,
                     m0: np.ndarray, expected: np.ndarray, stamp_cols: np.ndarray,
                     out_cols: np.ndarray, rng_photon: np.random.Generator,
                     rng_read: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """:func:`render_frames`' physical frames with ``model.gaussian_skew`` > 0 (module notes,
    "Gaussian photon noise"): one standard normal per pixel from ``rng_read`` scaled by the
    pixel's whole noise where the skewness bound allows, else by the read noise alone, with
    the exact photon draws of those pixels from ``rng_photon``."""
    mode = model.mode
    fn = mode.fowler
    nf = expected.shape[0]
    ny, nx = model.shape
    read_var = model.read_noise_e**2 * 2.0 / fn
    # the photon variance of each pixel: sum_k w_k^2 q_k / FN^2 (module fowler's notes)
    photon_var = np.empty_like(expected)
    j2 = np.arange(1, fn + 1, dtype=float) ** 2
    photon_var[:, stamp_cols] = np.tensordot(j2, groups, axes=(0, 0)) / fn**2
    w2 = fowler_weights(mode).astype(float) ** 2
    photon_var[:, out_cols] = rate_out * ((m0 * w2[None, :]).sum(axis=1) / fn**2)[:, None]
    total_var = photon_var + read_var
    exact = photon_var > model.gaussian_skew * total_var**1.5
    frames = rng_read.standard_normal(size=expected.shape)
    frames *= np.sqrt(np.where(exact, read_var, total_var))
    if exact.any():
        # the pixels whose noise keeps its exact draws: their photon part, as without the bound
        photon = expected.copy()
        stamp_exact = exact[:, stamp_cols]
        if stamp_exact.any():
            part = photon[:, stamp_cols]
            part[stamp_exact] = fowler_sample_grouped(groups[:, stamp_exact], mode, rng_photon,
                                                      0.0)
            photon[:, stamp_cols] = part
        out_exact = exact[:, out_cols]
        if out_exact.any():
            part = photon[:, out_cols]
            part[out_exact] = fowler_uniform(rate_out[out_exact], mode, rng_photon)
            photon[:, out_cols] = part
        frames += photon
    else:
        frames += expected
    return frames.reshape(nf, ny, nx), expected.reshape(nf, ny, nx)


def render_cube(*, model: FrameModel, star: Any, x_px, y_px, dx: np.ndarray | None,
                dy: np.ndarray | None, star_e_per_tick: np.ndarray,
                background_e_per_tick: np.ndarray, rng_photon: np.random.Generator,
                rng_read: np.random.Generator,
                moments: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One cube's frames of a star at ``(x_px, y_px)`` moving by ``(dx, dy)`` within each
    exposure: the step the challenge simulator (:mod:`.aor`) and the trust twins
    (:mod:`eclipsebench.trust.twin`) share.

    The tick moments of the motion (:func:`tick_moments`), the stamp about the
    cube's mean position (:func:`stamp_origin`), the star's Taylor basis there and
    its wings over ``model.shape`` (``star``: a
    :class:`~eclipsebench.simulation.star.StarImager`), then :func:`render_frames`.

    Parameters
    ----------
    model : FrameModel
    star : StarImager
    x_px, y_px : float or ndarray, shape (n_frames,)
        Each frame's mean position (0-based pixels of ``model.shape``).
    dx, dy : ndarray, shape (n_frames, model.grid_samples_per_frame)
        The offsets within each exposure (None with ``moments``).
    star_e_per_tick, background_e_per_tick, rng_photon, rng_read
        As :func:`render_frames`.
    moments : tuple, optional
        ``(x_mean, y_mean, moments)`` of the offsets, :func:`tick_moments` computed
        already (:func:`centred_tick_moments`); ``dx`` and ``dy`` are then not read.

    Returns
    -------
    frames_e, expected_e : ndarray, shape (n_frames, ny, nx)
    x_f, y_f : ndarray, shape (n_frames,)
        Each frame's Fowler-weighted mean position.
    """
    if moments is None:
        if dx is None or dy is None:
            raise ValueError("render_cube: give the offsets dx, dy or their moments")
        moments = tick_moments(dx, dy, model)
    x_off, y_off, tick = moments
    x_f = x_px + x_off
    y_f = y_px + y_off
    sx0, sy0 = stamp_origin(np.array([x_f.mean()]), np.array([y_f.mean()]), model.stamp_px,
                            model.shape)
    basis = star.taylor_basis(x_f, y_f, int(sx0[0]), int(sy0[0]), model.stamp_px)
    wings = star.image(float(x_f.mean()), float(y_f.mean()), model.shape)
    frames_e, expected_e = render_frames(
        model=model, moments=tick, basis=basis, stamp_x0=int(sx0[0]), stamp_y0=int(sy0[0]),
        wings=wings, star_e_per_tick=star_e_per_tick, background_e_per_tick=background_e_per_tick,
        rng_photon=rng_photon, rng_read=rng_read)
    return frames_e, expected_e, x_f, y_f
