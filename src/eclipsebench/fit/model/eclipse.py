"""The eclipse's astrophysical model (``event="eclipse"``): :class:`EclipseModel`.

The model of the stellar-system flux, normalised so that 1 is the star alone
(the flux during total eclipse), is::

    A(t) = R(t) * [1 + v(t) * p(t)]

- ``v(t)`` is the visible fraction of the planet (1 outside eclipse, 0 during
  totality): the physical shape of :class:`eclipsebench.astro.eclipse.EclipseShape`
  or a box of the same duration.
- ``p(t)`` is the planet-to-star flux ratio, a phase curve written so that
  ``p(t_ecl) = D`` exactly for every phase model (flat, linear, quadratic,
  sinusoid: :mod:`.parts`); then ``F_out = 1 + D`` at the centre of
  occultation and ``F_in = 1``, so ``D`` is the paper's depth (Eq.
  ``eclipse_depth``: ``D = (F_out - F_in) / F_in``).
- ``R(t)`` is the multiplicative detector ramp (none, linear, exponential:
  :mod:`.parts`).

The parameter vector is ``[depth, t_ecl_bmjd, phase coefficients..., ramp
coefficients...]`` (depth as a fraction, not ppm).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...astro.eclipse import EclipseShape
from ...errors import InputError
from .base import AstroModel, EventSettings
from .kernels import _NO_TABLE, _astro_rows, _interp_table, _search_table
from .parts import (
    VisibleFraction,
    box_visible_fraction,
    half_depth_duration,
    system_period_days,
)

__all__ = ["EclipseModel"]


class _BoxEclipse:
    """v(t) of a box eclipse of ``duration_d`` at the data times, averaged over each frame
    (:func:`box_visible_fraction`)."""

    def __init__(self, time_bmjd: np.ndarray, duration_d: float, exposure_d: float) -> None:
        self.time_bmjd = time_bmjd
        self.duration_d = duration_d
        self.exposure_d = exposure_d

    def visible_fraction(self, t_ecl_bmjd: float) -> np.ndarray:
        return box_visible_fraction(self.time_bmjd, t_ecl_bmjd, self.duration_d, self.exposure_d)

    def rows(self, t_ecl: np.ndarray) -> tuple[np.ndarray | None, np.ndarray]:
        """``(None, v)``: v (m, n) of every eclipse time in ``t_ecl``."""
        return None, box_visible_fraction(self.time_bmjd, t_ecl[:, None], self.duration_d,
                                          self.exposure_d)

    def kernel_arguments(self, t_ecl: np.ndarray) -> tuple:
        """The shape's arguments of :func:`_astro_rows` (``box`` and its half-duration)."""
        return (True, 0.5 * self.duration_d, self.exposure_d, *_NO_TABLE, False)


class _PhysicalEclipse:
    """v(t) of the eclipse shape ``shape`` (:class:`EclipseShape` or any
    ``visible_fraction(t_ecl)``) at the data times."""

    def __init__(self, time_bmjd: np.ndarray, shape: VisibleFraction) -> None:
        self.time_bmjd = time_bmjd
        self.t_start_bmjd = float(time_bmjd.min())
        self.t_stop_bmjd = float(time_bmjd.max())
        self.shape = shape
        self._table_cache: tuple | None = None
        #: times in non-decreasing order: :func:`_astro_rows` bisects for the table's frames
        self.time_ordered = bool(np.all(time_bmjd[1:] >= time_bmjd[:-1]))
        #: (:meth:`kernel_arguments` but for the eclipse times, half a period), made once
        self._kernel_table: tuple | None = None

    def visible_fraction(self, t_ecl_bmjd: float) -> np.ndarray:
        return np.asarray(self.shape.visible_fraction(t_ecl_bmjd), dtype=float)

    def rows(self, t_ecl: np.ndarray) -> tuple[np.ndarray | None, np.ndarray]:
        """:meth:`visible_fraction` of every eclipse time in ``t_ecl``.

        Returns ``(cols, v)``: ``v`` (m, len(cols)) at the frames ``cols``, the
        planet being wholly visible (v = 1) at every other frame; or ``(None,
        v)`` with ``v`` (m, n) at every frame.
        """
        shape = self.shape
        if not isinstance(shape, EclipseShape):
            return None, np.stack([self.visible_fraction(t) for t in t_ecl])
        table = self._table(shape)
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

    def kernel_arguments(self, t_ecl: np.ndarray) -> tuple | None:
        """The shape's arguments of :func:`_astro_rows` (its table), or None: a shape other
        than :class:`EclipseShape`'s table at these times, or eclipse times so far from the
        data that the shape would fold the offsets by a period."""
        if self._kernel_table is None:   # once: the shape and the times do not change
            shape = self.shape
            arguments, half = None, 0.0
            if (isinstance(shape, EclipseShape) and shape.time_bmjd.shape == self.time_bmjd.shape
                    and np.array_equal(shape.time_bmjd, self.time_bmjd)):
                table = self._table(shape)
                if table is not None:
                    arguments = (False, 0.0, 1.0, *table[:3], *table[3:], self.time_ordered)
                    half = 0.5 * shape.period
            self._kernel_table = (arguments, half)
        arguments, half = self._kernel_table
        if (arguments is None or self.t_start_bmjd - t_ecl.max() < -half
                or self.t_stop_bmjd - t_ecl.min() >= half):
            return None
        return arguments

    def _table(self, shape: EclipseShape):
        """The eclipse shape's table and an O(1) search index for :func:`_interp_table` (cached).

        The shape interpolates a table of v against the offset from
        mid-eclipse (``EclipseShape.at``, :func:`numpy.interp` with v = 1
        beyond both ends); this reads it once. None if the shape keeps no
        such table (then the batch calls ``shape.at``).
        """
        if self._table_cache is not None:
            return self._table_cache[0]
        xp = np.asarray(getattr(shape, "_offset", []), dtype=float)
        fp = np.asarray(getattr(shape, "_shape", []), dtype=float)
        table = None
        if xp.ndim == 1 and xp.shape == fp.shape and len(xp) >= 3 and np.all(np.diff(xp) > 0):
            table = _search_table(xp, fp)
        self._table_cache = (table,)
        return table


class EclipseModel(AstroModel):
    """The eclipse, phase-curve and ramp model at fixed times: ``A = R [1 + v p]``.

    ``AstroModel(time, system, event="eclipse", ...)`` (the default event)
    builds one; the parameters are :class:`AstroModel`'s.

    Examples
    --------
    >>> import numpy as np
    >>> class Flat:  # a planet that is always fully visible
    ...     def visible_fraction(self, t_ecl_bmjd):
    ...         return np.ones(3)
    >>> m = EclipseModel(np.array([0.0, 0.1, 0.2]), None, phase="flat", shape=Flat())
    >>> m.names
    ('depth', 't_ecl_bmjd')
    >>> m(np.array([0.002, 0.1]))
    array([1.002, 1.002, 1.002])
    """

    event = "eclipse"

    def _setup(self, system: Any, settings: EventSettings) -> None:
        """The eclipse shape (physical or box), the period and the parameter names."""
        shape = settings.shape
        if shape is None:
            if system is None:
                raise InputError("AstroModel: give a planetary system or a precomputed shape")
            shape = EclipseShape(self.time_bmjd, system)
        self.shape = shape
        self.period_d = (settings.period_d if settings.period_d is not None
                         else system_period_days(system))
        if self.phase_term.needs_period and not self.period_d:
            raise InputError("--phase sinusoid: the orbital period is unknown (give period_d)")
        #: v(t): the box or the physical shape.
        self._eclipse: _BoxEclipse | _PhysicalEclipse
        if self.eclipse_shape == "box":
            self.box_duration_d = self._box_duration(system, shape, settings.box_duration_d)
            self._eclipse = _BoxEclipse(self.time_bmjd, self.box_duration_d, self.exposure_d)
        else:
            self._eclipse = _PhysicalEclipse(self.time_bmjd, shape)
        self.names = ("depth", "t_ecl_bmjd") + self.phase_term.names + self.ramp_term.names

    def _box_duration(self, system: Any, shape: VisibleFraction,
                      given_d: float | None) -> float:
        """The box eclipse's duration: ``given_d``, or measured (:meth:`_measure_box_duration`)."""
        if given_d is None:
            given_d = self._measure_box_duration(system, shape)
            if given_d is None:
                raise InputError("eclipse_shape 'box': the data do not cover a whole eclipse "
                                 "centred in the time span, so its duration cannot be "
                                 "measured (give box_duration_d)")
        if not given_d > 0:
            raise InputError("box_duration_d: expected a positive duration in days")
        return float(given_d)

    def _measure_box_duration(self, system: Any, shape: VisibleFraction) -> float | None:
        """Half-depth duration of the physical eclipse.

        With a system: on a fine grid (half a period wide, 20,001 points)
        around one of its eclipses. Without one: on the data times, with the
        eclipse placed at the middle of the data.
        """
        if system is not None and self.period_d:
            mid = 0.5 * (self.t_start_bmjd + self.t_stop_bmjd)
            grid = mid + np.linspace(-0.25, 0.25, 20001) * self.period_d
            return half_depth_duration(grid, EclipseShape(grid, system).visible_fraction(mid))
        mid = 0.5 * (self.t_start_bmjd + self.t_stop_bmjd)
        return half_depth_duration(self.time_bmjd, np.asarray(shape.visible_fraction(mid)))

    def visible_fraction(self, t_ecl_bmjd: float) -> np.ndarray:
        """v(t): 1 = planet fully visible, 0 = fully eclipsed (the physical shape or the box)."""
        return self._eclipse.visible_fraction(t_ecl_bmjd)

    def stellar_flux(self, theta) -> np.ndarray:
        """An eclipse has no transit: an error."""
        raise InputError("stellar_flux: the model is of an eclipse, not a transit")

    def _model(self, theta: np.ndarray) -> np.ndarray:
        """A(t) = R(t) [1 + v(t) p(t)], normalised to 1 = the star alone."""
        flux = 1.0 + self.visible_fraction(theta[1]) * self.planet(theta)
        return self._with_ramp(flux, theta)

    def _rows(self, thetas: np.ndarray) -> np.ndarray:
        """The model of every row at once (:meth:`batch`), each the same as ``self(theta)``.

        Flat, linear and quadratic phase curves with no or a linear ramp are
        computed in one compiled pass over the frames (no temporary arrays),
        the physical eclipse with :func:`numpy.interp`'s formula on the
        shape's table but an O(1) search; the sinusoid and the exponential
        ramp are broadcast with numpy (their ``sin``, ``cos``, ``exp`` stay
        numpy's).
        """
        fused = self._fused_arguments(thetas)
        if fused is not None:
            return _astro_rows(self.time_bmjd, np.ascontiguousarray(thetas), *fused)
        t_ecl = thetas[:, 1]
        dt = self.time_bmjd - t_ecl[:, None]
        planet = self._planet_batch(thetas, dt)
        cols, visible = self._eclipse.rows(t_ecl)
        if cols is None:
            flux = 1.0 + visible * planet
        else:   # v = 1 outside cols: 1 + 1 * p is 1 + p exactly
            flux = 1.0 + planet
            flux[:, cols] = 1.0 + visible * planet[:, cols]
        return self.ramp_term.apply_rows(flux, thetas[:, self._ramp_at:], self._since_start)

    def _fused_arguments(self, thetas: np.ndarray) -> tuple | None:
        """The arguments of :func:`_astro_rows` after the times and thetas, or None.

        None (numpy broadcasting instead) for the sinusoid, the exponential
        ramp, a shape other than :class:`EclipseShape`'s table at these times,
        or eclipse times so far from the data that the shape would fold the
        offsets by a period.
        """
        phase_code = self.phase_term.kernel_code
        ramp_at = self.ramp_term.kernel_index(self._ramp_at)
        if phase_code is None or ramp_at is None:
            return None
        shape_arguments = self._eclipse.kernel_arguments(thetas[:, 1])
        if shape_arguments is None:
            return None
        return (phase_code, ramp_at, self.t_start_bmjd, *shape_arguments)

    def _planet_batch(self, thetas: np.ndarray, dt: np.ndarray) -> np.ndarray:
        """:meth:`planet` of every row (``dt = time - t_ecl`` of each row)."""
        c = thetas[:, 2:2 + self.n_phase]
        return self.phase_term.rows(thetas[:, :1], c, dt, self.period_d)
