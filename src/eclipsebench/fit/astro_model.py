"""The one astrophysical model that every decorrelation method shares.

The model of the stellar-system flux, normalised so that 1 is the star alone
(the flux during total eclipse), is::

    A(t) = R(t) * [1 + v(t) * p(t)]

- ``v(t)`` is the visible fraction of the planet (1 outside eclipse, 0 during
  totality): the physical shape of :class:`eclipsebench.astro.eclipse.EclipseShape`
  or a box of the same duration.
- ``p(t)`` is the planet-to-star flux ratio, a phase curve written so that
  ``p(t_ecl) = D`` exactly for every phase model; then ``F_out = 1 + D`` at the
  centre of occultation and ``F_in = 1``, so ``D`` is the paper's depth
  (Eq. ``eclipse_depth``: ``D = (F_out - F_in) / F_in``)::

      flat       p = D
      linear     p = D + c1 (t - t_ecl)
      quadratic  p = D + c1 (t - t_ecl) + c2 (t - t_ecl)^2
      sinusoid   p = D + c1 [cos(2 pi (t - t_ecl) / P) - 1] + c2 sin(2 pi (t - t_ecl) / P)

- ``R(t)`` is a multiplicative detector ramp: 1 (none), ``1 + r1 (t - t0)``
  (linear) or ``1 - a exp(-(t - t0) / tau)`` (exponential), ``t0`` the first
  frame. Its constant level is left to the systematics model (every method
  fits the flux normalisation).

The parameter vector is ``[depth, t_ecl_bmjd, phase coefficients..., ramp
coefficients...]`` (depth as a fraction, not ppm).
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from numba import njit

from ..astro.eclipse import EclipseShape
from ..errors import InputError

__all__ = ["AstroModel", "PHASE_MODELS", "RAMP_MODELS", "ECLIPSE_SHAPES", "box_visible_fraction",
           "system_period_days"]

PHASE_MODELS = ("flat", "linear", "quadratic", "sinusoid")
RAMP_MODELS = ("none", "linear", "exponential")
ECLIPSE_SHAPES = ("physical", "box")

_PHASE_NAMES = {
    "flat": (),
    "linear": ("c1_per_day",),
    "quadratic": ("c1_per_day", "c2_per_day2"),
    "sinusoid": ("c_cos", "c_sin"),
}
_RAMP_NAMES = {
    "none": (),
    "linear": ("ramp_slope_per_day",),
    "exponential": ("ramp_amplitude", "ramp_tau_days"),
}
# Typical magnitude of each parameter: sets finite-difference steps (1 % of it)
# and the size of the initial MCMC ball.
_SCALES = {"depth": 1e-4, "t_ecl_bmjd": 1e-3, "c1_per_day": 1e-3, "c2_per_day2": 1e-3,
           "c_cos": 1e-4, "c_sin": 1e-4, "ramp_slope_per_day": 1e-3, "ramp_amplitude": 1e-3,
           "ramp_tau_days": 1e-2}


class VisibleFraction(Protocol):
    """Anything with ``visible_fraction(t_ecl_bmjd) -> ndarray`` (the astro API)."""

    def visible_fraction(self, t_ecl_bmjd: float) -> np.ndarray: ...


def system_period_days(system: Any) -> float | None:
    """The orbital period of ``system`` in days, or None if it does not say."""
    for name in ("period_days", "period_d", "period"):
        value = getattr(system, name, None)
        if value is not None:
            return float(value)
    return None


def box_visible_fraction(time_bmjd: np.ndarray, t_ecl_bmjd: float, duration_d: float,
                         exposure_d: float) -> np.ndarray:
    """A box eclipse averaged over each exposure.

    The planet is invisible for ``|t - t_ecl| < duration_d / 2``; a frame of
    length ``exposure_d`` that straddles a contact sees the fraction of its
    exposure outside the box, which keeps the model continuous in ``t_ecl``
    (a fitter can move the box by less than a frame).
    """
    edge = (np.abs(np.asarray(time_bmjd) - t_ecl_bmjd) - 0.5 * duration_d) / exposure_d + 0.5
    return np.clip(edge, 0.0, 1.0)


def _half_depth_duration(time_bmjd: np.ndarray, visible: np.ndarray) -> float | None:
    """Time between the v = 0.5 crossings of ingress and egress, or None."""
    below = np.flatnonzero(visible < 0.5)
    if len(below) == 0 or below[0] == 0 or below[-1] == len(visible) - 1:
        return None
    i, j = below[0], below[-1]
    t_in = np.interp(0.5, [visible[i], visible[i - 1]], [time_bmjd[i], time_bmjd[i - 1]])
    t_out = np.interp(0.5, [visible[j], visible[j + 1]], [time_bmjd[j], time_bmjd[j + 1]])
    return float(t_out - t_in)


class AstroModel:
    """The eclipse, phase-curve and ramp model at fixed times.

    Parameters
    ----------
    time_bmjd : array_like, shape (n,)
        Times at which the model is evaluated (the method's data times).
    system : PlanetSystem or None
        The planetary system (:func:`eclipsebench.astro.catalogue.get_system`);
        gives the eclipse geometry and the period for the sinusoid. May be None
        when ``shape`` (and, for the sinusoid, ``period_d``) are given.
    phase : {"flat", "linear", "quadratic", "sinusoid"}
        Phase-curve model (Section 4.2 of the paper).
    ramp : {"none", "linear", "exponential"}
        Multiplicative detector ramp.
    eclipse_shape : {"physical", "box"}
        The orbit's eclipse shape, or a box of the same duration (measured
        between the half-depth points of ingress and egress, so the box removes
        the same planet flux as the physical eclipse).
    shape : object with ``visible_fraction(t_ecl_bmjd)``, optional
        Precomputed geometry at ``time_bmjd``; default
        ``EclipseShape(time_bmjd, system)``.
    period_d : float, optional
        Orbital period for the sinusoid (default: the system's).
    box_duration_d : float, optional
        Duration of the box eclipse (default: measured from the physical shape).

    Examples
    --------
    >>> import numpy as np
    >>> class Flat:  # a planet that is always fully visible
    ...     def visible_fraction(self, t_ecl_bmjd):
    ...         return np.ones(3)
    >>> m = AstroModel(np.array([0.0, 0.1, 0.2]), None, phase="flat", shape=Flat())
    >>> m.names
    ('depth', 't_ecl_bmjd')
    >>> m(np.array([0.002, 0.1]))
    array([1.002, 1.002, 1.002])
    """

    def __init__(self, time_bmjd, system: Any = None, *, phase: str = "quadratic",
                 ramp: str = "none", eclipse_shape: str = "physical",
                 shape: VisibleFraction | None = None, period_d: float | None = None,
                 box_duration_d: float | None = None) -> None:
        if phase not in PHASE_MODELS:
            raise InputError(f"--phase {phase!r}: expected one of {', '.join(PHASE_MODELS)}")
        if ramp not in RAMP_MODELS:
            raise InputError(f"--ramp {ramp!r}: expected one of {', '.join(RAMP_MODELS)}")
        if eclipse_shape not in ECLIPSE_SHAPES:
            raise InputError(f"eclipse_shape {eclipse_shape!r}: expected one of "
                             f"{', '.join(ECLIPSE_SHAPES)}")
        self.time_bmjd = np.ascontiguousarray(time_bmjd, dtype=float)
        if self.time_bmjd.ndim != 1 or len(self.time_bmjd) < 2:
            raise InputError("time_bmjd: expected at least two times")
        self.system = system
        self.phase = phase
        self.ramp = ramp
        self.eclipse_shape = eclipse_shape
        self.t_start_bmjd = float(self.time_bmjd.min())
        self.t_stop_bmjd = float(self.time_bmjd.max())
        if shape is None:
            if system is None:
                raise InputError("AstroModel: give a planetary system or a precomputed shape")
            shape = EclipseShape(self.time_bmjd, system)
        self.shape = shape
        self.period_d = period_d if period_d is not None else system_period_days(system)
        if phase == "sinusoid" and not self.period_d:
            raise InputError("--phase sinusoid: the orbital period is unknown (give period_d)")
        self.exposure_d = float(np.median(np.diff(np.sort(self.time_bmjd))))
        if not self.exposure_d > 0:
            raise InputError("time_bmjd: the frames do not advance in time")
        self.box_duration_d = None
        if eclipse_shape == "box":
            if box_duration_d is None:
                box_duration_d = self._measure_box_duration(system, shape)
                if box_duration_d is None:
                    raise InputError("eclipse_shape 'box': the data do not cover a whole eclipse "
                                     "centred in the time span, so its duration cannot be "
                                     "measured (give box_duration_d)")
            if not box_duration_d > 0:
                raise InputError("box_duration_d: expected a positive duration in days")
            self.box_duration_d = float(box_duration_d)
        self.names: tuple[str, ...] = ("depth", "t_ecl_bmjd") + _PHASE_NAMES[phase] \
            + _RAMP_NAMES[ramp]
        self.n_phase = len(_PHASE_NAMES[phase])
        self.n_ramp = len(_RAMP_NAMES[ramp])

    def _measure_box_duration(self, system: Any, shape: VisibleFraction) -> float | None:
        """Half-depth duration of the physical eclipse.

        With a system: on a fine grid (half a period wide, 20,001 points)
        around one of its eclipses. Without one: on the data times, with the
        eclipse placed at the middle of the data.
        """
        if system is not None and self.period_d:
            mid = 0.5 * (self.t_start_bmjd + self.t_stop_bmjd)
            grid = mid + np.linspace(-0.25, 0.25, 20001) * self.period_d
            return _half_depth_duration(grid, EclipseShape(grid, system).visible_fraction(mid))
        mid = 0.5 * (self.t_start_bmjd + self.t_stop_bmjd)
        return _half_depth_duration(self.time_bmjd, np.asarray(shape.visible_fraction(mid)))

    def __len__(self) -> int:
        return len(self.names)

    @property
    def scales(self) -> np.ndarray:
        """Typical magnitude of each parameter (finite-difference steps, MCMC ball)."""
        return np.array([_SCALES[n] for n in self.names])

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds (also the MCMC's uniform prior).

        The depth lies in (-0.1, 0.1); the eclipse centre inside the time span
        of the data; an exponential ramp has amplitude in (-0.2, 0.2) and a
        timescale between one frame and the time span.
        """
        lo = np.full(len(self.names), -np.inf)
        hi = np.full(len(self.names), np.inf)
        lo[0], hi[0] = -0.1, 0.1
        lo[1], hi[1] = self.t_start_bmjd, self.t_stop_bmjd
        if self.ramp == "exponential":
            k = 2 + self.n_phase
            lo[k], hi[k] = -0.2, 0.2
            lo[k + 1] = self.exposure_d
            hi[k + 1] = self.t_stop_bmjd - self.t_start_bmjd
        return lo, hi

    def initial(self, *, depth: float = 1e-3, t_ecl_bmjd: float | None = None) -> np.ndarray:
        """Starting parameters: the given depth and eclipse time, no phase variation or ramp."""
        if t_ecl_bmjd is None:
            t_ecl_bmjd = 0.5 * (self.t_start_bmjd + self.t_stop_bmjd)
        if not self.t_start_bmjd <= t_ecl_bmjd <= self.t_stop_bmjd:
            raise InputError(f"eclipse time {t_ecl_bmjd:.5f} BMJD lies outside the data "
                             f"({self.t_start_bmjd:.5f}-{self.t_stop_bmjd:.5f})")
        theta = np.zeros(len(self.names))
        theta[0] = depth
        theta[1] = t_ecl_bmjd
        if self.ramp == "exponential":
            theta[-1] = min(0.02, 0.25 * (self.t_stop_bmjd - self.t_start_bmjd))
        return theta

    def visible_fraction(self, t_ecl_bmjd: float) -> np.ndarray:
        """v(t): 1 = planet fully visible, 0 = fully eclipsed."""
        if self.eclipse_shape == "box":
            return box_visible_fraction(self.time_bmjd, t_ecl_bmjd, self.box_duration_d,
                                        self.exposure_d)
        return np.asarray(self.shape.visible_fraction(t_ecl_bmjd), dtype=float)

    def planet(self, theta) -> np.ndarray:
        """p(t), the planet-to-star flux ratio; p(t_ecl) = depth for every phase model."""
        theta = np.asarray(theta, dtype=float)
        depth, t_ecl = theta[0], theta[1]
        c = theta[2:2 + self.n_phase]
        dt = self.time_bmjd - t_ecl
        if self.phase == "flat":
            return np.full_like(dt, depth)
        if self.phase == "linear":
            return depth + c[0] * dt
        if self.phase == "quadratic":
            return depth + dt * (c[0] + c[1] * dt)
        arg = (2.0 * np.pi / self.period_d) * dt
        return depth + c[0] * (np.cos(arg) - 1.0) + c[1] * np.sin(arg)

    def ramp_factor(self, theta) -> np.ndarray:
        """R(t), the multiplicative ramp (1 when ``ramp="none"``)."""
        if self.ramp == "none":
            return np.ones_like(self.time_bmjd)
        r = np.asarray(theta, dtype=float)[2 + self.n_phase:]
        dt = self.time_bmjd - self.t_start_bmjd
        if self.ramp == "linear":
            return 1.0 + r[0] * dt
        return 1.0 - r[0] * np.exp(-dt / r[1])

    def __call__(self, theta) -> np.ndarray:
        """A(t) = R(t) [1 + v(t) p(t)], normalised to 1 = the star alone."""
        theta = np.asarray(theta, dtype=float)
        if len(theta) != len(self.names):
            raise ValueError(f"expected {len(self.names)} parameters {self.names}, "
                             f"got {len(theta)}")
        flux = 1.0 + self.visible_fraction(theta[1]) * self.planet(theta)
        if self.ramp != "none":
            flux *= self.ramp_factor(theta)
        return flux

    def batch(self, thetas) -> np.ndarray:
        """The model of every row of ``thetas`` at once: shape (m, n) (the MCMC's call).

        Each row equals ``self(theta)``: the same arithmetic, element by
        element. Flat, linear and quadratic phase curves with no or a linear
        ramp are computed in one compiled pass over the frames (no temporary
        arrays), the physical eclipse with :func:`numpy.interp`'s formula on
        the shape's table but an O(1) search; the sinusoid and the exponential
        ramp are broadcast with numpy (their ``sin``, ``cos``, ``exp`` stay
        numpy's).

        Parameters
        ----------
        thetas : array_like, shape (m, len(names))

        Examples
        --------
        >>> import numpy as np
        >>> class Flat:
        ...     def visible_fraction(self, t_ecl_bmjd):
        ...         return np.ones(3)
        >>> m = AstroModel(np.array([0.0, 0.1, 0.2]), None, phase="linear", shape=Flat())
        >>> m.batch([[0.002, 0.1, 0.0], [0.001, 0.1, 0.01]])
        array([[1.002, 1.002, 1.002],
               [1.   , 1.001, 1.002]])
        """
        thetas = np.atleast_2d(np.asarray(thetas, dtype=float))
        if thetas.ndim != 2 or thetas.shape[1] != len(self.names):
            raise ValueError(f"expected rows of {len(self.names)} parameters {self.names}, "
                             f"got shape {thetas.shape}")
        fused = self._fused_arguments(thetas)
        if fused is not None:
            return _astro_rows(self.time_bmjd, np.ascontiguousarray(thetas), *fused)
        t_ecl = thetas[:, 1]
        dt = self.time_bmjd - t_ecl[:, None]
        planet = self._planet_batch(thetas, dt)
        cols, visible = self._visible_fraction_batch(t_ecl)
        if cols is None:
            flux = 1.0 + visible * planet
        else:   # v = 1 outside cols: 1 + 1 * p is 1 + p exactly
            flux = 1.0 + planet
            flux[:, cols] = 1.0 + visible * planet[:, cols]
        if self.ramp != "none":
            flux *= self._ramp_factor_batch(thetas)
        return flux

    def _fused_arguments(self, thetas: np.ndarray) -> tuple | None:
        """The arguments of :func:`_astro_rows` after the times and thetas, or None.

        None (numpy broadcasting instead) for the sinusoid, the exponential
        ramp, a shape other than :class:`EclipseShape`'s table at these times,
        or eclipse times so far from the data that the shape would fold the
        offsets by a period.
        """
        if self.phase == "sinusoid" or self.ramp == "exponential":
            return None
        phase_code = ("flat", "linear", "quadratic").index(self.phase)
        ramp_at = 2 + self.n_phase if self.ramp == "linear" else -1
        if self.eclipse_shape == "box":
            return (phase_code, ramp_at, self.t_start_bmjd, True, 0.5 * self.box_duration_d,
                    self.exposure_d, *_NO_TABLE)
        shape = self.shape
        if not (isinstance(shape, EclipseShape) and shape.time_bmjd.shape == self.time_bmjd.shape
                and np.array_equal(shape.time_bmjd, self.time_bmjd)):
            return None
        table = self._shape_table(shape)
        half = 0.5 * shape.period
        t_ecl = thetas[:, 1]
        if (table is None or self.t_start_bmjd - t_ecl.max() < -half
                or self.t_stop_bmjd - t_ecl.min() >= half):
            return None
        return (phase_code, ramp_at, self.t_start_bmjd, False, 0.0, 1.0, *table[:3], *table[3:])

    def _planet_batch(self, thetas: np.ndarray, dt: np.ndarray) -> np.ndarray:
        """:meth:`planet` of every row (``dt = time - t_ecl`` of each row)."""
        depth = thetas[:, :1]
        c = thetas[:, 2:2 + self.n_phase]
        if self.phase == "flat":
            return np.broadcast_to(depth, dt.shape)
        if self.phase == "linear":
            return depth + c[:, :1] * dt
        if self.phase == "quadratic":
            return depth + dt * (c[:, :1] + c[:, 1:2] * dt)
        arg = (2.0 * np.pi / self.period_d) * dt
        return depth + c[:, :1] * (np.cos(arg) - 1.0) + c[:, 1:2] * np.sin(arg)

    def _ramp_factor_batch(self, thetas: np.ndarray) -> np.ndarray:
        """:meth:`ramp_factor` of every row."""
        r = thetas[:, 2 + self.n_phase:]
        dt = self.time_bmjd - self.t_start_bmjd
        if self.ramp == "linear":
            return 1.0 + r[:, :1] * dt
        return 1.0 - r[:, :1] * np.exp(-dt / r[:, 1:2])

    def _visible_fraction_batch(self, t_ecl: np.ndarray) -> tuple[np.ndarray | None, np.ndarray]:
        """:meth:`visible_fraction` of every eclipse time in ``t_ecl``.

        Returns ``(cols, v)``: ``v`` (m, len(cols)) at the frames ``cols``, the
        planet being wholly visible (v = 1) at every other frame; or ``(None,
        v)`` with ``v`` (m, n) at every frame.
        """
        if self.eclipse_shape == "box":
            return None, box_visible_fraction(self.time_bmjd, t_ecl[:, None],
                                              self.box_duration_d, self.exposure_d)
        shape = self.shape
        if not isinstance(shape, EclipseShape):
            return None, np.stack([self.visible_fraction(t) for t in t_ecl])
        table = self._shape_table(shape)
        times = shape.time_bmjd
        half = 0.5 * shape.period
        lo, hi = float(times.min() - t_ecl.max()), float(times.max() - t_ecl.min())
        if table is None or lo < -half or hi >= half:
            # no table to bound, or times a period apart: the shape's own fold and interpolation
            dt = times - t_ecl[:, None]
            return None, shape.at(dt.ravel(), 0.0).reshape(dt.shape)
        xp = table[0]
        cols = np.flatnonzero((times > t_ecl.min() + xp[0]) & (times < t_ecl.max() + xp[-1]))
        dt = times[cols] - t_ecl[:, None]
        return cols, _interp_table(dt, table)

    def _shape_table(self, shape: EclipseShape):
        """The eclipse shape's table and an O(1) search index for :func:`_interp_table` (cached).

        The shape interpolates a table of v against the offset from
        mid-eclipse (``EclipseShape.at``, :func:`numpy.interp` with v = 1
        beyond both ends); this reads it once. None if the shape keeps no
        such table (then the batch calls ``shape.at``).
        """
        cached = getattr(self, "_table_cache", None)
        if cached is not None and cached[0] is shape:
            return cached[1]
        xp = np.asarray(getattr(shape, "_offset", []), dtype=float)
        fp = np.asarray(getattr(shape, "_shape", []), dtype=float)
        table = None
        if xp.ndim == 1 and xp.shape == fp.shape and len(xp) >= 3 and np.all(np.diff(xp) > 0):
            table = _search_table(xp, fp)
        self._table_cache = (shape, table)
        return table

    def describe(self) -> dict[str, Any]:
        """The model's settings, for results and logs."""
        return {"phase": self.phase, "ramp": self.ramp, "eclipse_shape": self.eclipse_shape,
                "box_duration_d": self.box_duration_d, "period_d": self.period_d}


def _search_table(xp: np.ndarray, fp: np.ndarray) -> tuple:
    """``(xp, fp, slopes, start, step, index)`` for :func:`_interp_table`.

    ``index[k]`` is the last ``j`` with ``xp[j] <= start + k * step`` on a
    uniform grid whose step is the smallest spacing of ``xp`` (so a cell
    holds at most one table point); ``slopes`` are :func:`numpy.interp`'s.
    """
    step = float(np.min(np.diff(xp)))
    cells = np.arange(int(np.ceil((xp[-1] - xp[0]) / step)) + 2)
    index = np.searchsorted(xp, xp[0] + cells * step, side="right") - 1
    slopes = (fp[1:] - fp[:-1]) / (xp[1:] - xp[:-1])
    return (np.ascontiguousarray(xp), np.ascontiguousarray(fp), slopes, float(xp[0]), step,
            np.clip(index, 0, len(xp) - 2).astype(np.int64))


#: Placeholder table arguments of :func:`_astro_rows` for the box eclipse.
_NO_TABLE = (np.zeros(2), np.ones(2), np.zeros(1), 0.0, 1.0, np.zeros(1, dtype=np.int64))


@njit(cache=True)
def _astro_rows(time, thetas, phase_code, ramp_at, t_start, box, box_half, exposure,
                xp, fp, slopes, start, step, index):  # pragma: no cover - compiled
    """``AstroModel.__call__`` of every row of ``thetas``, one compiled pass per row.

    The expressions are those of :meth:`AstroModel.planet`,
    :func:`box_visible_fraction` (``box``) or :func:`_interp_table` (the
    physical shape's table), and :meth:`AstroModel.ramp_factor` (linear ramp
    when ``ramp_at >= 0``), in the same order, so each value is the same.
    """
    m, n = thetas.shape[0], len(time)
    out = np.empty((m, n))
    last = len(xp) - 1
    cells = len(index) - 1
    for i in range(m):
        depth, t_ecl = thetas[i, 0], thetas[i, 1]
        c0 = thetas[i, 2] if phase_code >= 1 else 0.0
        c1 = thetas[i, 3] if phase_code == 2 else 0.0
        slope = thetas[i, ramp_at] if ramp_at >= 0 else 0.0
        for k in range(n):
            dt = time[k] - t_ecl
            if phase_code == 0:
                p = depth
            elif phase_code == 1:
                p = depth + c0 * dt
            else:
                p = depth + dt * (c0 + c1 * dt)
            if box:
                v = min(max((abs(dt) - box_half) / exposure + 0.5, 0.0), 1.0)
            elif dt < xp[0] or dt > xp[last]:
                v = 1.0
            elif dt == xp[last]:
                v = fp[last]
            else:   # j: the last table point at or below dt (uniform index, then corrected)
                j = index[min(max(int((dt - start) / step), 0), cells)]
                while j > 0 and xp[j] > dt:
                    j -= 1
                while j < last - 1 and xp[j + 1] <= dt:
                    j += 1
                v = fp[j] if xp[j] == dt else slopes[j] * (dt - xp[j]) + fp[j]
            f = 1.0 + v * p
            if ramp_at >= 0:
                f = f * (1.0 + slope * (time[k] - t_start))
            out[i, k] = f
    return out


def _interp_table(x: np.ndarray, table: tuple) -> np.ndarray:
    """``numpy.interp(x, xp, fp, left=1, right=1)`` of a 2-D ``x``, with an O(1) search.

    Same formula as numpy's (``slope[j] * (x - xp[j]) + fp[j]``, ``fp[j]``
    where ``x == xp[j]``, ``fp[-1]`` at the last point), so the values are
    identical; ``j`` comes from the uniform index of :func:`_search_table`.
    """
    xp, fp, slopes, start, step, index = table
    return _interp_rows(np.ascontiguousarray(x, dtype=float), xp, fp, slopes, start, step, index)


@njit(cache=True)
def _interp_rows(x, xp, fp, slopes, start, step, index):  # pragma: no cover - compiled
    m, n = x.shape
    out = np.empty((m, n))
    last = len(xp) - 1
    cells = len(index) - 1
    for i in range(m):
        for k in range(n):
            xv = x[i, k]
            if xv < xp[0] or xv > xp[last]:
                out[i, k] = 1.0
            elif xv == xp[last]:
                out[i, k] = fp[last]
            else:
                j = index[min(max(int((xv - start) / step), 0), cells)]
                while j > 0 and xp[j] > xv:
                    j -= 1
                while j < last - 1 and xp[j + 1] <= xv:
                    j += 1
                out[i, k] = fp[j] if xp[j] == xv else slopes[j] * (xv - xp[j]) + fp[j]
    return out
