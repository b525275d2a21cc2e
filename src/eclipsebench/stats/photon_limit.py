"""The photon limit of an eclipse depth (Section 3.3 of the paper).

Pure functions on numbers or arrays. Conventions: electron counts per frame,
as measured by aperture photometry of a Fowler-sampled BCD (i.e. the charge
accumulated over the *exposure* time ``t_exp = (FN + WT) dt``).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["SHOT_NOISE_FORMS", "fowler_variance", "frame_snr", "eclipse_depth_photon_noise", "PhotonLimit",
           "photon_limit", "SUBARRAY_2S"]

#: IRAC 2 s subarray readout (paper Section 3.3): FN, WT, sample time (s), read noise (e).
SUBARRAY_2S = {"fowler": 8, "wait": 184, "sample_time_s": 0.01, "read_noise_e": 9.4}


#: How :func:`fowler_variance` counts the shot noise: ``"paper"``, the paper's
#: Eq. ``gar_for_var`` as printed; ``"poisson"``, the exact variance of
#: Fowler-sampled independent Poisson increments (see :func:`fowler_variance`).
SHOT_NOISE_FORMS = ("paper", "poisson")


def _check_readout(fowler: int, wait: int) -> None:
    if int(fowler) != fowler or fowler < 1:
        raise ValueError(f"fowler: expected an integer >= 1, got {fowler}")
    if int(wait) != wait or wait < 0:
        raise ValueError(f"wait: expected an integer >= 0, got {wait}")


def fowler_variance(flux_e, *, fowler: int = 8, wait: int = 184, read_noise_e: float = 9.4,
                    n_pixels: float = 1.0, shot_noise: str = "paper"):
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


def frame_snr(flux_net_e, flux_aperture_e, flux_background_e, *, fowler: int = 8, wait: int = 184,
              read_noise_e: float = 9.4, aperture_pixels: float | None = None,
              shot_noise: str = "paper"):
    """S/N of one aperture-photometry frame (Section 3.3).

    ``sigma_ap-bg^2 = sigma_ap^2 + sigma_bg^2``, each from
    :func:`fowler_variance` of the aperture sum before background subtraction
    and of the background in the aperture; S/N = ``F_ap-bg / sigma_ap-bg``.

    Returns
    -------
    tuple of float
        ``(sigma_e, snr)``: the noise of one net aperture flux (electrons)
        and the single-frame signal-to-noise ratio.
    """
    npix = 1.0 if aperture_pixels is None else float(aperture_pixels)
    var = (fowler_variance(flux_aperture_e, fowler=fowler, wait=wait, read_noise_e=read_noise_e,
                           n_pixels=npix, shot_noise=shot_noise)
           + fowler_variance(flux_background_e, fowler=fowler, wait=wait,
                             read_noise_e=read_noise_e, shot_noise=shot_noise))
    sigma = np.sqrt(var)
    return sigma, np.asarray(flux_net_e, dtype=float) / sigma


def eclipse_depth_photon_noise(n_frames, snr_single, depth, f_in: float = 1.0 / 3.0):
    """Photon-noise standard deviation of an eclipse depth (Eq. ``photon_noise``).

    ``sigma_phot^2 = (1+D)^2 / (N (S/N)^2) [1 / ((1 - f_in)(1 + D)) + 1 / f_in]``

    Parameters
    ----------
    n_frames : float
        Number of frames N in the light curve.
    snr_single : float
        S/N of a single frame.
    depth : float
        Eclipse depth D as a fraction (1520 ppm is 1.52e-3).
    f_in : float
        Fraction of the frames in eclipse, 0 < f_in < 1.

    Returns
    -------
    float
        sigma_phot as a fraction (multiply by 1e6 for ppm).
    """
    if not 0.0 < f_in < 1.0:
        raise ValueError(f"f_in: expected a number in (0, 1), got {f_in}")
    one_d = 1.0 + np.asarray(depth, dtype=float)
    var = one_d**2 / (np.asarray(n_frames, float) * np.asarray(snr_single, float) ** 2) * (
        1.0 / ((1.0 - f_in) * one_d) + 1.0 / f_in)
    return np.sqrt(var)


@dataclass(frozen=True)
class PhotonLimit:
    """Everything :func:`photon_limit` computes, with units in the names."""

    sigma_e: float
    snr_single: float
    sigma_phot_ppm: float | None
    t_int_s: float
    t_exp_s: float

    def to_dict(self) -> dict:
        """Plain dict for JSON."""
        return asdict(self)


def photon_limit(flux_net_e: float, flux_aperture_e: float, flux_background_e: float, *,
                 frames: float | None = None, depth_ppm: float | None = None,
                 f_in: float = 1.0 / 3.0, fowler: int = 8, wait: int = 184,
                 sample_time_s: float = 0.01, read_noise_e: float = 9.4,
                 aperture_pixels: float | None = None, shot_noise: str = "paper") -> PhotonLimit:
    """Single-frame S/N and, given ``frames`` and ``depth_ppm``, sigma_phot.

    Examples
    --------
    The paper's real-data inputs (Section 3.3) give S/N close to 264:

    >>> round(photon_limit(70858, 70917, 463).snr_single)
    263
    """
    sigma_e, snr = frame_snr(flux_net_e, flux_aperture_e, flux_background_e, fowler=fowler,
                             wait=wait, read_noise_e=read_noise_e, aperture_pixels=aperture_pixels,
                             shot_noise=shot_noise)
    sigma_phot_ppm = None
    if frames is not None and depth_ppm is not None:
        sigma_phot_ppm = 1e6 * float(eclipse_depth_photon_noise(frames, snr, depth_ppm * 1e-6, f_in))
    return PhotonLimit(sigma_e=float(sigma_e), snr_single=float(snr), sigma_phot_ppm=sigma_phot_ppm,
                       t_int_s=(2 * fowler + wait) * sample_time_s,
                       t_exp_s=(fowler + wait) * sample_time_s)
