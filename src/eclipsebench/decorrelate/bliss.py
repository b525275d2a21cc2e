"""BLISS: BiLinearly-Interpolated Subpixel Sensitivity mapping (Stevenson et al. 2012).

Paper Appendix B.1. A rectangular grid of "knots" spans the centroid cloud;
each knot takes the mean of ``flux / astro`` over the frames for which it is
the nearest knot, and the sensitivity at every frame is the bilinear
interpolation of the four knots around it::

    model_i = astro_i * sum_c w_ic * K[c_i],   K[k] = mean_{j: knot(j)=k} flux_j / astro_j

Everything except the two averages (the knot assignment, the bilinear corner
indices and weights) depends only on the centroids and is done once in
:func:`bliss_setup`; :func:`bliss_gain` is the cheap evaluation.

Sparse knots: POET (Stevenson et al. 2012) masks out the frames whose nearest
knot holds fewer than ``minnumpts`` frames. The interface here models every
frame, so such frames are instead merged into their nearest well-populated
knot, and a sparse (or empty) knot that is a corner of some frame's cell takes
the value of its nearest well-populated knot.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from scipy.spatial import cKDTree

from ..config.base import check
from ..errors import InputError
from .base import EpochData, MethodContext, MethodOptions, Systematics, register

__all__ = ["BlissGrid", "knot_spacing_from_data", "bliss_setup", "bliss_gain", "Bliss"]


@dataclass(frozen=True)
class BlissGrid:
    """Parameter-independent BLISS bookkeeping for one set of centroids.

    Attributes
    ----------
    x_knots, y_knots : ndarray
        Knot coordinates along each axis (pixels).
    n_knots : int
        ``len(x_knots) * len(y_knots)``; knot ``k = iy * nx + ix``.
    assign : ndarray of int, shape (n,)
        The (well-populated) knot whose mean each frame contributes to.
    counts : ndarray of float, shape (n_knots,)
        Frames per knot after merging (0 for dead knots).
    live : ndarray of bool, shape (n_knots,)
        Knots holding at least ``min_points`` frames.
    fill_from : ndarray of int, shape (n_knots,)
        For each knot, the live knot whose value it takes (itself if live).
    corners : ndarray of int, shape (4, n)
        The four knots around each frame: (x0,y0), (x1,y0), (x0,y1), (x1,y1).
    weights : ndarray of float, shape (4, n)
        The bilinear weights of those corners (sum to 1).
    """

    x_knots: np.ndarray
    y_knots: np.ndarray
    n_knots: int
    assign: np.ndarray
    counts: np.ndarray
    live: np.ndarray
    fill_from: np.ndarray
    corners: np.ndarray
    weights: np.ndarray

    @property
    def n_live(self) -> int:
        """Number of knots whose value is a mean of their own frames."""
        return int(self.live.sum())


def knot_spacing_from_data(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Knot spacing from the rms frame-to-frame centroid motion (Stevenson et al. 2012).

    Stevenson et al. choose the grid spacing so that it is about the rms of
    the point-to-point position variation: finer knots cannot be resolved by
    the centroids, coarser ones smooth real structure.

    Returns
    -------
    (dx_px, dy_px) : tuple of float
    """
    dx = float(np.sqrt(np.mean(np.diff(np.asarray(x, float)) ** 2)))
    dy = float(np.sqrt(np.mean(np.diff(np.asarray(y, float)) ** 2)))
    return dx, dy


def _axis_knots(v: np.ndarray, step: float) -> np.ndarray:
    """Knots at ``min(v) + i*step`` until the last one reaches ``max(v)`` (at least 2)."""
    lo, hi = float(v.min()), float(v.max())
    n = max(2, int(np.ceil((hi - lo) / step - 1e-9)) + 1)
    return lo + step * np.arange(n)


def bliss_setup(x: np.ndarray, y: np.ndarray, *, dx_px: float, dy_px: float,
                min_points: int = 4) -> BlissGrid:
    """Build the knot grid, the nearest-knot assignment and the bilinear weights.

    Parameters
    ----------
    x, y : ndarray, shape (n,)
        Centroids (pixels).
    dx_px, dy_px : float
        Knot spacing along x and y (pixels), > 0.
    min_points : int
        A knot needs at least this many nearest frames to be used; frames of
        sparser knots join their nearest live knot.

    Returns
    -------
    BlissGrid
    """
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    if not (dx_px > 0 and dy_px > 0 and np.isfinite(dx_px) and np.isfinite(dy_px)):
        raise InputError(f"option knot_spacing_px: expected positive spacings, got ({dx_px}, {dy_px})")
    xk = _axis_knots(x, dx_px)
    yk = _axis_knots(y, dy_px)
    nx, ny = len(xk), len(yk)
    n_knots = nx * ny

    # Nearest knot: round to the grid.
    ixn = np.clip(np.rint((x - xk[0]) / dx_px).astype(np.intp), 0, nx - 1)
    iyn = np.clip(np.rint((y - yk[0]) / dy_px).astype(np.intp), 0, ny - 1)
    nearest = iyn * nx + ixn
    counts0 = np.bincount(nearest, minlength=n_knots)
    live = counts0 >= max(1, int(min_points))
    if not live.any():
        raise InputError(f"option min_points_per_knot={min_points}: no knot has that many "
                         "frames; use a coarser knot_spacing_px")

    # Every knot (live or not) borrows from its nearest live knot, in units of the spacing.
    kx, ky = np.meshgrid(np.arange(nx), np.arange(ny))
    kpos = np.column_stack([kx.ravel(), ky.ravel()]).astype(float)
    live_idx = np.flatnonzero(live)
    _, j = cKDTree(kpos[live_idx]).query(kpos, k=1)
    fill_from = live_idx[np.asarray(j, dtype=np.intp)]
    assign = fill_from[nearest]
    counts = np.bincount(assign, minlength=n_knots).astype(float)

    # Bilinear cell: the knots at floor() and floor()+1 along each axis.
    fx = np.clip((x - xk[0]) / dx_px, 0.0, nx - 1.0)
    fy = np.clip((y - yk[0]) / dy_px, 0.0, ny - 1.0)
    ix = np.minimum(fx.astype(np.intp), nx - 2)
    iy = np.minimum(fy.astype(np.intp), ny - 2)
    tx, ty = fx - ix, fy - iy
    k00 = iy * nx + ix
    corners = np.stack([k00, k00 + 1, k00 + nx, k00 + nx + 1])
    weights = np.stack([(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty])
    return BlissGrid(x_knots=xk, y_knots=yk, n_knots=n_knots, assign=assign, counts=counts,
                     live=live, fill_from=fill_from, corners=fill_from[corners], weights=weights)


def bliss_knot_values(grid: BlissGrid, ratio: np.ndarray) -> np.ndarray:
    """Mean of ``ratio`` over the frames of each knot (dead knots: their live neighbour's)."""
    sums = np.bincount(grid.assign, weights=ratio, minlength=grid.n_knots)
    with np.errstate(invalid="ignore", divide="ignore"):
        return sums / grid.counts


def bliss_gain(grid: BlissGrid, ratio: np.ndarray) -> np.ndarray:
    """The BLISS sensitivity at every frame for the flux ratio ``flux / astro``.

    Parameters
    ----------
    grid : BlissGrid
        From :func:`bliss_setup`.
    ratio : ndarray, shape (n,)
        ``flux / astro`` (electrons).

    Returns
    -------
    ndarray, shape (n,)
        Bilinearly interpolated knot means (electrons).
    """
    k = bliss_knot_values(grid, ratio)
    c, w = grid.corners, grid.weights
    return w[0] * k[c[0]] + w[1] * k[c[1]] + w[2] * k[c[2]] + w[3] * k[c[3]]


def _with_flux(model: Systematics, flux: np.ndarray) -> Systematics:
    """A shallow copy of ``model`` whose data (and cached flux) are ``flux``."""
    flux = np.asarray(flux, dtype=float)
    if flux.shape != model.data.flux.shape:
        raise InputError(f"with_flux: expected {model.data.flux.shape[0]} fluxes, got {flux.shape}")
    new = copy.copy(model)
    new.data = dataclasses.replace(model.data, flux=flux)
    new._flux = flux
    return new


@dataclass(frozen=True)
class BlissOptions(MethodOptions):
    """Options of ``bliss`` (:class:`Bliss`)."""

    knot_spacing_px: float | tuple[float, ...] | None = None
    min_points_per_knot: int = 4

    def validate(self) -> None:
        sp = self.knot_spacing_px
        check(sp is None or (np.size(sp) in (1, 2) and np.all(np.asarray(sp) > 0)),
              "knot_spacing_px", "one or two positive spacings in pixels")
        check(self.min_points_per_knot >= 1, "min_points_per_knot", "an integer >= 1")


@register
class Bliss(Systematics):
    """BLISS mapping (Stevenson et al. 2012; paper Appendix B.1).

    Options (:class:`BlissOptions`)
    -------------------------------
    knot_spacing_px : float or (float, float), optional
        Knot spacing in x and y (pixels). Default: the rms frame-to-frame
        centroid motion along each axis, as Stevenson et al. choose it.
    min_points_per_knot : int, default 4
        Knots with fewer nearest frames are not used on their own (see module
        docstring).
    """

    name: ClassVar[str] = "bliss"
    requires: ClassVar[tuple[str, ...]] = ("x", "y")
    Options: ClassVar[type[MethodOptions]] = BlissOptions
    description: ClassVar[str] = "bilinearly interpolated knot means of flux/astro over (x, y)"
    #: The BLISS team sampled with DE-MC (ter Braak 2006); the fitter uses emcee's DE move.
    preferred_move: ClassVar[str] = "de"

    def __init__(self, data: EpochData, options: Any = None, *,
                 context: MethodContext | None = None, **kwargs: Any) -> None:
        super().__init__(data, options, context=context, **kwargs)
        x = np.asarray(data.x, float)
        y = np.asarray(data.y, float)
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise InputError("method 'bliss': centroids x, y must be finite")
        spacing = self.options.knot_spacing_px
        if spacing is None:
            dx, dy = knot_spacing_from_data(x, y)
            if not (dx > 0 and dy > 0):
                raise InputError("method 'bliss': the centroids do not move, so no knot "
                                 "spacing can be derived; give knot_spacing_px")
        else:
            sp = np.atleast_1d(np.asarray(spacing, dtype=float))
            dx, dy = float(sp[0]), float(sp[-1])
        min_points = self.options.min_points_per_knot
        self.knot_spacing_px = (dx, dy)
        self.grid = bliss_setup(x, y, dx_px=dx, dy_px=dy, min_points=int(min_points))
        self._flux = np.asarray(data.flux, float)

    def diagnostics(self) -> dict[str, Any]:
        """Knot spacing, knots in the grid and live ones."""
        return {"knot_spacing_px": list(self.knot_spacing_px), "n_knots": int(self.grid.n_knots),
                "n_live_knots": self.grid.n_live}

    def predict(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """``astro * BLISS(flux / astro)`` (electrons)."""
        astro = np.asarray(astro, float)
        return astro * bliss_gain(self.grid, self._flux / astro)

    def with_flux(self, flux: np.ndarray) -> Bliss:
        """The same knot grid on new fluxes (the grid depends only on the centroids)."""
        return _with_flux(self, flux)

    def n_effective_params(self) -> int:
        """The number of knots whose value is fitted (the live knots)."""
        return self.grid.n_live
