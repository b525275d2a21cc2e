"""Wavelet pixel-ICA (Morello et al. 2014 ApJ 786 22; 2015 ApJ 802 117; 2016 ApJ 820 86).

Paper, Appendix B.3: "the source separation operates on wavelet-transformed
individual pixel light curves, after which the resulting components are
transformed back to the time domain ... The sum of an eclipse light curve
model (including a linear phase variation) and scaled versions of the
non-eclipse independent components was then fit to the raw light curve ...
The final error bars were then increased to include the ICA component
separation error."

Steps (``docs/methods.md``, "ICA", says which are the authors' and which ours):

1. Pixel light curves of the stamp (``data.pixels``), divided by the median
   summed stamp flux (one common scale) and centred in time. Not normalised
   frame by frame (PLD's step): that would take the eclipse out of every
   pixel, and B.3 fits "the non-eclipse independent components", so the
   eclipse is one of the separated components.
2. Discrete wavelet transform of each (PyWavelets, ``db4``, periodic
   extension, all levels' coefficients concatenated): :func:`wavelet_coefficients`.
3. FastICA (scikit-learn, logcosh contrast, symmetric) on the coefficient
   matrix: :func:`separate`. Its seed is ``context.stream_ints("fastica", 0)``.
4. Back to the time domain: the DWT is linear and orthogonal, so the inverse
   transform of the separated coefficients is the unmixing matrix applied to
   the pixel series (:func:`time_domain_components`).
5. The eclipse component: an eclipse scales every pixel by the same fraction,
   so it enters component ``j`` with the gain of the unmixing row ``j`` on the
   mean stamp (:func:`common_mode_gains`); the component with the largest
   gain is the eclipse component, and its share of the squared gains is the
   separation's purity (:func:`eclipse_component_by_gain`; ours).
6. All non-eclipse components are kept (B.3: "scaled versions of the
   non-eclipse independent components"); ``selection = "bic"`` (ours) ranks
   them by the raw light-curve variance each explains and keeps as many as
   minimise the BIC (:func:`select_components`).
7. ``predict(astro) = F0 astro + sum_j o_j IC_j`` over the kept components,
   ``F0`` and ``o_j`` by weighted linear least squares for the given ``astro``
   (the shared astrophysical model: eclipse and phase curve).
8. Separation error: the interference-to-signal ratio (ISR) of the
   separation, from the asymptotic formula of symmetric FastICA
   (:func:`fastica_isr`) or, with ``n_restarts >= 2``, from bootstrap
   restarts (:func:`bootstrap_isr`); the contamination it implies in the
   fitted model, ``sigma_ICA^2 = sum_j o_j^2 sum_k ISR_jk``, is propagated to
   the depth (:meth:`IndependentComponents.extra_depth_variance`), plus the
   depth the kept components take because they carry part of the eclipse
   (:func:`eclipse_leak`, ours), in quadrature.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np
import pywt

from ..config.base import check
from ..errors import InputError
from .base import EpochData, MethodOptions, Systematics, register
from .linear import weighted_lstsq
from .record import FitterPolicy, MethodRecord, team_profile

__all__ = ["IndependentComponents", "IcaOptions", "wavelet_coefficients", "separate",
           "time_domain_components", "common_mode_gains", "eclipse_component_by_gain",
           "eclipse_component", "eclipse_component_by_shape",
           "eclipse_box_amplitudes", "eclipse_leak", "select_components",
           "fastica_isr", "bootstrap_isr", "separation_rms"]


def wavelet_coefficients(series: np.ndarray, wavelet: str, level: int) -> np.ndarray:
    """All-level DWT coefficients of each column, concatenated (periodic extension).

    Parameters
    ----------
    series : ndarray, shape (n, p)
        One time series per column.
    wavelet : str
        A PyWavelets discrete wavelet name (e.g. "db4").
    level : int
        Decomposition level.

    Returns
    -------
    ndarray, shape (m, p)
        Coefficients, approximation first, then details from coarse to fine
        (``m = n`` for a length divisible by ``2**level``).

    Examples
    --------
    >>> x = np.random.default_rng(0).normal(size=(64, 2))
    >>> c = wavelet_coefficients(x, "haar", 3)
    >>> bool(np.allclose((c**2).sum(axis=0), (x**2).sum(axis=0)))
    True
    """
    coeffs = pywt.wavedec(np.asarray(series, dtype=float), wavelet, mode="periodization",
                          level=level, axis=0)
    return np.concatenate(coeffs, axis=0)


def separate(coeffs: np.ndarray, n_components: int, seed_int: int, *, max_iter: int,
             tol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
    """Symmetric FastICA (logcosh contrast) on wavelet coefficients.

    Parameters
    ----------
    coeffs : ndarray, shape (m, p)
        Samples in rows, pixels in columns.
    n_components : int
        Components to extract (FastICA's whitening keeps the strongest
        principal directions when fewer than ``p``).
    seed_int : int
        FastICA's ``random_state``.
    max_iter, tol : int, float
        FastICA's iteration limit and tolerance.

    Returns
    -------
    unmixing : ndarray, shape (n_components, p)
        Rows map centred pixel vectors to unit-variance components.
    mixing : ndarray, shape (p, n_components)
        Columns are the pixel signatures of the components.
    sources : ndarray, shape (m, n_components)
        The separated coefficients (unit variance), for the ISR.
    converged : bool
        False when FastICA reached ``max_iter`` (the ConvergenceWarning is
        recorded, not shown).
    """
    # scikit-learn (about 0.7 s to import): loaded when ICA runs, not by every fit that
    # imports the registry of methods.
    from sklearn.decomposition import FastICA
    from sklearn.exceptions import ConvergenceWarning

    ica = FastICA(n_components=n_components, algorithm="parallel", fun="logcosh",
                  whiten="unit-variance", random_state=seed_int, max_iter=max_iter, tol=tol,
                  whiten_solver="svd")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConvergenceWarning)
        sources = ica.fit_transform(coeffs)
    converged = not any(issubclass(w.category, ConvergenceWarning) for w in caught)
    for w in caught:
        if not issubclass(w.category, ConvergenceWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return ica.components_, ica.mixing_, sources, converged


def time_domain_components(centred_pixels: np.ndarray, unmixing: np.ndarray) -> np.ndarray:
    """The components in the time domain, each scaled to unit standard deviation.

    The DWT is linear, so the inverse transform of the separated coefficients
    equals ``unmixing`` applied to the pixel series; the components are
    centred in time (the DWT's approximation coefficients carry the mean).

    Examples
    --------
    >>> pix = np.random.default_rng(1).normal(size=(100, 3))
    >>> ic = time_domain_components(pix - pix.mean(axis=0), np.eye(3)[:2])
    >>> ic.shape, bool(np.allclose(ic.std(axis=0), 1.0))
    ((100, 2), True)
    """
    comps = np.asarray(centred_pixels, dtype=float) @ np.asarray(unmixing, dtype=float).T
    comps = comps - comps.mean(axis=0)
    sd = comps.std(axis=0)
    return comps / np.where(sd > 0, sd, 1.0)


def common_mode_gains(unmixing: np.ndarray, centred_pixels: np.ndarray,
                      mean_stamp: np.ndarray) -> np.ndarray:
    """How much a change of every pixel by the same fraction enters each component.

    An eclipse (or any change of the star's flux) multiplies every pixel by
    ``1 + delta``: in the pixel series it is ``delta`` times the mean stamp.
    Component ``j`` is ``W_j x / sd_j`` (:func:`time_domain_components`), so it
    carries ``g_j delta`` with ``g_j = W_j . mean_stamp / sd_j``: the gain, in
    units of the component's standard deviation per unit fractional change.
    Unlike the mixing column (the pixel signature of the component, which a
    strong pointing signal correlated with the component dominates), the
    gain says what a uniform scaling does to the component.

    Parameters
    ----------
    unmixing : ndarray, shape (K, p)
        Rows of the separation (:func:`separate`).
    centred_pixels : ndarray, shape (n, p)
        The pixel series the components are made from.
    mean_stamp : ndarray, shape (p,)
        The mean of the (uncentred) pixel series on the same scale.

    Returns
    -------
    ndarray, shape (K,)

    Examples
    --------
    >>> t = np.arange(1000)
    >>> ecl = -1e-3 * ((t > 400) & (t < 600))
    >>> point = np.sin(t / 30.0)
    >>> stamp = np.array([1.0, 2.0, 1.0])
    >>> pix = stamp * (1 + ecl)[:, None] + np.outer(point, [0.1, 0.0, -0.1])
    >>> w = np.array([[1.0, 0.0, -1.0], [0.0, 1.0, 0.0]])   # pointing, centre pixel
    >>> g = common_mode_gains(w, pix - pix.mean(axis=0), pix.mean(axis=0))
    >>> np.round(g * 1e-3, 2).tolist()   # component sd per 0.1 % change of every pixel
    [0.0, 2.5]
    """
    w = np.asarray(unmixing, dtype=float)
    comps = np.asarray(centred_pixels, dtype=float) @ w.T
    sd = comps.std(axis=0)
    return (w @ np.asarray(mean_stamp, dtype=float)) / np.where(sd > 0, sd, np.inf)


def eclipse_component_by_gain(gains: np.ndarray) -> tuple[int, float]:
    """The component with the largest common-mode gain, and the separation's purity.

    The purity ``g_k^2 / sum_j g_j^2`` is the share of an eclipse's signal (in
    the components' own units) that lands in the eclipse component: 1 for a
    clean separation; below 1 the rest is in the components the fit keeps
    (:func:`common_mode_gains`; ours).

    Examples
    --------
    >>> k, purity = eclipse_component_by_gain(np.array([0.1, -2.0, 0.2]))
    >>> k, round(purity, 3)
    (1, 0.988)
    """
    g = np.asarray(gains, dtype=float)
    k = int(np.argmax(np.abs(g)))
    total = float(np.sum(g**2))
    return k, float(g[k] ** 2 / total) if total > 0 else 0.0


def eclipse_component(mixing: np.ndarray, mean_stamp: np.ndarray) -> tuple[int, np.ndarray]:
    """The component whose mixing column is most nearly parallel to the mean stamp.

    An eclipse changes every pixel by the same fraction of its mean value, so
    its pixel signature is the mean stamp; a pointing change moves light
    between pixels. Returns the index and the |cosine| of every column.
    Reported, not used to choose: the estimated column of a weak eclipse
    component takes the signature of any strong pointing signal that is
    correlated with it over the epoch (cosine 0.53-0.66 for the right
    component on low-noise simulated epochs; ``docs/methods.md``, ICA), so
    the eclipse component is chosen by :func:`eclipse_component_by_gain`.

    Examples
    --------
    >>> k, cos = eclipse_component(np.array([[1.0, 1.0], [-1.0, 1.0]]), np.array([2.0, 2.0]))
    >>> k, np.round(cos, 3).tolist()
    (1, [0.0, 1.0])
    """
    a = np.asarray(mixing, dtype=float)
    m = np.asarray(mean_stamp, dtype=float)
    den = np.linalg.norm(a, axis=0) * np.linalg.norm(m)
    cos = np.abs(m @ a) / np.where(den > 0, den, 1.0)
    return int(np.argmax(cos)), cos


def eclipse_box_amplitudes(series: np.ndarray, time_bmjd: np.ndarray, t_ecl_bmjd: float,
                           duration_d: float) -> tuple[np.ndarray, np.ndarray]:
    """Amplitude and significance of a box eclipse at ``t_ecl_bmjd`` in each column.

    Each column is fitted with a quadratic in time (the slow phase curve and
    drifts) plus a box of width ``duration_d`` centred on ``t_ecl_bmjd``
    (ordinary least squares). Returns the box coefficients (the column's
    change inside the box, a dip is negative) and their |t| values with a
    white-noise error from the residual scatter.

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 2001)
    >>> s = np.column_stack([np.where(abs(t - 0.5) < 0.1, -1.0, 0.0), np.sin(20 * t)])
    >>> amp, tval = eclipse_box_amplitudes(s, t, 0.5, 0.2)
    >>> np.round(amp, 3).tolist(), bool(tval[0] > 1e3 > tval[1])
    ([-1.0, -0.306], True)
    """
    t = np.asarray(time_bmjd, dtype=float)
    y = np.asarray(series, dtype=float)
    y = y[:, None] if y.ndim == 1 else y
    tn = (t - t.mean()) / max(float(np.ptp(t)), 1e-300)
    box = (np.abs(t - t_ecl_bmjd) < 0.5 * duration_d).astype(float)
    design = np.column_stack([np.ones_like(tn), tn, tn**2, box])
    coef = weighted_lstsq(design, y)
    resid = y - design @ coef
    dof = max(len(t) - design.shape[1], 1)
    cov_box = np.linalg.pinv(design.T @ design)[-1, -1]
    err = np.sqrt((resid**2).sum(axis=0) / dof * cov_box)
    return coef[-1], np.abs(coef[-1]) / np.where(err > 0, err, np.inf)


def eclipse_component_by_shape(components: np.ndarray, time_bmjd: np.ndarray,
                               t_ecl_bmjd: float,
                               durations_d: np.ndarray) -> tuple[int, np.ndarray, float]:
    """The component that looks most like an eclipse at the predicted time.

    Morello et al. identify the transit (here: eclipse) component by its
    shape. The expected shape is a dip centred on the ephemeris-predicted
    eclipse time; its duration is not known to the method (no planet
    parameters reach it), so a box is tried at each of ``durations_d`` and
    each component scored by the largest box |t| value
    (:func:`eclipse_box_amplitudes`) over them. Returns the index, the
    scores and the duration at which the winner scored best.

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 4001)
    >>> g = np.random.default_rng(3)
    >>> ics = g.normal(size=(4001, 3))
    >>> ics[:, 1] -= 0.3 * (abs(t - 0.45) < 0.08)
    >>> k, score, dur = eclipse_component_by_shape(ics, t, 0.45, np.array([0.1, 0.16, 0.3]))
    >>> k, dur
    (1, 0.16)
    """
    scores = np.zeros((len(durations_d), np.shape(components)[1]))
    for i, dur in enumerate(durations_d):
        scores[i] = eclipse_box_amplitudes(components, time_bmjd, t_ecl_bmjd, float(dur))[1]
    best = scores.max(axis=0)
    k = int(np.argmax(best))
    return k, best, float(durations_d[int(np.argmax(scores[:, k]))])


def eclipse_leak(systematics: np.ndarray, eclipse_per_depth: np.ndarray,
                 time_bmjd: np.ndarray) -> float:
    """The depth the kept components absorb: their fitted sum's eclipse-shaped part.

    ``systematics`` is ``sum_j o_j IC_j`` over the kept components (flux
    units), ``eclipse_per_depth`` the flux change per unit depth of the fitted
    eclipse (``F0 dastro/ddepth``). The sum is fitted with a quadratic in time
    plus that shape (ordinary least squares); the coefficient, a fraction of
    depth, is what the fitted depth loses to eclipse signal left in the
    components by an imperfect separation (ours: a truth-free measure of the
    separation error of the depth, which the ISR of a linear-mixture model
    does not see).

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 1001)
    >>> shape = -1e5 * (abs(t - 0.5) < 0.1)
    >>> round(eclipse_leak(3e-4 * shape + np.sin(9 * t), shape, t), 6)
    0.00031
    """
    t = np.asarray(time_bmjd, dtype=float)
    tn = (t - t.mean()) / max(float(np.ptp(t)), 1e-300)
    design = np.column_stack([np.ones_like(tn), tn, tn**2,
                              np.asarray(eclipse_per_depth, dtype=float)])
    coef = weighted_lstsq(design, np.asarray(systematics, dtype=float))
    return float(coef[-1])


def _box_durations(time_bmjd: np.ndarray, t_ecl_bmjd: float | None) -> np.ndarray:
    """Trial eclipse durations: 5% to 50% of the time span, boxes inside the data (ours)."""
    if t_ecl_bmjd is None or not np.isfinite(t_ecl_bmjd):
        return np.zeros(0)
    t0, t1 = float(np.min(time_bmjd)), float(np.max(time_bmjd))
    room = 2.0 * min(t_ecl_bmjd - t0, t1 - t_ecl_bmjd)
    trial = np.linspace(0.05, 0.5, 10) * (t1 - t0)
    return trial[trial <= room]


def _weighted_chi2(design: np.ndarray, y: np.ndarray, w: np.ndarray) -> float:
    coef = weighted_lstsq(design, y, w)
    r = (y - design @ coef) * w
    return float(r @ r)


def select_components(flux: np.ndarray, flux_err: np.ndarray, components: np.ndarray,
                      k_eclipse: int) -> dict[str, Any]:
    """Rank the non-eclipse components and keep those the raw light curve needs (BIC).

    The raw light curve is fitted with a constant, the eclipse component (the
    stand-in for the astrophysical signal, which is not known before the fit)
    and the non-eclipse components. These are mutually uncorrelated and of
    unit variance, so the raw light-curve variance each explains is its
    squared covariance with the flux: they are ranked by it, and the first
    ``n`` are kept, ``n`` minimising ``BIC = chi2 + k ln N`` over
    ``n = 0 ... n_max`` (chi2 weighted by ``flux_err``).

    Returns
    -------
    dict
        ``order`` (non-eclipse indices, best first), ``explained`` (fraction of
        the flux variance of each, in that order), ``bic`` (for ``n = 0 ...``),
        ``selected`` (the indices kept, in rank order).

    Examples
    --------
    >>> g = np.random.default_rng(0)
    >>> ics = g.normal(size=(2000, 3))
    >>> flux = 1e5 + 50 * ics[:, 2] + g.normal(0, 10, 2000)
    >>> select_components(flux, np.full(2000, 10.0), ics, 0)["selected"]
    [2]
    """
    y = np.asarray(flux, dtype=float)
    w = 1.0 / np.asarray(flux_err, dtype=float)
    ics = np.asarray(components, dtype=float)
    others = [j for j in range(ics.shape[1]) if j != k_eclipse]
    yc = y - y.mean()
    cov = np.array([ics[:, j] @ yc / len(y) for j in others])
    rank = np.argsort(-cov**2, kind="stable")
    order = [others[i] for i in rank]
    explained = (cov[rank] ** 2 / max(float(yc @ yc) / len(y), 1e-300)).tolist()
    base = np.column_stack([np.ones(len(y)), ics[:, k_eclipse]])
    n_log = np.log(len(y))
    bic = []
    for n in range(len(order) + 1):
        design = np.column_stack([base, ics[:, order[:n]]])
        bic.append(_weighted_chi2(design, y, w) + design.shape[1] * n_log)
    n_best = int(np.argmin(bic))
    return {"order": order, "explained": explained, "bic": bic, "selected": order[:n_best]}


def fastica_isr(sources: np.ndarray) -> np.ndarray:
    """Asymptotic interference-to-signal ratio of symmetric FastICA (logcosh).

    Tichavsky, Koldovsky & Oja (2006, IEEE Trans. Signal Process. 54, 1189),
    symmetric FastICA with the nonlinearity ``g = tanh``::

        ISR_kl = (gamma_k + gamma_l + tau_l^2) / (N (tau_k + tau_l)^2),  k != l

    with, for each unit-variance source, ``mu = E[s g(s)]``, ``rho = E[g'(s)]``,
    ``beta = E[g(s)^2]``, ``gamma = beta - mu^2``, ``tau = |mu - rho|``, the
    expectations estimated from the separated samples. ``ISR_kl`` is the
    expected power of source ``l`` left in the estimate of source ``k``,
    relative to that of source ``k``. The diagonal is 0.

    Parameters
    ----------
    sources : ndarray, shape (N, K)
        The separated samples (here: wavelet coefficients), unit variance.

    Returns
    -------
    ndarray, shape (K, K)

    Examples
    --------
    >>> s = np.random.default_rng(0).laplace(size=(20000, 2)) / np.sqrt(2)
    >>> isr = fastica_isr(s)
    >>> bool(0 < isr[0, 1] < 1e-3 and isr[0, 0] == 0)
    True
    """
    s = np.asarray(sources, dtype=float)
    n = s.shape[0]
    s = (s - s.mean(axis=0)) / s.std(axis=0)
    g = np.tanh(s)
    mu = np.mean(s * g, axis=0)
    rho = np.mean(1.0 - g**2, axis=0)
    gamma = np.mean(g**2, axis=0) - mu**2
    tau = np.abs(mu - rho)
    den = n * (tau[:, None] + tau[None, :]) ** 2
    isr = (gamma[:, None] + gamma[None, :] + tau[None, :] ** 2) / np.where(den > 0, den, np.inf)
    np.fill_diagonal(isr, 0.0)
    return isr


def bootstrap_isr(unmixings: list[np.ndarray], mixing: np.ndarray) -> np.ndarray:
    """Empirical ISR from repeated separations against a reference mixing matrix.

    For each restart ``r`` the gain ``G = W_r A`` (``A`` the reference
    mixing) is a permuted, scaled identity plus interference; rows are matched
    to the reference components by their largest |gain| and
    ``ISR_kl = mean_r (G_kl / G_kk)^2`` (the definition of Tichavsky et al.).

    Examples
    --------
    >>> a = np.eye(2)
    >>> w = [np.array([[0.0, 1.0], [1.0, 0.1]]), np.array([[1.0, 0.0], [0.1, 1.0]])]
    >>> np.round(bootstrap_isr(w, a), 4).tolist()
    [[0.0, 0.005], [0.005, 0.0]]
    """
    a = np.asarray(mixing, dtype=float)
    k = a.shape[1]
    acc = np.zeros((k, k))
    for w in unmixings:
        gain = np.asarray(w, dtype=float) @ a
        row_of = np.full(k, -1)
        used: set[int] = set()
        for comp in np.argsort(-np.max(np.abs(gain), axis=0)):
            for row in np.argsort(-np.abs(gain[:, comp])):
                if row not in used:
                    row_of[comp] = row
                    used.add(row)
                    break
        g = gain[row_of]
        acc += (g / np.diag(g)[:, None]) ** 2
    isr = acc / max(len(unmixings), 1)
    np.fill_diagonal(isr, 0.0)
    return isr


def separation_rms(coefficients: np.ndarray, isr: np.ndarray) -> float:
    """``sigma_ICA = sqrt(sum_j o_j^2 sum_k ISR_jk)`` for unit-variance components.

    ``coefficients`` are the fitted weights ``o_j`` of the components in the
    model (flux units per unit-variance component); ``isr`` is the ISR matrix
    restricted to their rows. Morello et al. (2014, 2015): the error on the
    model of the raw light curve that the imperfect separation implies.

    Examples
    --------
    >>> float(separation_rms(np.array([3.0]), np.array([[0.0, 0.01, 0.03]])))
    0.6
    """
    o = np.asarray(coefficients, dtype=float)
    return float(np.sqrt(np.sum(o**2 * np.asarray(isr, dtype=float).sum(axis=1))))


@dataclass(frozen=True)
class IcaOptions(MethodOptions):
    """Options of ``ica`` (:class:`IndependentComponents`)."""

    n_components: int = 0
    wavelet: str = "db4"
    level: int = 0
    combine: Literal["additive", "multiplicative"] = "additive"
    selection: Literal["all", "bic"] = "all"
    n_restarts: int = 0
    max_iter: int = 2000
    tol: float = 1e-5

    def validate(self) -> None:
        check(self.n_components == 0 or self.n_components >= 2, "n_components",
              "0 (one per pixel, at most 9) or at least 2")
        check(self.wavelet in pywt.wavelist(kind="discrete"), "wavelet",
              "a PyWavelets discrete wavelet (e.g. 'db4', 'sym8', 'haar')")
        check(self.level >= 0, "level", "0 (the largest allowed, at most 8) or a level >= 1")
        check(0 <= self.n_restarts <= 1000 and self.n_restarts != 1, "n_restarts",
              "0 (asymptotic ISR) or 2-1000 bootstrap restarts")
        check(self.max_iter >= 1, "max_iter", "at least 1 iteration")
        check(self.tol > 0, "tol", "a positive tolerance")


@register
class IndependentComponents(Systematics[IcaOptions]):
    """Wavelet pixel-ICA systematics (Morello et al. 2014, 2015, 2016).

    Options (:class:`IcaOptions`)
    -----------------------------
    n_components : int
        Independent components to extract (0: one per pixel, at most 9;
        FastICA's whitening keeps the strongest principal directions).
    wavelet : str
        PyWavelets discrete wavelet ("db4").
    level : int
        DWT level (0: the largest PyWavelets allows, at most 8).
    combine : {"additive", "multiplicative"}
        ``F0 astro + sum o_j IC_j`` (Morello et al.) or ``astro (F0 + sum o_j IC_j)``.
    selection : {"all", "bic"}
        Non-eclipse components kept: all of them ("all", paper App. B.3), or
        (ours) ranked by the raw light-curve variance they explain and as
        many as minimise the BIC ("bic").
    n_restarts : int
        0: the separation's ISR from the asymptotic formula of FastICA; 2 or
        more: from that many bootstrap FastICA restarts.
    max_iter, tol : int, float
        FastICA iteration limit and tolerance.

    Examples
    --------
    >>> from eclipsebench.decorrelate import get_method
    >>> get_method("ica").Options().selection
    'all'
    """

    name: ClassVar[str] = "ica"
    requires: ClassVar[tuple[str, ...]] = ("pixels",)
    record: ClassVar[MethodRecord] = MethodRecord(
        label="ICA", paper=team_profile("ica"), in_paper=True,
        policy=FitterPolicy(stochastic=True))

    def setup(self, data: EpochData) -> None:
        opts = self.options
        pix = np.asarray(data.pixels, dtype=float).reshape(len(data), -1)
        n, p = pix.shape
        if p < 3:
            raise InputError(f"ica: the pixel stamps have {p} pixels; expected a 3x3 or 5x5 stamp")
        n_comp = min(p, 9) if opts.n_components == 0 else int(opts.n_components)
        if not 2 <= n_comp <= p:
            raise InputError(f"method 'ica' option 'n_components': expected 2-{p}, "
                             f"got {opts.n_components!r}")
        scale = np.median(pix.sum(axis=1))
        if not scale > 0:
            raise InputError("ica: the summed pixel stamps need a positive median flux")
        max_level = pywt.dwt_max_level(n, pywt.Wavelet(opts.wavelet).dec_len)
        lev = min(8, max_level) if opts.level == 0 else int(opts.level)
        if not 1 <= lev <= max(max_level, 1):
            raise InputError(f"method 'ica' option 'level': expected 1-{max_level} for {n} "
                             f"frames, got {opts.level!r}")
        norm = pix / scale
        centred = norm - norm.mean(axis=0)
        coeffs = wavelet_coefficients(centred, opts.wavelet, lev)
        seed = self.context.stream_ints("fastica", 0)[0]
        unmix, mixing, sources, conv = separate(coeffs, n_comp, seed, max_iter=opts.max_iter,
                                                tol=opts.tol)
        self.unmixing, self.mixing = unmix, mixing
        #: All independent components in the time domain, unit variance, (n, K).
        self.all_components = time_domain_components(centred, unmix)
        # The eclipse scales every pixel alike: the component it enters most is the
        # eclipse component (ours; docs/methods.md, ICA, step 5).
        self.common_mode_gain = common_mode_gains(unmix, centred, norm.mean(axis=0))
        self.eclipse_index, purity = eclipse_component_by_gain(self.common_mode_gain)
        rule = "common_mode_gain"
        # Reported, not used: the mixing-column cosine picked a pointing component on
        # low-noise simulated epochs, and the box score at the predicted time a pointing
        # component on the real epoch 1 (red noise fools box |t| values).
        k_stamp, cosines = eclipse_component(mixing, norm.mean(axis=0))
        t_pred = data.meta.get("t_ecl_predicted_bmjd")
        durations = _box_durations(data.time_bmjd, t_pred)
        shape_index, shape_score, box_d = (eclipse_component_by_shape(
            self.all_components, data.time_bmjd, float(t_pred), durations)
            if durations.size and t_pred is not None else (None, None, None))

        if opts.n_restarts >= 2:
            g = self.context.stream("bootstrap")
            unmixings, n_conv = [], 0
            for r in range(1, opts.n_restarts + 1):
                rows = g.integers(0, len(coeffs), len(coeffs))
                sr = self.context.stream_ints("fastica", r)[0]
                u_r, _, _, c_r = separate(coeffs[rows], n_comp, sr, max_iter=opts.max_iter,
                                          tol=opts.tol)
                unmixings.append(u_r)
                n_conv += c_r
            self.isr = bootstrap_isr(unmixings, mixing)
            isr_kind = "bootstrap"
        else:
            self.isr = fastica_isr(sources)
            isr_kind = "asymptotic"
            n_conv = None

        self._diagnostics: dict[str, Any] = {
            "wavelet": opts.wavelet, "level": lev, "n_components": n_comp,
            "converged": conv, "eclipse_index": self.eclipse_index, "eclipse_rule": rule,
            "eclipse_purity": purity,
            "common_mode_gain": [float(v) for v in self.common_mode_gain],
            "eclipse_cosine": float(cosines[self.eclipse_index]),
            "mean_stamp_index": k_stamp, "mean_stamp_cosine": float(cosines[k_stamp]),
            "isr_method": isr_kind, "isr_max": float(self.isr.max()),
        }
        if n_conv is not None:
            self._diagnostics["restarts_converged"] = int(n_conv)
        if shape_score is not None:
            self._box_duration_d = box_d
            self._diagnostics.update({
                "shape_index": shape_index,
                "eclipse_shape_score": [float(v) for v in shape_score],
                "eclipse_box_duration_d": box_d})
        self._sw = 1.0 / np.asarray(data.flux_err, dtype=float)
        self._select()

    # ------------------------------------------------------------------ flux-dependent part
    def _select(self) -> None:
        """Rank and select the components for the current fluxes; prepare the projection."""
        if self.options.selection == "all":
            kept = [j for j in range(self.all_components.shape[1]) if j != self.eclipse_index]
            ranking: dict[str, Any] = {"order": kept}
        else:
            ranking = select_components(self.data.flux, self.data.flux_err,
                                        self.all_components, self.eclipse_index)
            kept = ranking["selected"]
        self.selected = list(kept)
        #: The regressors of the fit: the selected non-eclipse components, (n, k).
        self.components = self.all_components[:, self.selected]
        self._diagnostics.update({
            "selected": [int(j) for j in self.selected], "n_selected": len(self.selected),
            "rank_order": [int(j) for j in ranking["order"]]})
        if "explained" in ranking:
            self._diagnostics["explained_fraction"] = [float(v) for v in ranking["explained"]]
            self._diagnostics["selection_bic"] = [float(v) for v in ranking["bic"]]
        self._diagnostics.pop("depth_err_separation_ppm", None)
        q, _ = np.linalg.qr(self.components * self._sw[:, None]) if self.selected else \
            (np.zeros((len(self._sw), 0)), None)
        self._q = q
        fw = np.asarray(self.data.flux, dtype=float) * self._sw
        self._fw_perp = fw - q @ (q.T @ fw)

    def diagnostics(self) -> dict[str, Any]:
        """The decomposition, every component's common-mode gain and the eclipse
        component's purity, its mixing column's |cosine| with the mean stamp (and
        the largest cosine's component), the selection, the ISR and, once
        :meth:`extra_depth_variance` has run, ``depth_err_separation_ppm``."""
        return dict(self._diagnostics)

    def _design(self, astro: np.ndarray) -> np.ndarray:
        a = np.asarray(astro, dtype=float)
        if self.options.combine == "additive":
            return np.column_stack([a, self.components])
        return np.column_stack([a, a[:, None] * self.components])

    def _solve(self, astro: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Weighted least-squares ``(F0, o_1, ...)`` and the model, for ``astro``."""
        design = self._design(astro)
        coef = weighted_lstsq(design, self.data.flux, self._sw)
        return coef, design @ coef

    def predict(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """``F0 astro + sum_j o_j IC_j`` (or ``astro (F0 + ...)``), solved linearly."""
        a = np.asarray(astro, dtype=float)
        if self.options.combine != "additive":
            return self._solve(a)[1]
        aw = a * self._sw
        a_perp = aw - self._q @ (self._q.T @ aw)
        f0 = a_perp.dot(self._fw_perp) / a_perp.dot(a_perp)
        fit_w = f0 * aw + self._q @ (self._q.T @ (self.data.flux * self._sw - f0 * aw))
        return fit_w / self._sw

    def log_likelihood_batch(self, astro: np.ndarray, theta: np.ndarray | None = None,
                             noise_scale: float = 1.0) -> np.ndarray:
        """:meth:`log_likelihood` of every row of ``astro`` (the MCMC's call).

        Additive mode: with ``Q`` the orthonormal basis of the weighted
        components and ``P = I - Q Q^T``, the weighted residual of ``F0`` solved
        for each curve is ``P f_w - F0 P a_w``, so ``chi2 = |P f_w|^2 -
        (P a_w . P f_w)^2 / |P a_w|^2``: one matrix product for all rows. The
        multiplicative mode loops over :meth:`log_likelihood`.
        """
        if self.options.combine != "additive":
            return super().log_likelihood_batch(astro, theta, noise_scale)
        a = np.atleast_2d(np.asarray(astro, dtype=float))
        aw = a * self._sw[None, :]
        a_perp = aw - (aw @ self._q) @ self._q.T
        proj = a_perp @ self._fw_perp
        chi2 = self._fw_perp.dot(self._fw_perp) - proj**2 / np.einsum("ij,ij->i", a_perp, a_perp)
        sigma = self.data.flux_err * noise_scale
        return (-0.5 * chi2 / noise_scale**2 - np.sum(np.log(sigma))
                - 0.5 * len(sigma) * np.log(2 * np.pi))

    def with_flux(self, flux: np.ndarray) -> IndependentComponents:
        """The method on ``flux`` (prayer bead): equal to a fresh build.

        The separation depends on the pixel stamps only, which the prayer bead
        does not shift, and its seed is the same, so FastICA is not rerun;
        the ranking, selection and projection are redone for the new fluxes.
        """
        new = self._copy_with_flux(flux)
        new._diagnostics = dict(self._diagnostics)
        new._select()
        return new

    def extra_depth_variance(self, astro: np.ndarray, dastro_ddepth: np.ndarray) -> float:
        """The depth variance from the component-separation error (fraction squared).

        The fitted weights ``o_j`` of the selected components and the ISR give
        the model error ``sigma_ICA`` (:func:`separation_rms`, Morello et al.).
        As a per-frame error it adds to the depth the variance
        ``sigma_ICA^2 [(D^T D)^-1]_depth`` of the linearised fit, ``D`` the
        columns ``F0 dastro/ddepth``, ``astro`` (``F0``) and the components.
        The value is also written to ``diagnostics()["depth_err_separation_ppm"]``.

        Parameters
        ----------
        astro : ndarray, shape (n,)
            The best-fitting astrophysical curve.
        dastro_ddepth : ndarray, shape (n,)
            Its derivative with respect to the depth (per unit depth, as a fraction).
        """
        coef, _ = self._solve(astro)
        f0, weights = coef[0], coef[1:]
        if not self.selected:
            sigma = 0.0
        else:
            sigma = separation_rms(weights, self.isr[self.selected])
        design = self._design(astro)
        da = np.asarray(dastro_ddepth, dtype=float) * f0
        if self.options.combine != "additive":
            da = da * (1.0 + self.components @ weights / f0) if self.selected else da
        full = np.column_stack([da, design])
        cov = np.linalg.pinv(full.T @ full)
        var = float(sigma**2 * cov[0, 0])
        leak = eclipse_leak(self.components @ weights if self.selected else
                            np.zeros(len(da)), da, self.data.time_bmjd)
        self._diagnostics["separation_rms_ppm"] = float(sigma / f0 * 1e6)
        self._diagnostics["depth_err_isr_ppm"] = float(np.sqrt(max(var, 0.0)) * 1e6)
        self._diagnostics["eclipse_leak_ppm"] = float(leak * 1e6)
        var += leak**2
        self._diagnostics["depth_err_separation_ppm"] = float(np.sqrt(max(var, 0.0)) * 1e6)
        return var

    def n_effective_params(self) -> int:
        """``F0`` and one weight per selected component."""
        return 1 + len(self.selected)
