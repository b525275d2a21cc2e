"""Least-squares fit of the joint model, and its error estimates.

The astrophysical parameters (:class:`~eclipsebench.fit.model.AstroModel`)
and the method's own nonlinear parameters (``Systematics.param_names``) are
fitted together with :func:`scipy.optimize.least_squares` on
``Systematics.residuals``. Linear or non-parametric pieces (BLISS knots,
kernel-regression averages, PLD coefficients) are recomputed inside
``predict`` at every step, so the Jacobian is that of the profiled model.

Errors
------
- Jacobian: ``cov = (J^T J)^-1 * chi2_red`` with ``J`` the central-difference
  Jacobian of the normalised residuals at the solution.
- Red-noise factor ``beta_red`` (time averaging, Pont et al. 2006; Winn et al.
  2008): the rms of the residuals binned over N frames against the white-noise
  expectation ``sigma_1 / sqrt(N) * sqrt(M / (M - 1))`` (M bins), averaged over
  bin widths between 10 and 30 minutes by default (the ingress timescale).
  The depth error is multiplied by ``max(1, beta_red)``.
- Prayer bead (Wong et al. 2014): the residuals are shifted cyclically, added
  back to the model and refitted; the spread of the refitted depths is an
  error estimate that keeps the correlated noise.
- BIC and AIC (paper Eq. ``bicdef``; AIC = -2 ln L + 2k) with
  ``k = len(astro) + Systematics.n_effective_params()``.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from ..decorrelate.base import Systematics
from ..errors import InputError
from ..progress import progress
from .model import AstroModel

__all__ = ["FitResult", "fit_leastsq", "information_criteria", "rms_vs_bin_size",
           "red_noise_beta", "prayer_bead", "joint_names", "has_hyperparameters",
           "has_own_likelihood"]

_SECONDS_PER_DAY = 86400.0


def information_criteria(log_likelihood: float, k: int, n: int) -> tuple[float, float]:
    """BIC (paper Eq. ``bicdef``: ``-2 ln L + k ln n``) and AIC (``-2 ln L + 2 k``)."""
    return -2.0 * log_likelihood + k * np.log(n), -2.0 * log_likelihood + 2.0 * k


def rms_vs_bin_size(residuals: np.ndarray, sizes) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rms of residuals averaged in consecutive blocks of N frames, and its white expectation.

    Parameters
    ----------
    residuals : ndarray, shape (n,)
        Residuals in time order.
    sizes : array_like of int
        Bin sizes N (frames); sizes leaving fewer than 2 bins are dropped.

    Returns
    -------
    sizes, sigma_n, expected : ndarray
        The kept sizes, the measured rms of the bin means (population rms
        about their mean), and ``sigma_1 / sqrt(N) * sqrt(M / (M - 1))``.
    """
    r = np.asarray(residuals, dtype=float)
    sizes = np.unique(np.asarray(sizes, dtype=int))
    sizes = sizes[(sizes >= 1) & (len(r) // np.maximum(sizes, 1) >= 2)]
    sigma1 = float(np.std(r))
    sigma_n = np.empty(len(sizes))
    expected = np.empty(len(sizes))
    for i, size in enumerate(sizes):
        m = len(r) // size
        means = r[:m * size].reshape(m, size).mean(axis=1)
        sigma_n[i] = np.std(means)
        expected[i] = sigma1 / np.sqrt(size) * np.sqrt(m / (m - 1.0))
    return sizes, sigma_n, expected


def red_noise_beta(residuals: np.ndarray, time_bmjd: np.ndarray, *,
                   bin_minutes: tuple[float, ...] = (10.0, 30.0), n_sizes: int = 10,
                   min_bins: int = 8) -> float:
    """The time-averaging red-noise factor beta (Winn et al. 2008, Sect. 3).

    The ratio ``sigma_N / expected`` of :func:`rms_vs_bin_size`, averaged over
    ``n_sizes`` bin widths spaced logarithmically between ``bin_minutes``.
    Bin widths that leave fewer than ``min_bins`` bins are dropped; if none is
    left, the widest usable one (at least ``min_bins`` bins) is used. Returns
    the raw average (about 1 for white noise, > 1 with correlated noise).
    """
    r = np.asarray(residuals, dtype=float)
    t = np.asarray(time_bmjd, dtype=float)
    if len(r) < 2 * min_bins:
        return float("nan")
    cadence_min = float(np.median(np.diff(t))) * 1440.0
    lo, hi = (max(1.0, b / cadence_min) for b in bin_minutes)
    sizes = np.unique(np.round(np.geomspace(lo, hi, n_sizes)).astype(int))
    sizes = sizes[len(r) // sizes >= min_bins]
    if len(sizes) == 0:
        sizes = np.array([max(1, len(r) // min_bins)])
    sizes, sigma_n, expected = rms_vs_bin_size(r, sizes)
    ok = expected > 0
    if not np.any(ok):
        return float("nan")
    return float(np.mean(sigma_n[ok] / expected[ok]))


def joint_names(astro_model: AstroModel, systematics: Systematics) -> tuple[str, ...]:
    """Names of the joint parameter vector: astro parameters, then the method's."""
    return tuple(astro_model.names) + tuple(f"sys_{n}" for n in systematics.param_names)


@dataclass(frozen=True)
class FitResult:
    """The least-squares solution of one joint fit and its error estimates.

    Attributes
    ----------
    theta : ndarray
        Best joint parameters (astro then systematics, see ``names``).
    names : tuple of str
        Parameter names.
    n_astro : int
        Number of astrophysical parameters at the start of ``theta``.
    cov : ndarray
        Covariance from the Jacobian, scaled by ``chi2_red``.
    errors : ndarray
        ``sqrt(diag(cov))`` (not yet multiplied by ``beta_red``).
    chi2, chi2_red : float
        Sum of squares of ``Systematics.residuals`` (the chi-square with the
        reported flux errors, or the GP's whitened one), and per degree of freedom.
    n_data, k : int
        Number of fitted points and of free parameters (astro + effective
        systematics parameters).
    log_likelihood, bic, aic : float
        At the solution, with the reported flux errors.
    rms_ppm, beta_red : float
        Rms of the relative residuals ``flux / model - 1`` (ppm) and the
        red-noise factor of those residuals.
    """

    theta: np.ndarray
    names: tuple[str, ...]
    n_astro: int
    cov: np.ndarray
    errors: np.ndarray
    chi2: float
    chi2_red: float
    n_data: int
    k: int
    log_likelihood: float
    bic: float
    aic: float
    rms_ppm: float
    beta_red: float
    nfev: int
    success: bool
    message: str
    astro: np.ndarray = field(repr=False)
    model: np.ndarray = field(repr=False)

    @property
    def theta_astro(self) -> np.ndarray:
        return self.theta[:self.n_astro]

    @property
    def theta_sys(self) -> np.ndarray:
        return self.theta[self.n_astro:]

    def value(self, name: str) -> float:
        return float(self.theta[self.names.index(name)])

    def error(self, name: str) -> float:
        return float(self.errors[self.names.index(name)])


class _Problem:
    """The joint residual function of one epoch, with steps, scales and bounds."""

    def __init__(self, systematics: Systematics, astro_model: AstroModel):
        self.sys = systematics
        self.astro = astro_model
        self.n_astro = len(astro_model)
        self.n_sys = len(systematics.param_names)
        lo_a, hi_a = astro_model.bounds
        lo_s, hi_s = systematics.param_bounds()
        self.lower = np.concatenate([lo_a, np.asarray(lo_s, dtype=float)])
        self.upper = np.concatenate([hi_a, np.asarray(hi_s, dtype=float)])
        #: the last (theta, residuals): least_squares asks for the Jacobian where it has
        #: just evaluated the residuals, which the forward differences start from
        self._last: tuple[np.ndarray, np.ndarray] | None = None

    def forget(self) -> None:
        """Drop the remembered residuals (the method's state may have changed since)."""
        self._last = None

    def scales(self, theta: np.ndarray) -> np.ndarray:
        sys_scale = np.maximum(1e-2, np.abs(theta[self.n_astro:]))
        return np.concatenate([self.astro.scales, sys_scale])

    def split(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        return theta[:self.n_astro], (theta[self.n_astro:] if self.n_sys else None)

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        theta_a, theta_s = self.split(theta)
        resid = self.sys.residuals(self.astro(theta_a), theta_s)
        if getattr(self.astro, "n_priors", 0):   # Gaussian priors (a transit's q1, q2, ...)
            resid = np.concatenate([resid, self.astro.prior_residuals(theta_a)])
        self._last = (np.array(theta, dtype=float), np.array(resid, dtype=float))
        return resid

    def residuals_rows(self, thetas: np.ndarray) -> np.ndarray:
        """:meth:`residuals` of every row of ``thetas``, the same values: the astrophysical
        model of the rows and the method's ``residuals_batch`` of all of them.

        The model is ``AstroModel.batch`` (each row the same values as the model's own
        call, an eclipse's rows in one compiled pass) once numba is loaded in the process
        (a method's kernels, an MCMC, a run's worker), else a row at a time: a
        least-squares fit by a method without kernels of its own never loads numba
        (issue 40's start-up). KR/Data's prayer bead: 4,400 rows, 0.8 s a row at a time.
        """
        if "numba" in sys.modules:
            astro = self.astro.batch(thetas[:, :self.n_astro])
        else:
            astro = np.stack([self.astro(t) for t in thetas[:, :self.n_astro]])
        resid = self.sys.residuals_batch(astro, thetas[:, self.n_astro:] if self.n_sys else None)
        if getattr(self.astro, "n_priors", 0):   # Gaussian priors (a transit's q1, q2, ...)
            resid = np.hstack([resid, np.stack([self.astro.prior_residuals(t[:self.n_astro])
                                                for t in thetas])])
        return resid

    def jacobian(self, theta: np.ndarray, *, central: bool = False,
                 f0: np.ndarray | None = None) -> np.ndarray:
        """Finite-difference Jacobian with steps of 1 % of each parameter's scale.

        The shifted parameter vectors are evaluated together (:meth:`residuals_rows`);
        forward differences start from the residuals last evaluated if they were at
        ``theta`` (least_squares evaluates them there just before).
        """
        steps = 1e-2 * self.scales(theta)
        if f0 is None and not central:
            last = self._last
            f0 = last[1] if last is not None and np.array_equal(last[0], theta) else \
                self.residuals(theta)
        # step away from a bound that the forward point would cross
        steps = np.where(theta + steps > self.upper, -steps, steps)
        diag = np.arange(len(theta))
        up = np.tile(theta, (len(theta), 1))
        up[diag, diag] += steps
        if central:
            down = np.tile(theta, (len(theta), 1))
            down[diag, diag] -= steps
            both = self.residuals_rows(np.vstack([up, down]))
            cols = (both[:len(theta)] - both[len(theta):]) / (2 * steps)[:, None]
        else:
            cols = (self.residuals_rows(up) - f0) / steps[:, None]
        return np.ascontiguousarray(cols.T)


def _solve(problem: _Problem, theta0: np.ndarray, max_nfev: int | None):
    problem.forget()   # e.g. a GP's kernel set again since the last solve
    theta0 = np.clip(theta0, problem.lower, problem.upper)
    inside = (theta0 > problem.lower) & (theta0 < problem.upper)
    if not np.all(inside):  # least_squares wants a strictly feasible start
        width = np.where(np.isfinite(problem.upper - problem.lower),
                         problem.upper - problem.lower, 1.0)
        theta0 = np.where(inside, theta0, np.clip(theta0, problem.lower + 1e-6 * width,
                                                  problem.upper - 1e-6 * width))
    return least_squares(problem.residuals, theta0, jac=lambda th: problem.jacobian(th),
                         bounds=(problem.lower, problem.upper), x_scale=problem.scales(theta0),
                         method="trf", max_nfev=max_nfev, xtol=1e-10, ftol=1e-10, gtol=1e-10)


def _covariance(jac: np.ndarray, chi2_red: float) -> np.ndarray:
    u, s, vt = np.linalg.svd(jac, full_matrices=False)
    keep = s > s[0] * 1e-12
    inv = (vt[keep].T / s[keep] ** 2) @ vt[keep]
    return inv * chi2_red


def fit_leastsq(systematics: Systematics, astro_model: AstroModel, theta0_astro, *,
                theta0_sys=None, max_nfev: int | None = 200,
                beta_bin_minutes: tuple[float, ...] = (10.0, 30.0),
                max_alternations: int = 5) -> FitResult:
    """Fit astro and systematics parameters jointly by least squares.

    Parameters
    ----------
    systematics : Systematics
        The method, built on the epoch's data.
    astro_model : AstroModel
        The astrophysical model at ``systematics.data.time_bmjd``.
    theta0_astro : array_like
        Starting astrophysical parameters (``astro_model.initial()``).
    theta0_sys : array_like, optional
        Starting method parameters (default ``systematics.initial_params()``).
    max_nfev : int or None
        Cap on the number of least-squares iterations' function evaluations.
    beta_bin_minutes : (float, float)
        Bin widths over which the red-noise factor is averaged.
    max_alternations : int
        For methods that override ``optimise_hyperparameters`` (GP), at most
        this many rounds of "hyperparameters for the fitted astro, then the
        joint fit again", stopping when the depth moves by < 0.1 ppm and the
        eclipse time by < 0.1 s.

    Returns
    -------
    FitResult
    """
    if len(astro_model.time_bmjd) != len(systematics.data.time_bmjd):
        raise ValueError("astro_model must be evaluated at systematics.data.time_bmjd")
    problem = _Problem(systematics, astro_model)
    if theta0_sys is None:
        theta0_sys = systematics.initial_params()
    theta0 = np.concatenate([np.asarray(theta0_astro, dtype=float),
                             np.asarray(theta0_sys, dtype=float)])
    sol = _solve(problem, theta0, max_nfev)
    nfev = sol.nfev
    if has_hyperparameters(systematics):
        # coordinate ascent: hyperparameters for the fitted astro, then the joint fit again
        with progress(total=max_alternations, desc=f"hyperparameters ({systematics.name})",
                      unit="round") as bar:
            for _ in range(max_alternations):
                previous = sol.x
                changed = systematics.optimise_hyperparameters(
                    astro_model(previous[:problem.n_astro]))
                if changed is None:   # the method kept its settings: the fit stands
                    break
                sol = _solve(problem, previous, max_nfev)
                nfev += sol.nfev
                bar.update(1)
                step = np.abs(sol.x[:2] - previous[:2])
                if step[0] < 1e-7 and step[1] < 1e-6:  # 0.1 ppm and 0.09 s
                    break
    if not np.all(np.isfinite(sol.fun)):
        raise InputError(f"method '{systematics.name}': the model is not finite at the "
                         "least-squares solution")
    return _summarise(problem, sol.x, nfev, bool(sol.success), str(sol.message),
                      beta_bin_minutes)


def has_hyperparameters(systematics: Systematics | type[Systematics]) -> bool:
    """Whether the method (an instance or its class) sets parameters by maximum likelihood
    between fits (GP)."""
    cls = systematics if isinstance(systematics, type) else type(systematics)
    return cls.optimise_hyperparameters is not Systematics.optimise_hyperparameters


def has_own_likelihood(systematics: Systematics) -> bool:
    """Whether the method's likelihood models its own white noise (GP's ``s``).

    Such a likelihood is used as it is; any other (also a method's own, such as
    PLD's on bins) has its flux errors rescaled to chi2_red = 1 for the MCMC.
    """
    return bool(systematics.policy.likelihood_models_noise)


def _summarise(problem: _Problem, theta: np.ndarray, nfev: int, success: bool, message: str,
               beta_bin_minutes: tuple[float, ...]) -> FitResult:
    sys = problem.sys
    theta_a, theta_s = problem.split(theta)
    astro = problem.astro(theta_a)
    model = sys.predict(astro, theta_s)
    # the method's own normalised residuals (whitened ones for a GP)
    resid = sys.residuals(astro, theta_s)
    chi2 = float(np.dot(resid, resid))
    n = len(resid)
    k = problem.n_astro + int(sys.n_effective_params())
    dof = n - k
    if dof <= 0:
        raise InputError(f"method '{sys.name}': {k} free parameters for {n} data points")
    chi2_red = chi2 / dof
    jac = problem.jacobian(theta, central=True)
    cov = _covariance(jac, chi2_red)
    errors = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    loglike = sys.log_likelihood(astro, theta_s)
    bic, aic = information_criteria(loglike, k, n)
    rel = sys.data.flux / model - 1.0
    beta = red_noise_beta(rel, sys.data.time_bmjd, bin_minutes=beta_bin_minutes)
    return FitResult(theta=theta, names=joint_names(problem.astro, sys),
                     n_astro=problem.n_astro, cov=cov, errors=errors, chi2=chi2,
                     chi2_red=chi2_red, n_data=n, k=k, log_likelihood=float(loglike),
                     bic=float(bic), aic=float(aic), rms_ppm=float(np.std(rel) * 1e6),
                     beta_red=beta, nfev=int(nfev), success=success, message=message,
                     astro=astro, model=model)


def prayer_bead(systematics: Systematics, astro_model: AstroModel, fit: FitResult, *,
                n_shifts: int | None = 16, stride: int = 1,
                max_nfev: int | None = 50) -> np.ndarray:
    """Refit after cyclic shifts of the residuals (the "prayer bead").

    The residuals ``flux - model`` of ``fit`` are rolled, added back to the best
    model, and each series is refitted from ``fit.theta`` (the method is rebuilt
    on the new fluxes with ``Systematics.with_flux``).

    Parameters
    ----------
    n_shifts : int or None
        That many offsets spread evenly over the series; None cycles through
        every shift in steps of ``stride`` points (Wong et al. 2014; Gillon et
        al. 2009): ``n // stride - 1`` refits.
    stride : int
        Step of the full cycle (points; e.g. the 64 frames of one subarray
        cube, so that the correlated residuals of a cube move together).
    max_nfev : int or None
        Cap on each refit's evaluations (None: refit to convergence).

    Returns
    -------
    ndarray, shape (n_shifts + 1, len(fit.theta))
        The best-fit parameters of the unshifted fit (row 0) and of each shift.
    """
    n = len(systematics.data.flux)
    if n_shifts is None:
        shifts = np.arange(1, n // max(1, int(stride))) * max(1, int(stride))
    elif n_shifts < 1:
        return fit.theta[None, :]
    else:
        shifts = (np.arange(1, n_shifts + 1) * n) // (n_shifts + 1)
    resid = systematics.data.flux - fit.model
    rows = [fit.theta]
    for s in progress(shifts, desc=f"prayer bead ({systematics.name})", unit="shift"):
        shifted = systematics.with_flux(fit.model + np.roll(resid, int(s)))
        problem = _Problem(shifted, astro_model)
        rows.append(_solve(problem, fit.theta, max_nfev).x)
    return np.vstack(rows)
