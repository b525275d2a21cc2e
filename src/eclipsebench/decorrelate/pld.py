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

Binned fit (Deming et al. 2015, Sect. 3): the whole fit (coefficients and
eclipse) is made on data averaged in consecutive bins of ``b`` frames: the
design and the flux are binned the same way, so the binned fit is the fit of
the binned model, and :meth:`PixelLevelDecorrelation.residuals` are the
binned residuals. The coefficients are then applied to the unbinned frames.
The bin size is chosen as Deming et al. choose it: for each candidate, the
unbinned residuals are averaged over ``N`` frames for ``N = 1, 2, 4, ...``,
and the candidate whose log rms against log ``N`` has the slope closest to
the white-noise value -1/2 wins (:func:`residual_scatter_curve`,
:func:`scatter_slope`). The choice depends on the fitted eclipse, so it is
made in :meth:`PixelLevelDecorrelation.optimise_hyperparameters`, which the
fitter alternates with the joint fit.

Time-averaging error (paper App. B.5; Deming et al. 2015): the same slope
extrapolates the rms of the residuals to bins as long as the eclipse; that
rms is the depth error the PLD team reported
(:meth:`PixelLevelDecorrelation.depth_error_estimates`, ``"time_averaging"``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from ..config.base import check
from ..errors import InputError
from .base import EpochData, MethodOptions, register
from .linear import LinearDesign, LinearSystematics, solve_coefficients
from .record import MethodRecord, team_profile

__all__ = ["normalised_pixels", "central_stamp", "time_basis", "residual_scatter_curve", "scatter_slope",
           "eclipse_frames", "time_averaging_error", "PixelLevelDecorrelation"]

#: The rms of N-frame means is kept in the slope fit while there are at least
#: this many bins (its relative error is then 1/sqrt(2 (M-1)) <= 24 %).
SLOPE_MIN_BINS = 10
#: A candidate bin size is tried only if it leaves this many bins per regressor.
MIN_BINS_PER_REGRESSOR = 5


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


def residual_scatter_curve(residual: np.ndarray, *, min_bins: int = SLOPE_MIN_BINS
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rms of means of ``N`` consecutive residuals, for ``N = 1, 2, 4, ...``.

    Parameters
    ----------
    residual : ndarray, shape (n,)
        Residuals in time order (relative flux).
    min_bins : int
        ``N`` grows while at least this many complete bins remain.

    Returns
    -------
    n_per_bin, rms, n_bins : ndarray
        Frames per bin, the standard deviation (ddof=1) of the bin means, and
        the number of complete bins of each size.

    Examples
    --------
    >>> r = np.random.default_rng(1).standard_normal(4096)
    >>> n, rms, m = residual_scatter_curve(r)
    >>> n[:4].tolist(), bool(m[-1] >= 10)
    ([1, 2, 4, 8], True)
    """
    r = np.asarray(residual, float)
    sizes, rms, counts = [], [], []
    size = 1
    while len(r) // size >= max(int(min_bins), 2):
        m = len(r) // size
        means = r[:m * size].reshape(m, size).mean(axis=1)
        sizes.append(size)
        rms.append(float(np.std(means, ddof=1)))
        counts.append(m)
        size *= 2
    return np.asarray(sizes), np.asarray(rms), np.asarray(counts)


def scatter_slope(n_per_bin: np.ndarray, rms: np.ndarray, n_bins: np.ndarray
                  ) -> tuple[float, float]:
    """Slope and intercept of ``log rms = a + s log N``, weighted by ``M - 1`` bins.

    The variance of the log of an rms from ``M`` bins is about
    ``1 / (2 (M - 1))``, hence the weights. White noise has ``s = -1/2``.

    Returns
    -------
    (slope, intercept) : tuple of float
        In natural logarithms: ``rms(N) = exp(intercept) * N ** slope``.

    Examples
    --------
    >>> n = np.array([1, 2, 4, 8]); m = np.array([800, 400, 200, 100])
    >>> s, a = scatter_slope(n, 1e-3 / np.sqrt(n), m)
    >>> round(s, 6), round(float(np.exp(a)), 9)
    (-0.5, 0.001)
    """
    ok = np.asarray(rms) > 0
    x = np.log(np.asarray(n_per_bin, float)[ok])
    y = np.log(np.asarray(rms, float)[ok])
    w = np.asarray(n_bins, float)[ok] - 1.0
    if len(x) < 2:
        return float("nan"), float("nan")
    xm = np.sum(w * x) / np.sum(w)
    ym = np.sum(w * y) / np.sum(w)
    slope = float(np.sum(w * (x - xm) * (y - ym)) / np.sum(w * (x - xm) ** 2))
    return slope, float(ym - slope * xm)


def eclipse_frames(dastro_ddepth: np.ndarray) -> int:
    """Frames of the eclipse: where the planet's share of the light is below half its full value.

    ``dastro_ddepth`` is the visible fraction of the planet (times the phase
    curve and ramp) at each frame; the count is the eclipse's length from
    mid-ingress to mid-egress, in frames. A transit's derivative (negative:
    the planet takes the star's light) counts the frames where it is beyond
    half its extreme, mid-ingress to mid-egress of the transit.
    """
    d = np.asarray(dastro_ddepth, float)
    top = np.max(np.abs(d)) if d.size else 0.0
    if top > 0 and -d.min() == top:   # a transit
        return int(np.count_nonzero(np.abs(d) > 0.5 * top))
    return int(np.count_nonzero(np.abs(d) < 0.5 * top)) if top > 0 else 0


def time_averaging_error(residual: np.ndarray, n_eclipse: int, *, n_baseline: int = 0,
                         min_bins: int = SLOPE_MIN_BINS) -> float:
    """Deming et al.'s depth error: the residual rms extrapolated to eclipse-long bins.

    The rms of ``N``-frame means of the residuals is fitted as a power law in
    ``N`` (:func:`residual_scatter_curve`, :func:`scatter_slope`) and
    evaluated at ``N = n_eclipse``. With ``n_baseline > 0`` the same law at
    ``N = n_baseline`` (the out-of-eclipse level) is added in quadrature.

    Parameters
    ----------
    residual : ndarray
        Relative residuals of the unbinned frames, in time order.
    n_eclipse : int
        Frames in the eclipse (:func:`eclipse_frames`).
    n_baseline : int
        Frames outside it, or 0 for the eclipse bin alone (the default reading).

    Returns
    -------
    float
        The depth error (fraction of the stellar flux); NaN if undefined.

    Examples
    --------
    >>> r = 1e-3 * np.random.default_rng(2).standard_normal(2**14)
    >>> err = time_averaging_error(r, 4096)
    >>> bool(abs(err / (1e-3 / 64) - 1) < 0.2)
    True
    """
    if n_eclipse < 1:
        return float("nan")
    slope, intercept = scatter_slope(*residual_scatter_curve(residual, min_bins=min_bins))
    sigma_ecl = float(np.exp(intercept) * n_eclipse ** slope)
    if n_baseline > 0:
        return float(np.hypot(sigma_ecl, np.exp(intercept) * n_baseline ** slope))
    return sigma_ecl


@dataclass(frozen=True)
class PldOptions(MethodOptions):
    """Options of ``pld`` (:class:`PixelLevelDecorrelation`)."""

    stamp: Literal[3, 5] = 3
    time_poly_degree: int = 0
    bin_frames: int | None = None
    bin_candidates: tuple[int, ...] = (1, 2, 4, 8, 16, 32, 64, 128, 256)
    baseline_term: bool = False

    def validate(self) -> None:
        check(0 <= self.time_poly_degree <= 5, "time_poly_degree", "an integer 0-5")
        check(self.bin_frames is None or self.bin_frames >= 1, "bin_frames",
              "an integer >= 1 (or none: chosen from bin_candidates)")
        check(len(self.bin_candidates) >= 1 and all(b >= 1 for b in self.bin_candidates),
              "bin_candidates", "one or more integers >= 1")


@register
class PixelLevelDecorrelation(LinearSystematics[PldOptions]):
    """PLD (Deming et al. 2015; paper Appendix B.5), fitted on binned data.

    Options (:class:`PldOptions`)
    -----------------------------
    stamp : int, 3 or 5, default 3
        Side of the pixel stamp; a larger stamp in the table is cut to its
        central part.
    time_poly_degree : int, default 0
        Degree of the time polynomial added to the regressors (Deming et al.
        Eq. 4 uses 2, ``f t + g t^2``; the shared astrophysical model already
        carries the phase curve and ramp, so none by default).
    bin_frames : int, optional
        Fit on bins of this many consecutive frames. Default: chosen among
        ``bin_candidates`` by Deming et al.'s criterion (the slope of log
        residual rms against log bin size closest to -1/2).
    bin_candidates : tuple of int
        The bin sizes tried (frames); those leaving fewer than
        ``MIN_BINS_PER_REGRESSOR`` bins per regressor are skipped.
    baseline_term : bool, default False
        Add the out-of-eclipse level's extrapolated rms to the time-averaging
        error (default: the eclipse-long bin alone, as the PLD team reported).

    Examples
    --------
    >>> g = np.random.default_rng(0)
    >>> pix = g.uniform(50.0, 500.0, (2000, 9))
    >>> d = EpochData(time_bmjd=np.arange(2000) / 43200, flux=pix.sum(1),
    ...               flux_err=np.full(2000, 30.0), x=np.zeros(2000), y=np.zeros(2000),
    ...               pixels=pix)
    >>> m = PixelLevelDecorrelation(d, bin_frames=8)
    >>> m.bin_frames, len(m.residuals(np.ones(2000)))
    (8, 250)
    """

    name: ClassVar[str] = "pld"
    requires: ClassVar[tuple[str, ...]] = ("pixels",)
    record: ClassVar[MethodRecord] = MethodRecord(
        label="PLD", paper=team_profile("pld"), in_paper=True)

    def setup(self, data: EpochData) -> None:
        stamp = int(self.options.stamp)
        degree = int(self.options.time_poly_degree)
        n = len(data)
        p_hat = normalised_pixels(central_stamp(data.column("pixels"), stamp))
        regressors = np.column_stack([p_hat, time_basis(data.time_bmjd, degree)])
        p = regressors.shape[1]
        fixed = self.options.bin_frames
        if fixed is not None:
            n_bins = -(-n // int(fixed))
            if n_bins <= p:
                raise InputError(f"method 'pld': {n_bins} (binned) points for {p} "
                                 "regressors; use fewer bin_frames")
            sizes = [int(fixed)]
        else:
            sizes = sorted({int(b) for b in self.options.bin_candidates
                            if n // int(b) >= MIN_BINS_PER_REGRESSOR * p})
            if not sizes:
                raise InputError(f"method 'pld': no bin size in bin_candidates leaves "
                                 f"{MIN_BINS_PER_REGRESSOR} bins per regressor ({n} frames, "
                                 f"{p} regressors)")
        self.stamp = stamp
        self.order = np.argsort(np.asarray(data.time_bmjd), kind="stable")
        self.designs = {b: LinearDesign(regressors, data.flux, data.flux_err, b,
                                     time=data.time_bmjd) for b in sizes}
        self.bin_frames = sizes[0]
        self.bin_scores: dict[int, float] = {}

    @property
    def design(self) -> LinearDesign:
        """The regression of the current bin size."""
        return self.designs[self.bin_frames]

    def diagnostics(self) -> dict[str, Any]:
        """The stamp, the regressors, the bin size and each candidate's slope."""
        return {"stamp": self.stamp, "n_regressors": int(self.design.n_regressors),
                "bin_frames": int(self.bin_frames),
                "bin_choice": "fixed" if self.options.bin_frames is not None else "slope",
                "scatter_slope_by_bin": {str(b): v for b, v in self.bin_scores.items()},
                "n_fit_points": -(-len(self.data) // int(self.bin_frames))}

    def coefficients(self, astro: np.ndarray) -> np.ndarray:
        """The PLD coefficients ``c_i`` (of the unscaled regressors) for ``astro``."""
        return solve_coefficients(self.design, astro) / self.design.col_scale

    def relative_residuals(self, astro: np.ndarray) -> np.ndarray:
        """``flux / model - 1`` of the unbinned frames, in time order."""
        astro = np.asarray(astro, float)
        return (self.data.flux / self.predict(astro) - 1.0)[self.order]

    def optimise_hyperparameters(self, astro: np.ndarray) -> dict[str, Any] | None:
        """Choose the bin size as Deming et al. do, for the fitted ``astro``.

        For each candidate the binned fit's coefficients are applied to the
        unbinned frames; the candidate whose residual rms falls with bin size
        at the slope closest to -1/2 (white noise) is kept. Nothing changes
        when ``bin_frames`` is fixed.
        """
        if self.options.bin_frames is not None:
            return None
        astro = np.asarray(astro, float)
        scores = {}
        for b in self.designs:
            self.bin_frames = b
            scores[b] = scatter_slope(*residual_scatter_curve(self.relative_residuals(astro)))[0]
        finite = {b: s for b, s in scores.items() if np.isfinite(s)}
        self.bin_scores = scores
        self.bin_frames = (min(finite, key=lambda b: (abs(finite[b] + 0.5), b)) if finite
                           else min(self.designs))
        return {"bin_frames": self.bin_frames}

    def depth_error_estimates(self, astro: np.ndarray, dastro_ddepth: np.ndarray,
                              theta: np.ndarray | None = None) -> dict[str, float]:
        """``{"time_averaging": ...}``: the residual rms extrapolated to eclipse-long bins.

        The eclipse length is the number of frames where the planet's light is
        below half its full value (mid-ingress to mid-egress). With
        ``baseline_term`` the out-of-eclipse level's rms (same power law, its
        own length) is added in quadrature.
        """
        n_ecl = eclipse_frames(dastro_ddepth)
        if n_ecl < 1:
            return {}
        n_base = len(self.data) - n_ecl if self.options.baseline_term else 0
        value = time_averaging_error(self.relative_residuals(astro), n_ecl, n_baseline=n_base)
        return {"time_averaging": value} if np.isfinite(value) else {}

    def with_flux(self, flux: np.ndarray) -> PixelLevelDecorrelation:
        """The same designs (and the bin size in use) on new fluxes."""
        new = self._copy_with_flux(flux)
        new.designs = {b: d.with_flux(new.data.flux) for b, d in self.designs.items()}
        new.bin_scores = dict(self.bin_scores)
        return new

    def n_effective_params(self) -> int:
        """The number of linear regressors (pixels plus time terms)."""
        return self.design.n_regressors
