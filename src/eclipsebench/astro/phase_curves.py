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
           "design_matrix", "evaluate"]


def _x(time, t_ref: float) -> np.ndarray:
    return np.asarray(time, dtype=float) - float(t_ref)


def flat(time, coeffs: Sequence[float], *, t_ref: float = 0.0, period: float = 1.0):
    """``c0`` at every time."""
    (c0,) = coeffs
    return np.full(np.shape(time), float(c0))


def linear(time, coeffs: Sequence[float], *, t_ref: float = 0.0, period: float = 1.0):
    """``c0 + c1 x`` with ``x = t - t_ref`` in days."""
    c0, c1 = coeffs
    return c0 + c1 * _x(time, t_ref)


def quadratic(time, coeffs: Sequence[float], *, t_ref: float = 0.0, period: float = 1.0):
    """``c0 + c1 x + c2 x^2`` with ``x = t - t_ref`` in days."""
    c0, c1, c2 = coeffs
    x = _x(time, t_ref)
    return c0 + x * (c1 + c2 * x)


def sinusoid(time, coeffs: Sequence[float], *, t_ref: float = 0.0, period: float = 1.0):
    """``c0 + c1 (cos(2 pi x / P) - 1) + c2 sin(2 pi x / P)``."""
    c0, c1, c2 = coeffs
    ph = 2.0 * math.pi * _x(time, t_ref) / period
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
        ph = 2.0 * math.pi * x / period
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
