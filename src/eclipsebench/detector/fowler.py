"""Fowler sampling of the IRAC detectors (paper Appendix A.3) and unit conversions.

Pure kernels on arrays. Conventions
-----------------------------------
A frame is ``n_max = 2 FN + WT`` sample intervals ("ticks") of ``dt``. The
input of the kernels is the *mean* charge (electrons) collected in each tick,
``q[k]`` for ``k = 1 .. n_max`` (array index ``k - 1``), with any pixel shape
after the first axis. Pedestal read ``P_i`` is the accumulated charge after
tick ``i``; signal read ``S_i`` after tick ``FN + WT + i``; the frame value is
``e = sum_i (S_i - P_i) / FN`` (paper Eq. for e(i_p, j_p)).

Physical model (default)
    Photon noise as independent Poisson increments per tick, cumulated; a
    Gaussian read noise on each read. Because
    ``sum_i (S_i - P_i) = sum_k w_k q_k`` with the Fowler weight
    ``w_k = clip(min(k - 1, FN, n_max + 1 - k), 0)``
    (0 for the first tick, ramps 1..FN-1 up and down, FN over the WT + 1 ticks
    between), ticks of equal weight can be summed before the Poisson draw,
    so :func:`fowler_sample` draws FN Poisson variates per pixel ("grouped"
    form, :func:`group_charges`) instead of ``n_max``; it is exact in
    distribution. Its variance is
    ``sum_k w_k^2 q_k / FN^2 + 2 sigma_rn^2 / FN``.

``iracsim2015`` model
    What IRACSIM (prf_make_dce.pro, 2014-08-18 change) did: at each *read* a
    Poisson deviate of the *noisy* cumulative charge minus its mean is added
    to the cumulative charge, so the noise of earlier reads compounds. (Its
    inclusive sub-sample loop, read from the code as about 10% more signal,
    does not show in the public 2015 cube, whose level was set by a flux
    density: the mean charge is the true one; docs/simulate.md.) Its variance is about
    ``(FN+1)(2FN+1)/(6 FN)`` = 3.19 times the signal for FN = 8 to leading
    order (3.31 exactly for WT = 184). Read noise 16.8 e per read. Both
    scaled by IRACSIM's ``NOISE_FACTOR`` (0.907 for the public 2015 cube's
    pixels; ``detector.constants.NOISE_FACTOR_IRACSIM2015``).
"""

from __future__ import annotations

import numpy as np

from eclipsebench.errors import InputError

from .constants import READ_NOISE_E, SHOT_NOISE_FORMS, SUB_2S, ReadoutMode

__all__ = ["SHOT_NOISE_FORMS", "fowler_variance", "NOISE_MODELS", "fowler_weights", "group_charges", "read_charges",
           "fowler_sample", "fowler_sample_ticks",
           "fowler_sample_grouped", "fowler_sample_iracsim2015", "fowler_variance_exact",
           "electrons_to_dn", "dn_to_electrons", "electrons_to_mjysr", "mjysr_to_electrons",
           "bunc_mjysr"]

NOISE_MODELS = ("physical", "iracsim2015")


def _check_readout(fowler: int, wait: int) -> None:
    if int(fowler) != fowler or fowler < 1:
        raise ValueError(f"fowler: expected an integer >= 1, got {fowler}")
    if int(wait) != wait or wait < 0:
        raise ValueError(f"wait: expected an integer >= 0, got {wait}")


def fowler_variance(flux_e, *, fowler: int = SUB_2S.fowler, wait: int = SUB_2S.wait, read_noise_e: float = READ_NOISE_E,
                    n_pixels: float | np.ndarray = 1.0, shot_noise: str = "paper"):
    """Variance of Fowler-sampled electron counts (Garnett & Forrest 1993).

    ``shot_noise="paper"`` implements the paper's Eq. ``gar_for_var``::

        sigma_e^2 = sigma_int^2 [2 sigma_rn^2 / (sigma_int^2 FN)
                                 + 1 - 2 FN / (3 n_max) + 1 / (6 FN n_max)]

    with ``n_max = 2 FN + WT`` and ``sigma_int^2 = F (t_int / t_exp)``,
    ``t_int / t_exp = n_max / (FN + WT)`` (the sample time cancels).

    ``shot_noise="poisson"`` replaces the bracket's shot terms by the exact
    variance of the Fowler difference of a Poisson process read
    instantaneously every sample, ``1 - 4 FN / (3 n_max) + 1 / (3 FN n_max)``,
    i.e. ``q [FN + WT - (FN^2 - 1) / (3 FN)]`` for ``q`` electrons per
    sample. The printed equation exceeds the mean signal ``q (FN + WT)``,
    which no Poisson process can (for FN = 1, WT = 0 it gives 1.5 q where a
    correlated double sample has variance q); it is 2.7% above the exact value
    for FN = 8, WT = 184 (README, "Where the paper is inconsistent").

    Parameters
    ----------
    flux_e : float or array
        Electrons accumulated per exposure time (the BCD value times
        GAIN x EXPTIME / FLUXCONV, summed over the aperture).
    fowler, wait : int
        Fowler number FN (>= 1) and wait ticks WT (>= 0).
    read_noise_e : float
        Read noise per read, electrons (9.4 e for warm channel 2).
    n_pixels : float
        Pixels whose read noise adds (1 reproduces the paper's use of the
        equation on an aperture sum; the aperture area adds per-pixel noise).
    shot_noise : {"paper", "poisson"}
        The printed equation (default) or the exact Poisson-increment form.

    Returns
    -------
    float or array
        Variance in electrons squared.
    """
    _check_readout(fowler, wait)
    if shot_noise not in SHOT_NOISE_FORMS:
        raise ValueError(f"shot_noise: expected one of {', '.join(SHOT_NOISE_FORMS)}, "
                         f"got {shot_noise!r}")
    flux_e = np.asarray(flux_e, dtype=float)
    n_max = 2 * fowler + wait
    sigma_int2 = flux_e * n_max / (fowler + wait)
    if shot_noise == "paper":  # Eq. gar_for_var
        shot_factor = 1.0 - 2.0 * fowler / (3.0 * n_max) + 1.0 / (6.0 * fowler * n_max)
    else:
        shot_factor = 1.0 - 4.0 * fowler / (3.0 * n_max) + 1.0 / (3.0 * fowler * n_max)
    read_term = 2.0 * n_pixels * read_noise_e**2 / fowler
    result = read_term + sigma_int2 * shot_factor
    return float(result) if result.ndim == 0 else result


def _check_model(noise_model: str) -> None:
    if noise_model not in NOISE_MODELS:
        raise InputError(f"noise_model: expected one of {NOISE_MODELS}, got {noise_model!r}")


def fowler_weights(mode: ReadoutMode) -> np.ndarray:
    """Fowler weight ``w_k`` of the charge collected in tick ``k = 1 .. n_max``.

    ``sum_i (S_i - P_i) = sum_k w_k q_k``; ``w_k = max(0, min(k - 1, FN, n_max + 1 - k))``.

    Returns
    -------
    ndarray of int, shape (n_max,)
    """
    k = np.arange(1, mode.n_max + 1)
    return np.clip(np.minimum(np.minimum(k - 1, mode.fowler), mode.n_max + 1 - k), 0, None)


def _ticks(q_ticks, mode: ReadoutMode) -> np.ndarray:
    q = np.asarray(q_ticks, dtype=float)
    if q.ndim == 0 or q.shape[0] != mode.n_max:
        raise InputError(f"mean charge per tick: expected first axis of length n_max = "
                         f"{mode.n_max}, got shape {q.shape}")
    return q


def group_charges(q_ticks, mode: ReadoutMode) -> np.ndarray:
    """Sum the mean tick charges of equal Fowler weight.

    Parameters
    ----------
    q_ticks : array, shape (n_max, ...)
        Mean charge (e) collected in each tick.
    mode : ReadoutMode

    Returns
    -------
    ndarray, shape (FN, ...)
        Row ``j - 1`` is the total mean charge of the ticks with weight ``j``
        (``j = 1 .. FN``); the first tick (weight 0) does not enter the frame.
    """
    q = _ticks(q_ticks, mode)
    w = fowler_weights(mode)
    out = np.zeros((mode.fowler,) + q.shape[1:])
    for j in range(1, mode.fowler + 1):
        out[j - 1] = q[w == j].sum(axis=0)
    return out


def read_charges(q_ticks, mode: ReadoutMode) -> np.ndarray:
    """Mean cumulative charge at each of the 2 FN reads (pedestals first).

    Returns
    -------
    ndarray, shape (2 FN, ...)
        Rows ``0 .. FN-1``: ``P_1 .. P_FN``; rows ``FN .. 2FN-1``: ``S_1 .. S_FN``.
    """
    q = _ticks(q_ticks, mode)
    cum = np.cumsum(q, axis=0)
    fn, wt = mode.fowler, mode.wait
    idx = np.concatenate([np.arange(fn), fn + wt + np.arange(fn)])
    return cum[idx]


def fowler_sample_ticks(q_ticks, mode: ReadoutMode, rng: np.random.Generator,
                        read_noise_e: float) -> np.ndarray:
    """Physical Fowler sampling, literally: one Poisson increment per tick.

    The reference implementation of the physical model (``n_max`` Poisson
    draws per pixel); :func:`fowler_sample_grouped` gives the same
    distribution with FN draws.
    """
    q = _ticks(q_ticks, mode)
    cum = np.cumsum(rng.poisson(q).astype(float), axis=0)
    fn, wt = mode.fowler, mode.wait
    ped = cum[:fn] + rng.normal(0.0, read_noise_e, size=(fn,) + q.shape[1:])
    sig = cum[fn + wt:] + rng.normal(0.0, read_noise_e, size=(fn,) + q.shape[1:])
    return (sig - ped).sum(axis=0) / fn


def fowler_sample_grouped(groups, mode: ReadoutMode, rng: np.random.Generator,
                          read_noise_e: float) -> np.ndarray:
    """Physical Fowler sampling from grouped charges (:func:`group_charges`).

    ``e = [sum_j j Poisson(G_j) + Normal(0, sqrt(2 FN) sigma_rn)] / FN``: the
    2 FN independent read noises of ``sum_i (S_i - P_i)`` sum to one Gaussian.
    """
    g = np.asarray(groups, dtype=float)
    if g.ndim == 0 or g.shape[0] != mode.fowler:
        raise InputError(f"grouped charges: expected first axis of length FN = {mode.fowler}, "
                         f"got shape {g.shape}")
    if np.any(g < 0) or not np.all(np.isfinite(g)):
        raise InputError("grouped charges: expected finite non-negative electrons")
    weights = np.arange(1, mode.fowler + 1, dtype=float).reshape((-1,) + (1,) * (g.ndim - 1))
    total = (weights * rng.poisson(g)).sum(axis=0)
    total = total + rng.normal(0.0, read_noise_e * np.sqrt(2.0 * mode.fowler), size=total.shape)
    return total / mode.fowler


def fowler_sample_iracsim2015(reads, mode: ReadoutMode, rng: np.random.Generator,
                              read_noise_e: float, *, noise_factor: float = 1.0) -> np.ndarray:
    """IRACSIM's compounding noise model from the mean cumulative charge at each read.

    Parameters
    ----------
    reads : array, shape (2 FN, ...)
        Mean cumulative charge at ``P_1 .. P_FN, S_1 .. S_FN``
        (:func:`read_charges` of the tick charges).
    noise_factor : float
        IRACSIM's ``NOISE_FACTOR``: multiplies each Poisson deviate and the
        read noise, as ``prf_make_dce.pro`` does (variance ``factor**2`` times).

    Notes
    -----
    Between reads the noise carries forward unchanged, so only the reads
    matter: with ``F_r = mean_r + N_{r-1}`` (mean plus the noise so far),
    ``N_r = N_{r-1} + Poisson(max(round(F_r), 1)) - round(F_r)`` where
    ``F_r > 0``, literally as ``prf_make_dce.pro`` (so a read with
    ``0 < F_r < 0.5`` gains one electron on average; it is carried into the
    later reads and mostly cancels in ``S_i - P_i``).
    """
    m = np.asarray(reads, dtype=float)
    fn = mode.fowler
    if m.ndim == 0 or m.shape[0] != 2 * fn:
        raise InputError(f"read charges: expected first axis of length 2 FN = {2 * fn}, "
                         f"got shape {m.shape}")
    noise = np.zeros(m.shape[1:])
    values = np.empty_like(m)
    for r in range(2 * fn):
        f = m[r] + noise
        positive = f > 0
        rounded = np.where(positive, np.rint(f), 0.0)
        # as prf_make_dce.pro: Poisson(round(F) > 1) - round(F) (mean +1 when round(F) = 0)
        dev = noise_factor * (rng.poisson(np.maximum(rounded, 1.0)) - rounded)
        noise = noise + np.where(positive, dev, 0.0)
        values[r] = m[r] + noise
    values = values + rng.normal(0.0, noise_factor * read_noise_e, size=m.shape)
    return (values[fn:] - values[:fn]).sum(axis=0) / fn


def fowler_sample(mean_charge, mode: ReadoutMode, rng: np.random.Generator,
                  read_noise_e: float, noise_model: str = "physical", *,
                  grouped: bool = False) -> np.ndarray:
    """Fowler-sample one frame: mean tick charges in, electrons per exposure out.

    Parameters
    ----------
    mean_charge : array
        Mean charge (e) per tick, shape ``(n_max, ...)``; with ``grouped=True``
        (physical model only) the grouped form ``(FN, ...)`` of
        :func:`group_charges`.
    mode : ReadoutMode
    rng : numpy.random.Generator
    read_noise_e : float
        Gaussian read noise per read (e): 9.4 physical, 16.8 as IRACSIM.
    noise_model : {"physical", "iracsim2015"}
    grouped : bool
        Whether ``mean_charge`` is already grouped by Fowler weight.

    Returns
    -------
    ndarray
        ``sum_i (S_i - P_i) / FN`` in electrons, shape ``mean_charge.shape[1:]``.

    Examples
    --------
    >>> from eclipsebench.detector.constants import SUB_2S
    >>> q = np.full((SUB_2S.n_max, 2, 2), 5.0)
    >>> fowler_sample(q, SUB_2S, np.random.default_rng(1), 0.0).shape
    (2, 2)
    """
    _check_model(noise_model)
    if read_noise_e < 0:
        raise InputError(f"read_noise_e: expected a non-negative read noise, got {read_noise_e}")
    if noise_model == "physical":
        groups = np.asarray(mean_charge, float) if grouped else group_charges(mean_charge, mode)
        return fowler_sample_grouped(groups, mode, rng, read_noise_e)
    if grouped:
        raise InputError("fowler_sample: noise_model 'iracsim2015' needs per-tick charges, "
                         "not the grouped form")
    return fowler_sample_iracsim2015(read_charges(mean_charge, mode), mode, rng, read_noise_e)


def fowler_variance_exact(q_ticks, mode: ReadoutMode, read_noise_e: float) -> np.ndarray:
    """Exact variance of the physical model: ``sum_k w_k^2 q_k / FN^2 + 2 sigma^2 / FN``.

    For a constant rate ``q`` per tick this is
    ``q [n_max - 4 FN / 3 + 1 / (3 FN)] + 2 sigma^2 / FN``; the paper's
    Eq. ``gar_for_var`` gives ``q [n_max - 2 FN / 3 + 1 / (6 FN)] + ...``
    (2.8% more shot noise for FN = 8, WT = 184).
    """
    q = _ticks(q_ticks, mode)
    w = fowler_weights(mode).astype(float).reshape((-1,) + (1,) * (q.ndim - 1))
    return (w**2 * q).sum(axis=0) / mode.fowler**2 + 2.0 * read_noise_e**2 / mode.fowler


def electrons_to_dn(e, gain: float):
    """DN = e / GAIN."""
    return np.asarray(e, float) / gain


def dn_to_electrons(dn, gain: float):
    """e = DN x GAIN."""
    return np.asarray(dn, float) * gain


def electrons_to_mjysr(e, *, fluxconv: float, gain: float, t_exp_s: float):
    """BCD surface brightness: ``FLUXCONV e / (GAIN t_exp)`` (paper Appendix A.3, Eq. BCD)."""
    return fluxconv * np.asarray(e, float) / (gain * t_exp_s)


def mjysr_to_electrons(bcd, *, fluxconv: float, gain: float, t_exp_s: float):
    """Electrons per exposure from MJy/sr: ``bcd GAIN t_exp / FLUXCONV``."""
    return np.asarray(bcd, float) * gain * t_exp_s / fluxconv


def bunc_mjysr(e, mode: ReadoutMode, *, read_noise_e: float, fluxconv: float,
               gain: float) -> np.ndarray:
    """BUNC uncertainty (MJy/sr) of a Fowler-sampled image in electrons.

    Uses the paper's Eq. ``gar_for_var`` (via
    :func:`fowler_variance`) on the
    non-negative part of ``e`` (electrons per exposure time), one pixel each.
    """
    var = fowler_variance(np.clip(np.asarray(e, float), 0.0, None), fowler=mode.fowler,
                          wait=mode.wait, read_noise_e=read_noise_e)
    return electrons_to_mjysr(np.sqrt(var), fluxconv=fluxconv, gain=gain, t_exp_s=mode.t_exp_s)
