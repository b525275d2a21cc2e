"""Posterior sampling of the joint model with emcee.

The log-probability is ``Systematics.log_likelihood(astro(theta_a), theta_s,
noise_scale)`` inside the bounds of every parameter (a uniform prior) and
``-inf`` outside. The chain samples only the astrophysical parameters and the
method's own nonlinear ones (``param_names``): the linear pieces (PLD and
polynomial coefficients, BLISS knots, KR/Pmap's and SP(K2)'s ``F0``, the GP's
mean) are solved inside the likelihood for each astrophysical curve
(``docs/fitting.md``, "MCMC", says when that is the marginal posterior). All
walkers of a step are evaluated in one call (emcee's ``vectorize=True``):
:meth:`AstroModel.batch` and :meth:`Systematics.log_likelihood_batch`.

The move is the method's ``preferred_move``:

- ``"stretch"``: emcee's affine-invariant stretch move (Goodman & Weare 2010).
- ``"de"``: differential evolution (ter Braak 2006), the DE-MC of the BLISS
  team (Stevenson et al. 2012); 90 % of proposals with emcee's default
  ``gamma = 2.38 / sqrt(2 d)`` and 10 % with ``gamma = 1`` so that walkers can
  jump between modes, as ter Braak recommends.

Convergence (the emcee documentation's criterion): the chain is run in
blocks; after each block the integrated autocorrelation time tau of every
parameter is estimated (:func:`emcee.autocorr.integrated_time`), the first
``2 max(tau)`` steps are discarded as burn-in, tau is estimated again on the
rest, and sampling stops once the chain after burn-in is longer than
``tau_factor * max(tau)`` (50 by default) or the step cap is reached;
``converged`` says which, and ``n_over_tau`` is that ratio.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache
from typing import NamedTuple

import numpy as np
from threadpoolctl import threadpool_limits

from ..decorrelate.base import Systematics
from ..progress import progress
from .model import AstroModel

__all__ = ["McmcResult", "run_mcmc", "make_moves"]


@dataclass(frozen=True)
class McmcResult:
    """Posterior summary of one MCMC run.

    Attributes
    ----------
    names : tuple of str
        Parameter names (astro then systematics).
    median, std : ndarray
        Posterior median and standard deviation of each parameter.
    p16, p84 : ndarray
        16th and 84th percentiles.
    tau : ndarray
        Integrated autocorrelation time of each parameter (steps), estimated on
        the chain after burn-in.
    n_steps : int
        Steps per walker that were run (burn-in included).
    n_walkers, burn_in : int
        Ensemble size, and the steps discarded as burn-in (``2 max(tau)``).
    converged : bool
        Whether ``(n_steps - burn_in) > tau_factor * max(tau)``.
    acceptance : float
        Mean acceptance fraction.
    move : str
        "stretch" or "de".
    samples : ndarray
        Flat posterior samples after burn-in and thinning.
    n_over_tau : float
        ``(n_steps - burn_in) / max(tau)``: the chain after burn-in in units of
        the largest autocorrelation time.
    """

    names: tuple[str, ...]
    median: np.ndarray
    std: np.ndarray
    p16: np.ndarray
    p84: np.ndarray
    tau: np.ndarray
    n_steps: int
    n_walkers: int
    burn_in: int
    converged: bool
    acceptance: float
    move: str
    samples: np.ndarray = field(repr=False)
    n_over_tau: float = float("nan")

    def error(self, name: str) -> float:
        """Half the 16-84 percentile range of ``name`` (one sigma for a Gaussian)."""
        i = self.names.index(name)
        return float(0.5 * (self.p84[i] - self.p16[i]))


def make_moves(move: str):
    """The emcee moves for ``move`` ("stretch" or "de")."""
    import emcee  # scipy.stats with it, about 1 s: not paid by a least-squares fit

    if move == "stretch":
        return emcee.moves.StretchMove()
    if move == "de":
        return [(emcee.moves.DEMove(), 0.9), (emcee.moves.DEMove(gamma0=1.0), 0.1)]
    raise ValueError(f"unknown MCMC move {move!r} (expected 'stretch' or 'de')")


class _LogProb:
    """The log-posterior of a batch of walkers (emcee's ``vectorize=True``)."""

    def __init__(self, systematics: Systematics, astro_model: AstroModel, lower, upper,
                 noise_scale: float):
        self.sys = systematics
        self.astro = astro_model
        self.n_astro = len(astro_model)
        self.has_sys = len(systematics.param_names) > 0
        self.lower = lower
        self.upper = upper
        self.noise_scale = noise_scale

    def __call__(self, thetas: np.ndarray) -> np.ndarray:
        thetas = np.atleast_2d(thetas)
        out = np.full(len(thetas), -np.inf)
        inside = np.all((thetas >= self.lower) & (thetas <= self.upper), axis=1)
        if np.any(inside):
            th = thetas[inside]
            astro = self.astro.batch(th[:, :self.n_astro])
            theta_s = th[:, self.n_astro:] if self.has_sys else None
            value = self.sys.log_likelihood_batch(astro, theta_s, noise_scale=self.noise_scale)
            if getattr(self.astro, "n_priors", 0):   # Gaussian priors (a transit's q1, q2, ...)
                value = value + self.astro.log_prior_batch(th[:, :self.n_astro])
            out[inside] = np.where(np.isfinite(value), value, -np.inf)
        return out


def run_mcmc(systematics: Systematics, astro_model: AstroModel, theta_start, scale_start, *,
             names: tuple[str, ...], rng: np.random.Generator, n_walkers: int = 16,
             max_steps: int = 2000, block_steps: int = 100, tau_factor: float = 50.0,
             noise_scale: float = 1.0, move: str | None = None,
             cov_start: np.ndarray | None = None) -> McmcResult:
    """Sample the posterior of the joint parameters, starting near a least-squares solution.

    Parameters
    ----------
    systematics, astro_model
        As for :func:`~eclipsebench.fit.leastsq.fit_leastsq`.
    theta_start : ndarray
        Joint parameters to start from (the least-squares solution).
    scale_start : ndarray
        Width per parameter of the initial ball of walkers (e.g. the
        least-squares errors); the walkers start at ``theta_start`` plus 10 %
        of it times a standard normal deviate, folded into the bounds.
    names : tuple of str
        Parameter names.
    rng : numpy.random.Generator
        The stream (``eclipsebench.seeding.rng(seed, "reduce", epoch, method,
        "mcmc")``); it seeds both the initial ball and emcee's own generator.
    n_walkers, max_steps, block_steps, tau_factor
        Ensemble size, step cap, steps between convergence checks, and the
        chain length in units of tau required for convergence.
    noise_scale : float
        Multiplies the flux errors in the likelihood (the fitter passes
        ``sqrt(chi2_red)`` so that the white-noise level matches the residuals).
    move : {"stretch", "de"} or None
        Default ``systematics.policy.preferred_move`` (the method's record).
    cov_start : ndarray, shape (ndim, ndim), optional
        Covariance of the least-squares solution: the initial ball is then
        10 % of it (its correlations included) instead of 10 % of
        ``scale_start`` per parameter; ignored unless positive definite.
        Walkers that start across a narrow correlated ridge (many collinear
        linear parameters) take long to reach it.

    Returns
    -------
    McmcResult

    Examples
    --------
    >>> from eclipsebench.decorrelate import get_method
    >>> from eclipsebench.decorrelate.base import EpochData
    >>> from eclipsebench.fit.model import AstroModel
    >>> class Box:   # a 0.1-day eclipse at t_ecl
    ...     def __init__(self, t):
    ...         self.t = t
    ...     def visible_fraction(self, t_ecl):
    ...         return (np.abs(self.t - t_ecl) > 0.05).astype(float)
    >>> g = np.random.default_rng(1)
    >>> t = np.linspace(0.0, 0.3, 300)
    >>> x = 15.0 + 0.05 * np.sin(40 * t)
    >>> flux = 1e5 * (1 + 0.1 * (x - 15)) * (1 + 0.002 * Box(t).visible_fraction(0.15))
    >>> data = EpochData(time_bmjd=t, flux=flux + 100 * g.standard_normal(300),
    ...                  flux_err=np.full(300, 100.0), x=x, y=np.full(300, 15.0))
    >>> method = get_method("poly2")(data, bin_frames=1)
    >>> astro = AstroModel(t, None, phase="flat", shape=Box(t))
    >>> mc = run_mcmc(method, astro, [0.002, 0.15], [1e-4, 1e-3], names=astro.names,
    ...               rng=np.random.default_rng(2), n_walkers=16, max_steps=2000, move="de")
    >>> mc.converged, mc.n_over_tau > 50, bool(abs(mc.median[0] - 0.002) < 3 * mc.error("depth"))
    (True, True, True)
    """
    theta_start = np.asarray(theta_start, dtype=float)
    ndim = len(theta_start)
    lo_a, hi_a = astro_model.bounds
    lo_s, hi_s = systematics.param_bounds()
    lower = np.concatenate([lo_a, np.asarray(lo_s, dtype=float)])
    upper = np.concatenate([hi_a, np.asarray(hi_s, dtype=float)])
    move = move or systematics.policy.preferred_move
    n_walkers = max(int(n_walkers), 2 * ndim + 2)
    n_walkers += n_walkers % 2
    p0 = _initial_ball(theta_start, scale_start, cov_start, n_walkers, lower, upper, rng)

    log_prob = _LogProb(systematics, astro_model, lower, upper, noise_scale)
    sampler = _sampler_class()(n_walkers, ndim, log_prob, moves=make_moves(move),
                               vectorize=True)
    sampler.random_state = np.random.RandomState(int(rng.integers(2**32))).get_state()
    run = _run_blocks(sampler, p0, f"MCMC ({systematics.name})", max_steps=max_steps,
                      block_steps=block_steps, tau_factor=tau_factor)
    return _summarise(sampler, run, names=names, move=move)


@cache
def _sampler_class():
    """emcee's ``EnsembleSampler`` without a copy of its generator's state at every step.

    After every step emcee stores ``random_state`` (``get_state()`` of its
    Mersenne Twister: 624 words, 39 us, as long as a quarter of a cheap
    method's step) in the chain's ``State``, only to set the generator back to
    it when the next ``run_mcmc`` starts from that ``State``. Between two
    blocks of :func:`_run_blocks` nothing draws from the generator, so it is in
    that state already: the ``State`` carries None instead, which the setter
    skips, and every draw is the same. The setter sets a given state (there is
    no bare ``except`` to swallow an interrupt, as emcee's has).
    """
    import emcee  # scipy.stats with it, about 1 s: not paid by a least-squares fit

    class Sampler(emcee.EnsembleSampler):
        @property
        def random_state(self):
            return None

        @random_state.setter
        def random_state(self, state) -> None:
            if state is not None:
                self._random.set_state(state)

    return Sampler


class _ChainRun(NamedTuple):
    """How far :func:`_run_blocks` ran the chain and what it found."""

    n_steps: int
    tau: np.ndarray
    burn_in: int
    n_over_tau: float
    converged: bool


def _initial_ball(theta_start: np.ndarray, scale_start, cov_start: np.ndarray | None,
                  n_walkers: int, lower: np.ndarray, upper: np.ndarray,
                  rng: np.random.Generator) -> np.ndarray:
    """The walkers' starting points, shape (n_walkers, ndim), folded into the bounds.

    ``theta_start`` plus 10 % of a standard normal deviate times ``scale_start``
    (a non-positive or non-finite scale: ``1e-6 max(1, |theta|)``), or times
    the Cholesky factor of ``cov_start`` when that is positive definite.
    """
    ndim = len(theta_start)
    scale = np.where(np.isfinite(scale_start) & (np.asarray(scale_start) > 0),
                     scale_start, 1e-6 * np.maximum(1.0, np.abs(theta_start)))
    z = rng.standard_normal((n_walkers, ndim))
    chol = _cholesky(cov_start, ndim)
    p0 = theta_start + 0.1 * (z @ chol.T if chol is not None else scale * z)
    return _fold(p0, lower, upper)


def _run_blocks(sampler, p0: np.ndarray, desc: str, *, max_steps: int, block_steps: int,
                tau_factor: float) -> _ChainRun:
    """Run ``sampler`` from ``p0`` in blocks until ``N / tau > tau_factor`` or ``max_steps``.

    After each block of ``block_steps`` steps the autocorrelation time is
    estimated (:func:`_autocorrelation`); ``desc`` labels the progress bar.
    """
    state = p0
    n_steps = 0
    tau, burn_in, n_over_tau = np.full(p0.shape[1], np.inf), 0, 0.0
    converged = False
    # One BLAS thread: the batched likelihoods are small matrix products, which
    # threads slow down on a shared machine and would sum in a thread-dependent order.
    # A bar on a terminal (quiet and off a terminal: none); it may stop early, at convergence.
    bar = progress(total=int(max_steps), desc=desc, unit="step")
    with threadpool_limits(limits=1, user_api="blas"), bar:
        while n_steps < max_steps:
            steps = min(block_steps, max_steps - n_steps)
            state = sampler.run_mcmc(state, steps, progress=False)
            n_steps += steps
            bar.update(steps)
            tau, burn_in, n_over_tau = _autocorrelation(sampler.get_chain())
            bar.set_postfix_str(f"N/tau {n_over_tau:.0f} of {tau_factor:g}", refresh=False)
            if n_over_tau > tau_factor:
                converged = True
                break
    return _ChainRun(n_steps, tau, burn_in, n_over_tau, converged)


def _summarise(sampler, run: _ChainRun, *, names: tuple[str, ...], move: str) -> McmcResult:
    """The :class:`McmcResult` of a finished chain: burn-in dropped, thinned by ``tau / 2``."""
    tau = run.tau
    finite = bool(np.all(np.isfinite(tau)))
    thin = max(1, int(0.5 * np.min(tau))) if finite else 1
    samples = sampler.get_chain(discard=run.burn_in, thin=thin, flat=True)
    p16, p50, p84 = np.percentile(samples, [15.865525393145708, 50.0, 84.13447460685429], axis=0)
    return McmcResult(names=tuple(names), median=p50, std=np.std(samples, axis=0, ddof=1),
                      p16=p16, p84=p84, tau=np.asarray(tau, dtype=float), n_steps=run.n_steps,
                      n_walkers=sampler.nwalkers, burn_in=run.burn_in, converged=run.converged,
                      acceptance=float(np.mean(sampler.acceptance_fraction)), move=move,
                      samples=samples, n_over_tau=float(run.n_over_tau))


def _autocorrelation(chain: np.ndarray) -> tuple[np.ndarray, int, float]:
    """``(tau, burn_in, n_over_tau)`` of a chain of shape (steps, walkers, ndim).

    tau is first estimated on the whole chain; ``burn_in = ceil(2 max(tau))``
    (at most half the chain) is discarded and tau estimated again on the rest;
    ``n_over_tau = (steps - burn_in) / max(tau)``. A tau that cannot be
    estimated gives burn-in of half the chain and ``n_over_tau = 0``.
    """
    import emcee  # scipy.stats with it, about 1 s: not paid by a least-squares fit

    n = chain.shape[0]
    with np.errstate(divide="ignore", invalid="ignore"):   # a parameter that never moved
        tau = emcee.autocorr.integrated_time(chain, tol=0)
    if not np.all(np.isfinite(tau)):
        return tau, n // 2, 0.0
    burn_in = min(int(np.ceil(2.0 * np.max(tau))), n // 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = emcee.autocorr.integrated_time(chain[burn_in:], tol=0)
    if not np.all(np.isfinite(tau)) or np.max(tau) <= 0:
        return tau, burn_in, 0.0
    return tau, burn_in, float((n - burn_in) / np.max(tau))


def _cholesky(cov: np.ndarray | None, ndim: int) -> np.ndarray | None:
    """The lower Cholesky factor of ``cov``, or None if it is absent or not positive definite."""
    if cov is None:
        return None
    cov = np.asarray(cov, dtype=float)
    if cov.shape != (ndim, ndim) or not np.all(np.isfinite(cov)):
        return None
    try:
        return np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        return None


def _fold(p: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Reflect points that left the box back inside it."""
    p = np.where(p < lower, 2 * lower - p, p)
    p = np.where(p > upper, 2 * upper - p, p)
    return np.clip(p, lower, upper)
