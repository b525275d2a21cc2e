"""SP(K2): the two-stage segmented-polynomial detrending of Buzasi et al. (2015).

Paper, Appendix B.6: "In the first stage, a third-order polynomial is fit to
the flux vs. (x, y) centroid for the entire time series and removed. This
process is repeated, with successive third order polynomial fits being applied
to each set of residuals, until there is < 1% further reduction in the
high-frequency noise standard deviation. In the second stage, the resulting
time series is divided into segments, each of which is iteratively decorrelated
using polynomial fitting. This segmented detrending is repeated for 10
different segment lengths between 0.04 and 0.125 of the total time series
length, and the final time series is the result of applying a median filter to
the 10 results."

Choices where the text is silent (see ``docs/methods.md``):

- *Removed* means divided out: each fit is normalised to mean 1 and the flux
  divided by it (the systematics are multiplicative gains). Repeating the fit
  on the quotient is then not the identity, and each fit clips points more
  than ``clip_sigma`` robust standard deviations from it.
- *High-frequency noise standard deviation*: the robust standard deviation of
  the point-to-point differences divided by sqrt(2),
  ``1.4826 * MAD(diff(f)) / sqrt(2)``, relative to the median flux.
- Stage 2 decorrelates each time segment against (x, y) with a polynomial of
  ``segment_order`` (default 3, like stage 1), iterated with the same 1 %
  rule; the segment lengths are ``numpy.linspace(0.04, 0.125, 10)`` times the
  time span; the ten detrended series are combined frame by frame with the
  median.
- The K2 pipeline detrends without knowledge of the transit; on eclipse data
  the (x, y) polynomials then absorb the part of the eclipse that correlates
  with the pointing drift (900 ppm of 1875 on the tests' noiseless epochs).
  The paper's SP(K2) bias on its simulated data (-162 ppm) matches a masked
  detrend plus a box fit, so by default the eclipse is masked: first the
  central ``initial_mask_fraction`` of the span, then the fitted eclipse
  window (:meth:`SegmentedPolynomial.optimise_hyperparameters`, the hook the
  fitter alternates with its fit); ``mask_bmjd`` fixes a window,
  ``mask_eclipse=False`` masks nothing.
- Our addition (``divide_astro=True``): in that hook the polynomials are
  fitted to ``flux / astro`` so that they do not take the phase curve.

The detrending is done in ``__init__`` and again only when the hook changes
the mask or ``astro``; :meth:`SegmentedPolynomial.predict` returns
``F0 * astro * trend`` with ``F0`` solved linearly. The team fitted a box
eclipse: :attr:`SegmentedPolynomial.default_eclipse_shape` is ``"box"``.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace
from typing import Any, ClassVar

import numpy as np

from ..config.base import check
from ..errors import InputError
from .base import EpochData, MethodContext, MethodOptions, Systematics, register

__all__ = ["SegmentedPolynomial", "hf_scatter", "poly_design", "iterative_poly_detrend",
           "segment_fractions_default"]

#: The ten stage-2 segment lengths, as fractions of the time span (paper B.6).
segment_fractions_default = tuple(np.linspace(0.04, 0.125, 10))


def hf_scatter(flux: np.ndarray) -> float:
    """Robust high-frequency scatter: ``1.4826 MAD(diff(flux)) / sqrt(2)`` over the median.

    Parameters
    ----------
    flux : ndarray, shape (n,)
        A light curve (any units), n >= 3.

    Returns
    -------
    float
        Fractional white-noise standard deviation estimated from consecutive
        differences (insensitive to slow trends).
    """
    d = np.diff(flux)
    mad = np.median(np.abs(d - np.median(d)))
    return float(1.482602218505602 * mad / np.sqrt(2.0) / abs(np.median(flux)))


def poly_design(x: np.ndarray, y: np.ndarray, order: int) -> np.ndarray:
    """Design matrix of all monomials ``u**i v**j`` with ``i + j <= order``.

    ``u`` and ``v`` are ``x`` and ``y`` centred on their means and scaled by
    their standard deviations. A coordinate that varies by less than 1e-6 px
    (a star at rest: only rounding noise) gives zero columns, which the
    minimum-norm solver leaves at zero, instead of amplified rounding noise.

    Returns
    -------
    ndarray, shape (n, (order + 1)(order + 2) / 2)
    """
    def standard(a):
        s = np.std(a)
        return (a - np.mean(a)) / s if s > 1e-6 else np.zeros_like(a)
    u, v = standard(np.asarray(x, float)), standard(np.asarray(y, float))
    cols = [u**i * v**(k - i) for k in range(order + 1) for i in range(k, -1, -1)]
    return np.column_stack(cols)


def iterative_poly_detrend(flux: np.ndarray, design: np.ndarray, fit_mask: np.ndarray, *,
                           tolerance: float, max_iterations: int,
                           clip_sigma: float) -> tuple[np.ndarray, int]:
    """Divide out successive polynomial fits until the HF scatter improves by < ``tolerance``.

    Parameters
    ----------
    flux : ndarray, shape (n,)
        Light curve to detrend (positive).
    design : ndarray, shape (n, m)
        Polynomial design matrix (:func:`poly_design`).
    fit_mask : ndarray of bool, shape (n,)
        Frames allowed in the fits (the trend is evaluated on all frames).
    tolerance : float
        Stop when the relative drop of :func:`hf_scatter` is below this (0.01).
    max_iterations : int
        Upper limit on the number of passes.
    clip_sigma : float
        Points further than this many robust standard deviations from a fit
        are left out of the next pass's fit.

    Returns
    -------
    trend : ndarray, shape (n,)
        Product of the divided-out fits (each normalised to mean 1 over the
        fitted frames); ``flux / trend`` is the detrended series.
    n_iterations : int
        Passes kept.
    """
    trend = np.ones_like(flux)
    current = flux.copy()
    use = fit_mask.copy()
    scatter = hf_scatter(current[fit_mask]) if fit_mask.sum() > 2 else 0.0
    n_done = 0
    for _ in range(max_iterations):
        level = np.median(current[use])
        coef = _lstsq_small(design[use], current[use] / level)
        fit = np.einsum("ij,j->i", design, coef)
        fit /= np.mean(fit[fit_mask])
        if not np.all(fit > 0):
            break
        new = current / fit
        new_scatter = hf_scatter(new[fit_mask]) if fit_mask.sum() > 2 else 0.0
        trend *= fit
        current = new
        n_done += 1
        resid = current / np.median(current[fit_mask]) - 1.0
        sd = 1.482602218505602 * np.median(np.abs(resid[fit_mask]))
        use = fit_mask & (np.abs(resid) <= clip_sigma * sd) if sd > 0 else fit_mask.copy()
        if use.sum() < design.shape[1]:
            use = fit_mask.copy()
        if scatter <= 0 or (scatter - new_scatter) / scatter < tolerance:
            break
        scatter = new_scatter
    return trend, n_done


def _lstsq_small(design: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Least squares through the normal equations, without multithreaded BLAS.

    The Gram matrix is formed with ``einsum`` (OpenBLAS threads made ``lstsq``
    on these tall, thin matrices 30x slower on a loaded machine) and solved by
    SVD (minimum norm, so all-zero columns get zero coefficients).
    """
    gram = np.einsum("ni,nj->ij", design, design)
    rhs = np.einsum("ni,n->i", design, target)
    coef, *_ = np.linalg.lstsq(gram, rhs, rcond=1e-12)
    return coef


def _segments(time: np.ndarray, length: float, min_points: int) -> list[np.ndarray]:
    """Consecutive time segments of ``length``; a short last one joins its neighbour."""
    edges = np.arange(time[0], time[-1] + length, length)
    idx = np.searchsorted(time, edges[1:-1], side="left")
    pieces = [p for p in np.split(np.arange(len(time)), idx) if len(p)]
    merged: list[np.ndarray] = []
    for p in pieces:
        if merged and len(p) < min_points:
            merged[-1] = np.concatenate([merged[-1], p])
        else:
            merged.append(p)
    if len(merged) > 1 and len(merged[0]) < min_points:
        merged[1] = np.concatenate([merged[0], merged[1]])
        merged.pop(0)
    return merged


@dataclass(frozen=True)
class SegpolyOptions(MethodOptions):
    """Options of ``segpoly`` (:class:`SegmentedPolynomial`)."""

    order: int = 3
    segment_order: int = 3
    segment_fractions: tuple[float, ...] = segment_fractions_default
    tolerance: float = 0.01
    max_iterations: int = 20
    clip_sigma: float = 4.0
    mask_bmjd: tuple[float, ...] = ()
    mask_eclipse: bool = True
    mask_pad: float = 0.2
    initial_mask_fraction: float = 0.4
    divide_astro: bool = True

    def validate(self) -> None:
        check(0 <= self.order <= 6, "order", "an integer 0-6")
        check(0 <= self.segment_order <= 6, "segment_order", "an integer 0-6")
        check(len(self.segment_fractions) > 0
              and all(0 < f <= 1 for f in self.segment_fractions), "segment_fractions",
              "fractions in (0, 1]")
        check(0 < self.tolerance < 1, "tolerance", "a number in (0, 1)")
        check(self.max_iterations >= 1, "max_iterations", "at least 1 pass")
        check(self.clip_sigma > 0, "clip_sigma", "a positive number of standard deviations")
        check(len(self.mask_bmjd) in (0, 2), "mask_bmjd", "[start, end] BMJD or none")
        check(0 <= self.mask_pad <= 2, "mask_pad", "a number 0-2")
        check(0 <= self.initial_mask_fraction < 0.9, "initial_mask_fraction", "a number 0-0.9")


@register
class SegmentedPolynomial(Systematics):
    """SP(K2): stage-1 global and stage-2 segmented polynomial detrending (Buzasi et al. 2015).

    Options (:class:`SegpolyOptions`)
    ---------------------------------
    order : int
        Order of the stage-1 polynomial in (x, y); 3 as in the paper.
    segment_order : int
        Order of the stage-2 polynomial in (x, y) within each segment; 3.
    segment_fractions : sequence of float
        Stage-2 segment lengths as fractions of the time span; ten values
        from 0.04 to 0.125 as in the paper.
    tolerance : float
        The "< 1 %" stopping rule on the high-frequency scatter (0.01).
    max_iterations : int
        Cap on the passes of each iterative fit (20).
    clip_sigma : float
        Outlier clipping of each pass, robust standard deviations (4).
    mask_bmjd : (float, float) or empty
        A fixed time window left out of every polynomial fit.
    mask_eclipse : bool
        Without ``mask_bmjd``: detrend first with the central
        ``initial_mask_fraction`` of the time span masked (eclipse AORs are
        planned around the predicted eclipse), then, when the fitter calls
        :meth:`optimise_hyperparameters` with its fitted eclipse, again with
        the fitted eclipse window masked (default True). False never masks.
    initial_mask_fraction : float
        Length of the first, central mask as a fraction of the span (0.4).
    divide_astro : bool
        When the fitter calls :meth:`optimise_hyperparameters`, detrend
        ``flux / astro`` instead of the raw flux, so that the polynomials do
        not take the phase curve (default True, our addition; False detrends
        the raw flux as the K2 pipeline does).
    mask_pad : float
        Widening of the masked window on each side, as a fraction of the
        half-depth duration (0.2).
    """

    name: ClassVar[str] = "segpoly"
    requires: ClassVar[tuple[str, ...]] = ("x", "y")
    Options: ClassVar[type[MethodOptions]] = SegpolyOptions
    description: ClassVar[str] = ("SP(K2): iterated cubic (x, y) polynomial, then ten segmented "
                                  "detrendings combined by the median (Buzasi et al. 2015)")
    #: The SP(K2) team fitted a box eclipse (paper B.6); the fitter may use the shared model instead.
    default_eclipse_shape: ClassVar[str] = "box"
    #: The prayer bead's refits keep the detrend of the original data (see with_flux).
    with_flux_rebuilds: ClassVar[bool] = False

    def __init__(self, data: EpochData, options: Any = None, *,
                 context: MethodContext | None = None, **kwargs: Any) -> None:
        super().__init__(data, options, context=context, **kwargs)
        o = self.options
        order, segment_order = o.order, o.segment_order
        fracs = np.asarray(o.segment_fractions, dtype=float)
        tolerance, max_iterations, clip_sigma = o.tolerance, o.max_iterations, o.clip_sigma
        mask_bmjd = o.mask_bmjd or None
        mask_eclipse, divide_astro = o.mask_eclipse, o.divide_astro
        initial_mask_fraction = o.initial_mask_fraction
        time = np.asarray(data.time_bmjd, dtype=float)
        if np.any(np.diff(time) < 0):
            raise InputError("segpoly: frames must be in time order")
        if not np.all(np.asarray(data.flux, dtype=float) > 0):
            raise InputError("segpoly: the flux must be positive on every frame")
        n_terms1 = (order + 1) * (order + 2) // 2
        self._settings = dict(order=order, segment_order=segment_order, fracs=fracs,
                              kw=dict(tolerance=tolerance, max_iterations=max_iterations,
                                      clip_sigma=clip_sigma), min_fit=3 * n_terms1)
        self.mask_eclipse = bool(mask_eclipse)
        self.divide_astro = bool(divide_astro)
        self._astro_divisor: np.ndarray | None = None
        self.fixed_mask = mask_bmjd is not None
        self.mask_window_bmjd: tuple[float, float] | None = None
        if mask_bmjd is not None:
            lo, hi = (float(v) for v in mask_bmjd)
            self.mask_window_bmjd = (lo, hi)
        elif self.mask_eclipse and initial_mask_fraction > 0:
            mid, span = 0.5 * (time[0] + time[-1]), time[-1] - time[0]
            half = 0.5 * initial_mask_fraction * span
            self.mask_window_bmjd = (float(mid - half), float(mid + half))
        self._detrend()
        self._w = 1.0 / np.asarray(data.flux_err, dtype=float) ** 2

    def _detrend(self) -> None:
        """Stage 1 and stage 2 with the current mask; sets ``trend`` and ``diagnostics``."""
        data, st = self.data, self._settings
        time = np.asarray(data.time_bmjd, dtype=float)
        flux = np.asarray(data.flux, dtype=float)
        if self._astro_divisor is not None:
            flux = flux / self._astro_divisor
        fit_mask = np.ones(len(time), dtype=bool)
        if self.mask_window_bmjd is not None:
            lo, hi = self.mask_window_bmjd
            fit_mask = ~((time >= lo) & (time <= hi))
        if fit_mask.sum() < st["min_fit"]:
            raise InputError("segpoly option 'mask_bmjd': too few frames left outside the mask")
        kw = st["kw"]

        # Stage 1: the whole series against (x, y).
        design1 = poly_design(data.x, data.y, st["order"])
        trend1, n1 = iterative_poly_detrend(flux, design1, fit_mask, **kw)
        stage1 = flux / trend1

        # Stage 2: segments of ten lengths, each detrended against (x, y); median of the ten.
        span = time[-1] - time[0]
        n_terms2 = (st["segment_order"] + 1) * (st["segment_order"] + 2) // 2
        min_points = max(3 * n_terms2, 20)
        results = np.empty((len(st["fracs"]), len(time)))
        for k, frac in enumerate(st["fracs"]):
            trend2 = np.ones(len(time))
            for seg in _segments(time, frac * span, min_points):
                seg_mask = fit_mask[seg]
                if seg_mask.sum() < min_points:
                    continue  # a segment (almost) inside the mask keeps the stage-1 result
                design = poly_design(data.x[seg], data.y[seg], st["segment_order"])
                trend2[seg], _ = iterative_poly_detrend(stage1[seg], design, seg_mask, **kw)
            results[k] = stage1 / trend2
        final = np.median(results, axis=0)
        trend = flux / final
        self.trend = trend / np.mean(trend)
        self.detrended = np.asarray(data.flux, dtype=float) / self.trend
        self._diagnostics = {"stage1_iterations": n1,
                            "hf_scatter_raw": hf_scatter(flux),
                            "hf_scatter_stage1": hf_scatter(stage1),
                            "hf_scatter_final": hf_scatter(final),
                            "mask_window_bmjd": self.mask_window_bmjd,
                            "n_masked": int((~fit_mask).sum())}

    def diagnostics(self) -> dict[str, Any]:
        """The detrend: stage-1 passes, high-frequency scatter before and after each
        stage, and the masked window."""
        d = dict(self._diagnostics)
        d["mask_window_bmjd"] = None if d["mask_window_bmjd"] is None else list(
            d["mask_window_bmjd"])
        return d

    def optimise_hyperparameters(self, astro: np.ndarray) -> dict[str, Any] | None:
        """Detrend again with the fitted eclipse masked and ``astro`` divided out.

        The fitter calls this between fits (as for the GP's kernel). The
        window is where ``astro`` lies below half its range (the half-depth
        points of the fitted eclipse) widened by ``mask_pad`` of its length on
        each side (not with ``mask_eclipse=False`` or a fixed ``mask_bmjd``);
        with ``divide_astro`` the polynomials are fitted to ``flux / astro``.
        Nothing is redone when neither changed.

        Returns
        -------
        dict or None
            ``mask_window_bmjd`` and the diagnostics when the trend was redone.
        """
        a = np.asarray(astro, dtype=float)
        redo = False
        if self.divide_astro:
            if self._astro_divisor is None or not np.allclose(a, self._astro_divisor, rtol=0,
                                                              atol=1e-9):
                self._astro_divisor = a.copy()
                redo = True
        if not self.mask_eclipse or self.fixed_mask:
            if redo:
                self._detrend()
                return self.diagnostics()
            return None
        time = np.asarray(self.data.time_bmjd, dtype=float)
        inside = np.flatnonzero(a < a.min() + 0.5 * np.ptp(a))
        if np.ptp(a) > 0 and len(inside) >= 2:
            t_in, t_out = time[inside[0]], time[inside[-1]]
            pad = self.options.mask_pad * (t_out - t_in)
            window = (float(t_in - pad), float(t_out + pad))
            left = np.count_nonzero((time < window[0]) | (time > window[1]))
            if left < max(self._settings["min_fit"], len(time) // 3):
                # The fitted curve's phase variation exceeds its eclipse, so its
                # half-range level does not isolate the eclipse: keep the mask.
                window = self.mask_window_bmjd
            if window is not None and (self.mask_window_bmjd is None or not np.allclose(
                    window, self.mask_window_bmjd, rtol=0, atol=1e-7)):
                self.mask_window_bmjd = window
                redo = True
        if not redo:
            return None
        self._detrend()
        return self.diagnostics()

    def with_flux(self, flux: np.ndarray) -> SegmentedPolynomial:
        """The same trend with ``flux`` replaced (for the prayer bead).

        The detrending is a pre-processing step outside the fit (the SP(K2)
        team reported formal fit errors), so the shifted series are fitted
        with the trend of the original data instead of being detrended again.
        """
        new = copy.copy(self)
        new.data = replace(self.data, flux=np.asarray(flux, dtype=float))
        return new

    def predict(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """``F0 * astro * trend``, with ``F0`` the weighted least-squares normalisation."""
        m = np.asarray(astro, dtype=float) * self.trend
        f0 = np.sum(self._w * self.data.flux * m) / np.sum(self._w * m * m)
        return f0 * m

    def n_effective_params(self) -> int:
        """The normalisation ``F0`` (the detrend is a fixed pre-processing step)."""
        return 1
