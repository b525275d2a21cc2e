"""The photon limit of a challenge, analytic and empirical.

*Analytic* (paper Section 3.3): average the net aperture flux, the aperture
flux before background subtraction and the background in the aperture over
every good frame of every epoch, turn them into the single-frame S/N with
Eq. ``gar_for_var`` and propagate to the depth with Eq. ``photon_noise``
(:mod:`eclipsebench.stats.photon_limit`).

*Empirical* (beyond the paper): the same epochs simulated again with the
same noise seeds but without pointing motion, reduced the same way; the
sample SD of those depths over epochs is the scatter that photon and read
noise alone produce.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..stats.photon_limit import eclipse_depth_photon_noise, frame_snr

__all__ = ["analytic_photon_limit", "empirical_photon_limit", "in_eclipse_fraction"]


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
                          annulus_px: tuple[float, float] = (3.0, 7.0), fowler: int = 8,
                          wait: int = 184, read_noise_e: float = 9.4) -> dict:
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
    from scipy import stats as sps

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
