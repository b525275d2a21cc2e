"""The full per-frame measurement set on a stack of frames (arrays in, arrays out).

:func:`measure_stack` runs, for every frame and in parallel (numba):

- the brightest pixel near the expected position;
- a first background (mean of the 3-7 px annulus about that pixel, pixel
  centres inside the annulus), used by the centroids;
- center of light over the 7x7 box (paper Eqs. ``x_centroid``, ``y_centroid``)
  and noise pixels (Eq. ``noise_pixels``) on the background-subtracted box;
- a pixel-integrated 2-D Gaussian fit with free widths (``x_gauss``,
  ``y_gauss``, ``width_x``, ``width_y``), optionally one with a fixed width
  (``x_gfix``, ``y_gfix``) and the least-asymmetry centroid (``x_lsq``,
  ``y_lsq``);
- the background about the chosen centroid (annulus mean, sigma-clipped
  median and clipped standard deviation);
- exact-overlap aperture sums on the grid of radii and on the variable radii
  ``r = a sqrt(beta) + b``; net fluxes subtract background x aperture area;
- per-frame flux uncertainties from the Fowler-sampling noise model
  (:func:`eclipsebench.detector.fowler.fowler_variance`);
- 3x3 and 5x5 background-subtracted stamps about a given pixel.

Everything is in electrons per pixel and 0-based pixel coordinates of the
frames passed in.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from ..config.photometry import PhotometrySection
from ..detector.constants import READ_NOISE_E, SUB_2S
from ..detector.fowler import fowler_variance
from . import kernels
from .estimators import annulus_background, brightest_pixel, noise_pixels, per_frame

__all__ = ["radius_name", "variable_name", "measure_stack", "measure_noise_pixels",
           "flux_uncertainty", "read_radius_px"]

_CHUNK = 8192  # frames converted to float64 and measured per kernel call


def radius_name(radius_px: float) -> str:
    """Column suffix of an aperture radius: 2.25 -> ``"r2p25"``."""
    return f"r{radius_px:.2f}".replace(".", "p")


def variable_name(a: float, b: float) -> str:
    """Column suffix of a variable aperture ``a sqrt(beta) + b``: ``"va1p00b0p00"``."""
    return f"va{a:.2f}b{b:.2f}".replace(".", "p").replace("-", "m")


def flux_uncertainty(aperture_sum_e, background_e, area_px, n_annulus, *,
                     fowler: int = SUB_2S.fowler, wait: int = SUB_2S.wait,
                     read_noise_e: float = READ_NOISE_E, read: str = "pixels"):
    """Per-frame uncertainty (electrons) of a background-subtracted aperture flux.

    Uses the paper's Eq. ``gar_for_var`` (:func:`fowler_variance`) for the
    aperture sum before background subtraction and for the background:

    - ``read="pixels"``: read noise of every aperture pixel,
      ``var = V(F_ap; npix=A) + (A^2 / N_ann) V(b; npix=1)`` (the background is
      a mean over ``N_ann`` annulus pixels, scaled to the aperture area ``A``);
    - ``read="paper"``: Section 3.3 as written, ``var = V(F_ap) + V(b A)``.

    Negative sums (noise on an empty aperture) count as zero shot noise.
    """
    s = np.clip(np.asarray(aperture_sum_e, float), 0.0, None)
    b = np.clip(np.asarray(background_e, float), 0.0, None)
    area = np.asarray(area_px, float)
    kw: dict[str, Any] = {"fowler": fowler, "wait": wait, "read_noise_e": read_noise_e}
    if read == "paper":
        var = fowler_variance(s, **kw) + fowler_variance(b * area, **kw)
    elif read == "pixels":
        n_ann = np.maximum(np.asarray(n_annulus, float), 1.0)
        var = (fowler_variance(s, n_pixels=area, **kw)
               + area**2 / n_ann * fowler_variance(b, **kw))
    else:
        raise ValueError(f"read: expected 'pixels' or 'paper', got {read!r}")
    return np.sqrt(var)


def read_radius_px(options: PhotometrySection) -> float:
    """How far (px, pixel centre to point) from a frame's brightest pixel or its centroid
    :func:`measure_stack` may read a pixel with ``options``.

    The largest of: the annulus (pixel centres within its outer radius); the
    exact-overlap apertures (any pixel the circle touches: radius plus half a
    pixel diagonal), the variable ones at their largest, ``a box_px + b``
    (noise pixels over the ``box_px`` square box cannot exceed its area,
    by the Cauchy-Schwarz inequality); the centroid box and the 5x5 stamp
    (their corners); the least-asymmetry window with its search grid. The
    brightest pixel is searched within ``search_px`` of the guess.

    Examples
    --------
    >>> round(read_radius_px(PhotometrySection()), 2)   # the 7 px aperture at beta = 49
    7.71
    """
    opt = options
    corner = 0.5 * math.sqrt(2.0)
    radii = [*opt.radii_px, opt.radius_px, *(a * opt.box_px + b for a, b in opt.variable_apertures)]
    reach = [float(opt.annulus_px[1]), max(radii) + corner, (opt.box_px // 2) * math.sqrt(2.0),
             2 * math.sqrt(2.0), float(opt.search_px)]
    if opt.centroid == "lsq-asym":
        reach.append((kernels.LSQ_GRID_HALF_PX + kernels.LSQ_WINDOW_PX) * math.sqrt(2.0))
    return max(reach)


def measure_stack(frames_e: np.ndarray, *, guess_x, guess_y, stamp_x=None, stamp_y=None,
                  options: PhotometrySection | None = None, gauss_width_px: float | None = None,
                  fowler: int = SUB_2S.fowler, wait: int = SUB_2S.wait,
                  read_noise_e: float = READ_NOISE_E) -> dict:
    """Measure every frame of ``frames_e`` (n, ny, nx), electrons per pixel.

    Parameters
    ----------
    frames_e : ndarray
        Frames (any float dtype; measured in float64 chunks of 8192 frames);
        non-finite pixels are allowed.
    guess_x, guess_y : int or array of int
        Pixel about which the brightest pixel is searched (within
        ``options.search_px``), one for all frames or one per frame.
    stamp_x, stamp_y : int or array of int, optional
        Centre pixel of the stamps (default: the guess).
    options : PhotometrySection
        Centroid choice, box, radii, annulus, background estimator, noise model.
    gauss_width_px : float, optional
        Width of the fixed-width Gaussian fit; by default
        ``options.gauss_width_px``, or when that is unset and the centroid is
        ``gauss-fixed``, the median free-fit width over the frames.
    fowler, wait, read_noise_e : int, int, float
        Readout of the frames (FN, WT, read noise per read in electrons) for
        the noise model; default the 2 s subarray mode of the XO-3 data
        (:data:`~eclipsebench.detector.constants.SUB_2S`, ``READ_NOISE_E``).

    Returns
    -------
    dict of ndarray
        One array per column (see the module notes); ``flux`` and ``flux_err``
        are at ``options.radius_px``, ``flux_r<r>`` at each radius of
        ``options.radii_px``, ``flux_<va..b..>`` and ``radius_<va..b..>`` for the
        variable apertures, ``stamp3`` (n, 3, 3) and ``stamp5`` (n, 5, 5).
    """
    opt = options if options is not None else PhotometrySection()
    frames = np.asarray(frames_e)
    if frames.ndim != 3:
        raise ValueError(f"frames_e: expected (n, ny, nx), got shape {frames.shape}")
    n = frames.shape[0]
    gx = per_frame(guess_x, n, "guess_x", np.int64)
    gy = per_frame(guess_y, n, "guess_y", np.int64)
    sx = per_frame(gx if stamp_x is None else stamp_x, n, "stamp_x", np.int64)
    sy = per_frame(gy if stamp_y is None else stamp_y, n, "stamp_y", np.int64)
    radii = sorted(set(float(r) for r in opt.radii_px) | {float(opt.radius_px)})
    radii_arr = np.asarray(radii, dtype=np.float64)
    var_a = np.asarray([ab[0] for ab in opt.variable_apertures], dtype=np.float64)
    var_b = np.asarray([ab[1] for ab in opt.variable_apertures], dtype=np.float64)
    width = gauss_width_px if gauss_width_px is not None else opt.gauss_width_px
    code = kernels.CENTROID_CODES[opt.centroid]
    stack = (frames, (gx, gy, sx, sy), opt, radii_arr, var_a, var_b)

    if opt.centroid == "gauss-fixed" and width is None:
        width = _median_free_width(_run_kernels(*stack, 0.0, kernels.CENTROID_CODES["gauss"]).out)
    fixed = float(width) if width is not None else 0.0  # 0: no fixed-width fit
    raw = _run_kernels(*stack, fixed, code)
    result = _position_columns(raw.out, opt, fixed)
    result.update(_flux_columns(raw, result["background"], radii, opt, fowler=fowler, wait=wait,
                                read_noise_e=read_noise_e))
    return result


def measure_noise_pixels(frames_e: np.ndarray, *, guess_x, guess_y,
                         options: PhotometrySection | None = None) -> np.ndarray:
    """The ``noise_pixels`` column of :func:`measure_stack` alone: the same floats, without
    the fits, apertures and stamps (a fifth of its time on twins' frames; the twins'
    calibration measures 147,000 noise-free frames for the noise pixels only, issue 40).

    The same kernels in the same order as :func:`kernels.measure_frames`: the brightest
    pixel within ``options.search_px`` of the guess, the mean of the annulus about it
    (paper Section 3.1), and the noise pixels (paper Eq. ``noise_pixels``) of the
    ``box_px`` box about it net of that mean; NaN where :func:`measure_stack` gives NaN
    (no finite pixel near the guess, a box leaving the image or holding a non-finite
    value, no positive net flux).

    Parameters
    ----------
    frames_e : ndarray
        Frames (n, ny, nx), electrons per pixel (converted to float64 as
        :func:`measure_stack` converts them).
    guess_x, guess_y : int or array of int
        As :func:`measure_stack`.
    options : PhotometrySection
        Its ``search_px``, ``annulus_px`` and ``box_px`` are read.

    Returns
    -------
    ndarray, shape (n,)
    """
    opt = options if options is not None else PhotometrySection()
    frames = np.ascontiguousarray(frames_e, dtype=np.float64)
    if frames.ndim != 3:
        raise ValueError(f"frames_e: expected (n, ny, nx), got shape {frames.shape}")
    n = frames.shape[0]
    px, py = brightest_pixel(frames, per_frame(guess_x, n, "guess_x", np.int64),
                             per_frame(guess_y, n, "guess_y", np.int64), int(opt.search_px))
    bg0 = annulus_background(frames, px.astype(np.float64), py.astype(np.float64),
                             (float(opt.annulus_px[0]), float(opt.annulus_px[1])))["mean_e"]
    return noise_pixels(frames, int(opt.box_px // 2), around=(px, py), background_e=bg0)


class _KernelOutput(NamedTuple):
    """The arrays :func:`kernels.measure_frames` fills, for every frame of a stack."""

    out: np.ndarray
    ap_sums: np.ndarray
    ap_areas: np.ndarray
    var_sums: np.ndarray
    var_areas: np.ndarray
    var_radii: np.ndarray
    stamp3: np.ndarray
    stamp5: np.ndarray


def _run_kernels(frames: np.ndarray, positions: tuple[np.ndarray, ...], opt: PhotometrySection,
                 radii_arr: np.ndarray, var_a: np.ndarray, var_b: np.ndarray,
                 fixed_width: float, centroid_code: int) -> _KernelOutput:
    """:func:`kernels.measure_frames` over ``frames`` in float64 chunks of ``_CHUNK`` frames.

    ``positions`` are the per-frame ``(guess_x, guess_y, stamp_x, stamp_y)``;
    ``fixed_width`` 0 skips the fixed-width Gaussian fit.
    """
    gx, gy, sx, sy = positions
    n = frames.shape[0]
    out = np.empty((n, kernels.N_COLUMNS))
    ap_sums = np.empty((n, radii_arr.size))
    ap_areas = np.empty((n, radii_arr.size))
    nv = var_a.size
    var_sums = np.empty((n, nv))
    var_areas = np.empty((n, nv))
    var_radii = np.empty((n, nv))
    stamp3 = np.empty((n, 3, 3))
    stamp5 = np.empty((n, 5, 5))
    # float64 chunks: one compiled specialisation, bounded extra memory
    for a in range(0, n, _CHUNK):
        b = min(a + _CHUNK, n)
        chunk = np.ascontiguousarray(frames[a:b], dtype=np.float64)
        kernels.measure_frames(
            chunk, gx[a:b], gy[a:b], sx[a:b], sy[a:b], int(opt.search_px),
            int(opt.box_px // 2), float(opt.annulus_px[0]), float(opt.annulus_px[1]),
            float(opt.clip_sigma), int(opt.clip_iters), radii_arr, var_a, var_b,
            float(fixed_width), int(centroid_code), opt.background == "median",
            int(opt.gauss_max_iter), opt.centroid == "lsq-asym", out[a:b], ap_sums[a:b],
            ap_areas[a:b], var_sums[a:b], var_areas[a:b], var_radii[a:b], stamp3[a:b],
            stamp5[a:b])
    return _KernelOutput(out, ap_sums, ap_areas, var_sums, var_areas, var_radii, stamp3, stamp5)


def _median_free_width(out: np.ndarray) -> float:
    """The median free-fit Gaussian width ``(width_x + width_y) / 2`` of the frames whose
    fit converged (0.7 px when none did): the width of a ``gauss-fixed`` run left unset."""
    ok = (out[:, kernels.IDX["ok_gauss"]] > 0)
    widths = 0.5 * (out[ok, kernels.IDX["width_x"]] + out[ok, kernels.IDX["width_y"]])
    widths = widths[np.isfinite(widths)]
    return float(np.median(widths)) if widths.size else 0.7


def _position_columns(out: np.ndarray, opt: PhotometrySection,
                      fixed: float) -> dict[str, np.ndarray]:
    """The centroid, width, noise-pixel and background columns of the kernels' ``out``.

    The fixed-width Gaussian's columns are there when ``fixed > 0``, the
    least-asymmetry ones when it is the chosen centroid.
    """
    col = {name: out[:, k] for name, k in kernels.IDX.items()}
    bg = col["bg_median"] if opt.background == "median" else col["bg_mean"]
    result: dict[str, np.ndarray] = {
        "peak_x": col["peak_x"], "peak_y": col["peak_y"],
        "x": col["x"], "y": col["y"], "x_col": col["x_col"], "y_col": col["y_col"],
        "x_gauss": col["x_gauss"], "y_gauss": col["y_gauss"],
        "width_x": col["width_x"], "width_y": col["width_y"],
        "gauss_ok": col["ok_gauss"] > 0,
        "noise_pixels": col["noise_pixels"],
        "background": bg, "background_mean": col["bg_mean"],
        "background_median": col["bg_median"], "background_sigma": col["bg_std"],
        "background_npix": col["bg_npix"],
    }
    if fixed > 0.0:
        result.update({"x_gfix": col["x_gfix"], "y_gfix": col["y_gfix"],
                       "gfix_ok": col["ok_gfix"] > 0})
        result["gauss_fixed_width"] = np.full(len(out), fixed)
    if opt.centroid == "lsq-asym":
        result.update({"x_lsq": col["x_lsq"], "y_lsq": col["y_lsq"],
                       "lsq_ok": col["ok_lsq"] > 0})
    return result


def _flux_columns(raw: _KernelOutput, bg: np.ndarray, radii: list[float], opt: PhotometrySection,
                  *, fowler: int, wait: int, read_noise_e: float) -> dict[str, np.ndarray]:
    """The aperture fluxes (net of ``bg`` times the area), the main flux's uncertainty,
    the variable apertures' fluxes and radii, and the stamps."""
    result: dict[str, np.ndarray] = {}
    net = raw.ap_sums - bg[:, None] * raw.ap_areas
    k_main = radii.index(float(opt.radius_px))
    result["flux"] = net[:, k_main]
    result["flux_err"] = flux_uncertainty(raw.ap_sums[:, k_main], bg, raw.ap_areas[:, k_main],
                                          raw.out[:, kernels.IDX["bg_npix"]], fowler=fowler,
                                          wait=wait, read_noise_e=read_noise_e,
                                          read=opt.noise_read)
    result["flux_raw"] = raw.ap_sums[:, k_main]
    result["aperture_area"] = raw.ap_areas[:, k_main]
    for k, r in enumerate(radii):
        if any(abs(r - float(q)) < 1e-12 for q in opt.radii_px):
            result[f"flux_{radius_name(r)}"] = net[:, k]
    for k, (a, b) in enumerate(opt.variable_apertures):
        name = variable_name(a, b)
        result[f"flux_{name}"] = raw.var_sums[:, k] - bg * raw.var_areas[:, k]
        result[f"radius_{name}"] = raw.var_radii[:, k]
    result["stamp3"] = raw.stamp3
    result["stamp5"] = raw.stamp5
    return result
