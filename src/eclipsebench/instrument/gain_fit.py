"""The intra-pixel gain fitted to a gridded SSC warm pixel map.

Two fits of one map (the gain as a function of the sub-pixel phase about
the nearest pixel centre, :class:`~eclipsebench.instrument.prf.GainPolynomial`):

- :func:`fit_centroid_gain`: the map itself, a polynomial in the *centroid's*
  phase (what aperture photometry at the measured centroid sees; the
  committed ``pmap_poly`` of ``data/gainmap_ch<N>.json``);
- :func:`fit_true_phase_gain`: the gain that a PRF rendered at *true*
  positions needs so that its aperture sum at the measured centroid follows
  the map (paper Appendix A.2: IRACSIM scaled its PRF realisations with
  respect to each other; the committed ``builtin`` gain, and the gain of
  twins rendered with a user's map).

Both weight the cells whose occupancy exceeds ``occupancy_min`` (20) by 1 and
the rest by ``low_weight`` (0.05), so the whole pixel stays bounded while
the well-sampled cells decide. A map with NaN cells (channel 1: cells no
calibration measurement reached) is fitted only inside the box spanned by
its well-sampled cells, and the polynomial carries that box (evaluated with
the phase clamped to it: nothing is extrapolated).

``tools/fit_gainmap.py`` makes the committed coefficients with these
functions; :mod:`eclipsebench.trust.twin` fits a user's map with them.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import interpolate

from ..errors import InputError
from .prf import PRF, GainPolynomial, polynomial_powers, true_grid_photometry

__all__ = ["OCCUPANCY_MIN", "fit_centroid_gain", "fit_true_phase_gain", "trusted_box"]

#: Occupancy above which a map cell is well sampled (weight 1 in the fits).
OCCUPANCY_MIN = 20.0

Box = tuple[tuple[float, float], tuple[float, float]]


def _weighted_fit(u: np.ndarray, v: np.ndarray, target: np.ndarray, weights: np.ndarray,
                  degree: int) -> tuple[list[tuple[int, int]], np.ndarray, np.ndarray]:
    """Weighted least squares of a polynomial in ``(u, v)``: powers, coefficients, fitted values."""
    powers = polynomial_powers(degree)
    design = np.stack([u**m * v**n for m, n in powers], axis=-1)
    root_w = np.sqrt(weights)
    coeffs, *_ = np.linalg.lstsq(design * root_w[:, None], target * root_w, rcond=None)
    return powers, coeffs, design @ coeffs


def trusted_box(x_grid: np.ndarray, y_grid: np.ndarray, gain: np.ndarray, occupancy: np.ndarray,
                occupancy_min: float = OCCUPANCY_MIN) -> Box | None:
    """The phases ``((u_lo, u_hi), (v_lo, v_hi))`` spanned by the well-sampled cells, or
    None when the map has no NaN cell (nothing needs clamping).

    ``x_grid`` (nx,) and ``y_grid`` (ny,) are the cell centres, ``gain`` and
    ``occupancy`` (ny, nx) indexed ``[iy, ix]``.
    """
    if np.all(np.isfinite(gain)):
        return None
    xx, yy = np.meshgrid(x_grid, y_grid)
    high = occupancy > occupancy_min
    u, v = xx[high] - np.rint(xx[high]), yy[high] - np.rint(yy[high])
    return ((float(u.min()), float(u.max())), (float(v.min()), float(v.max())))


def _in_box(u: np.ndarray, v: np.ndarray, box: Box | None) -> np.ndarray:
    if box is None:
        return np.ones(np.shape(u), bool)
    (u0, u1), (v0, v1) = box
    return (u >= u0) & (u <= u1) & (v >= v0) & (v <= v1)


def _check_map(x_grid, y_grid, gain, occupancy) -> tuple[np.ndarray, ...]:
    x_grid, y_grid = np.asarray(x_grid, float), np.asarray(y_grid, float)
    gain, occupancy = np.asarray(gain, float), np.asarray(occupancy, float)
    if gain.shape != (len(y_grid), len(x_grid)) or occupancy.shape != gain.shape:
        raise InputError(f"gain map: expected gain and occupancy of shape ({len(y_grid)}, "
                         f"{len(x_grid)}) (y, x), got {gain.shape} and {occupancy.shape}")
    if not np.any(occupancy > OCCUPANCY_MIN):
        raise InputError(f"gain map: no cell has occupancy above {OCCUPANCY_MIN:g}")
    return x_grid, y_grid, gain, occupancy


def fit_centroid_gain(x_grid, y_grid, gain, occupancy, *, degree: int = 6,
                      low_weight: float = 0.05) -> tuple[GainPolynomial, dict[str, Any]]:
    """The map as a polynomial of total ``degree`` in the centroid's sub-pixel phase.

    Returns the polynomial and ``{"fit_rms", "occupancy_min", "box"}`` (the
    rms over the well-sampled cells).

    Examples
    --------
    >>> x = np.linspace(14.51, 15.49, 50)
    >>> xx, yy = np.meshgrid(x, x)
    >>> g, info = fit_centroid_gain(x, x, 1 + 0.01 * (xx - 15) - 0.02 * (yy - 15) ** 2,
    ...                             np.full(xx.shape, 100.0), degree=2)
    >>> round(float(g.evaluate(15.2, 15.1)), 6), info["fit_rms"] < 1e-12
    (1.0018, True)
    """
    x_grid, y_grid, gain, occupancy = _check_map(x_grid, y_grid, gain, occupancy)
    box = trusted_box(x_grid, y_grid, gain, occupancy)
    xx, yy = np.meshgrid(x_grid, y_grid)
    u, v = (xx - np.rint(xx)).ravel(), (yy - np.rint(yy)).ravel()
    high = (occupancy > OCCUPANCY_MIN).ravel()
    use = np.isfinite(gain.ravel()) & _in_box(u, v, box)
    weights = np.where(high, 1.0, low_weight)[use]
    powers, coeffs, fitted = _weighted_fit(u[use], v[use], gain.ravel()[use], weights, degree)
    rms = float(np.sqrt(np.mean((fitted - gain.ravel()[use])[high[use]] ** 2)))
    poly = GainPolynomial(tuple(powers), tuple(float(c) for c in coeffs), box)
    return poly, {"fit_rms": rms, "occupancy_min": OCCUPANCY_MIN, "box": box}


def fit_true_phase_gain(prf: PRF, x_grid, y_grid, gain, occupancy, *, radius_px: float = 3.0,
                        degree: int = 6, step_px: float = 0.02, low_weight: float = 0.05
                        ) -> tuple[GainPolynomial, dict[str, Any]]:
    """The gain in the true phase that makes aperture photometry of ``prf`` follow the map.

    Stars are rendered without gain on a grid of true positions (step
    ``step_px``) across pixel (15, 15); their 7x7 centre-of-light centroids
    and aperture sums (radius ``radius_px``, the map's: 3 px) are measured;
    ``G`` is fitted so that ``G x aperture sum`` equals the map at the
    measured centroid. ``prf``'s own gain is ignored (restored afterwards).

    Returns the polynomial and ``{"fit_rms", "n_positions", "gain_min",
    "gain_max", "box"}``: the relative rms over the positions whose centroid
    falls in a well-sampled cell (after the best scale), and the range of
    ``G / mean(G)`` over the pixel.
    """
    x_grid, y_grid, gain, occupancy = _check_map(x_grid, y_grid, gain, occupancy)
    box = trusted_box(x_grid, y_grid, gain, occupancy)
    xs, ys, xc, yc, ap_flux = true_grid_photometry(prf, step_px, radius_px)
    at = np.column_stack([yc, xc])
    value = interpolate.RegularGridInterpolator((y_grid, x_grid), gain, bounds_error=False,
                                                fill_value=np.nan)(at)
    occupied = interpolate.RegularGridInterpolator((y_grid, x_grid), occupancy, method="nearest",
                                                   bounds_error=False, fill_value=0.0)(at)
    inside = np.isfinite(value) & _in_box(xc - 15.0, yc - 15.0, box)
    ok = inside & (occupied > OCCUPANCY_MIN)
    weights = np.where(ok, 1.0, low_weight)[inside]
    powers, coeffs, fitted = _weighted_fit(xs[inside] - 15.0, ys[inside] - 15.0,
                                           value[inside] / ap_flux[inside], weights, degree)
    model = fitted * ap_flux[inside]
    sel = ok[inside]
    scale = np.sum(model[sel] * value[inside][sel]) / np.sum(model[sel] ** 2)
    rms = float(np.sqrt(np.mean((model[sel] * scale / value[inside][sel] - 1.0) ** 2)))
    true_box = None
    if box is not None:   # the true phases whose centroids fall in the map's box
        tu, tv = xs[inside] - 15.0, ys[inside] - 15.0
        true_box = ((float(tu.min()), float(tu.max())), (float(tv.min()), float(tv.max())))
    poly = GainPolynomial(tuple(powers), tuple(float(c) for c in coeffs), true_box)
    whole = poly.evaluate(xs, ys)
    return poly, {"fit_rms": rms, "n_positions": int(sel.sum()),
                  "gain_min": float(whole.min() / whole.mean()),
                  "gain_max": float(whole.max() / whole.mean()), "box": true_box}
