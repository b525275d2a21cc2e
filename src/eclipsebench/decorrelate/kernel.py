"""Kernel regression: KR/Data and KR/Pmap (paper Appendix B.4).

KR/Data (Ballard et al. 2010; Knutson et al. 2012; Lewis et al. 2013; Wong et
al. 2014) uses the science frames as their own training set: the sensitivity
at frame i is the Gaussian-kernel weighted mean of ``flux / astro`` over its k
nearest neighbours (k = 50) in centroid space, the frame itself excluded::

    w_ij = exp(-(x_j-x_i)^2 / 2 s_x,i^2 - (y_j-y_i)^2 / 2 s_y,i^2 [- (sqrt b_j - sqrt b_i)^2 / 2 s_b,i^2])
    model_i = astro_i * sum_j w_ij (flux_j / astro_j) / sum_j w_ij

The kernel widths belong to each frame: ``s_x,i``, ``s_y,i`` (and ``s_b,i``)
are the standard deviations of the offsets of frame i's k neighbours from it,
as the field's public kernel-regression codes compute them (J. Fraine's
Python translation of N. Lewis's IDL code, ``exowanderer/GaussianKernelRegression``,
``find_qhull_one_point``: ``sigx = std(x0[inds[point]] - x0[point])``; K.
Pearson's ``gaussian_weights``, same rule). The neighbours themselves are the
k nearest in Euclidean distance in (x, y[, sqrt b]) (Appendix B.4: "based on
the Euclidean distance"). The neighbour lists and normalised weights depend
only on the centroids, so they are built once (:func:`local_kernel_weights`)
into a sparse matrix; evaluating the model is one sparse matrix-vector product,
and the MCMC's walkers share one compiled pass over the neighbour lists
(:func:`_smooth_walkers`).

KR/Pmap (Krick et al. 2016) trains the same regression on a separate
calibration star: for each science frame the k nearest calibration frames in
(x, y, beta) give the kernel-weighted calibration flux, normalised by the
calibration flux averaged over the pixel, so the gain map is fixed and only a
flux scale ``F0`` is fitted (in closed form): ``model = F0 * astro * gain``.
For the real gridded SSC pmap (500x500 cells, itself a kernel-regression
product) the gain is the bilinear interpolation of the map at (x, y), as the
IRSA correction code does. Frames where the map's occupancy is below
``min_occupancy`` (20, the IRSA code's ``THRESHOLD_VAL``) are left out of the
fit, as that code sets them to ``MISSING``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Annotated, Any, ClassVar

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee
from scipy.spatial import cKDTree

from ..config.base import check
from ..errors import InputError
from ..io.pmap_files import find_pmap_path, load_pmap
from ..jit import lazy_njit
from .base import AtLeast, EpochData, MethodOptions, Systematics, register
from .pmap import CalibrationSet, GriddedPmap, interpolate_grid, kernel_occupancy
from .record import MethodRecord, team_profile

__all__ = ["scale_lengths", "knn_weights", "local_kernel_weights", "smoother_trace",
           "KernelRegressionData", "KernelRegressionPmap", "pmap_gain", "noise_pixels_offset"]


def scale_lengths(x: np.ndarray, y: np.ndarray,
                  noise_pixels: np.ndarray | None = None) -> np.ndarray:
    """Epoch-wide scale lengths: standard deviations of x, y [and sqrt(noise pixels)].

    KR/Pmap's kernel widths (the calibration neighbours lie far closer to
    each science frame than these, so its weights are nearly equal).

    Returns
    -------
    ndarray, shape (2,) or (3,)
    """
    cols = [np.asarray(x, float), np.asarray(y, float)]
    if noise_pixels is not None:
        cols.append(np.sqrt(np.asarray(noise_pixels, float)))
    return np.array([np.std(c) for c in cols])


def _coords(x, y, noise_pixels, scales: np.ndarray | None = None) -> np.ndarray:
    cols = [np.asarray(x, float), np.asarray(y, float)]
    if noise_pixels is not None:
        cols.append(np.sqrt(np.asarray(noise_pixels, float)))
    pts = np.column_stack(cols)
    return pts if scales is None else pts / scales


def _neighbours(query: np.ndarray, train: np.ndarray, *, k: int,
                exclude_self: bool) -> tuple[np.ndarray, np.ndarray]:
    """Indices and distances of the k nearest training points (self left out if asked)."""
    n = len(query)
    kk = k + 1 if exclude_self else k
    dist, idx = cKDTree(train).query(query, k=kk)
    dist = np.asarray(dist).reshape(n, kk)
    idx = np.asarray(idx).reshape(n, kk)
    if exclude_self:
        # The point itself is normally first; with exact duplicates it may not be,
        # so remove it wherever it appears, else drop the farthest neighbour.
        own = idx == np.arange(n)[:, None]
        drop = np.where(own.any(axis=1), own.argmax(axis=1), kk - 1)
        keep = np.ones_like(own)
        keep[np.arange(n), drop] = False
        dist = dist[keep].reshape(n, k)
        idx = idx[keep].reshape(n, k)
    return idx, dist


def _normalised_gaussian(sq_dist: np.ndarray) -> np.ndarray:
    # Shift by the smallest squared distance before exponentiating so the
    # weights never underflow to all zeros; normalisation removes the shift.
    w = np.exp(-0.5 * (sq_dist - sq_dist.min(axis=1, keepdims=True)))
    return w / w.sum(axis=1, keepdims=True)


def knn_weights(query: np.ndarray, train: np.ndarray, *, k: int,
                exclude_self: bool) -> tuple[np.ndarray, np.ndarray]:
    """Neighbour indices and normalised Gaussian weights in already-scaled coordinates.

    Fixed kernel widths (KR/Pmap): the coordinates are divided by the scale
    lengths beforehand, so the weight is ``exp(-d^2/2)``.

    Parameters
    ----------
    query : ndarray, shape (n, d)
        Points to estimate, already divided by the scale lengths.
    train : ndarray, shape (m, d)
        Training points, in the same scaled coordinates.
    k : int
        Neighbours per point.
    exclude_self : bool
        When query and train are the same set: drop each point from its own
        neighbour list (a leave-one-out average).

    Returns
    -------
    index : ndarray of int, shape (n, k)
    weight : ndarray, shape (n, k)
        ``exp(-d^2/2)`` normalised to sum to 1 along axis 1.
    """
    idx, dist = _neighbours(query, train, k=k, exclude_self=exclude_self)
    return idx, _normalised_gaussian(dist**2)


def local_kernel_weights(points: np.ndarray, *, k: int
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """KR/Data's neighbours and weights, with kernel widths from each point's neighbours.

    For each point i: its k nearest other points (Euclidean distance in the
    coordinates as given), the widths ``s_i`` = standard deviations of their
    offsets from i along each coordinate (``numpy.std``, about the mean
    offset, as in Lewis's and Fraine's code), and the weights
    ``exp(-sum_c (offset_c / s_c,i)^2 / 2)`` normalised to sum to 1. A
    coordinate along which every neighbour has the same offset (zero width)
    scales all of i's weights alike and drops out.

    Parameters
    ----------
    points : ndarray, shape (n, d)
        x, y [, sqrt(noise pixels)] of every frame, unscaled.
    k : int
        Neighbours per point (the point itself excluded).

    Returns
    -------
    index : ndarray of int, shape (n, k)
    weight : ndarray, shape (n, k)
        Normalised along axis 1.
    sq_dist : ndarray, shape (n, k)
        ``sum_c (offset_c / s_c,i)^2``, the squared kernel distances.
    widths : ndarray, shape (n, d)
        The per-point kernel widths.

    Examples
    --------
    >>> g = np.random.default_rng(1)
    >>> pts = g.normal(size=(500, 2)) * [0.03, 0.05]
    >>> idx, w, d2, s = local_kernel_weights(pts, k=50)
    >>> bool(np.median(w.max(axis=1) / w.min(axis=1)) > 1.5)
    True
    """
    idx, _ = _neighbours(points, points, k=k, exclude_self=True)
    offsets = points[idx] - points[:, None, :]
    widths = offsets.std(axis=1)
    inv = np.divide(1.0, widths, out=np.zeros_like(widths), where=widths > 0)
    sq_dist = np.sum((offsets * inv[:, None, :]) ** 2, axis=2)
    return idx, _normalised_gaussian(sq_dist), sq_dist, widths


def smoother_trace(sq_dist: np.ndarray) -> float:
    """Effective number of parameters of a kernel smoother that includes each point.

    ``tr(S)`` of the smoother whose weights are the k-neighbour Gaussian
    ``exp(-sq_dist/2)`` plus the point itself at distance 0 (the usual
    effective degrees of freedom of a linear smoother; the leave-one-out form
    used for the fit has trace 0).

    Parameters
    ----------
    sq_dist : ndarray, shape (n, k)
        Squared kernel distances of each point's neighbours.
    """
    return float(np.sum(1.0 / (1.0 + np.exp(-0.5 * sq_dist).sum(axis=1))))


@lazy_njit(cache=True)
def _smooth_walkers(rank: np.ndarray, near: np.ndarray, near_w: np.ndarray, flux: np.ndarray,
                    astro: np.ndarray) -> np.ndarray:
    """``smoother @ (flux / astro_c)`` of every row c of ``astro``: KR/Data's MCMC walkers.

    Each frame's smoothed ``flux / astro`` is summed over its neighbours in
    their stored order from 0.0, as scipy's ``csr_matvec`` sums a row of the
    smoother, so the values are identical to :meth:`KernelRegressionData.predict`'s.
    The frames are stored in the order ``rank`` (a reverse Cuthill-McKee
    ordering of the smoother, so that a frame's neighbours lie close in
    memory), the m curves' ratios of one frame adjacent and padded to a
    multiple of 4, and 8 (or a last 4) curves are summed at once in registers:
    about twice as fast as a sparse product of the (n, m) block (15,600
    frames, 8 walkers: the MCMC's step; 4 curves: a Jacobian's columns).

    Parameters
    ----------
    rank : ndarray of int, shape (n,)
        Storage position of each frame.
    near, near_w : ndarray, shape (n, k)
        Row p: the storage positions and weights of the neighbours of the frame stored at p.
    flux : ndarray, shape (n,)
        Fluxes, in frame order.
    astro : ndarray, shape (m, n)
        The astrophysical curves, in frame order.

    Returns
    -------
    ndarray, shape (m, n)
        In frame order.
    """
    m, n = astro.shape
    k = near.shape[1]
    width = (m + 3) // 4 * 4
    wide = np.uint64(width)
    ratio = np.zeros(n * width)
    for j in range(n):
        at = rank[j] * width
        for c in range(m):
            ratio[at + c] = flux[j] / astro[c, j]
    smooth = np.empty(n * width)
    for p in range(n):
        c0 = 0
        while c0 + 8 <= width:
            a0 = a1 = a2 = a3 = a4 = a5 = a6 = a7 = 0.0
            for q in range(k):
                b = np.uint64(near[p, q]) * wide + np.uint64(c0)   # unsigned: no wraparound test
                w = near_w[p, q]
                a0 += w * ratio[b]
                a1 += w * ratio[b + np.uint64(1)]
                a2 += w * ratio[b + np.uint64(2)]
                a3 += w * ratio[b + np.uint64(3)]
                a4 += w * ratio[b + np.uint64(4)]
                a5 += w * ratio[b + np.uint64(5)]
                a6 += w * ratio[b + np.uint64(6)]
                a7 += w * ratio[b + np.uint64(7)]
            at = p * width + c0
            smooth[at] = a0
            smooth[at + 1] = a1
            smooth[at + 2] = a2
            smooth[at + 3] = a3
            smooth[at + 4] = a4
            smooth[at + 5] = a5
            smooth[at + 6] = a6
            smooth[at + 7] = a7
            c0 += 8
        if c0 < width:   # a last block of 4
            a0 = a1 = a2 = a3 = 0.0
            for q in range(k):
                b = np.uint64(near[p, q]) * wide + np.uint64(c0)
                w = near_w[p, q]
                a0 += w * ratio[b]
                a1 += w * ratio[b + np.uint64(1)]
                a2 += w * ratio[b + np.uint64(2)]
                a3 += w * ratio[b + np.uint64(3)]
            at = p * width + c0
            smooth[at] = a0
            smooth[at + 1] = a1
            smooth[at + 2] = a2
            smooth[at + 3] = a3
    out = np.empty((m, n))
    for i in range(n):
        at = rank[i] * width
        for c in range(m):
            out[c, i] = smooth[at + c]
    return out


def _check_finite(name: str, method: str, *arrays) -> None:
    for a in arrays:
        if a is not None and not np.all(np.isfinite(np.asarray(a, float))):
            raise InputError(f"method '{method}': column(s) {name} must be finite")


@dataclass(frozen=True)
class KrDataOptions(MethodOptions):
    """Options of ``kr-data`` (:class:`KernelRegressionData`)."""

    k: Annotated[int, AtLeast(1)] = 50
    use_noise_pixels: bool = False


@register
class KernelRegressionData(Systematics[KrDataOptions]):
    """KR/Data: leave-one-out Gaussian kernel regression on the science frames.

    Each frame's kernel widths are the standard deviations of its k
    neighbours' offsets from it (:func:`local_kernel_weights`; Lewis et al.
    2013, Knutson et al. 2012, Wong et al. 2014 as their codes compute them).

    Options (:class:`KrDataOptions`)
    --------------------------------
    k : int, default 50
        Nearest neighbours (Wong et al. 2014).
    use_noise_pixels : bool, default False
        Add sqrt(noise pixels) as a third coordinate (Lewis et al. 2013); Wong
        et al. used x and y only.

    Examples
    --------
    >>> g = np.random.default_rng(0)
    >>> n = 2000
    >>> x, y = 15 + 0.03 * g.standard_normal(n), 15 + 0.05 * g.standard_normal(n)
    >>> data = EpochData(time_bmjd=np.arange(n) / 43200, flux=1e5 * (1 + 0.1 * (x - 15)),
    ...                  flux_err=np.full(n, 300.0), x=x, y=y)
    >>> model = KernelRegressionData(data)
    >>> bool(model.diagnostics()["weight_ratio_median"] > 1.5)
    True
    """

    name: ClassVar[str] = "kr-data"
    requires: ClassVar[tuple[str, ...]] = ("x", "y")
    record: ClassVar[MethodRecord] = MethodRecord(
        label="KR/Data", paper=team_profile("kr-data"), in_paper=True)

    def setup(self, data: EpochData) -> None:
        k = self.options.k
        use_np = self.options.use_noise_pixels
        if use_np and data.noise_pixels is None:
            raise InputError("method 'kr-data' with use_noise_pixels: needs the column "
                             "noise_pixels in the photometry table")
        n = len(data)
        if n < k + 1:
            raise InputError(f"method 'kr-data': {n} frames, fewer than k+1 = {k + 1}")
        beta = data.noise_pixels if use_np else None
        _check_finite("x, y" + (", noise_pixels" if use_np else ""), self.name, data.x, data.y, beta)
        if use_np and np.any(np.asarray(beta) <= 0):
            raise InputError("method 'kr-data': noise_pixels must be positive")
        idx, w, sq_dist, self.widths = local_kernel_weights(_coords(data.x, data.y, beta), k=k)
        self.k = k
        self.smoother = sp.csr_matrix((w.ravel(), idx.ravel(), np.arange(0, n * k + 1, k)),
                                      shape=(n, n))
        # The MCMC's compiled pass (_smooth_walkers) stores the frames in a reverse
        # Cuthill-McKee order of the smoother: neighbours close in memory.
        order = reverse_cuthill_mckee(self.smoother, symmetric_mode=False)
        self._rank = np.empty(n, dtype=np.int64)
        self._rank[order] = np.arange(n)
        self._near = np.ascontiguousarray(self._rank[idx][order])
        self._near_w = np.ascontiguousarray(w[order])
        self._dof = smoother_trace(sq_dist)
        self._weight_ratio_median = float(np.median(w.max(axis=1) / w.min(axis=1)))
        self._flux = np.asarray(data.flux, float)

    def diagnostics(self) -> dict[str, Any]:
        """Median per-frame kernel widths (x, y[, sqrt(beta)]), effective degrees of freedom,
        and how much the kernel weighs: the median over frames of the largest/smallest
        weight among its neighbours (1 is a plain nearest-neighbour mean)."""
        return {"width_median": np.median(self.widths, axis=0).tolist(),
                "dof": float(self._dof),
                "weight_ratio_median": self._weight_ratio_median}

    def predict(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """``astro * KR(flux / astro)`` (electrons)."""
        astro = np.asarray(astro, float)
        return astro * (self.smoother @ (self._flux / astro))

    def log_likelihood_batch(self, astro: np.ndarray, theta: np.ndarray | None = None,
                             noise_scale: float = 1.0) -> np.ndarray:
        """:meth:`log_likelihood` of every row of ``astro`` (shape (m, n)): one compiled
        pass over the neighbour lists for all rows (:func:`_smooth_walkers`)."""
        if not self._batch_is_exact(KernelRegressionData):
            return super().log_likelihood_batch(astro, theta, noise_scale)
        return self._white_log_likelihood_batch(self._predict_rows(astro), noise_scale)

    def residuals_batch(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """:meth:`residuals` of every row of ``astro`` (shape (m, n)), the same values: one
        compiled pass for all rows (:func:`_smooth_walkers`)."""
        if not self._batch_is_exact(KernelRegressionData):
            return super().residuals_batch(astro, theta)
        return (self.data.flux - self._predict_rows(astro)) / self.data.flux_err

    def _predict_rows(self, astro: np.ndarray) -> np.ndarray:
        """:meth:`predict` of every row of ``astro`` (shape (m, n)), the same values."""
        astro = np.ascontiguousarray(np.atleast_2d(np.asarray(astro, float)))
        return astro * _smooth_walkers(self._rank, self._near, self._near_w, self._flux, astro)

    def with_flux(self, flux: np.ndarray) -> KernelRegressionData:
        """The same neighbours and weights on new fluxes (they depend only on the centroids)."""
        new = self._copy_with_flux(flux)
        new._flux = new.data.flux
        return new

    def n_effective_params(self) -> int:
        """Effective degrees of freedom ``tr(S)`` of the smoother with the point included.

        The leave-one-out smoother used in the fit has zero trace, which would
        count the regression as free; ``tr(S)`` of the same kernel with each
        point included (weight 1 at distance 0) is the usual count for a
        linear smoother, about ``n / k_eff``.
        """
        return int(round(self._dof))


def pmap_gain(pmap: CalibrationSet | GriddedPmap, x: np.ndarray, y: np.ndarray,
              noise_pixels: np.ndarray | None, *, k: int, scales: np.ndarray | None):
    """The fixed KR/Pmap gain at each science frame (mean about 1).

    Parameters
    ----------
    pmap : CalibrationSet or GriddedPmap
    x, y : ndarray, shape (n,)
    noise_pixels : ndarray or None
        Science noise pixels; used as a third coordinate with a calibration set
        when given.
    k : int
        Neighbours (calibration set only).
    scales : ndarray or None
        Scale lengths of the coordinates (calibration set only).

    Returns
    -------
    gain : ndarray, shape (n,)
    """
    if isinstance(pmap, GriddedPmap):
        return interpolate_grid(pmap.gain, pmap.x_grid, pmap.y_grid, x, y)
    beta_cal = pmap.noise_pixels if noise_pixels is not None else None
    q = _coords(x, y, noise_pixels, scales)
    t = _coords(pmap.x, pmap.y, beta_cal, scales)
    idx, w = knn_weights(q, t, k=k, exclude_self=False)
    # Krick et al.: kernel-weighted calibration flux over the calibration flux
    # averaged over the pixel.
    return np.sum(w * pmap.flux[idx], axis=1) / np.mean(pmap.flux)


def noise_pixels_offset(pmap: CalibrationSet, x: np.ndarray, y: np.ndarray,
                        noise_pixels: np.ndarray, *, k: int, tree: cKDTree | None = None) -> float:
    """Median offset of the science noise pixels from the calibration set's at the same (x, y).

    The calibration star's frames may be shorter exposures than the science
    frames (0.1 s against 2 s for the warm pmap), so pointing jitter smears
    the science PSF more and raises its noise pixels by a near-constant
    amount. Each science frame is compared with the mean noise pixels of its
    ``k`` nearest calibration frames in (x, y) (``tree``: a k-d tree of the
    calibration (x, y), if already built).
    """
    if tree is None:
        tree = cKDTree(np.column_stack([pmap.x, pmap.y]))
    _, idx = tree.query(np.column_stack([x, y]), k=k)
    idx = np.asarray(idx).reshape(len(x), -1)
    return float(np.median(np.asarray(noise_pixels, float) - pmap.noise_pixels[idx].mean(axis=1)))


@dataclass(frozen=True)
class KrPmapOptions(KrDataOptions):
    """Options of ``kr-pmap`` (:class:`KernelRegressionPmap`): KR/Data's, and the map's."""

    use_noise_pixels: bool = True
    match_noise_pixels: bool = True
    max_distance_px: float = 0.1
    max_uncovered_fraction: float = 0.05
    min_occupancy: float = 20.0
    occupancy_sigma_px: float = 0.004

    def validate(self) -> None:
        check(self.max_distance_px > 0, "max_distance_px", "a positive distance in pixels")
        check(0 <= self.max_uncovered_fraction <= 1, "max_uncovered_fraction",
              "a fraction 0-1")
        check(self.min_occupancy >= 0, "min_occupancy", "an occupancy >= 0")
        check(self.occupancy_sigma_px > 0, "occupancy_sigma_px", "a positive width in pixels")


@register
class KernelRegressionPmap(Systematics[KrPmapOptions]):
    """KR/Pmap: kernel regression trained on a calibration star (Krick et al. 2016).

    The calibration set is the context resource ``pmap``: a calibration-star
    table (:class:`~eclipsebench.decorrelate.pmap.CalibrationSet`) or the
    gridded SSC pixel map (:class:`~eclipsebench.decorrelate.pmap.GriddedPmap`),
    loaded by :meth:`load_resources` from a path (default:
    ``SIMDIR/calibration/pmap_calibration.fits`` when the table comes from a
    simulation).

    Options (:class:`KrPmapOptions`)
    --------------------------------
    k : int, default 50
        Calibration neighbours per science frame.
    use_noise_pixels : bool, default True
        Use sqrt(noise pixels) as a third coordinate (the paper's KR/Pmap used
        x, y and beta); needs noise pixels in both tables. Ignored for a
        gridded map (x, y only).
    match_noise_pixels : bool, default True
        Before the regression, subtract from the science noise pixels their
        median offset from the calibration set's at the same (x, y)
        (:func:`noise_pixels_offset`; kept in ``noise_pixels_offset``). On the
        simulated challenge the 2 s science frames have noise pixels 0.18
        higher than the 0.1 s calibration frames, four times the science
        spread of sqrt(beta), which otherwise sends the neighbour search to the
        wrong positions.
    max_distance_px : float, default 0.1
        Frames whose nearest calibration point (gridded map: grid edge) is
        farther than this in (x, y) are "uncovered": the map says little about
        them, and they get the value of the nearest calibration data. Their
        number is kept in ``n_uncovered``.
    max_uncovered_fraction : float, default 0.05
        More uncovered frames than this fraction raise InputError (a map of
        another pixel, or a pointing far off the sweet spot).
    min_occupancy : float, default 20
        Frames whose occupancy is below this are left out of the fit and
        counted (``dropped_frames()["low_occupancy"]``, ``n_low_occupancy``),
        as the IRSA correction code flags them (``/THRESHOLD_OCC``, default
        ``THRESHOLD_VAL = 20``). Occupancy: the gridded map's ``occu_`` image
        interpolated at (x, y); for a calibration table the Gaussian
        kernel-weighted number of calibration points around (x, y)
        (:func:`~eclipsebench.decorrelate.pmap.kernel_occupancy`). 0 keeps
        every frame.
    occupancy_sigma_px : float, default 0.004
        Calibration table only: the width of the occupancy kernel, pixels. The
        SSC does not document the width behind its ``occu_`` images; 0.004 px
        is what the ch2 maps themselves imply (the Gaussian fall-off of the
        occupancy image's power spectrum: 0.0041-0.0049 px; the total
        occupancy over 2 pi N with the ~400,000 points of Appendix B.4:
        0.0032-0.0038 px), so a calibration table's occupancy counts points
        at the resolution of the SSC map.
    """

    name: ClassVar[str] = "kr-pmap"
    requires: ClassVar[tuple[str, ...]] = ("x", "y")
    record: ClassVar[MethodRecord] = MethodRecord(
        label="KR/Pmap", paper=team_profile("kr-pmap"), in_paper=True)
    resources: ClassVar[tuple[str, ...]] = ("pmap",)

    @classmethod
    def load_resources(cls, data: EpochData, sources: Mapping[str, Any]) -> dict[str, Any]:
        """``{"pmap": CalibrationSet or GriddedPmap}`` from a path, a loaded map, or the
        simulation folder named in the table's metadata."""
        given = sources.get("pmap")
        if isinstance(given, (CalibrationSet, GriddedPmap)):
            return {"pmap": given}
        time = float(np.min(data.time_bmjd)) if len(data.time_bmjd) else None
        return {"pmap": load_pmap(find_pmap_path(given, data.meta, time))}

    def setup(self, data: EpochData) -> None:
        o = self.options
        k, use_np, match_np = o.k, o.use_noise_pixels, o.match_noise_pixels
        max_d, max_frac = o.max_distance_px, o.max_uncovered_fraction
        self.pmap = self.context.resource("pmap")
        self._tree_xy: cKDTree | None = None
        path = self.pmap.source or "the calibration set"
        x = np.asarray(data.x, float)
        y = np.asarray(data.y, float)
        _check_finite("x, y", self.name, x, y)
        occupancy = self._occupancy(x, y)
        low = occupancy < o.min_occupancy
        self.n_low_occupancy = int(low.sum())
        if self.n_low_occupancy == len(x):
            raise InputError(f"pmap {path}: every frame ({len(x)}) falls where the map's occupancy "
                             f"is below min_occupancy={o.min_occupancy} (median occupancy "
                             f"{np.median(occupancy):.3g}): a map of another pixel?")
        if self.n_low_occupancy:
            # Left out of the fit as the IRSA code flags them (MISSING); the fitter
            # evaluates the astrophysical model at self.data's times.
            data = data.subset(np.flatnonzero(~low))
            self.data = data
            x, y = x[~low], y[~low]
        self.occupancy_median = float(np.median(occupancy[~low]))
        if isinstance(self.pmap, GriddedPmap):
            g = self.pmap
            out_x = np.maximum(g.x_grid[0] - x, x - g.x_grid[-1])
            out_y = np.maximum(g.y_grid[0] - y, y - g.y_grid[-1])
            far = np.hypot(np.maximum(out_x, 0), np.maximum(out_y, 0)) > max_d
            beta = None
            self.scales = None
            self.noise_pixels_offset = 0.0
        else:
            if len(self.pmap) < k:
                raise InputError(f"pmap {path}: {len(self.pmap)} calibration rows, fewer than k = {k}")
            beta = data.noise_pixels if use_np else None
            if use_np and beta is None:
                raise InputError("method 'kr-pmap' with use_noise_pixels: needs the column "
                                 "noise_pixels in the photometry table (or use_noise_pixels=false)")
            _check_finite("noise_pixels", self.name, beta)
            tree_xy = self._cal_tree()
            self.noise_pixels_offset = 0.0
            if beta is not None and match_np:
                self.noise_pixels_offset = noise_pixels_offset(self.pmap, x, y, beta, k=k,
                                                               tree=tree_xy)
                beta = np.asarray(beta, float) - self.noise_pixels_offset
                if np.any(beta <= 0):
                    raise InputError(f"pmap {path}: the science noise pixels minus their offset "
                                     f"from the calibration set ({self.noise_pixels_offset:.3g}) "
                                     "are not all positive; use match_noise_pixels=false")
            self.scales = scale_lengths(x, y, beta)
            if not np.all(self.scales > 0):
                raise InputError("method 'kr-pmap': a kernel coordinate does not vary over the "
                                 "epoch (zero standard deviation)")
            dist, _ = tree_xy.query(np.column_stack([x, y]), k=1)
            far = dist > max_d
        self.n_uncovered = int(far.sum())
        if self.n_uncovered > max_frac * len(x):
            raise InputError(f"pmap {path}: {self.n_uncovered} of {len(x)} frames lie more than "
                             f"{max_d} px from the calibration data (max_distance_px), more than "
                             f"max_uncovered_fraction={max_frac}")
        self.k = k
        self.gain = pmap_gain(self.pmap, x, y, beta, k=k, scales=self.scales)
        self._flux = np.asarray(data.flux, float)
        self._ivar = 1.0 / np.asarray(data.flux_err, float) ** 2

    def _cal_tree(self) -> cKDTree:
        """The k-d tree of the calibration (x, y), built once."""
        if self._tree_xy is None:
            self._tree_xy = cKDTree(np.column_stack([self.pmap.x, self.pmap.y]))
        return self._tree_xy

    def _occupancy(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The pixel map's occupancy at each science centroid (see ``min_occupancy``)."""
        if isinstance(self.pmap, GriddedPmap):
            g = self.pmap
            return interpolate_grid(g.occupancy, g.x_grid, g.y_grid, x, y)
        return kernel_occupancy(self.pmap.x, self.pmap.y, x, y,
                                sigma_px=self.options.occupancy_sigma_px, tree=self._cal_tree())

    def dropped_frames(self) -> dict[str, int]:
        """``{"low_occupancy": n}``: frames left out where the map's occupancy is below
        ``min_occupancy``."""
        return {"low_occupancy": self.n_low_occupancy}

    def flux_scale(self, astro: np.ndarray) -> float:
        """Weighted least-squares ``F0`` of ``flux = F0 * astro * gain`` (electrons)."""
        m = np.asarray(astro, float) * self.gain
        wm = self._ivar * m
        return float(np.einsum("i,i->", wm, self._flux) / np.einsum("i,i->", wm, m))

    def predict(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """``F0 * astro * gain`` with ``F0`` solved in closed form (electrons)."""
        m = np.asarray(astro, float) * self.gain
        # einsum rather than np.dot: no BLAS threads in the fitter's inner loop.
        wm = self._ivar * m
        return (np.einsum("i,i->", wm, self._flux) / np.einsum("i,i->", wm, m)) * m

    def log_likelihood_batch(self, astro: np.ndarray, theta: np.ndarray | None = None,
                             noise_scale: float = 1.0) -> np.ndarray:
        """:meth:`log_likelihood` of every row of ``astro`` (shape (m, n)), ``F0`` of each
        row in closed form as in :meth:`predict`."""
        if not self._batch_is_exact(KernelRegressionPmap):
            return super().log_likelihood_batch(astro, theta, noise_scale)
        m = np.atleast_2d(np.asarray(astro, float)) * self.gain
        wm = self._ivar * m
        f0 = np.einsum("ij,j->i", wm, self._flux) / np.einsum("ij,ij->i", wm, m)
        return self._white_log_likelihood_batch(f0[:, None] * m, noise_scale)

    def diagnostics(self) -> dict[str, Any]:
        """The calibration set used and how well it covers the science frames (frames
        dropped for low occupancy, the median occupancy of those kept, frames farther
        than ``max_distance_px`` from the calibration data)."""
        return {"pmap": str(self.pmap.source), "pmap_kind": type(self.pmap).__name__,
                "n_uncovered": self.n_uncovered, "n_low_occupancy": self.n_low_occupancy,
                "occupancy_median": self.occupancy_median,
                "noise_pixels_offset": float(self.noise_pixels_offset)}

    def with_flux(self, flux: np.ndarray) -> KernelRegressionPmap:
        """The same fixed gain on new fluxes."""
        new = self._copy_with_flux(flux)
        new._flux = new.data.flux
        return new

    def n_effective_params(self) -> int:
        """One: the flux scale F0 (the gain map is fixed by the calibration data)."""
        return 1
