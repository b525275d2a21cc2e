"""Gaussian-process regression of the systematics (Gibson et al. 2012; Evans et al. 2015).

Paper, Appendix B.2: a maximum-likelihood fit of the eclipse depth, the
mid-eclipse time, the white-noise variance and the parameters of a covariance
kernel over pixel position (x, y) and time; then MCMC on the eclipse
parameters "with the covariance kernel parameters and white noise variance
held fixed"; fluxes and centroids binned in ~30 s groups (N ~ 1000 points).

Model. With ``y_i = flux_i / astro_i`` (electrons; the systematics multiply
the astrophysical signal)::

    y = F0 + g + e,   g ~ GP(0, A^2 k((x, y, t), (x', y', t'))),   e_i ~ N(0, s^2 sigma_i^2)

``k`` is the squared exponential ``exp(-r^2 / 2)`` or the Matern-3/2
``(1 + sqrt(3) r) exp(-sqrt(3) r)`` with ``r^2 = sum_d (Delta_d / l_d)^2`` (one
length scale per input), ``A`` the amplitude relative to the median flux,
``sigma_i`` the binned photometric errors and ``s`` a white-noise scale (the
white-noise variance of Evans et al., per bin). ``F0`` is profiled (its
generalised-least-squares value for each ``astro``). The likelihood is that of
``y``; it omits the Jacobian ``prod 1 / astro_i``, which would only matter
together with the equally small dependence of the white noise on ``astro``.

Library: none beyond scipy (and numba). The covariance of the ~1000 binned
points is factorised with :func:`scipy.linalg.cho_factor`; with the kernel
fixed, each likelihood costs one triangular solve (O(N^2)). While the kernel is
optimised, each evaluation fills the covariance (:func:`_fill_covariance`) and
sums the gradient's kernel terms (:func:`_kernel_gradient_sums`) in compiled
passes over its lower triangle. Binning happens in
``__init__`` (default 30 s bins within each AOR, inverse-variance weights from
``flux_err``), and ``self.data`` becomes the binned :class:`EpochData`, so a
fitter evaluates its astrophysical model at ``self.data.time_bmjd``. More
than ``max_points`` points (default 3000: a 3000 x 3000 covariance plus its
factor and gradient work arrays use ~0.4 GB) are refused with an
:class:`~eclipsebench.errors.InputError` that says to bin; an unbinned epoch
of 15,000 frames is therefore binned automatically by default and refused
with ``bin_seconds=0``.

Hyperparameters (``ln A, ln l_x, ln l_y, ln l_t, ln s``; lengths in pixels and
days) start from the data (A = the flux scatter, l_x and l_y = the centroid
scatters, l_t = the time span, s = 1) and are set by maximising the marginal
likelihood (L-BFGS-B, analytic gradient) in
:meth:`GaussianProcess.optimise_hyperparameters` for a fitted ``astro``; the
fitter (:func:`eclipsebench.fit.leastsq.fit_leastsq`) alternates it with the
eclipse fit (coordinate ascent on the joint maximum likelihood of Evans et
al.). Optimising first with ``astro = 1`` (``optimise=True``) lets the time
kernel learn the eclipse: on the tests' noiseless epoch the depth then came
out 2400 ppm too low. ``sample_kernel=True`` makes offsets of them from
their maximum-likelihood values the method's own parameters (``param_names``
= ``OFFSET_NAMES``, uniform prior of +-3 in each ``ln``), which only the
likelihood uses, so the MCMC samples them (each step then refactorises the
covariance: slow, about 64,000 Cholesky factorisations for the default
sampler) while least squares, which cannot set them, keeps the ML kernel.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np
from scipy.linalg import cho_factor, cho_solve, solve_triangular
from scipy.linalg.lapack import dpotrf, dpotri
from scipy.optimize import minimize

from ..config.base import check
from ..errors import InputError
from ..jit import lazy_njit
from .base import EpochData, MethodOptions, Systematics, register
from .record import FitterPolicy, MethodRecord, team_profile

__all__ = ["GaussianProcess", "bin_epoch", "bin_index", "kernel_matrix", "KERNELS", "HYPER_NAMES",
           "OFFSET_NAMES"]

KERNELS = ("squared-exponential", "matern32")
HYPER_NAMES = ("gp_ln_amp", "gp_ln_len_x", "gp_ln_len_y", "gp_ln_len_t", "gp_ln_white")
#: Names of the sampled parameters with ``sample_kernel=True``: offsets from the ML values.
OFFSET_NAMES = ("gp_dln_amp", "gp_dln_len_x", "gp_dln_len_y", "gp_dln_len_t", "gp_dln_white")
#: Half-width of the uniform prior on each sampled offset (a factor e^3 = 20 either way).
OFFSET_RANGE = 3.0
_SQRT3 = np.sqrt(3.0)


def bin_index(data: EpochData, bin_seconds: float) -> np.ndarray:
    """The bin of every frame: time bins of ``bin_seconds`` from the first frame of each AOR.

    Returns
    -------
    ndarray of int, shape (n,)
        Bin numbers 0..m-1, numbered in order of the bins' mean times.
    """
    if not bin_seconds > 0:
        raise InputError(f"gp option 'bin_seconds': expected a positive width, got {bin_seconds!r}")
    t = np.asarray(data.time_bmjd, dtype=float)
    aor = np.zeros(len(t), dtype=np.int64) if data.aorkey is None else np.asarray(data.aorkey)
    _, aor_idx = np.unique(aor, return_inverse=True)
    start = np.full(aor_idx.max() + 1, np.inf)
    np.minimum.at(start, aor_idx, t)
    nbin = np.floor((t - start[aor_idx]) * 86400.0 / bin_seconds).astype(np.int64)
    _, inv = np.unique(aor_idx * (nbin.max() + 1) + nbin, return_inverse=True)
    mean_t = np.bincount(inv, weights=t) / np.bincount(inv)
    rank = np.empty(len(mean_t), dtype=np.int64)
    rank[np.argsort(mean_t, kind="stable")] = np.arange(len(mean_t))
    return rank[inv]


def bin_epoch(data: EpochData, bin_seconds: float) -> EpochData:
    """Inverse-variance weighted means of the frames in time bins within each AOR.

    Parameters
    ----------
    data : EpochData
        Frames in any order.
    bin_seconds : float
        Bin width; bins start at the first frame of each AOR (:func:`bin_index`).

    Returns
    -------
    EpochData
        One row per non-empty bin, in time order: weighted means (weights
        ``1 / flux_err**2``) of time, flux, centroids, noise pixels and pixel
        stamps; ``flux_err`` of a bin is ``1 / sqrt(sum of weights)``;
        ``meta['n_per_bin']`` holds the number of frames in each bin.
    """
    inv = bin_index(data, bin_seconds)
    w = 1.0 / np.asarray(data.flux_err, dtype=float) ** 2
    wsum = np.bincount(inv, weights=w)

    def wmean(a):
        if a is None:
            return None
        a = np.asarray(a, dtype=float)
        if a.ndim == 1:
            return np.bincount(inv, weights=w * a) / wsum
        flat = a.reshape(len(a), -1)
        out = np.column_stack([np.bincount(inv, weights=w * flat[:, j]) for j in
                               range(flat.shape[1])]) / wsum[:, None]
        return out.reshape((len(wsum),) + a.shape[1:])

    first = np.zeros(len(wsum), dtype=np.int64)
    first[inv[::-1]] = np.arange(len(inv))[::-1]
    meta = dict(data.meta)
    meta["n_per_bin"] = np.bincount(inv)
    meta["bin_seconds"] = float(bin_seconds)
    return EpochData(time_bmjd=wmean(data.time_bmjd), flux=wmean(data.flux),
                     flux_err=1.0 / np.sqrt(wsum), x=wmean(data.x), y=wmean(data.y),
                     noise_pixels=wmean(data.noise_pixels), pixels=wmean(data.pixels),
                     aorkey=None if data.aorkey is None else np.asarray(data.aorkey)[first],
                     meta=meta)


def kernel_matrix(inputs: np.ndarray, lengths: np.ndarray, kind: str,
                  gradient: bool = False):
    """Unit-amplitude kernel matrix and, optionally, its derivatives by ``ln l_d``.

    Parameters
    ----------
    inputs : ndarray, shape (n, d)
        Input coordinates (x, y, t).
    lengths : ndarray, shape (d,)
        One length scale per input.
    kind : {"squared-exponential", "matern32"}
    gradient : bool
        Also return ``dK / d ln l_d`` for each input (a list of (n, n) arrays).

    Returns
    -------
    K : ndarray, shape (n, n)
    dK : list of ndarray (only when ``gradient``)
    """
    z = np.asarray(inputs, dtype=float) / np.asarray(lengths, dtype=float)
    sq = [(z[:, d, None] - z[None, :, d]) ** 2 for d in range(z.shape[1])]
    r2 = np.sum(sq, axis=0)
    if kind == "squared-exponential":
        k = np.exp(-0.5 * r2)
        if not gradient:
            return k
        return k, [k * s for s in sq]
    if kind == "matern32":
        r = np.sqrt(r2)
        e = np.exp(-_SQRT3 * r)
        k = (1.0 + _SQRT3 * r) * e
        if not gradient:
            return k
        return k, [3.0 * e * s for s in sq]
    raise InputError(f"gp option 'kernel': expected one of {', '.join(KERNELS)}, got {kind!r}")


@lazy_njit(cache=True)
def _fill_covariance(scaled_t: np.ndarray, amp2: float, white: np.ndarray, matern: bool,
                     cov: np.ndarray) -> None:
    """Lower triangle and diagonal of ``amp2 K + diag(white)`` into ``cov`` (in place).

    The compiled form of :func:`kernel_matrix` for :meth:`GaussianProcess._neg_log_ml`:
    one pass over the pairs ``i > j``, no ``(n, n)`` temporaries; the upper
    triangle is not written (LAPACK's lower Cholesky factor does not read it).

    Parameters
    ----------
    scaled_t : ndarray, shape (d, n)
        The inputs divided by their length scales, one row per input.
    amp2 : float
        ``A^2``.
    white : ndarray, shape (n,)
        The white-noise variances ``(s sigma_i)^2``.
    matern : bool
        Matern-3/2 kernel, else squared exponential (the formulas of :func:`kernel_matrix`).
    cov : ndarray, shape (n, n)
        Output (Fortran order, for LAPACK in place).
    """
    nd, n = scaled_t.shape
    sqrt3 = np.sqrt(3.0)
    for j in range(n):
        cov[j, j] = amp2 + white[j]          # k(0) = 1
        for i in range(j + 1, n):
            r2 = 0.0
            for d in range(nd):
                dz = scaled_t[d, i] - scaled_t[d, j]
                r2 += dz * dz
            if matern:
                r = np.sqrt(r2)
                k = (1.0 + sqrt3 * r) * np.exp(-sqrt3 * r)
            else:
                k = np.exp(-0.5 * r2)
            cov[i, j] = amp2 * k


@lazy_njit(cache=True)
def _kernel_gradient_sums(scaled_t: np.ndarray, alpha: np.ndarray, cinv: np.ndarray,
                          matern: bool) -> np.ndarray:
    """``sum_ij (alpha_i alpha_j - Cinv_ij) G_ij`` for ``G = K`` and ``G = dK / d ln l_d``.

    The kernel terms of the marginal likelihood's gradient (Rasmussen &
    Williams 2006, eq. 5.9: ``d ln L / dh = 0.5 tr((alpha alpha^T - C^-1) dC/dh)``;
    each matrix is symmetric, so the trace is the sum of their elementwise
    product), accumulated over the lower triangle without building ``K``, its
    derivatives or ``C^-1``'s upper half. ``dK / d ln l_d`` is
    ``K (dz_d)^2`` (squared exponential) or ``3 exp(-sqrt(3) r) (dz_d)^2``
    (Matern-3/2), with ``dz_d`` the scaled separation; it vanishes on the diagonal.

    Parameters
    ----------
    scaled_t : ndarray, shape (d, n)
        The inputs divided by their length scales, one row per input.
    alpha : ndarray, shape (n,)
        ``C^-1 (y - F0)``.
    cinv : ndarray, shape (n, n)
        ``C^-1`` in its lower triangle (LAPACK ``dpotri``; the upper one is not read).
    matern : bool
        Matern-3/2 kernel, else squared exponential.

    Returns
    -------
    ndarray, shape (d + 1,)
        The sum for ``K``, then for each ``dK / d ln l_d``.
    """
    nd, n = scaled_t.shape
    sqrt3 = np.sqrt(3.0)
    total = np.zeros(nd + 1)
    column = np.zeros(nd + 1)
    sq = np.zeros(nd)
    for j in range(n):
        column[:] = 0.0
        for i in range(j + 1, n):
            r2 = 0.0
            for d in range(nd):
                dz = scaled_t[d, i] - scaled_t[d, j]
                sq[d] = dz * dz
                r2 += sq[d]
            w = alpha[i] * alpha[j] - cinv[i, j]
            if matern:
                r = np.sqrt(r2)
                e = np.exp(-sqrt3 * r)
                column[0] += w * (1.0 + sqrt3 * r) * e
                g = 3.0 * w * e
            else:
                g = w * np.exp(-0.5 * r2)
                column[0] += g
            for d in range(nd):
                column[1 + d] += g * sq[d]
        # the pair (i, j) and its mirror (j, i); the diagonal once (K_jj = 1, dK_jj = 0)
        total[0] += 2.0 * column[0] + alpha[j] * alpha[j] - cinv[j, j]
        for d in range(nd):
            total[1 + d] += 2.0 * column[1 + d]
    return total


@dataclass(frozen=True)
class GpOptions(MethodOptions):
    """Options of ``gp`` (:class:`GaussianProcess`)."""

    kernel: Literal["squared-exponential", "matern32"] = "squared-exponential"
    bin_seconds: float | None = 30.0
    max_points: int = 3000
    sample_kernel: bool = False
    hyperparameters: tuple[float, ...] | None = None
    optimise: bool = False

    def validate(self) -> None:
        check(self.bin_seconds is None or self.bin_seconds >= 0, "bin_seconds",
              "a bin width >= 0 s (0: unbinned)")
        check(self.max_points >= 10, "max_points", "at least 10 points")
        h = self.hyperparameters or ()
        check(len(h) in (0, 5) and all(np.isfinite(v) for v in h), "hyperparameters",
              f"5 finite numbers ({', '.join(HYPER_NAMES)}) or none")


@register
class GaussianProcess(Systematics[GpOptions]):
    """GP systematics over (x, y, t) on binned data (Evans et al. 2015).

    Options (:class:`GpOptions`)
    ----------------------------
    kernel : {"squared-exponential", "matern32"}
        Covariance function (default squared exponential, as Evans et al.).
    bin_seconds : float
        Time-bin width in seconds (30); 0 fits the frames unbinned.
    max_points : int
        Largest number of (binned) points accepted (3000); more raises
        InputError asking to bin.
    sample_kernel : bool
        Sample the hyperparameters in the MCMC too, as offsets from their
        maximum-likelihood values (default False: held fixed, as in the paper).
    hyperparameters : sequence of 5 floats, optional
        Fixed ``ln A, ln l_x, ln l_y, ln l_t, ln s``; skips the optimisation.
    optimise : bool
        Maximise the marginal likelihood already in ``__init__``, with
        ``astro = 1`` (default False: an unmodelled eclipse would be learnt by
        the time kernel; the fitter calls :meth:`optimise_hyperparameters`
        with its fitted eclipse instead).
    """

    name: ClassVar[str] = "gp"
    requires: ClassVar[tuple[str, ...]] = ("x", "y")
    #: the order of option ``hyperparameters`` (and of ``diagnostics()["hyperparameters"]``)
    hyperparameter_names: ClassVar[tuple[str, ...]] = HYPER_NAMES
    # No prayer bead: cyclic shifts of the residuals carry the correlated part the kernel
    # already models, so the bead double-counts it (199 vs 80 ppm on a simulated epoch)
    # and costs one kernel optimisation per shift; Evans et al. (2015) took their errors
    # from MCMC with the kernel fixed, which `--sampler mcmc` does. The kernel's
    # white-noise term ``s`` models the noise (likelihood_models_noise).
    record: ClassVar[MethodRecord] = MethodRecord(
        label="GP", paper=team_profile("gp"), in_paper=True,
        policy=FitterPolicy(use_prayer_bead=False, likelihood_models_noise=True))

    def setup(self, data: EpochData) -> None:
        opts = self.options
        kernel, bin_seconds, max_points = opts.kernel, opts.bin_seconds, opts.max_points
        hyperparameters = opts.hyperparameters or None
        sample_kernel, optimise = opts.sample_kernel, opts.optimise
        self.kernel = kernel
        self.unbinned_data = data
        binned = bin_epoch(data, bin_seconds) if bin_seconds else data
        self._bin_of_frame = bin_index(data, bin_seconds) if bin_seconds else None
        n = len(binned)
        if n > max_points:
            what = f"{bin_seconds:g} s bins give" if bin_seconds else "the unbinned epoch has"
            raise InputError(f"gp: {what} {n} points, more than max_points={max_points} (a dense "
                             f"{n}x{n} covariance needs {8 * n * n * 4 / 1e9:.1f} GB); bin the "
                             "data (option bin_seconds, default 30)")
        if n < 10:
            raise InputError(f"gp: only {n} points after binning; use smaller bins (bin_seconds)")
        self.data = binned
        t = np.asarray(binned.time_bmjd, dtype=float)
        self._t0 = t[0]
        self.inputs = np.column_stack([binned.x, binned.y, t - t[0]])
        if self._bin_of_frame is not None:
            w = 1.0 / np.asarray(data.flux_err, dtype=float) ** 2
            self._frame_w = w / np.bincount(self._bin_of_frame, weights=w)[self._bin_of_frame]
        self.norm = float(np.median(binned.flux))
        self.sigma_rel = np.asarray(binned.flux_err, dtype=float) / self.norm
        self.flux_rel = np.asarray(binned.flux, dtype=float) / self.norm
        self._lo, self._hi = self._hyper_bounds()
        if hyperparameters is not None:
            h = np.asarray(hyperparameters, dtype=float)
        else:
            h = self._hyper_start()
        self.sample_kernel = bool(sample_kernel)
        self.param_names = OFFSET_NAMES if self.sample_kernel else ()
        self._offset_cache: tuple[np.ndarray, tuple] | None = None
        self._factorise(h)
        self.ml_info: dict[str, Any] = {}
        #: given hyperparameters are held: the fitter's alternation leaves them as they are
        self.fixed_hyperparameters = hyperparameters is not None
        if hyperparameters is None and optimise:
            self.optimise_hyperparameters(np.ones(n))

    # ------------------------------------------------------------------ set-up
    def _hyper_start(self) -> np.ndarray:
        sx = max(np.std(self.inputs[:, 0]), 1e-3)
        sy = max(np.std(self.inputs[:, 1]), 1e-3)
        span = max(self.inputs[-1, 2], 1e-3)
        amp = max(np.std(self.flux_rel), 1e-5)
        # A time scale as long as the data: the first eclipse fit cannot hide the eclipse in it.
        return np.log([amp, sx, sy, span, 1.0])

    def _hyper_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        sx = max(np.std(self.inputs[:, 0]), 1e-3)
        sy = max(np.std(self.inputs[:, 1]), 1e-3)
        span = max(self.inputs[-1, 2], 1e-3)
        dt = max(np.median(np.diff(self.inputs[:, 2])), 1e-6)
        lo = np.log([1e-7, 0.02 * sx, 0.02 * sy, 2.0 * dt, 0.05])
        hi = np.log([0.5, 1e3 * sx, 1e3 * sy, 1e2 * span, 20.0])
        return lo, hi

    def _covariance(self, h: np.ndarray):
        amp2 = np.exp(2.0 * h[0])
        white = np.exp(2.0 * h[4]) * self.sigma_rel ** 2
        signal = amp2 * kernel_matrix(self.inputs, np.exp(h[1:4]), self.kernel)
        cov = signal.copy()
        cov[np.diag_indices_from(cov)] += white
        return cov, signal

    def _factor(self, h: np.ndarray) -> tuple:
        """Cholesky factor, signal covariance, GLS weights of F0 and half log-determinant."""
        cov, signal = self._covariance(h)
        try:
            cf = cho_factor(cov, lower=True, check_finite=False)
        except np.linalg.LinAlgError as exc:
            raise InputError(f"gp: covariance not positive definite for hyperparameters "
                             f"{np.round(h, 3).tolist()}") from exc
        ones = np.ones(len(cov))
        cinv1 = cho_solve(cf, ones, check_finite=False)
        return cf, signal, cinv1 / ones.dot(cinv1), float(np.sum(np.log(np.diag(cf[0]))))

    def _factorise(self, h: np.ndarray) -> None:
        self._cf, self._signal, self._gls_w, self._half_logdet = self._factor(h)
        self.hyper = np.array(h, dtype=float)
        self._offset_cache = None

    def _whitened(self, astro: np.ndarray, factor: tuple) -> np.ndarray:
        cf, _, gls_w, _ = factor
        yrel = self.flux_rel / self._binned_astro(astro)
        r = yrel - float(gls_w.dot(yrel))
        return solve_triangular(cf[0], r, lower=True, check_finite=False)

    # ------------------------------------------------------- hyperparameters
    def _neg_log_ml(self, h: np.ndarray, yrel: np.ndarray):
        """``-ln L`` of ``yrel`` at hyperparameters ``h`` (``F0`` profiled) and its gradient.

        ``d(-ln L)/dh = -0.5 (alpha^T dC alpha - tr(C^-1 dC))`` (Rasmussen &
        Williams 2006, eq. 5.9; ``F0`` profiled, envelope theorem), with ``dC/dh``
        = ``2 A^2 K``, ``A^2 dK/d ln l_d`` and ``diag(2 (s sigma_i)^2)``. The
        covariance is filled (:func:`_fill_covariance`), factorised and inverted
        (LAPACK ``dpotrf``, ``dpotri``) in one Fortran-ordered array, and the
        kernel traces summed over its lower triangle (:func:`_kernel_gradient_sums`);
        no other ``n x n`` array is made.
        """
        amp2 = np.exp(2.0 * h[0])
        white = np.exp(2.0 * h[4]) * self.sigma_rel ** 2
        matern = self.kernel == "matern32"   # else squared exponential (checked in setup)
        n = len(yrel)
        scaled_t = np.ascontiguousarray((self.inputs / np.exp(h[1:4])).T)
        cov = np.empty((n, n), order="F")
        _fill_covariance(scaled_t, amp2, white, matern, cov)
        c, info = dpotrf(cov, lower=1, clean=0, overwrite_a=1)
        if info != 0:
            return 1e25, np.zeros_like(h)
        cf = (c, True)
        ones = np.ones(n)
        cinv1 = cho_solve(cf, ones, check_finite=False)
        f0 = cinv1.dot(yrel) / cinv1.sum()
        r = yrel - f0
        alpha = cho_solve(cf, r, check_finite=False)
        half_logdet = np.sum(np.log(np.diag(c)))
        nll = 0.5 * r.dot(alpha) + half_logdet
        cinv, info = dpotri(c, lower=1, overwrite_c=1)  # C^-1 in the lower triangle
        if info != 0:
            return 1e25, np.zeros_like(h)
        sums = _kernel_gradient_sums(scaled_t, alpha, cinv, matern)
        grad = np.concatenate([[-amp2 * sums[0]], -0.5 * amp2 * sums[1:],
                               [-(alpha @ (white * alpha) - np.diag(cinv) @ white)]])
        return float(nll), grad

    def optimise_hyperparameters(self, astro: np.ndarray) -> dict[str, Any] | None:
        """Maximum-likelihood kernel and white-noise parameters for a given ``astro``.

        Parameters
        ----------
        astro : ndarray, shape (n_binned,)
            The astrophysical model at ``self.data.time_bmjd`` (1 = the star).

        Returns
        -------
        dict or None
            ``hyperparameters`` (the new ``ln`` values), ``neg_log_ml`` and
            ``converged``; the covariance is refactorised with them. None when
            the hyperparameters were given (option ``hyperparameters``): they
            are held, as that option says.
        """
        if self.fixed_hyperparameters:
            return None
        yrel = self.flux_rel / np.asarray(astro, dtype=float)
        h0 = np.clip(self.hyper, self._lo + 1e-6, self._hi - 1e-6)
        res = minimize(self._neg_log_ml, h0, args=(yrel,), jac=True, method="L-BFGS-B",
                       bounds=list(zip(self._lo, self._hi, strict=True)),
                       options={"maxiter": 200})
        self._factorise(res.x)
        self.ml_info = {"hyperparameters": dict(zip(HYPER_NAMES, res.x.tolist(), strict=True)),
                        "neg_log_ml": float(res.fun), "converged": bool(res.success),
                        "n_evaluations": int(res.nfev)}
        return self.ml_info

    @property
    def n_frames(self) -> int:
        """The frames behind the bins."""
        return len(self.unbinned_data)

    def diagnostics(self) -> dict[str, Any]:
        """The kernel in use, the binning, and the last likelihood maximisation."""
        return {"n_points": len(self.data), "n_frames": len(self.unbinned_data),
                "hyperparameters": dict(zip(HYPER_NAMES, np.asarray(self.hyper).tolist(),
                                            strict=True)),
                "ml": dict(self.ml_info)}

    # ------------------------------------------------------------- interface
    def initial_params(self) -> np.ndarray:
        """Zero offsets from the maximum-likelihood hyperparameters (when they are sampled)."""
        return np.zeros(5) if self.sample_kernel else np.zeros(0)

    def param_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """+-``OFFSET_RANGE`` in each ``ln`` hyperparameter around its ML value."""
        if self.sample_kernel:
            return np.full(5, -OFFSET_RANGE), np.full(5, OFFSET_RANGE)
        return np.zeros(0), np.zeros(0)

    def _binned_astro(self, astro: np.ndarray) -> np.ndarray:
        """``astro`` on the bins: as given, or binned like the flux when given per frame."""
        a = np.asarray(astro, dtype=float)
        if len(a) == len(self.data):
            return a
        if self._bin_of_frame is not None and len(a) == len(self.unbinned_data):
            return np.bincount(self._bin_of_frame, weights=self._frame_w * a)
        raise InputError(f"gp: astro has {len(a)} values; expected {len(self.data)} (bins) or "
                         f"{len(self.unbinned_data)} (frames)")

    def _residual_rel(self, astro: np.ndarray) -> tuple[np.ndarray, float]:
        yrel = self.flux_rel / self._binned_astro(astro)
        f0 = float(self._gls_w.dot(yrel))
        return yrel - f0, f0

    def predict(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """``astro * (F0 + E[g | data])`` in electrons: the GP's conditional mean.

        ``astro`` is given on the bins (``self.data.time_bmjd``, what a fitter
        uses) or on the original frames; in the second case the conditional
        mean is evaluated at every frame's (x, y, t), in blocks of 2000 frames.
        Always with the maximum-likelihood kernel (``theta`` is not used).
        """
        a = np.asarray(astro, dtype=float)
        r, f0 = self._residual_rel(a)
        alpha = cho_solve(self._cf, r, check_finite=False)
        if len(a) == len(self.data):
            return a * (f0 + self._signal @ alpha) * self.norm
        frames = self.unbinned_data
        z = np.column_stack([frames.x, frames.y, np.asarray(frames.time_bmjd) - self._t0])
        lengths = np.exp(self.hyper[1:4])
        amp2 = np.exp(2.0 * self.hyper[0])
        mean = np.empty(len(z))
        for i in range(0, len(z), 2000):
            zb = z[i:i + 2000] / lengths
            zi = self.inputs / lengths
            r2 = np.sum((zb[:, None, :] - zi[None, :, :]) ** 2, axis=2)
            k = np.exp(-0.5 * r2) if self.kernel == "squared-exponential" else \
                (1.0 + _SQRT3 * np.sqrt(r2)) * np.exp(-_SQRT3 * np.sqrt(r2))
            mean[i:i + 2000] = amp2 * (k @ alpha)
        return a * (f0 + mean) * self.norm

    def with_flux(self, flux: np.ndarray) -> GaussianProcess:
        """The same GP (same kernel and factorisation) on the bins with ``flux`` replaced.

        For the prayer bead; ``flux`` has one value per bin. The covariance
        does not depend on the flux, so nothing is refactorised.
        """
        new = self._copy_with_flux(flux)   # one flux per bin
        new.flux_rel = new.data.flux / self.norm
        return new

    def correct(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """The decorrelated light curve on the bins or, for per-frame ``astro``, the frames."""
        a = np.asarray(astro, dtype=float)
        flux = self.data.flux if len(a) == len(self.data) else self.unbinned_data.flux
        return flux / (self.predict(a, theta) / a)

    def residuals(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """Whitened residuals ``L^-1 (y - F0)``; their sum of squares is the GP chi-square.

        Always with the maximum-likelihood kernel: least squares cannot set
        kernel parameters (the determinant term is missing), so sampled
        offsets (``theta``) enter only :meth:`log_likelihood`.
        """
        return self._whitened(astro, (self._cf, self._signal, self._gls_w, self._half_logdet))

    def log_likelihood(self, astro: np.ndarray, theta: np.ndarray | None = None,
                       noise_scale: float = 1.0) -> float:
        """GP marginal log-likelihood of the fluxes (electrons), ``F0`` profiled.

        ``noise_scale`` multiplies the white-noise term (the covariance is then
        refactorised); the method's own white-noise scale makes it redundant,
        so a fitter should leave it at 1. With ``sample_kernel``, ``theta``
        holds offsets of the ``ln`` hyperparameters from their ML values; a
        non-zero offset refactorises the covariance (cached for the last one).
        """
        offset = np.zeros(5)
        if self.sample_kernel and theta is not None and len(theta) == 5:
            offset = np.asarray(theta, dtype=float).copy()
        offset[4] += np.log(noise_scale)
        factor = self._factor_at(offset)
        w = self._whitened(astro, factor)
        n = len(w)
        return float(-0.5 * w.dot(w) - factor[3] - n * np.log(self.norm)
                     - 0.5 * n * np.log(2.0 * np.pi))

    def _factor_at(self, offset: np.ndarray):
        """The covariance factorisation at ``hyper + offset`` (the fitted one at zero offset;
        the last other one is cached)."""
        if not np.any(offset):
            return (self._cf, self._signal, self._gls_w, self._half_logdet)
        if self._offset_cache is not None and np.array_equal(self._offset_cache[0], offset):
            return self._offset_cache[1]
        factor = self._factor(self.hyper + offset)
        self._offset_cache = (offset, factor)
        return factor

    def log_likelihood_batch(self, astro: np.ndarray, theta: np.ndarray | None = None,
                             noise_scale: float = 1.0) -> np.ndarray:
        """:meth:`log_likelihood` of every row of ``astro`` (shape (m, n_bins)).

        With the kernel fixed (no sampled offsets, the MCMC of Evans et al.)
        every row shares one factorisation, so all rows are whitened by one
        triangular solve with m right-hand sides. Sampled kernel offsets
        (``sample_kernel``) or curves given per frame loop over
        :meth:`log_likelihood`.
        """
        astro = np.atleast_2d(np.asarray(astro, dtype=float))
        sampled = self.sample_kernel and theta is not None and np.size(theta) > 0
        if (sampled or astro.shape[1] != len(self.data)
                or not self._batch_is_exact(GaussianProcess)):
            return super().log_likelihood_batch(astro, theta, noise_scale)
        offset = np.zeros(5)
        offset[4] += np.log(noise_scale)
        factor = self._factor_at(offset)
        cf, _, gls_w, half_logdet = factor
        yrel = self.flux_rel / astro
        r = yrel - (yrel @ gls_w)[:, None]
        w = solve_triangular(cf[0], r.T, lower=True, check_finite=False)
        n = w.shape[0]
        return (-0.5 * np.einsum("ij,ij->j", w, w) - half_logdet - n * np.log(self.norm)
                - 0.5 * n * np.log(2.0 * np.pi))

    def n_effective_params(self) -> int:
        """``F0`` and the five kernel and white-noise parameters."""
        return 1 + 5
