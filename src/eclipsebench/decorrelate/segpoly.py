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
the 10 results." The detrended series is then fitted with a box eclipse
("due to time limitations a simple box function was used").

The K2 pipeline knows nothing of the eclipse: by default the detrend sees only
the flux and the centroids, is done once in ``__init__`` and never depends on
the astrophysical model (:meth:`SegmentedPolynomial.optimise_hyperparameters`
then does nothing). Appendix B.6 is the only description of the pipeline we
could read: neither the text of Buzasi et al. (2015) nor a public code of it is
in the stored corpus. Where B.6 is silent (see ``docs/methods.md``):

- *Removed* means divided out, each fit normalised to mean 1 over the frames
  it was fitted to: "decorrelated" takes away the flux's dependence on (x, y),
  not its level (the systematics are gains). Each pass leaves out of the next
  pass's fit the points more than ``clip_sigma`` robust standard deviations
  from the current one; without a clip, or a division, "successive fits to
  each set of residuals" would be a no-op after the first.
- *High-frequency noise standard deviation*: the robust standard deviation of
  the point-to-point differences divided by sqrt(2),
  ``1.4826 * MAD(diff(f)) / sqrt(2)``, relative to the median flux.
- *Stopping rule*: the first fit is always removed; each later pass is kept
  only if it lowers that scatter by at least ``tolerance`` (1 %) of the
  previous value, and the first pass that does not is discarded and ends the
  iteration.
- Stage 2 decorrelates each time segment against (x, y) with a polynomial of
  ``segment_order`` (3, like stage 1) by the same iterative rule. Segments
  start at the first frame and have length ``f x span`` for the ten
  ``f = linspace(0.04, 0.125, 10)``; a remainder shorter than half a segment
  joins the last full one (no segment is shorter than half its nominal
  length). The ten detrended series are combined frame by frame with the
  median (the "median filter applied to the 10 results").

Named options that are *not* the K2 pipeline, off by default: ``mask_eclipse``
(leave the eclipse out of the polynomial fits: first the central
``initial_mask_fraction`` of the span, then the fitted eclipse window),
``mask_bmjd`` (a fixed window) and ``divide_astro`` (fit the polynomials to
``flux / astro`` for the fitted ``astro``).

:meth:`SegmentedPolynomial.predict` returns ``F0 * astro * trend`` with ``F0``
solved linearly. The team fitted a box eclipse: the paper profile does too
(``fit/profiles.py``); the controlled profile gives SP(K2) the shape every
method shares.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np

from ..config.base import check
from ..errors import InputError
from .base import EpochData, MethodOptions, Systematics, register
from .linear import gram_lstsq
from .record import FitterPolicy, MethodRecord, team_profile

__all__ = ["SegmentedPolynomial", "SegpolyOptions", "PolyDetrend", "SPK2Detrend", "hf_scatter",
           "poly_design", "iterative_poly_detrend", "segment_slices", "sp_k2_detrend",
           "segment_fractions_default"]

#: The ten stage-2 segment lengths, as fractions of the time span (paper B.6).
segment_fractions_default = tuple(float(f) for f in np.linspace(0.04, 0.125, 10))

_MAD_TO_SD = 1.482602218505602


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

    Examples
    --------
    >>> g = np.random.default_rng(1)
    >>> round(hf_scatter(100.0 * (1 + 1e-3 * g.standard_normal(100000))), 4)
    0.001
    """
    d = np.diff(flux)
    mad = np.median(np.abs(d - np.median(d)))
    return float(_MAD_TO_SD * mad / np.sqrt(2.0) / abs(np.median(flux)))


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


class PolyDetrend(NamedTuple):
    """Result of :func:`iterative_poly_detrend`."""

    #: Product of the divided-out fits; ``flux / trend`` is the detrended series.
    trend: np.ndarray
    #: Passes kept (the first is always kept).
    n_passes: int
    #: Frames of ``fit_mask`` left out of the last kept pass's fit by the clip.
    n_clipped: int


def iterative_poly_detrend(flux: np.ndarray, design: np.ndarray, fit_mask: np.ndarray, *,
                           tolerance: float, max_iterations: int,
                           clip_sigma: float) -> PolyDetrend:
    """Divide out successive polynomial fits while each lowers the HF scatter by >= ``tolerance``.

    Paper B.6, stage 1: fit, remove, refit the residuals "until there is < 1 %
    further reduction in the high-frequency noise standard deviation". The
    first fit is always removed; a later pass whose relative drop of
    :func:`hf_scatter` is below ``tolerance`` is discarded and ends the loop.

    Parameters
    ----------
    flux : ndarray, shape (n,)
        Light curve to detrend (positive).
    design : ndarray, shape (n, m)
        Polynomial design matrix (:func:`poly_design`).
    fit_mask : ndarray of bool, shape (n,)
        Frames allowed in the fits (the trend is evaluated on all frames).
    tolerance : float
        The stopping threshold on the relative drop of the scatter (0.01).
    max_iterations : int
        Upper limit on the number of passes.
    clip_sigma : float
        Points further than this many robust standard deviations from the
        current detrended series are left out of the next pass's fit.

    Returns
    -------
    PolyDetrend
        ``trend`` (each fit normalised to mean 1 over the ``fit_mask``
        frames), ``n_passes`` and ``n_clipped``.

    Examples
    --------
    >>> g = np.random.default_rng(0)
    >>> x, y = g.normal(0, 0.1, 500), g.normal(0, 0.1, 500)
    >>> gain = 1 + 0.3 * x - 0.5 * x * y + 0.2 * y**3
    >>> flux = 1e4 * gain * (1 + 1e-4 * g.standard_normal(500))
    >>> res = iterative_poly_detrend(flux, poly_design(x, y, 3), np.ones(500, bool),
    ...                              tolerance=0.01, max_iterations=20, clip_sigma=4.0)
    >>> ratio = res.trend / gain
    >>> res.n_passes, bool(np.std(ratio) / np.mean(ratio) < 5e-5)
    (1, True)
    """
    trend = np.ones_like(flux, dtype=float)
    current = np.asarray(flux, dtype=float).copy()
    use = fit_mask.copy()
    enough = fit_mask.sum() > 2
    scatter = hf_scatter(current[fit_mask]) if enough else 0.0
    n_done = 0
    for _ in range(max_iterations):
        level = np.median(current[use])
        coef = gram_lstsq(design[use], current[use] / level)
        fit = np.einsum("ij,j->i", design, coef)
        fit /= np.mean(fit[fit_mask])
        if not np.all(fit > 0):
            break
        new = current / fit
        new_scatter = hf_scatter(new[fit_mask]) if enough else 0.0
        if n_done > 0 and (scatter <= 0 or (scatter - new_scatter) / scatter < tolerance):
            break
        trend *= fit
        current = new
        scatter = new_scatter
        n_done += 1
        resid = current / np.median(current[fit_mask]) - 1.0
        sd = _MAD_TO_SD * np.median(np.abs(resid[fit_mask]))
        use = fit_mask & (np.abs(resid) <= clip_sigma * sd) if sd > 0 else fit_mask.copy()
        if use.sum() < design.shape[1]:
            use = fit_mask.copy()
    return PolyDetrend(trend, n_done, int(fit_mask.sum() - use.sum()))


def segment_slices(time_bmjd: np.ndarray, length_d: float, min_points: int = 1) -> list[slice]:
    """Consecutive time segments of ``length_d`` days from the first frame.

    A remainder shorter than half a segment joins the last full segment, so
    every segment lasts between half and one and a half ``length_d``; a
    segment with fewer than ``min_points`` frames (a gap in the data) joins
    its left neighbour (the right one for the first segment).

    Parameters
    ----------
    time_bmjd : ndarray, shape (n,)
        Frame times in increasing order.
    length_d : float
        Nominal segment length (days).
    min_points : int
        Fewest frames a segment may hold.

    Returns
    -------
    list of slice
        Contiguous, covering ``0 .. n``.

    Examples
    --------
    >>> t = np.arange(100) / 100.0
    >>> [s.stop - s.start for s in segment_slices(t, 0.3)]
    [30, 30, 40]
    """
    t = np.asarray(time_bmjd, dtype=float)
    n_lengths = (t[-1] - t[0]) / length_d
    n_full = max(int(np.floor(n_lengths + 1e-9)), 1)
    n_segments = n_full + 1 if n_lengths - n_full >= 0.5 else n_full
    edges = t[0] + length_d * np.arange(1, n_segments)
    cuts = [0, *np.searchsorted(t, edges, side="left").tolist(), len(t)]
    pieces = [[a, b] for a, b in zip(cuts[:-1], cuts[1:], strict=True) if b > a]
    merged: list[list[int]] = []
    for p in pieces:
        if merged and p[1] - p[0] < min_points:
            merged[-1][1] = p[1]
        else:
            merged.append(p)
    if len(merged) > 1 and merged[0][1] - merged[0][0] < min_points:
        merged[1][0] = merged[0][0]
        merged.pop(0)
    return [slice(a, b) for a, b in merged]


class SPK2Detrend(NamedTuple):
    """Result of :func:`sp_k2_detrend`."""

    #: Multiplicative trend, mean 1: ``flux / trend`` is the final detrended series.
    trend: np.ndarray
    #: Stage-1 detrended series.
    stage1: np.ndarray
    #: Stage-2 detrended series, one row per segment length (their median is the result).
    stage2: np.ndarray
    #: Counts and scatters for the diagnostics.
    info: dict[str, Any]


def sp_k2_detrend(time_bmjd: np.ndarray, flux: np.ndarray, x: np.ndarray, y: np.ndarray,
                  fit_mask: np.ndarray | None = None, *, order: int = 3,
                  segment_order: int = 3,
                  segment_fractions: tuple[float, ...] = segment_fractions_default,
                  tolerance: float = 0.01, max_iterations: int = 20,
                  clip_sigma: float = 4.0) -> SPK2Detrend:
    """The two-stage SP(K2) detrend of paper Appendix B.6, on arrays.

    Stage 1: :func:`iterative_poly_detrend` with an ``order`` polynomial in
    (x, y) over the whole series. Stage 2: for each fraction ``f`` of
    ``segment_fractions``, the stage-1 series is cut into
    :func:`segment_slices` of ``f x span`` and each segment detrended
    against (x, y) with a ``segment_order`` polynomial by the same rule; the
    frame-by-frame median of the len(segment_fractions) series is the result.

    Parameters
    ----------
    time_bmjd, flux, x, y : ndarray, shape (n,)
        Frame times (increasing), positive fluxes and centroids (px).
    fit_mask : ndarray of bool, shape (n,), optional
        Frames the polynomials may be fitted to (default: all; the K2
        pipeline has no mask). A segment with fewer than
        ``max(3 x terms, 20)`` such frames keeps its stage-1 values.
    order, segment_order, segment_fractions, tolerance, max_iterations, clip_sigma
        As :class:`SegpolyOptions`.

    Returns
    -------
    SPK2Detrend

    Examples
    --------
    >>> g = np.random.default_rng(2)
    >>> t = np.arange(3000) * 2.0 / 86400
    >>> x, y = 15 + g.normal(0, 0.05, 3000), 15 + g.normal(0, 0.05, 3000)
    >>> gain = 1 - 0.8 * (x - 15.1) ** 2 - 0.6 * (y - 15.0) ** 2
    >>> res = sp_k2_detrend(t, 1e5 * gain, x, y)
    >>> bool(np.std(1e5 * gain / res.trend) / 1e5 < 1e-8)
    True
    """
    time = np.asarray(time_bmjd, dtype=float)
    flux = np.asarray(flux, dtype=float)
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    n = len(time)
    fit_mask = np.ones(n, dtype=bool) if fit_mask is None else np.asarray(fit_mask, bool)
    kw: dict[str, Any] = dict(tolerance=tolerance, max_iterations=max_iterations,
                              clip_sigma=clip_sigma)

    one = iterative_poly_detrend(flux, poly_design(x, y, order), fit_mask, **kw)
    stage1 = flux / one.trend

    span = time[-1] - time[0]
    n_terms2 = (segment_order + 1) * (segment_order + 2) // 2
    min_points = max(3 * n_terms2, 20)
    stage2 = np.empty((len(segment_fractions), n))
    n_segments, passes, n_skipped = [], [], 0
    for k, frac in enumerate(segment_fractions):
        trend2 = np.ones(n)
        slices = segment_slices(time, frac * span, min_points)
        n_segments.append(len(slices))
        for seg in slices:
            seg_mask = fit_mask[seg]
            if seg_mask.sum() < min_points:
                n_skipped += 1   # a segment (almost) inside the mask keeps the stage-1 values
                continue
            design = poly_design(x[seg], y[seg], segment_order)
            res = iterative_poly_detrend(stage1[seg], design, seg_mask, **kw)
            trend2[seg] = res.trend
            passes.append(res.n_passes)
        stage2[k] = stage1 / trend2
    final = np.median(stage2, axis=0)
    trend = flux / final
    trend /= np.mean(trend)
    info = {"stage1_iterations": one.n_passes,
            "stage1_n_clipped": one.n_clipped,
            "stage2_n_segments": n_segments,
            "stage2_iterations_median": float(np.median(passes)) if passes else 0.0,
            "stage2_n_segments_skipped": n_skipped,
            "hf_scatter_raw": hf_scatter(flux),
            "hf_scatter_stage1": hf_scatter(stage1),
            "hf_scatter_final": hf_scatter(final)}
    return SPK2Detrend(trend, stage1, stage2, info)


@dataclass(frozen=True)
class SegpolyOptions(MethodOptions):
    """Options of ``segpoly`` (:class:`SegmentedPolynomial`)."""

    order: int = 3
    segment_order: int = 3
    segment_fractions: tuple[float, ...] = segment_fractions_default
    tolerance: float = 0.01
    max_iterations: int = 20
    clip_sigma: float = 4.0
    mask_eclipse: bool = False
    mask_bmjd: tuple[float, ...] = ()
    mask_pad: float = 0.2
    initial_mask_fraction: float = 0.4
    divide_astro: bool = False

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
class SegmentedPolynomial(Systematics[SegpolyOptions]):
    """SP(K2): stage-1 global and stage-2 segmented polynomial detrending (Buzasi et al. 2015).

    By default the detrend is the K2 pipeline's, blind to the eclipse: it
    depends on the flux and the centroids only (:func:`sp_k2_detrend`).

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
    mask_eclipse : bool
        Not the K2 pipeline (default False). True: detrend first with the
        central ``initial_mask_fraction`` of the time span left out of the
        polynomial fits, then, each time the fitter calls
        :meth:`optimise_hyperparameters` with its fitted eclipse, with the
        fitted eclipse window left out.
    mask_bmjd : (float, float) or empty
        Not the K2 pipeline: a fixed time window left out of every polynomial
        fit (empty by default).
    mask_pad : float
        With ``mask_eclipse``: widening of the window on each side, as a
        fraction of the half-depth duration (0.2).
    initial_mask_fraction : float
        With ``mask_eclipse``: length of the first, central window as a
        fraction of the span (0.4).
    divide_astro : bool
        Not the K2 pipeline (default False). True: when the fitter calls
        :meth:`optimise_hyperparameters`, detrend ``flux / astro`` instead of
        the flux, so that the polynomials do not take the phase curve.

    Examples
    --------
    >>> from eclipsebench.decorrelate.base import EpochData
    >>> g = np.random.default_rng(0)
    >>> n = 3000
    >>> x, y = 15 + g.normal(0, 0.05, n), 15 + g.normal(0, 0.05, n)
    >>> flux = 1e5 * (1 - 0.8 * (x - 15.1) ** 2)
    >>> data = EpochData(time_bmjd=57000 + np.arange(n) * 2 / 86400, flux=flux,
    ...                  flux_err=np.sqrt(flux), x=x, y=y)
    >>> m = SegmentedPolynomial(data)
    >>> m.options.mask_eclipse, m.optimise_hyperparameters(np.ones(n))
    (False, None)
    """

    name: ClassVar[str] = "segpoly"
    requires: ClassVar[tuple[str, ...]] = ("x", "y")
    #: The prayer bead's refits keep the detrend of the original data (see with_flux).
    record: ClassVar[MethodRecord] = MethodRecord(
        label="SP(K2)", paper=team_profile("segpoly"), in_paper=True,
        policy=FitterPolicy(with_flux_rebuilds=False))

    def setup(self, data: EpochData) -> None:
        o = self.options
        time = np.asarray(data.time_bmjd, dtype=float)
        if np.any(np.diff(time) < 0):
            raise InputError("segpoly: frames must be in time order")
        if not np.all(np.asarray(data.flux, dtype=float) > 0):
            raise InputError("segpoly: the flux must be positive on every frame")
        n_terms1 = (o.order + 1) * (o.order + 2) // 2
        self._min_fit = 3 * n_terms1
        self._kw: dict[str, Any] = dict(order=o.order, segment_order=o.segment_order,
                        segment_fractions=tuple(float(f) for f in o.segment_fractions),
                        tolerance=o.tolerance, max_iterations=o.max_iterations,
                        clip_sigma=o.clip_sigma)
        self.mask_eclipse = bool(o.mask_eclipse)
        self.divide_astro = bool(o.divide_astro)
        self._astro_divisor: np.ndarray | None = None
        self.fixed_mask = bool(o.mask_bmjd)
        self.mask_window_bmjd: tuple[float, float] | None = None
        if self.fixed_mask:
            lo, hi = (float(v) for v in o.mask_bmjd)
            self.mask_window_bmjd = (lo, hi)
        elif self.mask_eclipse and o.initial_mask_fraction > 0:
            mid, span = 0.5 * (time[0] + time[-1]), time[-1] - time[0]
            half = 0.5 * o.initial_mask_fraction * span
            self.mask_window_bmjd = (float(mid - half), float(mid + half))
        self._detrend()
        self._w = 1.0 / np.asarray(data.flux_err, dtype=float) ** 2

    @property
    def blind(self) -> bool:
        """True when the detrend knows nothing of the eclipse (the K2 pipeline; default)."""
        return not (self.mask_eclipse or self.divide_astro or self.fixed_mask)

    def _detrend(self) -> None:
        """Run :func:`sp_k2_detrend` with the current mask and divisor; sets ``trend``."""
        data = self.data
        time = np.asarray(data.time_bmjd, dtype=float)
        flux = np.asarray(data.flux, dtype=float)
        if self._astro_divisor is not None:
            flux = flux / self._astro_divisor
        fit_mask = np.ones(len(time), dtype=bool)
        if self.mask_window_bmjd is not None:
            lo, hi = self.mask_window_bmjd
            fit_mask = ~((time >= lo) & (time <= hi))
        if fit_mask.sum() < self._min_fit:
            raise InputError("segpoly option 'mask_bmjd': too few frames left outside the mask")
        res = sp_k2_detrend(time, flux, data.x, data.y, fit_mask, **self._kw)
        self.trend = res.trend
        self.detrended = np.asarray(data.flux, dtype=float) / self.trend
        self._diagnostics = {**res.info, "blind": self.blind,
                             "astro_divided": self._astro_divisor is not None,
                             "mask_window_bmjd": self.mask_window_bmjd,
                             "n_masked": int((~fit_mask).sum())}

    def diagnostics(self) -> dict[str, Any]:
        """The detrend: passes, clipped frames, segments, high-frequency scatter
        before and after each stage, whether it was blind, and any masked window."""
        d = dict(self._diagnostics)
        d["mask_window_bmjd"] = None if d["mask_window_bmjd"] is None else list(
            d["mask_window_bmjd"])
        return d

    def optimise_hyperparameters(self, astro: np.ndarray) -> dict[str, Any] | None:
        """With ``mask_eclipse`` or ``divide_astro``: detrend again for the fitted ``astro``.

        By default (the K2 pipeline) this does nothing and returns None: the
        detrend does not depend on the astrophysical model. The fitter calls
        this between fits (as for the GP's kernel). With ``mask_eclipse`` (and
        no fixed ``mask_bmjd``) the window is where ``astro`` lies below half
        its range (the half-depth points of the fitted eclipse) widened by
        ``mask_pad`` of its length on each side; with ``divide_astro`` the
        polynomials are fitted to ``flux / astro``. Nothing is redone when
        neither changed.

        Returns
        -------
        dict or None
            The diagnostics when the trend was redone.
        """
        if not (self.mask_eclipse or self.divide_astro):
            return None
        a = np.asarray(astro, dtype=float)
        redo = False
        if self.divide_astro:
            if self._astro_divisor is None or not np.allclose(a, self._astro_divisor, rtol=0,
                                                              atol=1e-9):
                self._astro_divisor = a.copy()
                redo = True
        if self.mask_eclipse and not self.fixed_mask:
            window = self._eclipse_window(a)
            if window is not None and (self.mask_window_bmjd is None or not np.allclose(
                    window, self.mask_window_bmjd, rtol=0, atol=1e-7)):
                self.mask_window_bmjd = window
                redo = True
        if not redo:
            return None
        self._detrend()
        return self.diagnostics()

    def _eclipse_window(self, astro: np.ndarray) -> tuple[float, float] | None:
        """The padded half-depth window of a fitted ``astro``, or the current window.

        When the fitted curve's phase variation exceeds its eclipse, its
        half-range level does not isolate the eclipse and would leave fewer
        than a third of the frames outside: the current window is kept.
        """
        time = np.asarray(self.data.time_bmjd, dtype=float)
        inside = np.flatnonzero(astro < astro.min() + 0.5 * np.ptp(astro))
        if not (np.ptp(astro) > 0 and len(inside) >= 2):
            return self.mask_window_bmjd
        t_in, t_out = time[inside[0]], time[inside[-1]]
        pad = self.options.mask_pad * (t_out - t_in)
        window = (float(t_in - pad), float(t_out + pad))
        left = np.count_nonzero((time < window[0]) | (time > window[1]))
        if left < max(self._min_fit, len(time) // 3):
            return self.mask_window_bmjd
        return window

    def with_flux(self, flux: np.ndarray) -> SegmentedPolynomial:
        """The same trend with ``flux`` replaced (for the prayer bead).

        The detrending is a pre-processing step outside the fit (the SP(K2)
        team reported formal fit errors), so the shifted series are fitted
        with the trend of the original data instead of being detrended again.
        """
        return self._copy_with_flux(flux)

    def predict(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """``F0 * astro * trend``, with ``F0`` the weighted least-squares normalisation."""
        m = np.asarray(astro, dtype=float) * self.trend
        f0 = np.sum(self._w * self.data.flux * m) / np.sum(self._w * m * m)
        return f0 * m

    def log_likelihood_batch(self, astro: np.ndarray, theta: np.ndarray | None = None,
                             noise_scale: float = 1.0) -> np.ndarray:
        """:meth:`log_likelihood` of every row of ``astro`` (shape (m, n)), ``F0`` of each
        row in closed form as in :meth:`predict` (the trend is fixed)."""
        if not self._batch_is_exact(SegmentedPolynomial):
            return super().log_likelihood_batch(astro, theta, noise_scale)
        m = np.atleast_2d(np.asarray(astro, dtype=float)) * self.trend
        wm = self._w * m
        f0 = np.einsum("ij,j->i", wm, self.data.flux) / np.einsum("ij,ij->i", wm, m)
        return self._white_log_likelihood_batch(f0[:, None] * m, noise_scale)

    def n_effective_params(self) -> int:
        """The normalisation ``F0`` (the detrend is a fixed pre-processing step)."""
        return 1
