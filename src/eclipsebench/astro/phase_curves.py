"""Empirical out-of-eclipse phase curves used by the fits: flat, linear, quadratic, sinusoid.

Each is the planet-to-star flux ratio ``F(t)`` as a pure function of time and
coefficients, to be combined with an eclipse shape ``V(t)`` as
``L(t) = 1 + F(t) V(t)`` (star = 1, so the eclipse depth is ``F(t_ecl)``,
the paper's Eq. eclipse_depth).  Polynomials are written in
``x = t - t_ref`` (days); with ``t_ref`` the mid-eclipse time the first
coefficient is the depth itself.  The sinusoid is
``c0 + c1 (cos(2 pi (t - t_ref)/P) - 1) + c2 sin(2 pi (t - t_ref)/P)``, again
with ``c0`` the value at ``t_ref``.

All models are linear in their coefficients; :func:`design_matrix` gives
the columns so a fit can solve for them by linear least squares.

Examples
--------
>>> import numpy as np
>>> t = np.array([-0.1, 0.0, 0.1])
>>> quadratic(t, (1e-3, 0.0, -1e-3)).tolist()
[0.00099, 0.001, 0.00099]
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

__all__ = ["PHASE_MODELS", "N_COEFFS", "flat", "linear", "quadratic", "sinusoid",
           "design_matrix", "evaluate", "harmonic_curve", "harmonic_terms",
           "harmonic_from_terms", "harmonic_summary", "fit_harmonics",
           "fit_harmonic_light_curve"]


def _x(time, t_ref: float) -> np.ndarray:
    x = np.asarray(time, dtype=float)
    return x if t_ref == 0 else x - float(t_ref)


# The one definition of each phase model, used by the astro bias tool and by the fitter
# (fit/model/parts.py), whose coefficients may be arrays of shape (m, 1) against times of
# shape (m, n); fit/model/kernels.py holds a compiled copy of flat, linear and quadratic,
# held equal by tests/fit/test_fit_mcmc.py::test_astro_batch_is_the_model_of_each_row.
def flat(time, coeffs: Sequence[float], *, t_ref: float = 0.0, period: float = 1.0):
    """``c0`` at every time."""
    (c0,) = coeffs
    return np.full(np.broadcast_shapes(np.shape(time), np.shape(c0)), c0, dtype=float)


def linear(time, coeffs: Sequence[float], *, t_ref: float = 0.0, period: float = 1.0):
    """``c0 + c1 x`` with ``x = t - t_ref`` in days."""
    c0, c1 = coeffs
    return c0 + c1 * _x(time, t_ref)


def quadratic(time, coeffs: Sequence[float], *, t_ref: float = 0.0, period: float = 1.0):
    """``c0 + c1 x + c2 x^2`` with ``x = t - t_ref`` in days."""
    c0, c1, c2 = coeffs
    x = _x(time, t_ref)
    return c0 + x * (c1 + c2 * x)


def _orbital_phase(x: np.ndarray, period: float) -> np.ndarray:
    return (2.0 * math.pi / period) * x


def sinusoid(time, coeffs: Sequence[float], *, t_ref: float = 0.0, period: float = 1.0):
    """``c0 + c1 (cos(2 pi x / P) - 1) + c2 sin(2 pi x / P)``."""
    c0, c1, c2 = coeffs
    ph = _orbital_phase(_x(time, t_ref), period)
    return c0 + c1 * (np.cos(ph) - 1.0) + c2 * np.sin(ph)


PHASE_MODELS: dict[str, Callable] = {
    "flat": flat, "linear": linear, "quadratic": quadratic, "sinusoid": sinusoid,
}
N_COEFFS = {"flat": 1, "linear": 2, "quadratic": 3, "sinusoid": 3}


def design_matrix(name: str, time, *, t_ref: float = 0.0, period: float = 1.0) -> np.ndarray:
    """Columns ``(n_times, n_coeffs)`` such that ``model = A @ coeffs``."""
    if name not in PHASE_MODELS:
        raise ValueError(f"unknown phase model {name!r} (known: {', '.join(PHASE_MODELS)})")
    x = _x(time, t_ref)
    ones = np.ones_like(x)
    if name == "flat":
        cols = [ones]
    elif name == "linear":
        cols = [ones, x]
    elif name == "quadratic":
        cols = [ones, x, x * x]
    else:
        ph = _orbital_phase(x, period)
        cols = [ones, np.cos(ph) - 1.0, np.sin(ph)]
    return np.stack(cols, axis=-1)


def evaluate(name: str, time, coeffs: Sequence[float], *, t_ref: float = 0.0,
             period: float = 1.0) -> np.ndarray:
    """The named model at ``time``."""
    if name not in PHASE_MODELS:
        raise ValueError(f"unknown phase model {name!r} (known: {', '.join(PHASE_MODELS)})")
    if len(coeffs) != N_COEFFS[name]:
        raise ValueError(f"{name} phase model takes {N_COEFFS[name]} coefficients")
    return PHASE_MODELS[name](time, coeffs, t_ref=t_ref, period=period)


# ---------------------------------------------------------------- whole phase curves
def harmonic_curve(phase_rad, depth: float, harmonics: Sequence[float] | np.ndarray) -> np.ndarray:
    """The planet-to-star flux ratio of a harmonic phase curve at orbital phase ``phase_rad``.

    ``phase_rad = 2 pi (t - t_ecl) / P`` (0 at mid-eclipse) and ``harmonics`` is
    ``(a1, b1)`` or ``(a1, b1, a2, b2)``::

        p = depth + a1 (cos phi - 1) + b1 sin phi + a2 (cos 2 phi - 1) + b2 sin 2 phi

    the first (and second) harmonic of SPCA's phase curves (Bell et al. 2021,
    Eq. 2), written so that ``p(0) = depth`` (the paper's eclipse depth).

    Examples
    --------
    >>> harmonic_curve([0.0, math.pi], 2e-3, (5e-4, 0.0)).tolist()
    [0.002, 0.001]
    """
    h = tuple(float(v) for v in harmonics)
    if len(h) not in (2, 4):
        raise ValueError(f"harmonics: expected (a1, b1) or (a1, b1, a2, b2), got {len(h)} values")
    return harmonic_from_terms(harmonic_terms(phase_rad, len(h) // 2), depth, h)


def harmonic_terms(phase_rad, n_harmonics: int) -> tuple[np.ndarray, ...]:
    """``cos phi - 1, sin phi`` (and ``cos 2 phi - 1, sin 2 phi`` for two harmonics): what
    :func:`harmonic_curve` weighs by its coefficients (a fitter moving only the
    coefficients reuses them)."""
    phi = np.asarray(phase_rad, dtype=float)
    terms: tuple[np.ndarray, ...] = (np.cos(phi) - 1.0, np.sin(phi))
    if n_harmonics == 2:
        terms += (np.cos(2.0 * phi) - 1.0, np.sin(2.0 * phi))
    return terms


def harmonic_from_terms(terms: Sequence[np.ndarray] | np.ndarray, depth: float,
                        harmonics: Sequence[float]) -> np.ndarray:
    """:func:`harmonic_curve` from its :func:`harmonic_terms`."""
    h = tuple(float(v) for v in harmonics)
    p = depth + h[0] * terms[0] + h[1] * terms[1]
    if len(h) == 4:
        p = p + h[2] * terms[2] + h[3] * terms[3]
    return p


def harmonic_summary(depth: float, harmonics: Sequence[float], *,
                     transit_phase_rad: float = math.pi, n_grid: int = 3600) -> dict[str, float]:
    """What the literature reports of a harmonic phase curve (:func:`harmonic_curve`).

    - ``phase_amplitude``: the semi-amplitude, half of max - min over an orbit
      (``sqrt(a1^2 + b1^2)`` for the first harmonic alone);
    - ``phase_offset_deg``: the hotspot offset, minus the orbital phase (deg) of
      the curve's maximum: the maximum before mid-eclipse (a hotspot east of
      the substellar point) is positive, west is negative (Knutson et al. 2007;
      Bell et al. 2021);
    - ``nightside_flux``: the planet's flux at mid-transit (``transit_phase_rad``,
      pi for a circular orbit; ``2 pi (t_tr - t_ecl) / P`` otherwise);
    - ``planet_flux_min``: the curve's minimum over an orbit (negative is
      unphysical).

    The first harmonic alone has closed forms; with the second the maximum is
    found on an ``n_grid`` grid refined by a parabola through its neighbours.

    Examples
    --------
    >>> s = harmonic_summary(2e-3, (5e-4, -5e-4))   # peak 45 deg before eclipse
    >>> round(s["phase_amplitude"] * 1e6, 3), round(s["phase_offset_deg"], 3)
    (707.107, 45.0)
    >>> round(s["nightside_flux"] * 1e6, 3)
    1000.0
    """
    h = tuple(float(v) for v in harmonics)
    night = float(harmonic_curve(transit_phase_rad, depth, h))
    if len(h) == 2:
        amp = math.hypot(h[0], h[1])
        peak = math.atan2(h[1], h[0])
        const = depth - h[0]
        return {"phase_amplitude": amp, "phase_offset_deg": -math.degrees(peak),
                "nightside_flux": night, "planet_flux_min": const - amp}
    phi = np.linspace(-math.pi, math.pi, n_grid, endpoint=False)
    p = harmonic_curve(phi, depth, h)
    i = int(np.argmax(p))
    left, mid, right = p[(i - 1) % n_grid], p[i], p[(i + 1) % n_grid]
    curvature = left - 2.0 * mid + right
    step = phi[1] - phi[0]
    shift = 0.5 * (left - right) / curvature * step if curvature < 0 else 0.0
    peak = phi[i] + shift
    p_max = float(harmonic_curve(peak, depth, h))
    p_min = float(p.min())
    peak = (peak + math.pi) % (2.0 * math.pi) - math.pi
    return {"phase_amplitude": 0.5 * (p_max - p_min), "phase_offset_deg": -math.degrees(peak),
            "nightside_flux": night, "planet_flux_min": p_min}


def _harmonic_basis(phi: np.ndarray, n_harmonics: int) -> list[np.ndarray]:
    """The columns of :func:`harmonic_curve`: 1, cos phi - 1, sin phi (, cos 2 phi - 1, sin 2 phi)."""
    if n_harmonics not in (1, 2):
        raise ValueError(f"n_harmonics: expected 1 or 2, got {n_harmonics}")
    cols = [np.ones_like(phi), np.cos(phi) - 1.0, np.sin(phi)]
    if n_harmonics == 2:
        cols += [np.cos(2.0 * phi) - 1.0, np.sin(2.0 * phi)]
    return cols


def fit_harmonics(time_bmjd, planet_flux, t_ecl_bmjd: float, period_d: float, *,
                  n_harmonics: int = 1) -> tuple[float, tuple[float, ...]]:
    """Least-squares ``depth`` and harmonics of :func:`harmonic_curve` to a planet flux series.

    The truth of a simulated phase curve: its noiseless planet-to-star flux
    ratio ``F(t)`` (out of eclipse and transit) fitted with one or two
    harmonics, so that the truth and the fit define the amplitude and offset
    the same way.

    Examples
    --------
    >>> t = np.linspace(0.0, 3.0, 301)
    >>> f = harmonic_curve(2 * math.pi * (t - 1.0) / 3.0, 2e-3, (4e-4, 1e-4))
    >>> d, h = fit_harmonics(t, f, 1.0, 3.0)
    >>> round(d * 1e6, 6), [round(v * 1e6, 6) for v in h]
    (2000.0, [400.0, 100.0])
    """
    t = np.asarray(time_bmjd, dtype=float)
    f = np.asarray(planet_flux, dtype=float)
    ok = np.isfinite(t) & np.isfinite(f)
    cols = _harmonic_basis(2.0 * math.pi * (t[ok] - t_ecl_bmjd) / period_d, n_harmonics)
    coeffs = np.linalg.lstsq(np.stack(cols, axis=-1), f[ok], rcond=None)[0]
    return float(coeffs[0]), tuple(float(c) for c in coeffs[1:])


def fit_harmonic_light_curve(time_bmjd, flux, visible, stellar, t_ecl_bmjd: float,
                             period_d: float, *, n_harmonics: int = 1,
                             segments=None) -> tuple[float, tuple[float, ...]]:
    """Least-squares harmonic phase curve of a whole light curve, eclipses and transits included.

    ``flux ~ F0 [S(t) + V(t) p(t)]`` with ``p`` of :func:`harmonic_curve`,
    ``S`` the stellar flux (transits) and ``V`` the planet's visible fraction
    (eclipses) held at their true values: the model of ``reduce --event
    phase-curve`` without systematics, linear in ``(F0, F0 depth, F0 a1, ...)``
    as the paper's Section 4.2 fit of an eclipse (:mod:`.bias`). On a
    simulated phase curve's noiseless ``L(t)`` it gives what a perfect fit of
    that model reports, so the truth and the fit share one definition also
    when the planet's phase curve is not a harmonic series.

    ``segments`` (one label per sample, e.g. the AORKEY) gives each segment
    its own normalisation ``F0_k``, as the reducer's flux offset per AOR
    (to first order in ``p``: ``F0_k V p`` is taken as ``F0 V p``, an error
    of ``(F0_k / F0 - 1) p``, about 1e-6 of the star for offsets of 1e-3).

    Returns
    -------
    depth : float
        ``p(t_ecl)``, the model's eclipse depth (fraction).
    harmonics : tuple of float
        ``(a1, b1)`` or ``(a1, b1, a2, b2)``.

    Examples
    --------
    >>> t = np.linspace(0.0, 3.0, 3001)
    >>> v = np.where(np.abs(t - 1.0) < 0.05, 0.0, 1.0)
    >>> s = np.where(np.abs(t - 2.5) < 0.05, 0.99, 1.0)
    >>> p = harmonic_curve(2 * math.pi * (t - 1.0) / 3.0, 2e-3, (4e-4, 1e-4))
    >>> d, h = fit_harmonic_light_curve(t, 1.7 * (s + v * p), v, s, 1.0, 3.0)
    >>> round(d * 1e6, 6), [round(x * 1e6, 6) for x in h]
    (2000.0, [400.0, 100.0])
    """
    t = np.asarray(time_bmjd, dtype=float)
    v = np.asarray(visible, dtype=float)
    basis = _harmonic_basis(2.0 * math.pi * (t - t_ecl_bmjd) / period_d, n_harmonics)
    stellar = np.asarray(stellar, dtype=float)
    labels = np.zeros(t.shape, dtype=int) if segments is None else np.asarray(segments)
    keys = np.unique(labels)
    norm = [stellar * (labels == k) for k in keys]
    a = np.stack(norm + [v * c for c in basis], axis=-1)
    f = np.asarray(flux, dtype=float)
    ok = np.all(np.isfinite(a), axis=1) & np.isfinite(f)
    coeffs = np.linalg.lstsq(a[ok], f[ok], rcond=None)[0]
    f0 = float(np.sum(coeffs[:len(keys)] * np.bincount(np.searchsorted(keys, labels[ok]),
                                                       minlength=len(keys))) / np.sum(ok))
    planet = coeffs[len(keys):] / f0
    return float(planet[0]), tuple(float(c) for c in planet[1:])
