"""Pixel maps for KR/Pmap, as arrays: bilinear interpolation of a gridded map, kernel occupancy.

Two kinds of pixel map are supported (Krick et al. 2016; paper Appendix B.4),
read from their files by :mod:`eclipsebench.io.pmap_files` (the kernels here
take arrays, never paths):

* a **calibration-star table** (:class:`CalibrationSet`): photometry of a
  separate, constant star whose centroid wandered over the sweet-spot pixel.
  KR/Pmap regresses the science centroids on it with a Gaussian kernel over
  the k nearest neighbours;
* the **gridded warm pmap** of the Spitzer Science Center
  (:class:`GriddedPmap`). It is already a kernel-regression product on
  about 400,000 measurements, so KR/Pmap interpolates it bilinearly at the
  science centroids, as the IRSA correction code ``iracpc_pmap_corr.pro``
  does.

Occupancy. The IRSA code (``iracpc_pmap_corr.pro``, keywords ``/THRESHOLD_OCC``
and ``THRESHOLD_VAL``, default 20) defines the "occupation" of the map as "the
gaussian kernel-weighted number of data points that contribute to each grid
location", interpolates it bilinearly at each science centroid, and flags the
frames below the threshold as missing. For a gridded map the occupancy comes
from its ``occu_`` file (:func:`interpolate_grid`); for a calibration-star
table :func:`kernel_occupancy` counts the calibration points around each frame
with the same Gaussian weight, ``exp(-r^2 / 2 sigma^2)`` in (x, y).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..io.pmap_files import CalibrationSet, GriddedPmap

__all__ = ["CalibrationSet", "GriddedPmap", "interpolate_grid", "kernel_occupancy"]


def interpolate_grid(values: np.ndarray, x_grid: np.ndarray, y_grid: np.ndarray,
                     x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Bilinear interpolation of ``values[iy, ix]`` on a regular grid at points (x, y).

    Points outside the grid take the value at the nearest edge (as IDL's
    ``interpolate`` does in the IRSA correction code).

    Parameters
    ----------
    values : ndarray, shape (ny, nx)
    x_grid, y_grid : ndarray, shape (nx,), (ny,)
        Regular, increasing cell-centre coordinates.
    x, y : ndarray, shape (n,)
        Where to interpolate.

    Returns
    -------
    ndarray, shape (n,)
    """
    nx, ny = len(x_grid), len(y_grid)
    fx = np.clip((np.asarray(x, float) - x_grid[0]) / (x_grid[1] - x_grid[0]), 0.0, nx - 1.0)
    fy = np.clip((np.asarray(y, float) - y_grid[0]) / (y_grid[1] - y_grid[0]), 0.0, ny - 1.0)
    ix = np.minimum(fx.astype(np.intp), nx - 2)
    iy = np.minimum(fy.astype(np.intp), ny - 2)
    tx, ty = fx - ix, fy - iy
    return ((1 - tx) * (1 - ty) * values[iy, ix] + tx * (1 - ty) * values[iy, ix + 1]
            + (1 - tx) * ty * values[iy + 1, ix] + tx * ty * values[iy + 1, ix + 1])


#: Neighbours farther than this many kernel widths add less than 4e-6 each; not counted.
_OCCUPANCY_REACH_SIGMAS = 5.0
#: Science positions per block of the pair search in :func:`kernel_occupancy`.
_OCCUPANCY_BLOCK = 2048


def kernel_occupancy(cal_x: np.ndarray, cal_y: np.ndarray, x: np.ndarray, y: np.ndarray, *,
                     sigma_px: float, tree: cKDTree | None = None) -> np.ndarray:
    """Gaussian kernel-weighted number of calibration points around each position.

    The SSC's definition of a pixel map's occupancy (``iracpc_pmap_corr.pro``:
    "the gaussian kernel-weighted number of data points that contribute to
    each grid location"), evaluated at the science centroids instead of at
    grid cells::

        occupancy_i = sum_j exp(-((x_i - X_j)^2 + (y_i - Y_j)^2) / (2 sigma^2))

    Parameters
    ----------
    cal_x, cal_y : ndarray, shape (m,)
        Calibration centroids, pixels.
    x, y : ndarray, shape (n,)
        Where to count, pixels.
    sigma_px : float
        Kernel width, pixels.
    tree : cKDTree, optional
        A k-d tree of the calibration (x, y), if already built.

    Returns
    -------
    ndarray, shape (n,)

    Examples
    --------
    >>> occ = kernel_occupancy(np.zeros(3), np.zeros(3), np.array([0.0, 1.0]),
    ...                        np.array([0.0, 0.0]), sigma_px=0.01)
    >>> occ.round(6).tolist()
    [3.0, 0.0]
    """
    if tree is None:
        tree = cKDTree(np.column_stack([cal_x, cal_y]))
    q = np.column_stack([np.asarray(x, float), np.asarray(y, float)])
    occupancy = np.zeros(len(q))
    reach = _OCCUPANCY_REACH_SIGMAS * sigma_px
    # Pairs within reach come from the C++ tree-tree search in blocks of
    # positions, to bound the memory of the pair list.
    for start in range(0, len(q), _OCCUPANCY_BLOCK):
        block = cKDTree(q[start:start + _OCCUPANCY_BLOCK])
        pairs = block.sparse_distance_matrix(tree, reach, output_type="ndarray")
        occupancy[start:start + block.n] = np.bincount(
            pairs["i"], weights=np.exp(-0.5 * (pairs["v"] / sigma_px) ** 2), minlength=block.n)
    return occupancy
