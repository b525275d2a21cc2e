"""PLD: pixel-level decorrelation (Deming et al. 2015; paper Appendix B.5).

The sensitivity is a linear combination of the normalised pixel values of a
small stamp around the star (Deming et al. 2015, Eq. 4)::

    P_hat_it = P_it / sum_i P_it
    flux_t = astro_t * (sum_i c_i P_hat_it [+ f t + g t^2 ...])

Normalising by the frame's own sum removes the astrophysical signal from the
regressors, so they carry only the pointing. The coefficients are linear and
are solved by weighted least squares inside every evaluation, for the given
astrophysical curve. Because ``sum_i P_hat_it = 1`` the pixel basis already
contains a constant, so the optional time polynomial starts at degree 1.

Deming et al. multiply by the eclipse additively (``S = sum c P_hat + D E(t)``);
the multiplicative form used here is identical to first order in the
sensitivity variations (~0.3 %) and is the form shared by every method of this
package.

Binning (Deming et al. 2015, Sect. 3.2): with ``bin_frames > 1`` the
coefficients are fitted on data averaged in consecutive bins of that many
frames (the design and the flux are binned the same way, so the binned fit is
the fit of the binned model), then applied to the unbinned frames.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from ..config.base import check
from ..errors import InputError
from .base import EpochData, MethodContext, MethodOptions, Systematics, register

__all__ = ["normalised_pixels", "central_stamp", "time_basis", "PldDesign", "pld_solve",
           "PixelLevelDecorrelation"]


def central_stamp(pixels: np.ndarray, size: int) -> np.ndarray:
    """The central ``size x size`` pixels of square stamps, flattened to (n, size*size).

    Parameters
    ----------
    pixels : ndarray, shape (n, p) or (n, m, m)
        Stamps, flattened row-major or not; ``p`` must be a square ``m*m`` with
        ``m >= size`` and ``m - size`` even.
    """
    a = np.asarray(pixels, float)
    n = a.shape[0]
    m = int(round(np.sqrt(a[0].size)))
    if m * m != a[0].size:
        raise InputError(f"pixel stamps: {a[0].size} values per frame is not a square stamp")
    if size > m or (m - size) % 2:
        raise InputError(f"method 'pld': cannot take a {size}x{size} stamp from {m}x{m} stamps "
                         "(read the table's 5x5 stamps with reduce.stamp = \"stamp5\")")
    a = a.reshape(n, m, m)
    o = (m - size) // 2
    return a[:, o:o + size, o:o + size].reshape(n, size * size)


def normalised_pixels(pixels: np.ndarray) -> np.ndarray:
    """``P_hat = P / sum(P)`` per frame (Deming et al. 2015, Eq. 3)."""
    p = np.asarray(pixels, float)
    total = p.sum(axis=1, keepdims=True)
    if np.any(total <= 0) or not np.all(np.isfinite(p)):
        raise InputError("method 'pld': every pixel stamp must be finite with a positive sum")
    return p / total


def time_basis(time: np.ndarray, degree: int) -> np.ndarray:
    """Columns ``tau, tau^2, ... tau^degree`` with ``tau`` the time scaled to [-1, 1]."""
    t = np.asarray(time, float)
    span = t.max() - t.min()
    tau = (2.0 * (t - t.min()) / span - 1.0) if span > 0 else np.zeros_like(t)
    return np.column_stack([tau**d for d in range(1, degree + 1)]) if degree else np.empty((len(t), 0))


_OUTER_BYTES_MAX = 64 * 2**20


class PldDesign:
    """Parameter-independent pieces of the PLD regression.

    Parameters
    ----------
    regressors : ndarray, shape (n, p)
        Normalised pixels and any time terms.
    flux, flux_err : ndarray, shape (n,)
    bin_frames : int
        Frames per bin for the coefficient fit (1 = unbinned).
    time : ndarray, shape (n,), optional
        Frame times; bins hold consecutive frames in time order.
    """

    def __init__(self, regressors: np.ndarray, flux: np.ndarray, flux_err: np.ndarray,
                 bin_frames: int = 1, time: np.ndarray | None = None) -> None:
        d = np.asarray(regressors, float)
        n = d.shape[0]
        self.n_regressors = d.shape[1]
        self.bin_frames = int(bin_frames)
        # Unit-rms columns keep the normal equations well conditioned.
        self.col_scale = np.sqrt(np.mean(d**2, axis=0))
        self.col_scale[self.col_scale == 0] = 1.0
        self.design = d / self.col_scale
        self.iu = np.triu_indices(self.n_regressors)
        self.outer = None
        if self.bin_frames == 1:
            self.starts = None
            self.b_flux = np.asarray(flux, float)
            self.b_ivar_sqrt = 1.0 / np.asarray(flux_err, float)
            # Per-frame products D_i D_j (upper triangle): the normal matrix is
            # then one weighted sum per evaluation, with no BLAS call (BLAS
            # threads stall on a loaded machine for arrays this small).
            if n * len(self.iu[0]) * 8 <= _OUTER_BYTES_MAX:
                self.outer = self.design[:, self.iu[0]] * self.design[:, self.iu[1]]
        else:
            self.order = None if time is None else np.argsort(np.asarray(time), kind="stable")
            self.starts = np.arange(0, n, self.bin_frames)
            counts = np.diff(np.append(self.starts, n)).astype(float)
            self.counts = counts
            self.b_flux = self._binned(np.asarray(flux, float))
            var = self._binned(np.asarray(flux_err, float) ** 2) / counts
            self.b_ivar_sqrt = 1.0 / np.sqrt(var)
        self.b_target = self.b_flux * self.b_ivar_sqrt

    def with_flux(self, flux: np.ndarray) -> PldDesign:
        """A copy whose target is ``flux`` (same regressors, errors and bins)."""
        new = copy.copy(self)
        new.b_flux = self._binned(np.asarray(flux, float))
        new.b_target = new.b_flux * self.b_ivar_sqrt
        return new

    def _binned(self, a: np.ndarray) -> np.ndarray:
        if self.starts is None:
            return a
        if self.order is not None:
            a = a[self.order]
        s = np.add.reduceat(a, self.starts, axis=0)
        return s / (self.counts[:, None] if s.ndim == 2 else self.counts)


def pld_solve(design: PldDesign, astro: np.ndarray) -> np.ndarray:
    """Weighted least-squares coefficients (of the scaled columns) for ``astro``.

    Minimises ``sum_b ((F_b - (astro D)_b c) / sigma_b)^2`` over bins ``b``
    (frames when unbinned) through the p x p normal equations.
    """
    astro = np.asarray(astro, float)
    if design.outer is not None:
        s = astro * design.b_ivar_sqrt
        tri = np.einsum("n,nk->k", s * s, design.outer)
        a = np.empty((design.n_regressors, design.n_regressors))
        a[design.iu] = tri
        a.T[design.iu] = tri
        b = np.einsum("n,nk->k", s * design.b_target, design.design)
    else:
        gw = design._binned(design.design * astro[:, None]) * design.b_ivar_sqrt[:, None]
        a = np.einsum("bi,bj->ij", gw, gw)
        b = np.einsum("bi,b->i", gw, design.b_target)
    try:
        return np.linalg.solve(a, b)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(a, b, rcond=None)[0]


@dataclass(frozen=True)
class PldOptions(MethodOptions):
    """Options of ``pld`` (:class:`PixelLevelDecorrelation`)."""

    stamp: Literal[3, 5] = 3
    time_poly_degree: int = 0
    bin_frames: int = 1

    def validate(self) -> None:
        check(0 <= self.time_poly_degree <= 5, "time_poly_degree", "an integer 0-5")
        check(self.bin_frames >= 1, "bin_frames", "an integer >= 1")


@register
class PixelLevelDecorrelation(Systematics):
    """PLD (Deming et al. 2015; paper Appendix B.5).

    Options (:class:`PldOptions`)
    -----------------------------
    stamp : int, 3 or 5, default 3
        Side of the pixel stamp; a larger stamp in the table is cut to its
        central part.
    time_poly_degree : int, default 0
        Degree of the time polynomial added to the regressors (Deming et al.
        Eq. 4 uses 2, ``f t + g t^2``; the shared astrophysical model already
        carries the phase curve and ramp, so none by default).
    bin_frames : int, default 1
        Fit the coefficients on bins of this many consecutive frames.
    """

    name: ClassVar[str] = "pld"
    requires: ClassVar[tuple[str, ...]] = ("pixels",)
    Options: ClassVar[type[MethodOptions]] = PldOptions
    description: ClassVar[str] = "linear regression on normalised pixel values"

    def __init__(self, data: EpochData, options: Any = None, *,
                 context: MethodContext | None = None, **kwargs: Any) -> None:
        super().__init__(data, options, context=context, **kwargs)
        stamp = self.options.stamp
        degree = self.options.time_poly_degree
        bin_frames = self.options.bin_frames
        n = len(data)
        p_hat = normalised_pixels(central_stamp(data.pixels, int(stamp)))
        regressors = np.column_stack([p_hat, time_basis(data.time_bmjd, int(degree))])
        n_bins = -(-n // int(bin_frames))
        if n_bins <= regressors.shape[1]:
            raise InputError(f"method 'pld': {n_bins} (binned) points for {regressors.shape[1]} "
                             "regressors; use fewer bin_frames")
        self.stamp = int(stamp)
        self.design = PldDesign(regressors, data.flux, data.flux_err, int(bin_frames),
                                time=data.time_bmjd)

    def diagnostics(self) -> dict[str, Any]:
        """The stamp, the regressors and the points the coefficients are fitted on."""
        return {"stamp": self.stamp, "n_regressors": int(self.design.n_regressors),
                "bin_frames": self.options.bin_frames,
                "n_fit_points": -(-len(self.data) // self.options.bin_frames)}

    def coefficients(self, astro: np.ndarray) -> np.ndarray:
        """The PLD coefficients ``c_i`` (of the unscaled regressors) for ``astro``."""
        return pld_solve(self.design, astro) / self.design.col_scale

    def predict(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """``astro * (P_hat c [+ poly])`` with ``c`` solved by weighted least squares."""
        astro = np.asarray(astro, float)
        return astro * np.einsum("nk,k->n", self.design.design, pld_solve(self.design, astro))

    def with_flux(self, flux: np.ndarray) -> PixelLevelDecorrelation:
        """The same design on new fluxes."""
        flux = np.asarray(flux, dtype=float)
        if flux.shape != self.data.flux.shape:
            raise InputError(f"with_flux: expected {self.data.flux.shape[0]} fluxes, got {flux.shape}")
        new = copy.copy(self)
        new.data = dataclasses.replace(self.data, flux=flux)
        new.design = self.design.with_flux(flux)
        return new

    def n_effective_params(self) -> int:
        """The number of linear regressors (pixels plus time terms)."""
        return self.design.n_regressors
