"""Synthetic epochs and a test-only systematics model for the fitting framework.

The synthetic epoch is an eclipse of known depth and time (a quadratic phase
curve), multiplied by a smooth known intra-pixel gain g(x, y) sampled along a
simulated pointing track (jitter, wobble, drift), plus white noise. The
test-only method ``PolyGain`` models the gain as a quadratic polynomial in
(x, y) whose coefficients are solved linearly inside ``predict``, which
exercises the whole framework without the real methods.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import pytest

from eclipsebench.decorrelate import base
from eclipsebench.decorrelate.base import EpochData, Systematics

TRUE_DEPTH = 1875e-6
TRUE_C1 = 1.0e-3      # per day
TRUE_C2 = -8.0e-3     # per day^2
CADENCE_D = 6.0 / 86400.0
F0 = 2.0e5            # electrons


def gain(x, y):
    """The known intra-pixel gain (a quadratic surface, peak near the pixel centre)."""
    dx, dy = x - 15.0, y - 15.0
    return 1.0 + 0.03 * dx - 0.02 * dy - 0.6 * dx**2 - 0.4 * dy**2 + 0.2 * dx * dy


def design(x, y):
    dx, dy = x - 15.0, y - 15.0
    return np.column_stack([np.ones_like(dx), dx, dy, dx**2, dy**2, dx * dy])


class PolyGain(Systematics):
    """Test-only: flux = astro * (quadratic polynomial in x, y), solved linearly."""

    name: ClassVar[str] = "test-polygain"
    requires: ClassVar[tuple[str, ...]] = ("x", "y")

    def __init__(self, data: EpochData, options=None, *, context=None, **kwargs) -> None:
        super().__init__(data, options, context=context, **kwargs)
        a = design(data.x, data.y)
        w = 1.0 / data.flux_err
        self._a = a
        self._pinv_w = np.linalg.pinv(a * w[:, None]) * w[None, :]

    def predict(self, astro, theta=None):
        coef = self._pinv_w @ (self.data.flux / astro)
        return astro * (self._a @ coef)

    def n_effective_params(self) -> int:
        return self._a.shape[1]


class TrapezoidShape:
    """Test double of the astro API: a trapezoidal eclipse (linear ingress/egress)."""

    def __init__(self, time_bmjd, *, duration_d=0.12, ingress_d=0.015):
        self.time_bmjd = np.asarray(time_bmjd, dtype=float)
        self.duration_d = duration_d
        self.ingress_d = ingress_d

    def visible_fraction(self, t_ecl_bmjd):
        half = 0.5 * self.duration_d
        d = np.abs(self.time_bmjd - t_ecl_bmjd)
        return np.clip((d - (half - self.ingress_d)) / self.ingress_d, 0.0, 1.0)


def pointing(time, rng):
    t = time - time[0]
    x = 15.02 + 0.05 * np.sin(2 * np.pi * t / 0.028) + 0.08 * t + 0.01 * rng.standard_normal(len(t))
    y = 14.95 + 0.04 * np.cos(2 * np.pi * t / 0.021) - 0.1 * t + 0.01 * rng.standard_normal(len(t))
    return x, y


def make_epoch_table(*, t_ecl, visible, time, noise=1e-3, seed=1, systematics=True,
                     c1=TRUE_C1, c2=TRUE_C2, depth=TRUE_DEPTH, red_noise=0.0):
    """A photometry table (contract columns) of a synthetic epoch."""
    from astropy.table import Table
    rng = np.random.default_rng(seed)
    dt = time - t_ecl
    astro = 1.0 + visible * (depth + c1 * dt + c2 * dt**2)
    x, y = pointing(time, rng)
    g = gain(x, y) if systematics else np.ones_like(x)
    flux = F0 * g * astro
    if noise:
        flux = flux * (1.0 + noise * rng.standard_normal(len(time)))
    if red_noise:
        walk = np.convolve(rng.standard_normal(len(time)), np.ones(200) / np.sqrt(200), "same")
        flux = flux * (1.0 + red_noise * walk)
    n = len(time)
    stamp = np.broadcast_to(flux[:, None, None] / 9.0, (n, 3, 3)).copy()
    stamp5 = np.broadcast_to(flux[:, None, None] / 25.0, (n, 5, 5)).copy()
    t = Table({"time_bmjd": time, "aorkey": np.full(n, 20150001),
               "expid": np.arange(n) // 64, "frame": np.arange(n) % 64, "x": x, "y": y,
               "x_gauss": x, "y_gauss": y,
               "noise_pixels": np.full(n, 7.0) + 0.1 * np.sin(time * 50),
               "width_x": np.full(n, 0.6), "width_y": np.full(n, 0.6),
               "background": np.full(n, 0.1), "flux": flux,
               "flux_err": np.full(n, F0 * max(noise, 1e-4)), "flag": np.zeros(n, dtype=np.int32),
               "stamp3": stamp, "stamp5": stamp5})
    t.meta["EPOCH"] = 3
    t.meta["SYSTEM"] = "XO-3b (2015 challenge)"  # the planet this synthetic epoch simulates
    return t


@pytest.fixture
def polygain(monkeypatch):
    """Register the test-only method for one test (the registry is restored afterwards)."""
    monkeypatch.setitem(base._REGISTRY, PolyGain.name, PolyGain)
    return PolyGain


@pytest.fixture
def trapezoid_epoch():
    """A synthetic epoch with a trapezoid eclipse (no astro package needed)."""
    time = 57000.0 + np.arange(0, 0.3, CADENCE_D)
    t_ecl = 57000.0 + 0.155
    shape = TrapezoidShape(time)
    table = make_epoch_table(t_ecl=t_ecl, visible=shape.visible_fraction(t_ecl), time=time)
    return {"table": table, "time": time, "t_ecl": t_ecl, "shape": shape}


@pytest.fixture(scope="session")
def kit():
    """The helpers of this file, for test modules (conftest cannot be imported directly)."""
    from types import SimpleNamespace
    return SimpleNamespace(TrapezoidShape=TrapezoidShape, PolyGain=PolyGain, gain=gain,
                           design=design, make_epoch_table=make_epoch_table, pointing=pointing,
                           TRUE_DEPTH=TRUE_DEPTH, TRUE_C1=TRUE_C1, TRUE_C2=TRUE_C2,
                           CADENCE_D=CADENCE_D, F0=F0)


@pytest.fixture(scope="session")
def xo3_epoch():
    """A synthetic XO-3b epoch built with the astro package's eclipse shape.

    The truth eclipse is 0.003 d after the catalogue ephemeris (so the fit has
    to move it), the data start 0.2 d before it and stop 0.17 d after it.
    """
    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.astro.eclipse import EclipseShape
    from eclipsebench.astro.orbit import eclipse_time_bmjd
    from eclipsebench.config.system import SystemSection

    system = get_system(SystemSection().name)  # the default planet, which reduce_epoch assumes
    t_pred = eclipse_time_bmjd(system, 57000.0)
    t_true = t_pred + 0.003
    time = t_true + np.arange(-0.2, 0.17, CADENCE_D)
    visible = EclipseShape(time, system).visible_fraction(t_true)

    def table(**kw):
        return make_epoch_table(t_ecl=t_true, visible=visible, time=time, **kw)

    return {"system": system, "t_true": t_true, "t_pred": t_pred, "time": time,
            "visible": visible, "table": table}
