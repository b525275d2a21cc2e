"""The photon limit of an eclipse depth (Section 3.3 of the paper).

Pure functions on numbers or arrays. Conventions: electron counts per frame,
as measured by aperture photometry of a Fowler-sampled BCD (i.e. the charge
accumulated over the *exposure* time ``t_exp = (FN + WT) dt``).

The photon limit of a whole challenge, two ways:

*Analytic* (paper Section 3.3, :func:`analytic_photon_limit`): average the
net aperture flux, the aperture flux before background subtraction and the
background in the aperture over every good frame of every epoch, turn them
into the single-frame S/N with Eq. ``gar_for_var`` and propagate to the
depth with Eq. ``photon_noise``.

*Empirical* (beyond the paper, :func:`empirical_photon_limit`): the same
epochs simulated again with the same noise seeds but without pointing
motion, reduced the same way; the sample SD of those depths over epochs is
the scatter that photon and read noise alone produce.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from ..detector.constants import READ_NOISE_E, SUB_2S
from ..detector.fowler import fowler_variance

__all__ = ["frame_snr", "eclipse_depth_photon_noise", "PhotonLimit",
           "photon_limit", "SUBARRAY_2S", "analytic_photon_limit", "empirical_photon_limit",
           "in_eclipse_fraction"]

#: IRAC 2 s subarray readout (paper Section 3.3): FN, WT, sample time (s), read noise (e).
SUBARRAY_2S = {"fowler": SUB_2S.fowler, "wait": SUB_2S.wait,
               "sample_time_s": SUB_2S.sample_time_s, "read_noise_e": READ_NOISE_E}


def frame_snr(flux_net_e, flux_aperture_e, flux_background_e, *, fowler: int = SUB_2S.fowler, wait: int = SUB_2S.wait,
              read_noise_e: float = READ_NOISE_E, aperture_pixels: float | None = None,
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
                 f_in: float = 1.0 / 3.0, fowler: int = SUB_2S.fowler, wait: int = SUB_2S.wait,
                 sample_time_s: float = SUB_2S.sample_time_s, read_noise_e: float = READ_NOISE_E,
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


def in_eclipse_fraction(visible_fraction) -> float:
    """Fraction of frames in eclipse, counting ingress/egress frames by the hidden fraction.

    Parameters
    ----------
    visible_fraction : array_like
        Visible fraction of the planet per frame (1 out of eclipse, 0 in it).
    """
    v = np.asarray(visible_fraction, dtype=float)
    return float(np.mean(1.0 - v)) if v.size else float("nan")


def analytic_photon_limit(flux_e: Sequence[np.ndarray], background_e_per_px: Sequence[np.ndarray],
                          *, depth_ppm: float, f_in: float = 1.0 / 3.0,
                          aperture_radius_px: float = 2.25,
                          annulus_px: tuple[float, float] = (3.0, 7.0), fowler: int = SUB_2S.fowler,
                          wait: int = SUB_2S.wait, read_noise_e: float = READ_NOISE_E) -> dict:
    """sigma_phot of one epoch's depth from photometry (Section 3.3).

    Parameters
    ----------
    flux_e : sequence of arrays
        Background-subtracted aperture flux of the good frames, one array per
        epoch (electrons per frame).
    background_e_per_px : sequence of arrays
        Background per pixel of the same frames (electrons).
    depth_ppm : float
        Eclipse depth D (the truth for simulations, the mean for real data).
    f_in : float
        Fraction of frames in eclipse.
    aperture_radius_px : float
        Aperture radius: ``F_ap = F_ap-bg + pi r^2 b``.
    annulus_px : (float, float)
        Background annulus radii: ``F_bg = pi (r_out^2 - r_in^2) b``, the
        electrons in the annulus, as the paper's numbers show (simulated:
        F_ap - F_ap-bg = 112 e in the aperture, F_bg = 881 e, both 7.0 e/px).
    fowler, wait, read_noise_e
        Readout (2 s subarray defaults).

    Returns
    -------
    dict
        ``sigma_phot_ppm`` and its inputs: ``flux_net_e``, ``flux_aperture_e``,
        ``flux_background_e`` (means over all frames), ``snr_single``,
        ``frames`` (mean good frames per epoch), ``f_in``, ``depth_ppm``.
    """
    flux = np.concatenate([np.asarray(f, float).ravel() for f in flux_e])
    bkg = np.concatenate([np.asarray(b, float).ravel() for b in background_e_per_px])
    f_net = float(np.mean(flux))
    b = float(np.mean(bkg))
    f_ap = f_net + b * math.pi * aperture_radius_px**2
    f_bg = b * math.pi * (annulus_px[1] ** 2 - annulus_px[0] ** 2)
    _, snr = frame_snr(f_net, f_ap, f_bg, fowler=fowler, wait=wait, read_noise_e=read_noise_e)
    frames = float(np.mean([np.size(f) for f in flux_e]))
    sigma = float(eclipse_depth_photon_noise(frames, snr, depth_ppm * 1e-6, f_in)) * 1e6
    return {"sigma_phot_ppm": sigma, "flux_net_e": f_net, "flux_aperture_e": f_ap,
            "flux_background_e": f_bg, "snr_single": float(snr), "frames": frames,
            "f_in": float(f_in), "depth_ppm": float(depth_ppm),
            "aperture_radius_px": float(aperture_radius_px),
            "annulus_px": [float(a) for a in annulus_px]}


def empirical_photon_limit(depth_ppm, error_ppm) -> dict:
    """Scatter of the depths measured on systematics-free twins of the epochs.

    Returns
    -------
    dict
        ``sigma_phot_ppm`` (sample SD, N - 1), its 68% interval from the
        chi-square distribution with N - 1 degrees of freedom
        (``sigma_phot_lo_ppm``, ``sigma_phot_hi_ppm``), the mean reported
        error ``mean_error_ppm``, the mean depth and ``N``.
    """
    from scipy import stats as sps  # about 0.7 s: the calculator (photon-limit) does without

    d = np.asarray(depth_ppm, float)
    n = d.size
    if n < 2:
        return {"sigma_phot_ppm": None, "N": int(n)}
    sd = float(np.std(d, ddof=1))
    return {"sigma_phot_ppm": sd,
            "sigma_phot_lo_ppm": sd * math.sqrt((n - 1) / sps.chi2.ppf(0.84, n - 1)),
            "sigma_phot_hi_ppm": sd * math.sqrt((n - 1) / sps.chi2.ppf(0.16, n - 1)),
            "mean_error_ppm": float(np.mean(error_ppm)), "mean_depth_ppm": float(np.mean(d)),
            "N": int(n)}
