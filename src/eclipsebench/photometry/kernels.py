"""Per-frame measurement kernels, compiled with numba and run over all frames.

Each ``_frame_*`` function is the one definition of an estimator on one
frame; :func:`measure_frames` runs the whole measurement set over a stack of
frames in parallel (``numba.prange``). The public, documented entry points are
:func:`.measure.measure_stack` (the whole set) and the single estimators of
:mod:`.estimators`; this module holds the compiled pieces they share.

Conventions: ``frames[k, j, i]`` is frame ``k``, row ``y = j``, column
``x = i``; a pixel's centre is at integer coordinates (0-based) and it covers
``[i - 0.5, i + 0.5] x [j - 0.5, j + 0.5]``. Values are electrons per pixel.
Non-finite pixels make the quantities that use them NaN (the frame is then
flagged by the caller), except in the background annulus, where they are
skipped.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .overlap import _signed_area

# Columns of the scalar output array of measure_frames.
COLUMNS = ("peak_x", "peak_y", "bg0", "x_col", "y_col", "noise_pixels", "x_gauss", "y_gauss",
           "width_x", "width_y", "amp_gauss", "offset_gauss", "ok_gauss", "x_gfix", "y_gfix",
           "ok_gfix", "x_lsq", "y_lsq", "ok_lsq", "x", "y", "bg_mean", "bg_median", "bg_std",
           "bg_npix")
IDX = {name: k for k, name in enumerate(COLUMNS)}
N_COLUMNS = len(COLUMNS)

CENTROID_CODES = {"col": 0, "gauss": 1, "gauss-fixed": 2, "lsq-asym": 3}
#: Starting width (px) of the free-width Gaussian fit.
GAUSS_START_WIDTH_PX = 0.7
#: Least-asymmetry search grid half-width and window radius (px).
LSQ_GRID_HALF_PX = 2
LSQ_WINDOW_PX = 3
_SQRT2 = math.sqrt(2.0)
_INV_SQRT2PI = 1.0 / math.sqrt(2.0 * math.pi)


# ----------------------------------------------------------------------------- peak, background
@njit(cache=True)
def _frame_peak(img, gx, gy, half):
    """Brightest finite pixel within ``half`` px of (gx, gy); (-1, -1) if none."""
    ny, nx = img.shape
    best = -np.inf
    bx = -1
    by = -1
    for j in range(max(gy - half, 0), min(gy + half + 1, ny)):
        for i in range(max(gx - half, 0), min(gx + half + 1, nx)):
            v = img[j, i]
            if v > best:  # False for NaN
                best = v
                bx = i
                by = j
    return bx, by


@njit(cache=True)
def _frame_annulus(img, xc, yc, r_in, r_out, clip_sigma, clip_iters, buf):
    """Annulus statistics about (xc, yc) over pixels whose centres lie in [r_in, r_out].

    Returns (mean, sigma-clipped median, clipped standard deviation, number of
    pixels used by the mean); with ``clip_iters <= 0`` only the mean (the
    median and deviation are NaN). Non-finite pixels are skipped. ``buf`` is scratch
    space at least as large as the number of pixels in the annulus.
    """
    ny, nx = img.shape
    n = 0
    total = 0.0
    ri2 = r_in * r_in
    ro2 = r_out * r_out
    j0 = max(int(math.floor(yc - r_out)), 0)
    j1 = min(int(math.ceil(yc + r_out)), ny - 1)
    i0 = max(int(math.floor(xc - r_out)), 0)
    i1 = min(int(math.ceil(xc + r_out)), nx - 1)
    for j in range(j0, j1 + 1):
        dy2 = (j - yc) * (j - yc)
        for i in range(i0, i1 + 1):
            d2 = (i - xc) * (i - xc) + dy2
            if d2 >= ri2 and d2 <= ro2:
                v = img[j, i]
                if math.isfinite(v):
                    buf[n] = v
                    total += v
                    n += 1
    if n == 0:
        return np.nan, np.nan, np.nan, 0
    mean = total / n
    if clip_iters <= 0:  # the mean only
        return mean, np.nan, np.nan, n
    vals = buf[:n]
    vals.sort()  # in place: buf is scratch space
    lo = 0
    hi = n  # the current sample is vals[lo:hi]
    for _ in range(max(clip_iters, 1)):
        med, std = _median_std_sorted(vals, lo, hi)
        if clip_sigma <= 0 or std == 0.0:
            break
        new_lo = lo
        while new_lo < hi and vals[new_lo] < med - clip_sigma * std:
            new_lo += 1
        new_hi = hi
        while new_hi > new_lo and vals[new_hi - 1] > med + clip_sigma * std:
            new_hi -= 1
        if (new_lo == lo and new_hi == hi) or new_hi - new_lo < 3:
            break
        lo = new_lo
        hi = new_hi
    # statistics of the surviving values (as astropy's sigma_clipped_stats)
    med, std = _median_std_sorted(vals, lo, hi)
    return mean, med, std, n


@njit(cache=True, inline="always")
def _median_std_sorted(vals, lo, hi):
    m = hi - lo
    if m % 2 == 1:
        med = vals[lo + m // 2]
    else:
        med = 0.5 * (vals[lo + m // 2 - 1] + vals[lo + m // 2])
    s = 0.0
    s2 = 0.0
    for k in range(lo, hi):
        s += vals[k]
        s2 += vals[k] * vals[k]
    var = s2 / m - (s / m) ** 2
    return med, (math.sqrt(var) if var > 0 else 0.0)


# ----------------------------------------------------------------------------- centroids
@njit(cache=True)
def _frame_col(img, px, py, h, bg):
    """Center of light and noise pixels over the (2h+1)^2 box about (px, py).

    Paper Eqs. ``x_centroid``, ``y_centroid`` and ``noise_pixels`` on the
    background-subtracted values. Returns (x, y, beta); NaN if the box leaves
    the image, holds a non-finite value, or has no positive net flux.
    """
    ny, nx = img.shape
    if px - h < 0 or py - h < 0 or px + h >= nx or py + h >= ny:
        return np.nan, np.nan, np.nan
    s = 0.0
    sx = 0.0
    sy = 0.0
    s2 = 0.0
    for j in range(py - h, py + h + 1):
        for i in range(px - h, px + h + 1):
            f = img[j, i] - bg
            s += f
            sx += i * f
            sy += j * f
            s2 += f * f
    if not (s > 0.0) or not math.isfinite(s2):
        return np.nan, np.nan, np.nan
    return sx / s, sy / s, s * s / s2


@njit(cache=True, inline="always")
def _pixel_integrals(lo, n, c, s, e, de_dc, de_ds):
    """Integrated unit Gaussian over pixels lo..lo+n-1 and its derivatives."""
    inv_s = 1.0 / s
    u_prev = (lo - 0.5 - c) * inv_s
    cdf_prev = 0.5 * (1.0 + math.erf(u_prev / _SQRT2))
    pdf_prev = _INV_SQRT2PI * math.exp(-0.5 * u_prev * u_prev)
    for k in range(n):
        u = (lo + k + 0.5 - c) * inv_s
        cdf = 0.5 * (1.0 + math.erf(u / _SQRT2))
        pdf = _INV_SQRT2PI * math.exp(-0.5 * u * u)
        e[k] = cdf - cdf_prev
        de_dc[k] = -(pdf - pdf_prev) * inv_s
        de_ds[k] = -(u * pdf - u_prev * pdf_prev) * inv_s
        u_prev = u
        cdf_prev = cdf
        pdf_prev = pdf


@njit(cache=True)
def _solve_small(a, b, n):
    """Solve a x = b in place (Gaussian elimination, partial pivoting); False if singular."""
    for col in range(n):
        piv = col
        big = abs(a[col, col])
        for r in range(col + 1, n):
            if abs(a[r, col]) > big:
                big = abs(a[r, col])
                piv = r
        if not (big > 0.0):
            return False
        if piv != col:
            for k in range(n):
                t = a[col, k]
                a[col, k] = a[piv, k]
                a[piv, k] = t
            t = b[col]
            b[col] = b[piv]
            b[piv] = t
        for r in range(col + 1, n):
            f = a[r, col] / a[col, col]
            for k in range(col, n):
                a[r, k] -= f * a[col, k]
            b[r] -= f * b[col]
    for r in range(n - 1, -1, -1):
        s = b[r]
        for k in range(r + 1, n):
            s -= a[r, k] * b[k]
        b[r] = s / a[r, r]
    return True


@njit(cache=True)
def _gauss_chi2(d, x_lo, y_lo, n, p, fixed, width, ex, ey, dex, dey, dexs, deys):
    sx = width if fixed else p[3]
    sy = width if fixed else p[4]
    _pixel_integrals(x_lo, n, p[1], sx, ex, dex, dexs)
    _pixel_integrals(y_lo, n, p[2], sy, ey, dey, deys)
    c = p[3] if fixed else p[5]
    chi2 = 0.0
    for j in range(n):
        for i in range(n):
            r = d[j, i] - (p[0] * ex[i] * ey[j] + c)
            chi2 += r * r
    return chi2


# per-axis vectors (0 value, 1 d/dcentre, 2 d/dwidth, 3 ones) of each Jacobian column,
# parameters (A, x0, y0, C) with a fixed width, (A, x0, y0, sx, sy, C) with free widths
_GAUSS_FIXED_X = np.array([0, 1, 0, 3], dtype=np.int64)
_GAUSS_FIXED_Y = np.array([0, 0, 1, 3], dtype=np.int64)
_GAUSS_FREE_X = np.array([0, 1, 0, 2, 0, 3], dtype=np.int64)
_GAUSS_FREE_Y = np.array([0, 0, 1, 0, 2, 3], dtype=np.int64)


@njit(cache=True)
def _frame_gauss(img, px, py, h, bg, x0, y0, width, fixed, max_iter):
    """Least-squares fit of a pixel-integrated 2-D Gaussian plus a constant.

    The model of pixel (i, j) is ``A * Ex_i * Ey_j + C`` with
    ``Ex_i = Phi((i + 1/2 - x0) / sx) - Phi((i - 1/2 - x0) / sx)`` (the
    Gaussian integrated over the pixel), fitted by Levenberg-Marquardt to the
    background-subtracted (2h+1)^2 box about (px, py). With ``fixed`` the
    widths are held at ``width``. Returns (x0, y0, sx, sy, A, C, ok).
    """
    ny, nx = img.shape
    nan = np.nan
    if px - h < 0 or py - h < 0 or px + h >= nx or py + h >= ny or not (
            math.isfinite(x0) and math.isfinite(y0)):
        return nan, nan, nan, nan, nan, nan, 0.0
    n = 2 * h + 1
    x_lo = px - h
    y_lo = py - h
    d = np.empty((n, n))
    finite, total = _gauss_box(img, x_lo, y_lo, bg, d)
    if not finite:
        return nan, nan, nan, nan, nan, nan, 0.0
    p = _gauss_start(total, x0, y0, width, fixed)
    converged = _gauss_levenberg_marquardt(d, x_lo, y_lo, h, p, fixed, width, x0, y0, max_iter)
    if fixed:
        return p[1], p[2], width, width, p[0], p[3], 1.0 if converged else 0.0
    return p[1], p[2], p[3], p[4], p[0], p[5], 1.0 if converged else 0.0


@njit(cache=True)
def _gauss_box(img, x_lo, y_lo, bg, d):
    """Fill ``d`` (n, n) with the image minus ``bg`` from corner (x_lo, y_lo).

    Returns (True, the sum of ``d``), or (False, 0) at the first non-finite value.
    """
    n = d.shape[0]
    total = 0.0
    for j in range(n):
        for i in range(n):
            v = img[y_lo + j, x_lo + i] - bg
            if not math.isfinite(v):
                return False, 0.0
            d[j, i] = v
            total += v
    return True, total


@njit(cache=True)
def _gauss_start(total, x0, y0, width, fixed):
    """Starting parameters: (A, x0, y0, C) with a fixed width, else (A, x0, y0, sx, sy, C).

    The amplitude starts at the box's sum, the widths at ``width``, C at 0.
    """
    npar = 4 if fixed else 6
    p = np.empty(npar)
    p[0] = total
    p[1] = x0
    p[2] = y0
    if fixed:
        p[3] = 0.0
    else:
        p[3] = width
        p[4] = width
        p[5] = 0.0
    return p


@njit(cache=True)
def _gauss_levenberg_marquardt(d, x_lo, y_lo, h, p, fixed, width, x0, y0, max_iter):
    """Levenberg-Marquardt iterations of the Gaussian fit to the box ``d``, updating ``p``.

    Stops after ``max_iter`` iterations, when the centre moves by less than
    1e-5 px or chi^2 by less than 1e-14 of itself, or when no damping gives
    a downhill step. Returns whether it converged.
    """
    n = d.shape[0]
    npar = p.shape[0]
    ex = np.empty(n)
    ey = np.empty(n)
    dex = np.empty(n)
    dey = np.empty(n)
    dexs = np.empty(n)
    deys = np.empty(n)
    jtj = np.empty((npar, npar))
    jtr = np.empty(npar)
    a = np.empty((npar, npar))
    step = np.empty(npar)
    trial = np.empty(npar)
    # The model A Ex_i Ey_j + C is separable, so every Jacobian column is
    # coef * U[i] * V[j] with U, V taken from per-axis vectors (value,
    # d/dcentre, d/dwidth, ones): J^T J entries are products of 1-D sums.
    xb = np.empty((4, n))
    yb = np.empty((4, n))
    sxx = np.empty((4, 4))
    syy = np.empty((4, 4))
    ry = np.empty((4, n))
    res = np.empty((n, n))
    coef = np.empty(npar)
    # Jacobian column q is built from x vector cx_idx[q] and y vector cy_idx[q];
    # A multiplies all but the amplitude and constant
    cx_idx = _GAUSS_FIXED_X if fixed else _GAUSS_FREE_X
    cy_idx = _GAUSS_FIXED_Y if fixed else _GAUSS_FREE_Y
    chi2 = _gauss_chi2(d, x_lo, y_lo, n, p, fixed, width, ex, ey, dex, dey, dexs, deys)
    lam = 1e-3
    converged = False
    fresh = True  # ex, ey and their derivatives hold the values at p
    for _ in range(max_iter):
        if not fresh:  # a rejected trial overwrote them
            chi2 = _gauss_chi2(d, x_lo, y_lo, n, p, fixed, width, ex, ey, dex, dey, dexs, deys)
        c = p[3] if fixed else p[5]
        _axis_basis(ex, dex, dexs, xb, sxx)
        _axis_basis(ey, dey, deys, yb, syy)
        _gauss_residual_rows(d, p[0], c, ex, ey, yb, res, ry)
        _gauss_normal_equations(p, cx_idx, cy_idx, xb, ry, sxx, syy, coef, jtj, jtr)
        improved, converged, chi2, lam = _gauss_damped_step(
            d, x_lo, y_lo, h, p, fixed, width, x0, y0, chi2, lam, jtj, jtr, a, step, trial,
            ex, ey, dex, dey, dexs, deys)
        fresh = improved
        if not improved:
            # no downhill step: p is a (numerical) minimum unless the first try failed
            converged = lam >= 1e12 and math.isfinite(chi2)
            break
        if converged:
            break
    return converged


@njit(cache=True)
def _axis_basis(e, de_dc, de_ds, basis, gram):
    """One axis's vectors (value, d/dcentre, d/dwidth, ones) as the rows of ``basis``
    (4, n), and their inner products in ``gram`` (4, 4)."""
    n = e.shape[0]
    for i in range(n):
        basis[0, i] = e[i]
        basis[1, i] = de_dc[i]
        basis[2, i] = de_ds[i]
        basis[3, i] = 1.0
    for u in range(4):
        for v in range(u, 4):
            s = 0.0
            for i in range(n):
                s += basis[u, i] * basis[v, i]
            gram[u, v] = s
            gram[v, u] = s


@njit(cache=True)
def _gauss_residual_rows(d, amp, c, ex, ey, yb, res, ry):
    """Residuals ``res = d - (amp Ex Ey + c)`` and their projections ``ry[b, i] =
    sum_j res[j, i] yb[b, j]`` on the y-axis vectors."""
    n = d.shape[0]
    for j in range(n):
        for i in range(n):
            res[j, i] = d[j, i] - (amp * ex[i] * ey[j] + c)
    for b in range(4):
        for i in range(n):
            acc = 0.0
            for j in range(n):
                acc += res[j, i] * yb[b, j]
            ry[b, i] = acc


@njit(cache=True)
def _gauss_normal_equations(p, cx_idx, cy_idx, xb, ry, sxx, syy, coef, jtj, jtr):
    """``J^T J`` and ``J^T r`` from the per-axis sums (see :func:`_gauss_levenberg_marquardt`)."""
    n = xb.shape[1]
    npar = p.shape[0]
    for q in range(npar):
        coef[q] = 1.0 if (q == 0 or cx_idx[q] == 3) else p[0]
    for q in range(npar):
        acc = 0.0
        for i in range(n):
            acc += xb[cx_idx[q], i] * ry[cy_idx[q], i]
        jtr[q] = coef[q] * acc
        for k in range(q, npar):
            v = coef[q] * coef[k] * sxx[cx_idx[q], cx_idx[k]] * syy[cy_idx[q], cy_idx[k]]
            jtj[q, k] = v
            jtj[k, q] = v


@njit(cache=True)
def _gauss_damped_step(d, x_lo, y_lo, h, p, fixed, width, x0, y0, chi2, lam, jtj, jtr, a, step,
                       trial, ex, ey, dex, dey, dexs, deys):
    """Raise the damping ``lam`` (x10) until a step lowers chi^2, then take it.

    A step is tried only if its widths stay within 0.05-10 px and its centre
    within ``h`` px of (x0, y0). Returns (improved, converged, chi2, lam);
    when improved, ``p`` holds the new parameters and ``ex``... the model's
    vectors at them.
    """
    n = d.shape[0]
    npar = p.shape[0]
    while lam < 1e12:
        for q in range(npar):
            for k in range(npar):
                a[q, k] = jtj[q, k]
            a[q, q] += lam * max(jtj[q, q], 1e-300)
            step[q] = jtr[q]
        if _solve_small(a, step, npar):
            for q in range(npar):
                trial[q] = p[q] + step[q]
            ok_w = fixed or (trial[3] > 0.05 and trial[4] > 0.05
                             and trial[3] < 10.0 and trial[4] < 10.0)
            if ok_w and abs(trial[1] - x0) < h and abs(trial[2] - y0) < h:
                c2 = _gauss_chi2(d, x_lo, y_lo, n, trial, fixed, width, ex, ey, dex, dey,
                                 dexs, deys)
                if c2 <= chi2:
                    for q in range(npar):
                        p[q] = trial[q]
                    lam = max(lam * 0.1, 1e-9)
                    converged = (abs(step[1]) < 1e-5 and abs(step[2]) < 1e-5) or (
                        chi2 - c2 <= 1e-14 * chi2)
                    return True, converged, c2, lam
        lam *= 10.0
    return False, False, chi2, lam


@njit(cache=True)
def _frame_lsq_asym(img, px, py, bg, grid_h, win_r):
    """Least-asymmetry centroid (Lust et al. 2014) about the peak pixel.

    For each integer candidate centre within ``grid_h`` (>= 2) px of (px, py),
    the asymmetry is the sum over rings of equal distance (pixels within
    ``win_r`` px) of the squared deviations from the ring mean. The centre is
    the vertex of the parabola through the smallest asymmetry within 1 px of
    (px, py) and its two neighbours along each axis.
    Returns (x, y, ok).
    """
    ny, nx = img.shape
    reach = grid_h + win_r
    if px - reach < 0 or py - reach < 0 or px + reach >= nx or py + reach >= ny:
        return np.nan, np.nan, 0.0
    ng = 2 * grid_h + 1
    asym = np.empty((ng, ng))
    nring = win_r * win_r + 1  # ring index = d^2 (integer offsets)
    s1 = np.empty(nring)
    s2 = np.empty(nring)
    cnt = np.empty(nring)
    for gj in range(ng):
        cy = py - grid_h + gj
        for gi in range(ng):
            cx = px - grid_h + gi
            for k in range(nring):
                s1[k] = 0.0
                s2[k] = 0.0
                cnt[k] = 0.0
            for dy in range(-win_r, win_r + 1):
                for dx in range(-win_r, win_r + 1):
                    d2 = dx * dx + dy * dy
                    if d2 <= win_r * win_r:
                        v = img[cy + dy, cx + dx] - bg
                        s1[d2] += v
                        s2[d2] += v * v
                        cnt[d2] += 1.0
            a = 0.0
            for k in range(nring):
                if cnt[k] > 1.0:
                    a += s2[k] - s1[k] * s1[k] / cnt[k]
            asym[gj, gi] = a
    # the unnormalised asymmetry is also small far from the star (little light in the
    # window), so the minimum is sought within 1 px of the brightest pixel only
    gi0 = 0
    gj0 = 0
    amin = np.inf
    for gj in range(grid_h - 1, grid_h + 2):
        for gi in range(grid_h - 1, grid_h + 2):
            if asym[gj, gi] < amin:
                amin = asym[gj, gi]
                gi0 = gi
                gj0 = gj
    if not math.isfinite(amin) or gi0 == 0 or gj0 == 0 or gi0 == ng - 1 or gj0 == ng - 1:
        return np.nan, np.nan, 0.0
    # vertex of the parabola through the minimum and its two neighbours, per axis
    cx = asym[gj0, gi0 - 1] - 2.0 * amin + asym[gj0, gi0 + 1]
    cy = asym[gj0 - 1, gi0] - 2.0 * amin + asym[gj0 + 1, gi0]
    if not (cx > 0.0 and cy > 0.0):
        return np.nan, np.nan, 0.0
    ox = 0.5 * (asym[gj0, gi0 - 1] - asym[gj0, gi0 + 1]) / cx
    oy = 0.5 * (asym[gj0 - 1, gi0] - asym[gj0 + 1, gi0]) / cy
    return px - grid_h + gi0 + ox, py - grid_h + gj0 + oy, 1.0


# ----------------------------------------------------------------------------- apertures
@njit(cache=True)
def _frame_apertures(img, xc, yc, radii, sums, areas):
    """Exact-overlap aperture sums for each radius (``sums[k] = sum w f``, ``areas[k] = sum w``).

    For each radius the signed quadrant areas ``S`` are evaluated once per
    pixel corner (shared by the four pixels that meet there); a pixel's
    overlap is ``S11 - S01 - S10 + S00``. Pixels entirely inside get weight 1
    and pixels entirely outside are skipped exactly. Pixels outside the image
    contribute nothing (as in photutils); a non-finite pixel with non-zero
    weight makes that radius's sum NaN.
    """
    ny, nx = img.shape
    nr = radii.shape[0]
    for k in range(nr):
        sums[k] = 0.0
        areas[k] = 0.0
    if not (math.isfinite(xc) and math.isfinite(yc)):
        for k in range(nr):
            sums[k] = np.nan
            areas[k] = np.nan
        return
    rmax = 0.0
    for k in range(nr):
        if radii[k] > rmax:
            rmax = radii[k]
    if not (rmax > 0.0):
        for k in range(nr):
            sums[k] = np.nan
            areas[k] = np.nan
        return
    side = int(2.0 * rmax + 4.0)
    corners = np.empty((side, side))
    for k in range(nr):
        r = radii[k]
        if not (r > 0.0):
            sums[k] = np.nan
            areas[k] = np.nan
            continue
        r2 = r * r
        # pixels i with i + 1/2 > xc - r and i - 1/2 < xc + r
        i0 = max(int(math.floor(xc - r - 0.5)) + 1, 0)
        i1 = min(int(math.ceil(xc + r + 0.5)) - 1, nx - 1)
        j0 = max(int(math.floor(yc - r - 0.5)) + 1, 0)
        j1 = min(int(math.ceil(yc + r + 0.5)) - 1, ny - 1)
        if i1 < i0 or j1 < j0:
            continue
        for a in range(j1 - j0 + 2):
            cy = j0 - 0.5 + a - yc
            for b in range(i1 - i0 + 2):
                corners[a, b] = _signed_area(i0 - 0.5 + b - xc, cy, r)
        s = 0.0
        ar = 0.0
        for j in range(j0, j1 + 1):
            a = j - j0
            ady = max(abs(j - yc) - 0.5, 0.0)
            fdy = abs(j - yc) + 0.5
            for i in range(i0, i1 + 1):
                adx = max(abs(i - xc) - 0.5, 0.0)
                if adx * adx + ady * ady >= r2:
                    continue
                fdx = abs(i - xc) + 0.5
                if fdx * fdx + fdy * fdy <= r2:
                    w = 1.0
                else:
                    b = i - i0
                    w = (corners[a + 1, b + 1] - corners[a + 1, b] - corners[a, b + 1]
                         + corners[a, b])
                    if w <= 0.0:
                        continue
                    if w > 1.0:
                        w = 1.0
                s += w * img[j, i]
                ar += w
        sums[k] = s
        areas[k] = ar


# ----------------------------------------------------------------------------- the whole set
@njit(cache=True, parallel=True)
def measure_frames(frames, guess_x, guess_y, stamp_x, stamp_y, search_half, box_half,
                   r_in, r_out, clip_sigma, clip_iters, radii, var_a, var_b, fixed_width,
                   centroid_code, use_median, max_iter, want_lsq, out, ap_sums, ap_areas,
                   var_sums, var_areas, var_radii, stamp3, stamp5):
    """Run every per-frame measurement on ``frames`` (n, ny, nx), in parallel.

    Inputs per frame: ``guess_x/guess_y`` (int, the pixel about which the
    brightest pixel is searched within ``search_half``), ``stamp_x/stamp_y``
    (int, the centre pixel of the 3x3 and 5x5 stamps). Outputs are written
    into the preallocated arrays: ``out`` (n, N_COLUMNS) in the order of
    :data:`COLUMNS`, ``ap_sums/ap_areas`` (n, len(radii)) raw aperture sums
    (not background-subtracted) and areas, ``var_*`` (n, len(var_a)) for the
    variable apertures ``r = a sqrt(beta) + b``, and the background-subtracted
    stamps ``stamp3`` (n, 3, 3) and ``stamp5`` (n, 5, 5).
    """
    n = frames.shape[0]
    nbuf = int((2 * r_out + 3) * (2 * r_out + 3)) + 1
    nvar = var_a.shape[0]
    for f in prange(n):
        img = frames[f]
        buf = np.empty(nbuf)
        row = out[f]
        for c in range(N_COLUMNS):
            row[c] = np.nan
        px, py = _frame_peak(img, guess_x[f], guess_y[f], search_half)
        if px < 0:
            _no_star(ap_sums[f], ap_areas[f], var_sums[f], var_areas[f], var_radii[f],
                     stamp3[f], stamp5[f])
            continue
        row[0] = px
        row[1] = py
        bg0, _m, _s, _n = _frame_annulus(img, float(px), float(py), r_in, r_out, 0.0, 0, buf)
        row[2] = bg0
        _centroid_set(img, px, py, box_half, bg0, fixed_width, max_iter, want_lsq, row)
        beta = row[5]
        if centroid_code == 0:
            xc, yc = row[3], row[4]
        elif centroid_code == 1:
            xc, yc = row[6], row[7]
        elif centroid_code == 2:
            xc, yc = row[13], row[14]
        else:
            xc, yc = row[16], row[17]
        row[19] = xc
        row[20] = yc
        if math.isfinite(xc) and math.isfinite(yc):
            mean, med, std, nb = _frame_annulus(img, xc, yc, r_in, r_out, clip_sigma, clip_iters,
                                                buf)
        else:
            mean, med, std, nb = np.nan, np.nan, np.nan, 0
        row[21] = mean
        row[22] = med
        row[23] = std
        row[24] = nb
        bg = med if use_median else mean
        _frame_apertures(img, xc, yc, radii, ap_sums[f], ap_areas[f])
        if nvar > 0:
            _variable_apertures(img, xc, yc, beta, var_a, var_b, var_radii[f],
                                      var_sums[f], var_areas[f])
        _stamps(img, stamp_x[f], stamp_y[f], bg, stamp3[f], stamp5[f])


@njit(cache=True)
def _no_star(ap_sums, ap_areas, var_sums, var_areas, var_radii, stamp3, stamp5):
    """NaN in every aperture, variable-aperture and stamp output of a frame with no star."""
    for k in range(ap_sums.shape[0]):
        ap_sums[k] = np.nan
        ap_areas[k] = np.nan
    for k in range(var_sums.shape[0]):
        var_sums[k] = np.nan
        var_areas[k] = np.nan
        var_radii[k] = np.nan
    for a in range(3):
        for b in range(3):
            stamp3[a, b] = np.nan
    for a in range(5):
        for b in range(5):
            stamp5[a, b] = np.nan


@njit(cache=True)
def _centroid_set(img, px, py, box_half, bg0, fixed_width, max_iter, want_lsq, row):
    """Every centroid of one frame about its peak (px, py), into ``row`` (:data:`COLUMNS`).

    Center of light and noise pixels, the free-width Gaussian started there,
    the fixed-width one when ``fixed_width > 0`` and the least-asymmetry
    centroid when ``want_lsq``; the columns of the fits not run stay as they are.
    """
    xcol, ycol, beta = _frame_col(img, px, py, box_half, bg0)
    row[3] = xcol
    row[4] = ycol
    row[5] = beta
    xg, yg, sxg, syg, ag, cg, okg = _frame_gauss(img, px, py, box_half, bg0, xcol, ycol,
                                                 GAUSS_START_WIDTH_PX, False, max_iter)
    row[6] = xg
    row[7] = yg
    row[8] = sxg
    row[9] = syg
    row[10] = ag
    row[11] = cg
    row[12] = okg
    if fixed_width > 0.0:
        xf, yf, _a, _b, _c, _d, okf = _frame_gauss(img, px, py, box_half, bg0, xcol, ycol,
                                                   fixed_width, True, max_iter)
        row[13] = xf
        row[14] = yf
        row[15] = okf
    if want_lsq:
        xl, yl, okl = _frame_lsq_asym(img, px, py, bg0, LSQ_GRID_HALF_PX, LSQ_WINDOW_PX)
        row[16] = xl
        row[17] = yl
        row[18] = okl


@njit(cache=True)
def _variable_apertures(img, xc, yc, beta, var_a, var_b, var_radii, var_sums, var_areas):
    """Aperture sums and areas at the radii ``a sqrt(beta) + b`` (NaN when beta is not finite)."""
    nvar = var_a.shape[0]
    vr = np.empty(nvar)
    for k in range(nvar):
        vr[k] = var_a[k] * math.sqrt(beta) + var_b[k]
        var_radii[k] = vr[k]
    if math.isfinite(beta):
        _frame_apertures(img, xc, yc, vr, var_sums, var_areas)
    else:
        for k in range(nvar):
            var_sums[k] = np.nan
            var_areas[k] = np.nan


@njit(cache=True)
def _stamps(img, sx0, sy0, bg, stamp3, stamp5):
    """The 5x5 and 3x3 stamps about pixel (sx0, sy0) minus ``bg``; NaN off the image."""
    ny, nx = img.shape
    for a in range(5):
        for b in range(5):
            j = sy0 - 2 + a
            i = sx0 - 2 + b
            if 0 <= j < ny and 0 <= i < nx:
                v = img[j, i] - bg
            else:
                v = np.nan
            stamp5[a, b] = v
            if 1 <= a <= 3 and 1 <= b <= 3:
                stamp3[a - 1, b - 1] = v
