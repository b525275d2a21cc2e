"""The photometric estimators, one definition each, on stacks of frames (arrays in, arrays out).

Each estimator is one per-frame numba kernel of :mod:`.kernels`:

========================  ==========================  ====================================
estimator                 kernel                      here
========================  ==========================  ====================================
brightest pixel           ``_frame_peak``             :func:`brightest_pixel`
annulus background        ``_frame_annulus``          :func:`annulus_background`
center of light           ``_frame_col``              :func:`centroid_col`
noise pixels              ``_frame_col``              :func:`noise_pixels`
2-D Gaussian centroid     ``_frame_gauss``            :func:`centroid_gauss`
least-asymmetry centroid  ``_frame_lsq_asym``         :func:`centroid_lsq_asym`
circular apertures        ``_frame_apertures``        :func:`aperture_sums`,
                                                      :func:`aperture_flux`
========================  ==========================  ====================================

:func:`.measure.measure_stack` chains the kernels into the full measurement set
used for science frames and for the calibration-star set
(:mod:`eclipsebench.simulation.calibration`); the functions here run a single
estimator over a stack, for the PRF checks of
:mod:`eclipsebench.instrument.prf` and for users.

Conventions (as in :mod:`.kernels`): ``frames_e[k, j, i]`` is frame ``k``,
row ``y = j``, column ``x = i``, in electrons per pixel; a pixel's centre is
at integer 0-based coordinates. A single 2-D image is treated as a stack of
one. Positions and backgrounds are one value for every frame or one per frame.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from . import kernels

__all__ = ["per_frame", "brightest_pixel", "annulus_background", "centroid_col",
           "noise_pixels", "centroid_gauss", "centroid_lsq_asym", "aperture_sums",
           "aperture_flux", "CENTROID_HALF_PX", "GAUSS_START_WIDTH_PX", "LSQ_GRID_HALF_PX",
           "LSQ_WINDOW_PX"]

#: Half-width of the paper's 7x7 centroid box (Section 3.1).
CENTROID_HALF_PX = 3
GAUSS_START_WIDTH_PX = kernels.GAUSS_START_WIDTH_PX
LSQ_GRID_HALF_PX = kernels.LSQ_GRID_HALF_PX
LSQ_WINDOW_PX = kernels.LSQ_WINDOW_PX


# ----------------------------------------------------------------------------- inputs
def _stack(frames_e) -> np.ndarray:
    frames = np.asarray(frames_e, dtype=np.float64)
    if frames.ndim == 2:
        frames = frames[None]
    if frames.ndim != 3:
        raise ValueError(f"frames_e: expected (n, ny, nx) or (ny, nx), got shape {frames.shape}")
    return np.ascontiguousarray(frames)


def per_frame(value, n: int, name: str, dtype=np.float64) -> np.ndarray:
    """``value`` as a contiguous array of ``n`` values (one value is repeated).

    Raises
    ------
    ValueError
        When ``value`` is neither one value nor ``n`` values.
    """
    arr = np.asarray(value, dtype=dtype)
    if arr.ndim == 0:
        arr = np.full(n, arr, dtype=dtype)
    if arr.shape != (n,):
        raise ValueError(f"{name}: expected one value or {n}, got shape {arr.shape}")
    return np.ascontiguousarray(arr)


def _box_centres(frames: np.ndarray, around) -> tuple[np.ndarray, np.ndarray]:
    """Integer box centres: ``around = (x, y)`` (per frame or shared), else the brightest pixel."""
    n = frames.shape[0]
    if around is None:
        return brightest_pixel(frames)
    return per_frame(around[0], n, "around[0]", np.int64), per_frame(around[1], n, "around[1]",
                                                                      np.int64)


# ----------------------------------------------------------------------------- stack drivers
# Serial loops: the PRF checks run them while building a PRF, in processes that may
# fork workers later, and a started OpenMP thread pool does not survive a fork.
# measure_stack is the parallel path for long stacks.
@njit(cache=True)
def _peak_stack(frames, gx, gy, half, px, py):
    for f in range(frames.shape[0]):
        px[f], py[f] = kernels._frame_peak(frames[f], gx[f], gy[f], half)


@njit(cache=True)
def _annulus_stack(frames, xc, yc, r_in, r_out, clip_sigma, clip_iters, out):
    nbuf = int((2 * r_out + 3) * (2 * r_out + 3)) + 1
    for f in range(frames.shape[0]):
        out[f, 0], out[f, 1], out[f, 2], out[f, 3] = kernels._frame_annulus(
            frames[f], xc[f], yc[f], r_in, r_out, clip_sigma, clip_iters, np.empty(nbuf))


@njit(cache=True)
def _col_stack(frames, px, py, half, bg, out):
    for f in range(frames.shape[0]):
        out[f, 0], out[f, 1], out[f, 2] = kernels._frame_col(frames[f], px[f], py[f], half, bg[f])


@njit(cache=True)
def _gauss_stack(frames, px, py, half, bg, x0, y0, width, fixed, max_iter, out):
    for f in range(frames.shape[0]):
        (out[f, 0], out[f, 1], out[f, 2], out[f, 3], out[f, 4], out[f, 5],
         out[f, 6]) = kernels._frame_gauss(frames[f], px[f], py[f], half, bg[f], x0[f], y0[f],
                                           width, fixed, max_iter)


@njit(cache=True)
def _lsq_stack(frames, px, py, bg, grid_h, win_r, out):
    for f in range(frames.shape[0]):
        out[f, 0], out[f, 1], out[f, 2] = kernels._frame_lsq_asym(frames[f], px[f], py[f], bg[f],
                                                                  grid_h, win_r)


@njit(cache=True)
def _aperture_stack(frames, xc, yc, radii, sums, areas):
    for f in range(frames.shape[0]):
        kernels._frame_apertures(frames[f], xc[f], yc[f], radii, sums[f], areas[f])


# ----------------------------------------------------------------------------- estimators
def brightest_pixel(frames_e, guess_x=None, guess_y=None, search_half_px: int | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The brightest finite pixel of each frame, near a guess or anywhere.

    Parameters
    ----------
    frames_e : array_like, shape (n, ny, nx) or (ny, nx)
        Images, electrons per pixel.
    guess_x, guess_y : int or array of int, optional
        Centre of the searched box (default: the image centre).
    search_half_px : int, optional
        Half-width of the searched box (default: the whole image).

    Returns
    -------
    px, py : ndarray of int64, shape (n,)
        Column and row of the brightest pixel; -1 where the box holds no finite pixel.
        Ties go to the first pixel in row-major order.
    """
    frames = _stack(frames_e)
    n, ny, nx = frames.shape
    gx = per_frame(nx // 2 if guess_x is None else guess_x, n, "guess_x", np.int64)
    gy = per_frame(ny // 2 if guess_y is None else guess_y, n, "guess_y", np.int64)
    half = max(nx, ny) if search_half_px is None else int(search_half_px)
    px = np.empty(n, np.int64)
    py = np.empty(n, np.int64)
    _peak_stack(frames, gx, gy, half, px, py)
    return px, py


def annulus_background(frames_e, x_px, y_px, annulus_px=(3.0, 7.0), *, clip_sigma: float = 0.0,
                       clip_iters: int = 0) -> dict[str, np.ndarray]:
    """Background statistics in a circular annulus about ``(x_px, y_px)`` (paper Section 3.1).

    A pixel belongs to the annulus when its centre lies within
    ``annulus_px[0] <= d <= annulus_px[1]`` of the position; non-finite
    pixels and pixels beyond the image edge are skipped.

    Parameters
    ----------
    frames_e : array_like, shape (n, ny, nx) or (ny, nx)
        Images, electrons per pixel.
    x_px, y_px : float or array of float
        Annulus centre.
    annulus_px : (float, float)
        Inner and outer radius (px).
    clip_sigma, clip_iters : float, int
        Sigma clipping of the median and standard deviation (``clip_iters <= 0``:
        the mean only; the median and deviation are NaN).

    Returns
    -------
    dict of ndarray, shape (n,)
        ``mean_e`` (all annulus pixels), ``median_e`` and ``std_e`` (of the
        values surviving the clipping), ``npix`` (pixels in the mean).
    """
    frames = _stack(frames_e)
    n = frames.shape[0]
    out = np.empty((n, 4))
    _annulus_stack(frames, per_frame(x_px, n, "x_px"), per_frame(y_px, n, "y_px"),
                   float(annulus_px[0]), float(annulus_px[1]), float(clip_sigma),
                   int(clip_iters), out)
    return {"mean_e": out[:, 0], "median_e": out[:, 1], "std_e": out[:, 2],
            "npix": out[:, 3].astype(np.int64)}


def _col(frames_e, half: int, around, background_e) -> np.ndarray:
    frames = _stack(frames_e)
    n = frames.shape[0]
    px, py = _box_centres(frames, around)
    out = np.empty((n, 3))
    _col_stack(frames, px, py, int(half), per_frame(background_e, n, "background_e"), out)
    return out


def centroid_col(frames_e, half: int = CENTROID_HALF_PX, around=None, *, background_e=0.0
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Center-of-light centroids (paper Eqs. ``x_centroid``, ``y_centroid``).

    Over the ``(2 half + 1)^2`` box (7x7 by default) about the integer pixel
    ``around = (x, y)`` (one for all frames or one per frame), or about each
    frame's brightest pixel, of the images minus ``background_e``.

    Returns
    -------
    x, y : ndarray, shape (n,)
        Centroids (px); NaN where the box leaves the image, holds a
        non-finite value, or has no positive net flux.
    """
    out = _col(frames_e, half, around, background_e)
    return out[:, 0], out[:, 1]


def noise_pixels(frames_e, half: int = CENTROID_HALF_PX, around=None, *, background_e=0.0
                 ) -> np.ndarray:
    """Noise pixels ``beta = (sum f)^2 / sum f^2`` (paper Eq. ``noise_pixels``).

    Over the same box and background as :func:`centroid_col`; NaN where that is.
    """
    return _col(frames_e, half, around, background_e)[:, 2]


def centroid_gauss(frames_e, half: int = CENTROID_HALF_PX, around=None, *, background_e=0.0,
                   start=None, width_px: float = GAUSS_START_WIDTH_PX, fixed_width: bool = False,
                   max_iter: int = 30) -> dict[str, np.ndarray]:
    """Least-squares fit of a pixel-integrated 2-D Gaussian plus a constant.

    The model of pixel ``(i, j)`` is ``A Ex_i Ey_j + C`` with ``Ex_i`` the
    Gaussian integrated over the pixel, fitted by Levenberg-Marquardt over the
    ``(2 half + 1)^2`` box about ``around`` (default: the brightest pixel) of
    the images minus ``background_e``.

    Parameters
    ----------
    start : (x, y), optional
        Starting centre (default: the center of light of the same box).
    width_px : float
        Starting width, or the width held fixed with ``fixed_width``.
    fixed_width : bool
        Fit the centre, amplitude and constant only.
    max_iter : int
        Levenberg-Marquardt iterations.

    Returns
    -------
    dict of ndarray, shape (n,)
        ``x``, ``y``, ``width_x``, ``width_y`` (px), ``amplitude_e``,
        ``offset_e`` and ``ok`` (bool, converged).
    """
    frames = _stack(frames_e)
    n = frames.shape[0]
    px, py = _box_centres(frames, around)
    bg = per_frame(background_e, n, "background_e")
    if start is None:
        col = np.empty((n, 3))
        _col_stack(frames, px, py, int(half), bg, col)
        x0, y0 = col[:, 0].copy(), col[:, 1].copy()
    else:
        x0, y0 = per_frame(start[0], n, "start[0]"), per_frame(start[1], n, "start[1]")
    out = np.empty((n, 7))
    _gauss_stack(frames, px, py, int(half), bg, x0, y0, float(width_px), bool(fixed_width),
                 int(max_iter), out)
    return {"x": out[:, 0], "y": out[:, 1], "width_x": out[:, 2], "width_y": out[:, 3],
            "amplitude_e": out[:, 4], "offset_e": out[:, 5], "ok": out[:, 6] > 0}


def centroid_lsq_asym(frames_e, around=None, *, background_e=0.0,
                      grid_half_px: int = LSQ_GRID_HALF_PX, window_px: int = LSQ_WINDOW_PX
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least-asymmetry centroids (Lust et al. 2014) about ``around`` or the brightest pixel.

    Returns
    -------
    x, y : ndarray, shape (n,)
        Centroids (px), NaN where the search failed.
    ok : ndarray of bool, shape (n,)
    """
    frames = _stack(frames_e)
    n = frames.shape[0]
    px, py = _box_centres(frames, around)
    out = np.empty((n, 3))
    _lsq_stack(frames, px, py, per_frame(background_e, n, "background_e"), int(grid_half_px),
               int(window_px), out)
    return out[:, 0], out[:, 1], out[:, 2] > 0


def aperture_sums(frames_e, x_px, y_px, radii_px) -> tuple[np.ndarray, np.ndarray]:
    """Exact-overlap circular aperture sums (no background subtracted).

    Pixel weights are the exact area of each pixel inside the circle (the
    quantity photutils computes with ``method="exact"``); pixels beyond the
    image edge contribute nothing, a non-finite pixel with non-zero weight
    makes the sum NaN.

    Parameters
    ----------
    frames_e, x_px, y_px
        Images and aperture centres, as for :func:`annulus_background`.
    radii_px : float or sequence of float
        Aperture radii (px).

    Returns
    -------
    sums_e, areas_px : ndarray, shape (n, len(radii_px))
        ``sum w f`` and ``sum w`` per frame and radius.
    """
    frames = _stack(frames_e)
    n = frames.shape[0]
    radii = np.ascontiguousarray(np.atleast_1d(np.asarray(radii_px, np.float64)))
    sums = np.empty((n, radii.size))
    areas = np.empty((n, radii.size))
    _aperture_stack(frames, per_frame(x_px, n, "x_px"), per_frame(y_px, n, "y_px"), radii,
                    sums, areas)
    return sums, areas


def aperture_flux(frames_e, x_px, y_px, radius_px: float) -> np.ndarray:
    """Exact-overlap sums of ``frames_e`` in circles of ``radius_px`` at ``(x_px, y_px)``.

    :func:`aperture_sums` for one radius; shape (n,).
    """
    return aperture_sums(frames_e, x_px, y_px, float(radius_px))[0][:, 0]
