"""The paper's Section 4.2 check: depth bias from fitting an empirical phase model to L(t).

The noiseless light curve is fitted by linear least squares with
``F0 [1 + V(t) p(t)]`` (``F0`` a free normalisation, ``V`` the eclipse shape
at the true mid-eclipse time, ``p`` a flat, linear, quadratic or sinusoidal
phase model written about mid-eclipse, see :mod:`.phase_curves`); the fitted
depth ``p(t_ecl)`` minus the true depth is the bias of that phase model.

The model is linear in ``(F0, F0 c_0, F0 c_1, ...)``, so each fit is one
``lstsq`` call.
"""

from __future__ import annotations

import numpy as np

from .eclipse import EclipseShape
from .phase_curves import design_matrix
from .times import EPOCH10_START_BMJD

__all__ = ["EPOCH10_START_BMJD", "epoch_times", "phase_model_bias"]


def epoch_times(start_bmjd: float = EPOCH10_START_BMJD, hours: float = 8.8,
                cadence_s: float = 2.008) -> np.ndarray:
    """Evenly spaced frame times (BMJD) covering ``hours`` from ``start_bmjd``."""
    n = int(np.floor(hours * 3600.0 / cadence_s)) + 1
    return start_bmjd + (cadence_s / 86400.0) * np.arange(n)


def phase_model_bias(lc, time_bmjd, phase_models=("flat", "linear", "quadratic"),
                     t_ecl_bmjd: float | None = None) -> dict[str, float]:
    """Fitted-minus-true eclipse depth (ppm) for each phase model.

    Parameters
    ----------
    lc : LightCurve
        The truth; ``lc.depth_ppm`` is the true depth.
    time_bmjd : array_like
        Sample times (one eclipse inside).
    phase_models : sequence of str
    t_ecl_bmjd : float, optional
        Mid-eclipse time held fixed in the fit (default: the true one nearest
        the middle of the data).
    """

    t = np.asarray(time_bmjd, dtype=float)
    if t_ecl_bmjd is None:
        mid = 0.5 * (t[0] + t[-1])
        p = lc.system.period_days
        t_ecl_bmjd = min(lc.eclipse_times_bmjd(mid - p, mid + p), key=lambda x: abs(x - mid))
    flux = lc(t)
    vis = EclipseShape(t, lc.system).visible_fraction(t_ecl_bmjd)
    out = {}
    for name in phase_models:
        cols = design_matrix(name, t, t_ref=t_ecl_bmjd, period=lc.system.period_days)
        a = np.column_stack([np.ones_like(t), vis[:, None] * cols])
        coef, *_ = np.linalg.lstsq(a, flux, rcond=None)
        out[name] = float(coef[1] / coef[0] * 1e6 - lc.depth_ppm)
    return out
