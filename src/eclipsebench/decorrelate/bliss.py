"""BLISS: BiLinearly-Interpolated Subpixel Sensitivity mapping (Stevenson et al. 2012).

Paper Appendix B.1. A rectangular grid of "knots" spans the centroid cloud;
each knot takes the mean of ``flux / astro`` over the frames for which it is
the nearest knot, and the sensitivity at every frame is the bilinear
interpolation of the four knots around it::

    model_i = astro_i * sum_c w_ic * K[c_i],   K[k] = mean_{j: knot(j)=k} flux_j / astro_j

The rules are those of POET, the BLISS team's pipeline (kevin218/POET,
``code/lib/p6model.py``, the ``ipmap`` set-up):

* the grid runs from ``floor(10 min)/10 - step`` to ``ceil(10 max)/10 + step``
  along each axis (positions relative to the rounded median pixel), with
  ``int(span / step + 1)`` knots spread evenly over that span;
* a frame belongs to the knot within half a step of it along both axes (its
  nearest knot);
* frames whose nearest knot holds fewer than ``minnumpts`` frames are masked
  out of the fit (``minnumptsmask``);
* a frame whose grid cell has a corner knot without frames is interpolated by
  nearest neighbour (the value of its own knot), otherwise bilinearly.

Everything except the knot averages depends only on the centroids and is done
once in :func:`bliss_setup`; :func:`bliss_gain` is the cheap evaluation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any, ClassVar

import numpy as np
import scipy.sparse as sp

from ..config.base import check
from ..errors import InputError
from .base import AtLeast, EpochData, MethodOptions, Systematics, register
from .record import FitterPolicy, MethodRecord, team_profile

__all__ = ["BlissGrid", "knot_spacing_from_data", "poet_axis_knots", "bliss_setup",
           "bliss_knot_values", "bliss_gain", "Bliss"]

#: POET rounds the grid edges to tenths of a pixel (``yfactor = xfactor = 10``).
_EDGE_PER_PX = 10.0


@dataclass(frozen=True)
class BlissGrid:
    """Parameter-independent BLISS bookkeeping for one set of centroids.

    Attributes
    ----------
    x_knots, y_knots : ndarray
        Knot coordinates along each axis (pixels).
    n_knots : int
        ``len(x_knots) * len(y_knots)``; knot ``k = iy * nx + ix``.
    keep : ndarray of bool, shape (n,)
        Frames kept: their nearest knot holds at least ``min_points`` frames.
    assign : ndarray of int, shape (n_kept,)
        The nearest knot of each kept frame.
    counts : ndarray of float, shape (n_knots,)
        Kept frames per knot (0 for the knots that are not live).
    live : ndarray of bool, shape (n_knots,)
        Knots holding at least ``min_points`` frames.
    corners : ndarray of int, shape (4, n_kept)
        The four knots around each kept frame: (x0,y0), (x1,y0), (x0,y1),
        (x1,y1); all four are the frame's own knot where it is interpolated by
        nearest neighbour.
    weights : ndarray of float, shape (4, n_kept)
        The interpolation weights of those corners (sum to 1).
    nearest_neighbour : ndarray of bool, shape (n_kept,)
        Frames whose cell has a corner that is not live (nearest-neighbour value).
    """

    x_knots: np.ndarray
    y_knots: np.ndarray
    n_knots: int
    keep: np.ndarray
    assign: np.ndarray
    counts: np.ndarray
    live: np.ndarray
    corners: np.ndarray
    weights: np.ndarray
    nearest_neighbour: np.ndarray

    @property
    def n_live(self) -> int:
        """Number of knots whose value is a mean of their own frames."""
        return int(self.live.sum())

    @property
    def n_masked(self) -> int:
        """Frames masked out because their nearest knot is sparse."""
        return int(self.keep.size - np.count_nonzero(self.keep))

    @property
    def steps_px(self) -> tuple[float, float]:
        """The knot steps actually used along x and y (pixels)."""
        return (float(self.x_knots[1] - self.x_knots[0]), float(self.y_knots[1] - self.y_knots[0]))


def knot_spacing_from_data(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Knot spacing from the rms frame-to-frame centroid motion (Stevenson et al. 2012).

    Stevenson et al. choose the grid spacing so that it is about the rms of
    the point-to-point position variation: finer knots cannot be resolved by
    the centroids, coarser ones smooth real structure.

    Returns
    -------
    (dx_px, dy_px) : tuple of float

    Examples
    --------
    >>> [round(s, 4) for s in knot_spacing_from_data([0.0, 0.3, 0.1], [1.0, 1.0, 1.2])]
    [0.255, 0.1414]
    """
    dx = float(np.sqrt(np.mean(np.diff(np.asarray(x, float)) ** 2)))
    dy = float(np.sqrt(np.mean(np.diff(np.asarray(y, float)) ** 2)))
    return dx, dy


def poet_axis_knots(v: np.ndarray, step_px: float) -> np.ndarray:
    """Knot positions along one axis, as POET lays them out.

    Relative to the rounded median ``c``, the grid runs from
    ``floor(10 min(v - c)) / 10 - step`` to ``ceil(10 max(v - c)) / 10 + step``
    with ``int(span / step + 1)`` evenly spread knots (so the step actually used
    is ``span / (n - 1)``, at least the requested one).

    Examples
    --------
    >>> poet_axis_knots(np.array([15.02, 15.08]), 0.05)
    array([14.95, 15.  , 15.05, 15.1 , 15.15])
    """
    centre, lo, hi, n = _axis_extent(v, step_px)
    return centre + np.linspace(lo, hi, n)


#: A grid with more knots than this and than frames is refused before it is allocated.
_MAX_KNOTS = 1_000_000


def _axis_extent(v: np.ndarray, step_px: float) -> tuple[float, float, float, int]:
    """Centre, first and last knot offsets and knot count of :func:`poet_axis_knots`."""
    v = np.asarray(v, float)
    centre = float(np.round(np.median(v)))
    lo = np.floor(_EDGE_PER_PX * (v.min() - centre)) / _EDGE_PER_PX - step_px
    hi = np.ceil(_EDGE_PER_PX * (v.max() - centre)) / _EDGE_PER_PX + step_px
    return centre, lo, hi, max(int((hi - lo) / step_px + 1), 2)


def bliss_setup(x: np.ndarray, y: np.ndarray, *, dx_px: float, dy_px: float,
                min_points: int = 4) -> BlissGrid:
    """Build the knot grid, the sparse-knot mask, the nearest knots and the interpolation.

    Parameters
    ----------
    x, y : ndarray, shape (n,)
        Centroids (pixels).
    dx_px, dy_px : float
        Requested knot spacing along x and y (pixels), finite and > 0 (as
        :class:`BlissOptions` checks them, or derived from centroids that move).
    min_points : int
        POET's ``minnumpts``: a frame whose nearest knot holds fewer frames is
        masked out (``BlissGrid.keep`` is False).

    Returns
    -------
    BlissGrid

    Examples
    --------
    >>> x = np.array([15.00, 15.01, 15.00, 15.30])
    >>> g = bliss_setup(x, np.full(4, 15.0), dx_px=0.1, dy_px=0.1, min_points=2)
    >>> g.keep.tolist(), g.n_live
    ([True, True, True, False], 1)
    """
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    n_grid = _axis_extent(x, dx_px)[3] * _axis_extent(y, dy_px)[3]
    if n_grid > max(len(x), _MAX_KNOTS):  # e.g. centroids that do not move: spacing ~ 1e-13 px
        raise InputError(f"method 'bliss': knot spacing ({dx_px:.3g}, {dy_px:.3g}) px gives "
                         f"{n_grid:.3g} knots for {len(x)} frames (centroids that barely move); "
                         "give a coarser knot_spacing_px")
    xk = poet_axis_knots(x, dx_px)
    yk = poet_axis_knots(y, dy_px)
    nx, ny = len(xk), len(yk)
    sx, sy = xk[1] - xk[0], yk[1] - yk[0]
    n_knots = nx * ny

    # Nearest knot: within half a step along both axes.
    fx = (x - xk[0]) / sx
    fy = (y - yk[0]) / sy
    nearest = (np.clip(np.rint(fy).astype(np.intp), 0, ny - 1) * nx
               + np.clip(np.rint(fx).astype(np.intp), 0, nx - 1))
    counts_all = np.bincount(nearest, minlength=n_knots)
    live = counts_all >= max(1, int(min_points))
    keep = live[nearest]
    if not keep.any():
        raise InputError(f"option min_points_per_knot={min_points}: no knot has that many "
                         "frames; use a coarser knot_spacing_px")
    assign = nearest[keep]
    counts = np.where(live, counts_all, 0).astype(float)

    # The cell of a frame: knots m, m+1 with knot[m] < v <= knot[m+1] (POET's convention).
    ix = np.clip(np.ceil(fx[keep]).astype(np.intp) - 1, 0, nx - 2)
    iy = np.clip(np.ceil(fy[keep]).astype(np.intp) - 1, 0, ny - 2)
    tx = np.clip(fx[keep] - ix, 0.0, 1.0)
    ty = np.clip(fy[keep] - iy, 0.0, 1.0)
    k00 = iy * nx + ix
    corners = np.stack([k00, k00 + 1, k00 + nx, k00 + nx + 1])
    weights = np.stack([(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty])
    nn = ~np.all(live[corners], axis=0)
    corners[:, nn] = assign[nn]
    weights[:, nn] = np.array([1.0, 0.0, 0.0, 0.0])[:, None]
    return BlissGrid(x_knots=xk, y_knots=yk, n_knots=n_knots, keep=keep, assign=assign,
                     counts=counts, live=live, corners=corners, weights=weights,
                     nearest_neighbour=nn)


def bliss_knot_values(grid: BlissGrid, ratio: np.ndarray) -> np.ndarray:
    """Mean of ``ratio`` (kept frames) over the frames of each knot; NaN for knots not live."""
    sums = np.bincount(grid.assign, weights=ratio, minlength=grid.n_knots)
    with np.errstate(invalid="ignore", divide="ignore"):
        return sums / grid.counts


def bliss_gain(grid: BlissGrid, ratio: np.ndarray) -> np.ndarray:
    """The BLISS sensitivity at every kept frame for the flux ratio ``flux / astro``.

    Parameters
    ----------
    grid : BlissGrid
        From :func:`bliss_setup`.
    ratio : ndarray, shape (n_kept,)
        ``flux / astro`` of the kept frames (electrons).

    Returns
    -------
    ndarray, shape (n_kept,)
        Interpolated knot means (electrons).
    """
    k = bliss_knot_values(grid, ratio)
    c, w = grid.corners, grid.weights
    return w[0] * k[c[0]] + w[1] * k[c[1]] + w[2] * k[c[2]] + w[3] * k[c[3]]


@dataclass(frozen=True)
class BlissOptions(MethodOptions):
    """Options of ``bliss`` (:class:`Bliss`)."""

    knot_spacing_px: float | tuple[float, ...] | None = None
    min_points_per_knot: Annotated[int, AtLeast(1)] = 4

    def validate(self) -> None:
        sp = self.knot_spacing_px
        check(sp is None or (np.size(sp) in (1, 2) and bool(np.all(np.asarray(sp) > 0))
                             and bool(np.all(np.isfinite(sp)))),
              "knot_spacing_px", "one or two positive spacings in pixels")


@register
class Bliss(Systematics[BlissOptions]):
    """BLISS mapping (Stevenson et al. 2012; paper Appendix B.1), with POET's rules.

    The frames whose nearest knot is sparse are left out: ``self.data`` is the
    kept subset, and :meth:`dropped_frames` counts the others as
    ``"sparse_knot"``.

    Options (:class:`BlissOptions`)
    -------------------------------
    knot_spacing_px : float or (float, float), optional
        Requested knot spacing in x and y (pixels). Default: the rms
        frame-to-frame centroid motion along each axis, Stevenson et al.'s
        rule. POET spreads the knots evenly over its grid, so the step used
        (``diagnostics()["knot_step_px"]``) can be slightly larger.
    min_points_per_knot : int, default 4
        POET's ``minnumpts``: frames whose nearest knot holds fewer frames are
        masked out of the fit.

    Examples
    --------
    >>> x = np.r_[np.full(6, 15.0), 15.3]
    >>> d = EpochData(time_bmjd=np.arange(7.0), flux=np.ones(7), flux_err=np.ones(7),
    ...               x=x, y=np.full(7, 15.0))
    >>> m = Bliss(d, knot_spacing_px=0.1)
    >>> len(m.data), m.dropped_frames()
    (6, {'sparse_knot': 1})
    """

    name: ClassVar[str] = "bliss"
    requires: ClassVar[tuple[str, ...]] = ("x", "y")
    #: DE-MC, as the BLISS team sampled (ter Braak 2006). The grid and the mask depend
    #: only on the centroids, which a refit does not change; a rebuild on the kept subset
    #: would re-derive the spacing from other frame-to-frame differences, so refits keep
    #: the grid (``with_flux_rebuilds=False``).
    record: ClassVar[MethodRecord] = MethodRecord(
        label="BLISS", paper=team_profile("bliss"), in_paper=True,
        policy=FitterPolicy(preferred_move="de", with_flux_rebuilds=False))

    def setup(self, data: EpochData) -> None:
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
        self.knot_spacing_px = (dx, dy)
        self.grid = bliss_setup(x, y, dx_px=dx, dy_px=dy,
                                min_points=int(self.options.min_points_per_knot))
        self.n_input_frames = len(data)
        if self.grid.n_masked:
            self.data = data.subset(np.flatnonzero(self.grid.keep))
        self._flux = np.asarray(self.data.flux, float)

    def diagnostics(self) -> dict[str, Any]:
        """Knot spacing and step, knots in the grid and live ones, masked and NN frames."""
        return {"knot_spacing_px": list(self.knot_spacing_px),
                "knot_step_px": list(self.grid.steps_px),
                "n_knots": int(self.grid.n_knots), "n_live_knots": self.grid.n_live,
                "min_points_per_knot": int(self.options.min_points_per_knot),
                "n_sparse_knot_frames": self.grid.n_masked,
                "n_nearest_neighbour_frames": int(np.count_nonzero(self.grid.nearest_neighbour))}

    def dropped_frames(self) -> dict[str, int]:
        """The frames masked because their nearest knot is sparse (POET's ``minnumpts``)."""
        return {"sparse_knot": self.grid.n_masked}

    def predict(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """``astro * BLISS(flux / astro)`` at the kept frames (electrons)."""
        astro = np.asarray(astro, float)
        return astro * bliss_gain(self.grid, self._flux / astro)

    def log_likelihood_batch(self, astro: np.ndarray, theta: np.ndarray | None = None,
                             noise_scale: float = 1.0) -> np.ndarray:
        """:meth:`log_likelihood` of every row of ``astro`` (shape (m, n)) at once.

        The knot sums of all rows are one sparse product (frames to knots),
        the interpolation a second one (knots to frames): the same arithmetic
        as :func:`bliss_gain`, vectorised over the rows.
        """
        if not self._batch_is_exact(Bliss):
            return super().log_likelihood_batch(astro, theta, noise_scale)
        astro = np.atleast_2d(np.asarray(astro, float))
        to_knots, to_frames = self._batch_operators()
        means = (to_knots @ (self._flux / astro).T) / self._batch_counts[:, None]
        gain = (to_frames @ means).T
        return self._white_log_likelihood_batch(astro * gain, noise_scale)

    def _batch_operators(self):
        """Sparse (knots x frames) sum and (frames x live knots) bilinear interpolation."""
        ops = getattr(self, "_batch_ops", None)
        if ops is None:
            g = self.grid
            live = np.flatnonzero(g.live)
            column = np.full(g.n_knots, -1)
            column[live] = np.arange(len(live))
            n = len(g.assign)
            to_knots = sp.csr_matrix((np.ones(n), (column[g.assign], np.arange(n))),
                                     shape=(len(live), n))
            rows = np.tile(np.arange(n), 4)
            to_frames = sp.csr_matrix((g.weights.ravel(), (rows, column[g.corners.ravel()])),
                                      shape=(n, len(live)))
            ops = self._batch_ops = (to_knots, to_frames)
            self._batch_counts = g.counts[live]
        return ops

    def with_flux(self, flux: np.ndarray) -> Bliss:
        """The same knot grid and mask on new fluxes of the kept frames."""
        new = self._copy_with_flux(flux)
        new._flux = new.data.flux
        return new

    def n_effective_params(self) -> int:
        """The number of knots whose value is fitted (the live knots)."""
        return self.grid.n_live
