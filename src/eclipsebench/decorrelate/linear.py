"""The weighted linear solve that the linear methods share.

A linear method writes the flux as ``astro * (R c)`` with regressors ``R``
(PLD's normalised pixels, SPCA's polynomials in the centroid, PLDAper's
pixels) and solves the coefficients ``c`` by weighted least squares for each
astrophysical curve, per frame or on consecutive bins of frames (Deming et
al. 2015, Sect. 3). :class:`LinearDesign` holds the parameter-independent
pieces (scaled columns, bins, weights, per-frame outer products);
:func:`solve_coefficients`, :func:`fit_residuals`, :func:`fit_log_likelihood`
and :func:`fit_log_likelihood_batch` are the calls in the fit's loop.
:func:`weighted_lstsq` and :func:`gram_lstsq` are the plain solves of ICA's
component weights and SP(K2)'s detrending polynomials.
:class:`LinearSystematics` is the method machinery the linear methods share
(PLD's and SPCA's models): prediction, residuals and likelihoods from a
:class:`LinearDesign`.
"""

from __future__ import annotations

import copy
from abc import abstractmethod

import numpy as np

from .base import OptionsT, Systematics

__all__ = ["LinearDesign", "weighted_binned_design", "solve_coefficients", "fit_residuals",
           "fit_log_likelihood", "fit_log_likelihood_batch", "binned_design_batch",
           "weighted_lstsq", "gram_lstsq", "LinearSystematics"]


_OUTER_BYTES_MAX = 64 * 2**20


class LinearDesign:
    """Parameter-independent pieces of a weighted linear regression, per frame or on bins.

    Parameters
    ----------
    regressors : ndarray, shape (n, p)
        The regressors (PLD's normalised pixels and time terms, SPCA's polynomials).
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
        #: (frame order or None, the design in time order), built by the batched likelihood.
        self._batch_sorted: tuple[np.ndarray | None, np.ndarray] | None = None
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
            if self.order is not None and np.array_equal(self.order, np.arange(n)):
                self.order = None   # already in time order: no copy per binning (issue 40)
            self.starts = np.arange(0, n, self.bin_frames)
            counts = np.diff(np.append(self.starts, n)).astype(float)
            self.counts = counts
            self.b_flux = self._binned(np.asarray(flux, float))
            var = self._binned(np.asarray(flux_err, float) ** 2) / counts
            self.b_ivar_sqrt = 1.0 / np.sqrt(var)
        self.b_target = self.b_flux * self.b_ivar_sqrt

    def with_flux(self, flux: np.ndarray) -> LinearDesign:
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


def weighted_binned_design(design: LinearDesign, astro: np.ndarray) -> np.ndarray | None:
    """``(astro D)_b / sigma_b``, the binned design times ``astro``, weighted: what
    :func:`solve_coefficients` and :func:`fit_residuals` both take on a binned fit without the
    per-frame products (None otherwise), made once when both are called (issue 40)."""
    if design.outer is not None or design.starts is None:
        return None
    astro = np.asarray(astro, float)
    return design._binned(design.design * astro[:, None]) * design.b_ivar_sqrt[:, None]


def solve_coefficients(design: LinearDesign, astro: np.ndarray,
                       gw: np.ndarray | None = None) -> np.ndarray:
    """Weighted least-squares coefficients (of the scaled columns) for ``astro``.

    Minimises ``sum_b ((F_b - (astro D)_b c) / sigma_b)^2`` over bins ``b``
    (frames when unbinned) through the p x p normal equations. ``gw``:
    :func:`weighted_binned_design` of ``astro``, when the caller has it.
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
        if gw is None:
            gw = design._binned(design.design * astro[:, None]) * design.b_ivar_sqrt[:, None]
        a = np.einsum("bi,bj->ij", gw, gw)
        b = np.einsum("bi,b->i", gw, design.b_target)
    try:
        return np.linalg.solve(a, b)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(a, b, rcond=None)[0]


def fit_residuals(design: LinearDesign, astro: np.ndarray, coef: np.ndarray,
                  gw: np.ndarray | None = None) -> np.ndarray:
    """Normalised residuals of the fitted points (bins, or frames when unbinned).

    ``(F_b - (astro D)_b c) / sigma_b``: the quantity whose sum of squares
    :func:`solve_coefficients` minimises over ``c``. ``gw``:
    :func:`weighted_binned_design` of ``astro``, when the caller has it.
    """
    astro = np.asarray(astro, float)
    if design.starts is None:
        model = astro * np.einsum("nk,k->n", design.design, coef)
        return (design.b_flux - model) * design.b_ivar_sqrt
    if gw is None:
        gw = design._binned(design.design * astro[:, None]) * design.b_ivar_sqrt[:, None]
    return design.b_target - gw @ coef


def binned_design_batch(design: LinearDesign, astro: np.ndarray) -> np.ndarray:
    """``design._binned(design.design * a[:, None])`` for every row ``a`` of ``astro``.

    Shape (m, n_bins, p). The full bins are one stacked matrix product (bins
    x rows x frames-in-bin times bins x frames-in-bin x regressors); the
    last, partial bin (if any) is added on its own.
    """
    cache = design._batch_sorted
    if cache is None:   # (the frames' order if they are not in time order, the sorted design)
        order = design.order
        if order is not None and np.array_equal(order, np.arange(len(order))):
            order = None
        cache = design._batch_sorted = (order, design.design if order is None
                                        else design.design[order])
    order, d = cache
    a = astro if order is None else astro[:, order]
    m, n = a.shape
    size, p = design.bin_frames, d.shape[1]
    n_full = n // size
    starts = design.starts
    if starts is None:
        raise ValueError("the batched binned product needs a binned design (bin_frames > 1)")
    out = np.empty((m, len(starts), p))
    if n_full:
        full = np.matmul(a[:, :n_full * size].reshape(m, n_full, size).transpose(1, 0, 2),
                         d[:n_full * size].reshape(n_full, size, p))
        out[:, :n_full] = full.transpose(1, 0, 2)
    if n_full < len(starts):
        out[:, n_full] = a[:, n_full * size:] @ d[n_full * size:]
    return out / design.counts[None, :, None]


def _solve_batch(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.linalg.solve`` of each (p, p) system, with :func:`solve_coefficients`'s lstsq fallback."""
    try:
        return np.linalg.solve(a, b[..., None])[..., 0]
    except np.linalg.LinAlgError:
        out = np.empty_like(b)
        for i in range(len(b)):
            try:
                out[i] = np.linalg.solve(a[i], b[i])
            except np.linalg.LinAlgError:
                out[i] = np.linalg.lstsq(a[i], b[i], rcond=None)[0]
        return out


def _solve_coefficients_batch(design: LinearDesign, astro: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray | None] | None:
    """:func:`solve_coefficients` for every row of ``astro`` (m, n): ``(coef (m, p), gw)``.

    ``gw`` is the weighted binned design of each row (m, n_bins, p) when the
    fit is binned, else None. Returns None where no batched form is kept
    (unbinned without the per-frame products): the caller then loops.
    """
    astro = np.atleast_2d(np.asarray(astro, float))
    p = design.n_regressors
    if design.outer is not None:
        s = astro * design.b_ivar_sqrt
        tri = (s * s) @ design.outer
        a = np.empty((len(astro), p, p))
        a[:, design.iu[0], design.iu[1]] = tri
        a[:, design.iu[1], design.iu[0]] = tri
        b = (s * design.b_target) @ design.design
        return _solve_batch(a, b), None
    if design.starts is None:
        return None
    gw = binned_design_batch(design, astro)
    gw *= design.b_ivar_sqrt[None, :, None]
    a = np.matmul(gw.transpose(0, 2, 1), gw)
    b = design.b_target @ gw
    return _solve_batch(a, b), gw


def fit_log_likelihood(design: LinearDesign, residuals: np.ndarray,
                       noise_scale: float = 1.0) -> float:
    """Gaussian log-likelihood of the fitted points from their normalised residuals.

    ``residuals`` are :func:`fit_residuals` (one per bin, or per frame
    when unbinned); each point's sigma is the bin's error times ``noise_scale``.
    """
    r = np.asarray(residuals, float) / noise_scale
    sigma = noise_scale / design.b_ivar_sqrt
    return float(-0.5 * np.dot(r, r) - np.sum(np.log(sigma)) - 0.5 * len(r) * np.log(2 * np.pi))


def fit_log_likelihood_batch(design: LinearDesign, astro: np.ndarray,
                             noise_scale: float = 1.0) -> np.ndarray | None:
    """:func:`fit_log_likelihood` of the fit of every row of ``astro`` (m, n), or None.

    The coefficients of all rows are solved together (:func:`_solve_coefficients_batch`);
    None where no batched form is kept (the caller then loops).
    """
    solved = _solve_coefficients_batch(design, astro)
    if solved is None:
        return None
    coef, gw = solved
    astro = np.atleast_2d(np.asarray(astro, float))
    if gw is None:
        r = (design.b_flux - astro * (coef @ design.design.T)) * design.b_ivar_sqrt
    else:
        r = design.b_target - np.matmul(gw, coef[:, :, None])[:, :, 0]
    r = r / noise_scale
    sigma = noise_scale / design.b_ivar_sqrt
    return (-0.5 * np.einsum("ij,ij->i", r, r) - np.sum(np.log(sigma))
            - 0.5 * r.shape[1] * np.log(2 * np.pi))


def weighted_lstsq(design: np.ndarray, target: np.ndarray,
                   weights: np.ndarray | None = None) -> np.ndarray:
    """Least-squares coefficients of ``design @ c ~ target``, rows weighted by ``weights``.

    ``numpy.linalg.lstsq`` of ``design * w[:, None]`` and ``target * w`` (SVD,
    machine-precision cutoff); unweighted without ``weights``.
    """
    if weights is None:
        return np.linalg.lstsq(design, target, rcond=None)[0]
    return np.linalg.lstsq(design * weights[:, None], target * weights, rcond=None)[0]


def gram_lstsq(design: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Least squares through the normal equations, without multithreaded BLAS.

    The Gram matrix is formed with ``einsum`` (OpenBLAS threads made ``lstsq``
    on these tall, thin matrices 30x slower on a loaded machine) and solved by
    SVD (minimum norm, so all-zero columns get zero coefficients).
    """
    gram = np.einsum("ni,nj->ij", design, design)
    rhs = np.einsum("ni,n->i", design, target)
    coef, *_ = np.linalg.lstsq(gram, rhs, rcond=1e-12)
    return coef


class LinearSystematics(Systematics[OptionsT]):
    """A method whose model is ``a * (D c)``, ``c`` solved on :attr:`design` for each ``a``.

    ``D`` are the design's scaled regressors and ``a`` the curve they multiply
    (:meth:`regressed_curve`): the astrophysical curve, or that curve times a
    term of the method's own parameters. The coefficients ``c`` are solved by
    weighted least squares inside every evaluation; the residuals and the
    likelihood are those of the design's points (bins, or frames when
    unbinned), on which the whole fit is made. A subclass provides
    :attr:`design` and, if ``a`` is not the astrophysical curve,
    :meth:`regressed_curve` and :meth:`regressed_curves`.
    """

    @property
    @abstractmethod
    def design(self) -> LinearDesign:
        """The regression the coefficients are solved on."""

    def regressed_curve(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """The curve ``a`` the regressors multiply (default: ``astro``)."""
        return np.asarray(astro, float)

    def regressed_curves(self, astro: np.ndarray, theta: np.ndarray | None) -> np.ndarray:
        """:meth:`regressed_curve` of every row of ``astro`` (m, n), ``theta`` (m, k) or None."""
        return astro

    def predict(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """``a * (D c)`` at every frame, ``c`` fitted on the design's points."""
        a = self.regressed_curve(astro, theta)
        return a * np.einsum("nk,k->n", self.design.design, solve_coefficients(self.design, a))

    def residuals(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """Normalised residuals of the fitted points (one per bin; per frame when unbinned)."""
        a = self.regressed_curve(astro, theta)
        gw = weighted_binned_design(self.design, a)   # the solve's and the residuals' (issue 40)
        return fit_residuals(self.design, a, solve_coefficients(self.design, a, gw), gw)

    def log_likelihood(self, astro: np.ndarray, theta: np.ndarray | None = None,
                       noise_scale: float = 1.0) -> float:
        """Gaussian log-likelihood of the binned points the fit is made on."""
        return fit_log_likelihood(self.design, self.residuals(astro, theta), noise_scale)

    def log_likelihood_batch(self, astro: np.ndarray, theta: np.ndarray | None = None,
                             noise_scale: float = 1.0) -> np.ndarray:
        """:meth:`log_likelihood` of every row of ``astro`` (shape (m, n)) and of ``theta``
        (shape (m, k) or None): the normal equations of all rows are built and solved
        together."""
        astro = np.atleast_2d(np.asarray(astro, float))
        out = (fit_log_likelihood_batch(self.design, self.regressed_curves(astro, theta),
                                        noise_scale)
               if self._batch_is_exact(LinearSystematics) else None)
        return super().log_likelihood_batch(astro, theta, noise_scale) if out is None else out
