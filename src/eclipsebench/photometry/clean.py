"""Frame and pixel cleaning: flag bits, running medians, cosmic rays, outliers.

Frames are never dropped: each reason sets one bit of the ``flag`` column
(0 = good). The bits and their meanings are :data:`FLAG_BITS` and are written
into every table's metadata (``FLAGBITS``).
"""

from __future__ import annotations

from typing import overload

import numpy as np
from numba import njit
from scipy.ndimage import median_filter

__all__ = ["FLAG_BITS", "FLAG_DESCRIPTIONS", "FAULT_BITS", "flag_counts", "frame_faults",
           "keep_fault_reasons", "running_median", "nanmedian0", "robust_sigma", "outliers",
           "reject_cosmic_rays"]

#: bit value of each reason a frame is not good
FLAG_BITS = {
    "first_frame": 1,
    "nonfinite": 2,
    "cosmic_ray": 4,
    "bimsk": 8,
    "centroid_outlier": 16,
    "flux_outlier": 32,
    "fit_failed": 64,
    "no_star": 128,
    "constant": 256,
    "negative": 512,
}
FLAG_DESCRIPTIONS = {
    "first_frame": "first frame of a subarray cube (first-frame effect), dropped by default",
    "nonfinite": "a non-finite pixel reached the centroid box or an aperture (all-NaN frames too)",
    "cosmic_ray": "a pixel of the centroid box or apertures deviated from its running median "
                  "in time (replaced by that median)",
    "bimsk": "a pixel of the centroid box or apertures has a fatal bimsk bit",
    "centroid_outlier": "the center-of-light minus Gaussian centroid difference (x or y) "
                        "deviates from its running median by more than outlier_sigma",
    "flux_outlier": "flux deviates from its running median by more than outlier_sigma",
    "fit_failed": "the Gaussian centroid fit did not converge",
    "no_star": "no finite brightest pixel, non-positive net flux, or non-finite measurements "
               "(an all-zero frame too)",
    "constant": "every finite pixel has the same non-zero value (a frame that holds no image)",
    "negative": "the frame's strongest feature points down: a negated (sign-flipped) image",
}
#: the reasons :func:`frame_faults` gives; such frames stay out of every running statistic
FAULT_BITS = FLAG_BITS["no_star"] | FLAG_BITS["constant"] | FLAG_BITS["negative"]


def flag_counts(flag: np.ndarray) -> dict[str, int]:
    """Number of frames carrying each flag bit, plus ``good`` and ``total``."""
    flag = np.asarray(flag, dtype=np.int64)
    out = {name: int(np.count_nonzero(flag & bit)) for name, bit in FLAG_BITS.items()}
    out["good"] = int(np.count_nonzero(flag == 0))
    out["total"] = int(flag.size)
    return out


def frame_faults(frames: np.ndarray) -> np.ndarray:
    """Flag bits of frames that cannot hold a star image, judged before any cleaning.

    ``no_star`` for an all-zero frame, ``constant`` for a frame whose finite
    pixels all have one non-zero value, ``negative`` for a negated image (its
    finite pixels reach farther below their median than twice as far above
    it). Frames without a finite pixel get 0 here (the ``nonfinite`` flag
    covers them). Such frames must stay out of the running statistics that
    judge their neighbours (cosmic rays, outliers).

    Examples
    --------
    >>> star = np.zeros((3, 5, 5)); star[:, 2, 2] = 100.0; star += 1.0
    >>> star[1] = 0.0; star[2] = -star[2]
    >>> frame_faults(star).tolist()
    [0, 128, 512]
    """
    frames = np.asarray(frames)
    n = frames.shape[0]
    flat = frames.reshape(n, -1)
    if not np.issubdtype(flat.dtype, np.floating):
        flat = flat.astype(np.float64)
    finite = np.isfinite(flat)
    out = np.zeros(n, dtype=np.int64)
    any_finite = finite.any(axis=1)
    if not any_finite.any():
        return out
    all_finite = finite.all(axis=1)
    if all_finite.all():   # the extremes are exact in the frames' own precision
        hi = flat.max(axis=1).astype(np.float64)
        lo = flat.min(axis=1).astype(np.float64)
    else:
        hi = np.where(finite, flat, -np.inf).max(axis=1).astype(np.float64)
        lo = np.where(finite, flat, np.inf).min(axis=1).astype(np.float64)
    med = np.full(n, np.nan)
    # The median is needed only where it could make the frame negated: it lies within one
    # standard deviation of the mean, so a frame whose mean + SD (with a margin for
    # rounding) is not negated is not (any star frame; issue 40: the median of every frame
    # cost a third of the photometry of a twin). The others get numpy's median, as before.
    whole = np.flatnonzero(all_finite)
    if whole.size:
        rows = flat if whole.size == n else flat[whole]
        mean = rows.mean(axis=1, dtype=np.float64)
        bound = mean + rows.std(axis=1, dtype=np.float64)
        slack = 1e-9 * (np.abs(hi[whole]) + np.abs(lo[whole]) + np.abs(bound)) + 1e-300
        clear = (bound - lo[whole]) + slack < 2.0 * (hi[whole] - bound)
        need = whole[~clear]
        med[whole[clear]] = bound[clear]
        if need.size:
            med[need] = np.median(flat[need].astype(np.float64), axis=1)
    partial = any_finite & ~all_finite
    if partial.any():
        med[partial] = np.nanmedian(np.where(finite[partial], flat[partial].astype(np.float64),
                                             np.nan), axis=1)
    flat_frame = any_finite & (hi == lo)
    out[flat_frame & (hi == 0)] = FLAG_BITS["no_star"]
    out[flat_frame & (hi != 0)] = FLAG_BITS["constant"]
    with np.errstate(invalid="ignore"):
        negated = any_finite & ~flat_frame & ((med - lo) > 2.0 * (hi - med))
    out[negated] = FLAG_BITS["negative"]
    return out


def keep_fault_reasons(flag: np.ndarray, faults: np.ndarray) -> np.ndarray:
    """``flag`` with each faulty frame's reason being its fault alone (plus ``first_frame``).

    Measuring a frame without an image sets other bits too (``no_star``,
    ``nonfinite``); the fault from :func:`frame_faults` is the reason.
    """
    flag = np.asarray(flag)
    faults = np.asarray(faults)
    return np.where(faults != 0, (flag & FLAG_BITS["first_frame"]) | faults, flag)


def running_median(values: np.ndarray, window: int, valid: np.ndarray | None = None) -> np.ndarray:
    """Running median of a series over ``window`` samples (odd), ignoring invalid ones.

    Invalid or non-finite samples are skipped (the window runs over the valid
    samples only) and get the running median of their nearest valid
    neighbours. Edges use the nearest valid value (``mode="nearest"``).
    """
    values = np.asarray(values, dtype=float)
    ok = np.isfinite(values) if valid is None else (np.asarray(valid, bool) & np.isfinite(values))
    out = np.full(values.shape, np.nan)
    if not ok.any():
        return out
    idx = np.flatnonzero(ok)
    med = median_filter(values[idx], size=min(int(window), idx.size) | 1, mode="nearest")
    out[idx] = med
    # fill the invalid samples from the nearest valid one before them (or the first)
    pos = np.clip(np.searchsorted(idx, np.arange(values.size), side="right") - 1, 0, None)
    out[~ok] = med[pos[~ok]]
    return out


@njit(cache=True)
def _median_in_time(values, size):
    """``median_filter(values, size=(size, 1), mode="nearest")`` of finite ``values`` (m, k):
    each column's running median over ``size`` (odd) samples, the first and last sample
    repeated beyond the ends. A median of an odd count is one of the values, so this gives
    scipy's bytes; it keeps each window sorted and moves it one sample at a time (a few
    comparisons per sample, where scipy's 2-d filter costs 20 times more: issue 40)."""
    if size == 9:
        return _median9_in_time(values)
    m, k = values.shape
    h = size // 2
    out = np.empty((m, k))
    win = np.empty(size)
    for c in range(k):
        for t in range(size):
            win[t] = values[min(max(t - h, 0), m - 1), c]
        win.sort()
        out[0, c] = win[h]
        for i in range(1, m):
            old = values[max(i - 1 - h, 0), c]
            new = values[min(i + h, m - 1), c]
            if old != new:
                p = 0
                while win[p] != old:
                    p += 1
                if new > old:
                    while p + 1 < size and win[p + 1] < new:
                        win[p] = win[p + 1]
                        p += 1
                else:
                    while p > 0 and win[p - 1] > new:
                        win[p] = win[p - 1]
                        p -= 1
                win[p] = new
            out[i, c] = win[h]
    return out


#: The compare-exchanges of a median of 9 (Paeth's network, "opt_med9" in Devillard 1998):
#: after them the fifth value is the median.
_MEDIAN9_PAIRS = ((1, 2), (4, 5), (7, 8), (0, 1), (3, 4), (6, 7), (1, 2), (4, 5), (7, 8),
                  (0, 3), (5, 8), (4, 7), (3, 6), (1, 4), (2, 5), (4, 7), (4, 2), (6, 4), (4, 2))


@njit(cache=True)
def _median9_in_time(values):
    """:func:`_median_in_time` of the default 9-frame window (the same values: the median of
    nine values is one of them): the 19 compare-exchanges of :data:`_MEDIAN9_PAIRS` on the
    window of every column at once, without branches, where keeping the window sorted
    mispredicts a branch or two per sample (three times faster on a twin's frames, issue 40)."""
    m, k = values.shape
    out = np.empty((m, k))
    p = np.empty((9, k))
    for i in range(m):
        for t in range(9):
            row = values[min(max(i - 4 + t, 0), m - 1)]
            for c in range(k):
                p[t, c] = row[c]
        for a, b in _MEDIAN9_PAIRS:
            pa = p[a]
            pb = p[b]
            for c in range(k):
                x = pa[c]
                y = pb[c]
                pa[c] = min(x, y)
                pb[c] = max(x, y)
        for c in range(k):
            out[i, c] = p[4, c]
    return out


def nanmedian0(values: np.ndarray) -> np.ndarray:
    """Median along axis 0 skipping NaNs; NaN (without a warning) where all are NaN."""
    values = np.asarray(values, dtype=float)
    if values.shape[0] == 0:
        return np.full(values.shape[1:], np.nan)
    if not np.isnan(values).any():  # the same values as numpy's nanmedian, without its loop
        return np.median(values, axis=0)
    allnan = np.isnan(values).all(axis=0)
    out = np.nanmedian(np.where(allnan[None], 0.0, values), axis=0)
    return np.where(allnan, np.nan, out)


@overload
def robust_sigma(resid: np.ndarray, axis: None = None) -> float: ...
@overload
def robust_sigma(resid: np.ndarray, axis: int) -> np.ndarray: ...
def robust_sigma(resid: np.ndarray, axis: int | None = None) -> float | np.ndarray:
    """1.4826 x the median absolute deviation about zero of ``resid`` (NaNs skipped).

    With ``axis=None`` the whole array is used; with ``axis=0`` one value per
    column (NaN where a column has no finite value).
    """
    a = np.abs(np.asarray(resid, dtype=float))
    if axis is None:
        a = a[np.isfinite(a)]
        return 1.4826 * float(np.median(a)) if a.size else float("nan")
    if axis != 0:
        raise ValueError("axis: expected None or 0")
    return 1.4826 * nanmedian0(a)


def outliers(values: np.ndarray, window: int, nsigma: float,
             valid: np.ndarray | None = None) -> np.ndarray:
    """Samples farther than ``nsigma`` robust sigmas from their running median.

    Non-finite samples are not reported here (other flags cover them).
    """
    values = np.asarray(values, dtype=float)
    ok = np.isfinite(values) if valid is None else (np.asarray(valid, bool) & np.isfinite(values))
    if window <= 0 or ok.sum() < 3:
        return np.zeros(values.shape, dtype=bool)
    resid = values - running_median(values, window, ok)
    sigma = robust_sigma(resid[ok])
    if not sigma > 0:
        return np.zeros(values.shape, dtype=bool)
    return np.isfinite(values) & (np.abs(resid) > nsigma * sigma)


def reject_cosmic_rays(cube: np.ndarray, window: int, nsigma: float,
                       valid: np.ndarray | None = None,
                       read_var_e2: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Replace per-pixel outliers in time by the pixel's running median.

    Parameters
    ----------
    cube : ndarray
        (n, ny, nx) pixel values of consecutive frames.
    window : int
        Running-median window in frames (odd); with fewer valid frames than
        that, nothing is rejected.
    nsigma : float
        Threshold in robust sigmas of each pixel's residuals from its running
        median (1.4826 x MAD over the whole series).
    valid : ndarray of bool, optional
        Frames used to build the medians (e.g. not the first frames).
    read_var_e2 : float
        Read-noise variance per pixel (electrons^2). The noise of a pixel is at
        least ``sqrt(max(median, 0) + read_var_e2)`` (photon + read noise), so a
        pixel whose residuals are quantised or nearly constant is not
        over-flagged.

    Returns
    -------
    cleaned : ndarray
        A copy of ``cube`` with outlying pixels replaced.
    hits : ndarray of bool
        (n, ny, nx), True where a pixel was replaced.
    """
    cube = np.asarray(cube)
    n = cube.shape[0]
    cleaned = np.array(cube, dtype=np.result_type(cube.dtype, np.float32), copy=True)
    hits = np.zeros(cube.shape, dtype=bool)
    if window <= 0 or n < 3:
        return cleaned, hits
    use = np.ones(n, dtype=bool) if valid is None else np.asarray(valid, bool)
    idx = np.flatnonzero(use)
    if idx.size < max(int(window), 3):  # too few frames for a running median in time
        return cleaned, hits
    size = min(int(window), idx.size) | 1
    # pixels are independent: one row of pixels at a time bounds the temporaries
    for j in range(cube.shape[1]):
        sub = np.asarray(cube[idx, j], dtype=float)          # (m, nx)
        finite = np.isfinite(sub)
        if finite.all():   # nothing to fill: no median over time to take for it (issue 40)
            filled = sub
        else:
            fill = nanmedian0(np.where(finite, sub, np.nan))
            filled = np.where(finite, sub, np.where(np.isfinite(fill), fill, 0.0)[None])
        med = _median_in_time(filled, size)
        resid = np.where(finite, sub - med, np.nan)
        sigma = robust_sigma(resid, axis=0)
        floor = np.sqrt(np.clip(med, 0.0, None) + float(read_var_e2))
        sigma = np.where(np.isfinite(sigma), np.maximum(sigma[None], floor), floor)
        with np.errstate(invalid="ignore"):
            bad = finite & (np.abs(resid) > nsigma * np.where(sigma > 0, sigma, np.inf))
        if bad.any():
            rows = idx[np.flatnonzero(bad.any(axis=1))]
            hits[idx, j] = bad
            cleaned[rows, j] = np.where(hits[rows, j], med[np.searchsorted(idx, rows)],
                                        cleaned[rows, j])
    return cleaned, hits
