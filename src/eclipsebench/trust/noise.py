"""The real observation's correlated noise that its twins lack, added to them.

A twin has the real photon and read noise by construction (the real flux,
background and readout, Fowler sampling), and the pointing systematics the
simulator makes (its motion within an exposure calibrated on the real noise
pixels). What the real residuals hold beyond a twin's (red noise from the
star, the detector, whatever the simulator does not make) is found by
comparing the first method's real fit with its fit of a *pilot* twin (twin
0, made and reduced exactly as the others but never scored):

1. both fits' residuals, in time order, mean removed, and their
   periodograms ``P_real(f)`` and ``P_twin(f)`` (the frames are evenly
   spaced but for short gaps; frequencies in cycles per day);
2. the periodograms averaged in logarithmic frequency bins of at least
   :data:`MIN_PER_BIN` frequencies each (``S_real``, ``S_twin``);
3. in each bin, the excess ``S_real - S_twin`` where the ratio
   ``S_real / S_twin`` is significant, else 0: the real residuals are
   redder than the twin's there. Each periodogram value of Gaussian noise
   is exponential about its spectrum, so the ratio of two averages of ``k``
   and ``k'`` values follows an F distribution with ``2k, 2k'`` degrees of
   freedom when the spectra are equal; the excess counts above its
   ``1 -`` :data:`FALSE_EXCESS` quantile;
4. the part of the real residuals carrying that excess:
   ``c = F^-1[H F[r_real]]`` with ``H = sqrt(excess / S_real)`` (a Wiener
   filter, Press et al., Numerical Recipes Sect. 13.3).

``c`` holds only what a twin lacks: where the real residuals are no redder
than the twin's (their white part, photon noise included, and the red noise
the simulator already makes) ``H`` is 0, so nothing is doubled. Each twin
adds ``c``, cyclically shifted by a number of frames drawn from the seed and
the twin's number (as the prayer bead shifts residuals, Wong et al. 2014),
to its photometry: every aperture flux and pixel stamp times ``1 + c``, an
injection-recovery on the real noise. Nothing of a twin's truth enters:
``c`` comes from the real fit's residuals, and the pilot only says how red
a twin already is.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from astropy.table import Table
from scipy.stats import f as f_distribution

from ..fit.leastsq import red_noise_beta
from ..seeding import rng

__all__ = ["correlated_component", "add_correlated", "twin_shift", "MIN_PER_BIN",
           "FALSE_EXCESS"]

#: Fewest periodogram values averaged in one frequency bin (its relative error 1/sqrt(16)).
MIN_PER_BIN = 16

#: The chance that a bin whose spectra are equal is found in excess (Gaussian 3 sigma one-sided;
#: with the 20-30 bins of an 8-hour observation, about 3 % that any one is).
FALSE_EXCESS = 0.00135


def _sorted_residuals(time_bmjd, residual) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(time_bmjd, float)
    r = np.asarray(residual, float)
    ok = np.isfinite(t) & np.isfinite(r)
    order = np.argsort(t[ok], kind="stable")
    t, r = t[ok][order], r[ok][order]
    return t, r - r.mean()


def _periodogram(t: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The FFT of ``r``, its periodogram and the frequencies (cycles/day) of its samples."""
    n = r.size
    spectrum = np.fft.rfft(r)
    dt_d = (t[-1] - t[0]) / max(n - 1, 1)
    return spectrum, np.abs(spectrum) ** 2 / n, np.arange(spectrum.size) / (n * dt_d)


def _bin_edges(freq: np.ndarray) -> np.ndarray:
    """Logarithmic bin edges over ``freq[1:]``, merged until each holds MIN_PER_BIN values."""
    raw = np.geomspace(freq[1], freq[-1] * (1 + 1e-9), 60)
    edges = [raw[0]]
    for e in raw[1:]:
        if np.count_nonzero((freq >= edges[-1]) & (freq < e)) >= MIN_PER_BIN:
            edges.append(e)
    edges[-1] = raw[-1]
    return np.asarray(edges)


def correlated_component(time_bmjd: np.ndarray, real: tuple[np.ndarray, np.ndarray],
                         twin: tuple[np.ndarray, np.ndarray]
                         ) -> tuple[np.ndarray, dict[str, Any]]:
    """The part of the real residuals that a twin's lack (module docstring), on every frame.

    Parameters
    ----------
    time_bmjd : ndarray
        The observation's frame times (the twins').
    real, twin : (ndarray, ndarray)
        ``(time_bmjd, residual)`` (relative flux) of the real fit and of the
        same method's fit of the pilot twin.

    Returns
    -------
    correlated : ndarray
        ``c`` at each of ``time_bmjd`` (interpolated between the real fit's
        frames; 0 outside their span).
    diagnostics : dict
        ``rms_ppm`` (of ``c``), ``white_ppm`` (the real residuals' rms per frame),
        ``bins_in_excess`` of ``bins`` and their periods (``periods_in_excess_min``,
        minutes); the other way round, ``bins_twin_in_excess`` and
        ``periods_twin_in_excess_min`` (``[shortest, longest, S_twin / S_real]``):
        where the pilot's residuals are significantly redder than the real ones
        (the same F test), which nothing added can undo: there the twins
        overstate the noise; ``beta_red_real`` and ``beta_red_pilot``
        (of the two fits' residuals, 10-30 minute bins) and
        ``beta_red_pilot_plus_correlated`` (of the pilot's residuals plus ``c``:
        what a twin's residuals show before its fit absorbs any of ``c``).

    Examples
    --------
    >>> t = 56000.0 + np.arange(8192) * 2.0 / 86400
    >>> g = np.random.default_rng(1)
    >>> slow = 6e-4 * np.sin(2 * np.pi * (t - t[0]) / 0.03)
    >>> c, info = correlated_component(t, (t, g.normal(0, 1e-3, t.size) + slow),
    ...                                (t, g.normal(0, 1e-3, t.size)))
    >>> bool(np.std(c - slow) < 0.4 * np.std(slow))           # the slow part, recovered
    True
    >>> c, info = correlated_component(t, (t, g.normal(0, 1e-3, t.size)),
    ...                                (t, g.normal(0, 1e-3, t.size)))
    >>> bool(info["rms_ppm"] < 0.1 * info["white_ppm"])       # as white as the twin's
    True
    """
    t_r, r = _sorted_residuals(*real)
    t_p, p = _sorted_residuals(*twin)
    spec_r, pow_r, f_r = _periodogram(t_r, r)
    _, pow_p, f_p = _periodogram(t_p, p)
    edges = _bin_edges(f_r)
    gain = np.zeros(spec_r.size)
    in_excess: list[list[float]] = []
    twin_redder: list[list[float]] = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        sel_r = (f_r >= lo) & (f_r < hi)
        sel_p = (f_p >= lo) & (f_p < hi)
        k_r, k_p = int(sel_r.sum()), int(sel_p.sum())
        if k_r == 0 or k_p == 0:
            continue
        s_r, s_p = float(pow_r[sel_r].mean()), float(pow_p[sel_p].mean())
        excess = s_r - s_p
        if s_r > s_p * float(f_distribution.ppf(1.0 - FALSE_EXCESS, 2 * k_r, 2 * k_p)):
            gain[sel_r] = np.sqrt(excess / s_r)
            in_excess.append([1440.0 / hi, 1440.0 / lo])
        elif s_p > s_r * float(f_distribution.ppf(1.0 - FALSE_EXCESS, 2 * k_p, 2 * k_r)):
            twin_redder.append([1440.0 / hi, 1440.0 / lo, float(s_p / s_r)])
    c = np.fft.irfft(gain * spec_r, r.size)
    times = np.asarray(time_bmjd, float)
    inside = (times >= t_r[0]) & (times <= t_r[-1])
    out = np.where(inside, np.interp(times, t_r, c), 0.0)
    at_pilot = np.interp(t_p, t_r, c)
    return out, {"method": "the real fit's residuals in excess of a pilot twin's (Wiener "
                           "filter in frequency bins where their power ratio is significant "
                           "at 3 sigma), cyclically shifted per twin",
                 "rms_ppm": float(np.std(c)) * 1e6, "white_ppm": float(np.std(r)) * 1e6,
                 "bins_in_excess": len(in_excess), "bins": int(edges.size - 1),
                 "periods_in_excess_min": in_excess,
                 "bins_twin_in_excess": len(twin_redder),
                 "periods_twin_in_excess_min": twin_redder,
                 "beta_red_real": red_noise_beta(r, t_r),
                 "beta_red_pilot": red_noise_beta(p, t_p),
                 "beta_red_pilot_plus_correlated": red_noise_beta(p + at_pilot, t_p),
                 "n_residuals": int(r.size)}


def twin_shift(n_frames: int, *, seed: int, twin: int) -> int:
    """The cyclic shift (frames, 1 to ``n_frames - 1``) of twin ``twin``'s correlated noise.

    Examples
    --------
    >>> twin_shift(1000, seed=0, twin=1) == twin_shift(1000, seed=0, twin=1)
    True
    """
    return int(rng(seed, "trust", "twin", twin, "correlated").integers(1, max(2, n_frames)))


def add_correlated(table: Table, correlated: np.ndarray | None, *, seed: int, twin: int
                   ) -> Table:
    """Twin ``twin``'s photometry ``table`` with ``correlated`` (per frame of the observation,
    in time order) shifted by :func:`twin_shift`: every aperture flux (``flux``,
    ``flux_r*``, ``flux_raw``, ``flux_va*``) and pixel stamp (``stamp*``) times ``1 + c``.
    ``correlated`` None: the table as it is. The table's metadata record the shift
    (``TWINSHFT``)."""
    if correlated is None:
        return table
    c = np.roll(np.asarray(correlated, float), twin_shift(len(correlated), seed=seed, twin=twin))
    order = np.argsort(np.asarray(table["time_bmjd"], float), kind="stable")
    factor = np.empty(len(table))
    factor[order] = 1.0 + c
    for name in table.colnames:
        flux_like = name.startswith("flux") and name != "flux_err"
        stamp = name.startswith("stamp") and name not in ("stamp_x", "stamp_y")
        if flux_like or stamp:
            col = table[name]
            col[...] = np.asarray(col) * factor.reshape((-1,) + (1,) * (col.ndim - 1))
    table.meta["TWINSHFT"] = twin_shift(len(correlated), seed=seed, twin=twin)
    return table
