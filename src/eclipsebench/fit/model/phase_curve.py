"""The whole phase curve's astrophysical model (``event="phase-curve"``): :class:`PhaseCurveModel`.

Whole phase curves put both events and the planet's phase variation in one
model over several AORs::

    A(t) = R(t) O(t) [T(t) + v(t) p(t)]

- ``T(t)`` is the transit's stellar flux (:mod:`.transit`; ``rp_rs``
  free; a_rs, b and limb darkening fixed), its mid-transit at ``t_ecl`` plus
  the catalogue orbit's transit-minus-eclipse time; ``v(t)`` the eclipse's
  physical shape (:mod:`.eclipse`), which repeats every period;
- ``p(t)`` the harmonic phase curve of :func:`eclipsebench.astro.phase_curves.harmonic_curve`
  (``harmonic1``: ``D + a1 (cos phi - 1) + b1 sin phi``; ``harmonic2`` adds
  ``a2 (cos 2 phi - 1) + b2 sin 2 phi``; ``phi = 2 pi (t - t_ecl) / P``), the
  first and second harmonic of SPCA (Bell et al. 2021, MNRAS 504, 3316);
- ``R(t)`` the detector ramp (:mod:`.parts`);
- ``O(t)`` a flux offset ``1 + o_k`` for each AOR after the first (the step
  at each repointing, as SPCA fits it), from the table's ``aorkey``.

Its parameter vector is ``[depth, t_ecl_bmjd, rp_rs, phase_a1, phase_b1,
(phase_a2, phase_b2), ramp..., aor_offset_1, ...]``; each row is averaged
over its exposure (binned tables; :func:`~.parts.integration_offsets_d`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...astro.eclipse import EclipseShape
from ...astro.orbit import eclipse_time_bmjd, transit_time_bmjd
from ...astro.phase_curves import harmonic_summary
from ...errors import InputError
from ..names import PHASE_CURVE_MODELS
from .base import AstroModel, EventSettings
from .parts import (
    NONNEGATIVE_SCALE,
    TRANSIT_BOUNDS,
    FirstHarmonic,
    VisibleFraction,
    aor_order,
    integration_offsets_d,
    system_period_days,
)
from .settings import PhaseCurveSettings
from .transit import TransitGeometry, _TransitCurve

__all__ = ["PhaseCurveModel"]


class PhaseCurveModel(TransitGeometry, AstroModel):
    """A whole phase curve at fixed times: ``A = R O [T + v p]``, averaged over each exposure.

    ``AstroModel(time, system, event="phase-curve", phase="harmonic1", ...)``
    builds one; the parameters are :class:`AstroModel`'s (its own ``settings`` a
    :class:`~.settings.PhaseCurveSettings`: limb darkening, AOR offsets, exposure,
    non-negative planet; a/R*, b and the limb darkening stay fixed).
    """

    event = "phase-curve"
    phase_models = PHASE_CURVE_MODELS
    settings_class = PhaseCurveSettings

    def _setup(self, system: Any, settings: EventSettings) -> None:
        """T(t) as the transit's, v(t) as the eclipse's, p(t) harmonic, and the AOR
        offsets O(t)."""
        if system is None:
            raise InputError("event 'phase-curve': give the planetary system (its orbit)")
        if self.eclipse_shape != "physical":
            raise InputError(f"eclipse_shape {self.eclipse_shape!r}: a phase curve's eclipses "
                             "repeat every orbit; use 'physical'")
        period = settings.period_d if settings.period_d is not None else system_period_days(system)
        self.period_d = float(period) if period is not None else float("nan")
        if not self.period_d > 0:
            raise InputError("event 'phase-curve': the orbital period is unknown (give period_d)")
        # the transit exactly as event "transit" makes it, with Rp/R* free and a/R*, b and
        # the limb darkening fixed (their defaults there)
        self.transit_free = ()
        self._set_transit_geometry(system, settings.own.limb_darkening_q)
        self._set_exposures(system, settings.shape, settings.own.exposure_s)
        # the catalogue orbit's mid-transit minus mid-eclipse (observed, light travel included);
        # the fitted eclipse time carries every transit with it (one orbit, period fixed)
        t_e = eclipse_time_bmjd(system, self.t_start_bmjd)
        self.transit_minus_eclipse_d = float(transit_time_bmjd(system, t_e - 0.5 * self.period_d)
                                             - t_e)
        self.transit_phase_rad = 2.0 * math.pi * self.transit_minus_eclipse_d / self.period_d
        self._set_aors(settings.own.aorkey)
        self.nonnegative_planet = bool(settings.own.nonnegative_planet)
        self.n_priors = 1 if self.nonnegative_planet else 0
        self.n_shape = 1   # rp_rs
        self.names = ("depth", "t_ecl_bmjd", "rp_rs") + self.phase_term.names \
            + self.ramp_term.names + tuple(f"aor_offset_{k}" for k in range(1, self.n_aor + 1))

    def _set_exposures(self, system: Any, shape: VisibleFraction | None,
                       exposure_s: float | None) -> None:
        """The sub-exposure times of every row, and v(t) and T(t) at them."""
        # integration over each row's exposure (binned tables: one row per 64-frame cube)
        self.exposure_s = float(self.exposure_d * 86400.0 if exposure_s is None else exposure_s)
        self._sub_offsets_d = integration_offsets_d(self.exposure_s)
        n_sub = len(self._sub_offsets_d)
        self._sub_time = (self.time_bmjd if n_sub == 1 else
                          (self.time_bmjd[:, None] + self._sub_offsets_d[None, :]).ravel())
        if shape is not None and n_sub > 1:
            raise InputError("shape: a precomputed eclipse shape cannot be integrated over "
                             f"{self.exposure_s:g} s exposures (leave it out)")
        self.shape = shape if shape is not None else EclipseShape(self._sub_time, system)
        #: v(t) at the sub-exposure times (``shape``).
        self._visible: VisibleFraction = self.shape
        self._transit = _TransitCurve(self._sub_time, system, fixed_orbit=True)
        #: The parts last computed, by the parameters they read (:meth:`_remembered`).
        self._memory: dict[str, list[tuple[tuple, np.ndarray]]] = {}

    def _set_aors(self, aorkey) -> None:
        """One flux offset (1 + o_k) per AOR after the first (Bell et al. 2021, SPCA)."""
        self.aor_keys = ()
        self._aor_rank = None
        if aorkey is not None:
            aorkey = np.asarray(aorkey)
            if aorkey.shape != self.time_bmjd.shape:
                raise InputError(f"aorkey: expected {len(self.time_bmjd)} values, got "
                                 f"{aorkey.shape}")
            keys, self._aor_rank = aor_order(self.time_bmjd, aorkey)
            self.aor_keys = tuple(k.item() if hasattr(k, "item") else k for k in keys)
        self.n_aor = max(len(self.aor_keys) - 1, 0)

    # ------------------------------------------------------------------ bounds and start
    def _bound_event(self, lo: np.ndarray, hi: np.ndarray) -> None:
        """The eclipse time within half a period of the data (the first eclipse may precede
        them), Rp/R* in [0, 0.5], each AOR offset in (-0.5, 0.5)."""
        lo[1] -= 0.5 * self._period()
        hi[1] += 0.5 * self._period()
        lo[2], hi[2] = TRANSIT_BOUNDS["rp_rs"]
        if self.n_aor:
            lo[-self.n_aor:], hi[-self.n_aor:] = -0.5, 0.5

    def _check_event_time(self, t_bmjd: float) -> None:
        """Refuse a starting eclipse time more than half a period from the data."""
        lo, hi = self.bounds
        if not lo[1] <= t_bmjd <= hi[1]:
            raise InputError(f"eclipse time {t_bmjd:.5f} BMJD lies more than half a period "
                             f"from the data ({self.t_start_bmjd:.5f}-{self.t_stop_bmjd:.5f})")

    def _start_event(self, theta: np.ndarray, *, depth: float | None,
                     rp_rs: float | None) -> None:
        """``depth`` (default 1e-3) and the catalogue's ``rp_rs`` (unless given)."""
        super()._start_event(theta, depth=depth, rp_rs=rp_rs)
        theta[2] = self.rp_rs_catalogue if rp_rs is None else rp_rs

    # ------------------------------------------------------------------ the model's parts
    def _integrated(self, values: np.ndarray) -> np.ndarray:
        """The mean over each row's sub-exposures of values at ``_sub_time``."""
        n_sub = len(self._sub_offsets_d)
        return values if n_sub == 1 else values.reshape(-1, n_sub).mean(axis=1)

    def visible_fraction(self, t_ecl_bmjd: float) -> np.ndarray:
        """v(t) of the eclipse shape, averaged over each row's exposure."""
        return self._integrated(np.asarray(self._visible.visible_fraction(t_ecl_bmjd),
                                           dtype=float))

    def _remembered(self, part: str, key: tuple, compute) -> np.ndarray:
        """``compute()`` for ``key`` (the parameters the part reads), remembered for the last
        two keys of each part, read-only.

        A finite-difference Jacobian moves one parameter at a time, so most of its columns
        find the transit, the eclipse shape and the harmonics as the others left them (a
        whole phase curve's least squares spent about 40 % of its time recomputing them).
        """
        memory = self._memory.setdefault(part, [])
        for known, value in memory:
            if known == key:
                return value
        value = np.asarray(compute())
        value.flags.writeable = False
        memory[:] = [(key, value), *memory[:1]]
        return value

    def _stellar_sub(self, theta: np.ndarray) -> np.ndarray:
        """T(t) at the sub-exposure times (Rp/R* is ``theta[2]``)."""
        v = self.transit_values(theta)
        args = (float(theta[2]), float(theta[1]) + self.transit_minus_eclipse_d,
                v["a_rs"], v["inc_deg"], v["u1"], v["u2"])
        return self._remembered("transit", args, lambda: self._transit(*args))

    def _planet_at(self, theta: np.ndarray, time: np.ndarray) -> np.ndarray:
        """p(t) at ``time``; at the sub-exposure times the harmonics of the eclipse time
        ``theta[1]`` are remembered (:meth:`_remembered`)."""
        term = self.phase_term
        if time is not self._sub_time or not isinstance(term, FirstHarmonic):
            return super()._planet_at(theta, time)
        t_ecl = float(theta[1])
        terms = self._remembered("harmonics", (t_ecl,),
                                 lambda: np.stack(term.terms(time - t_ecl, self.period_d)))
        k = 2 + self.n_shape
        return term.from_terms(self._planet_level(theta), theta[k:k + self.n_phase], terms)

    def stellar_flux(self, theta) -> np.ndarray:
        """T(t): the transits follow the eclipse time (``t_ecl + transit_minus_eclipse_d``,
        modulo the period), averaged over each row's exposure."""
        return self._integrated(self._stellar_sub(theta))

    def aor_factor(self, theta) -> np.ndarray:
        """O(t): ``1`` in the first AOR, ``1 + aor_offset_k`` in the k-th after it."""
        if not self.n_aor:
            return np.ones_like(self.time_bmjd)
        theta = np.asarray(theta, dtype=float)
        levels = np.concatenate([[1.0], 1.0 + theta[len(self.names) - self.n_aor:]])
        return levels[self._aor_rank]

    def phase_summary(self, theta) -> dict[str, float]:
        """What the literature reports of the fitted phase curve.

        :func:`~eclipsebench.astro.phase_curves.harmonic_summary` of the depth and
        harmonics, the night side at this orbit's mid-transit phase: keys
        ``phase_amplitude``, ``phase_offset_deg`` (east positive),
        ``nightside_flux``, ``planet_flux_min`` (fractions of the star's flux).
        """
        theta = np.asarray(theta, dtype=float)
        k = 2 + self.n_shape
        return harmonic_summary(float(theta[0]), theta[k:k + self.n_phase],
                                transit_phase_rad=self.transit_phase_rad)

    def _model(self, theta: np.ndarray) -> np.ndarray:
        """A(t) = R(t) O(t) [T(t) + v(t) p(t)], T, v and p averaged over each exposure."""
        t_ecl = float(theta[1])
        v = self._remembered("visible", (t_ecl,),
                             lambda: np.asarray(self._visible.visible_fraction(t_ecl), dtype=float))
        flux = self._integrated(self._stellar_sub(theta) + v * self._planet_at(theta,
                                                                               self._sub_time))
        flux = self._with_ramp(flux, theta)
        if self.n_aor:
            flux *= self.aor_factor(theta)
        return flux

    # ------------------------------------------------------------------ priors
    def prior_residuals(self, theta) -> np.ndarray:
        """With ``nonnegative_planet``: one penalty residual, ``min(p_min, 0) /
        NONNEGATIVE_SCALE`` (0 while the planet's flux stays non-negative over the
        orbit); else none."""
        theta = np.asarray(theta, dtype=float)
        if not self.nonnegative_planet:
            return np.zeros(0)
        p_min = self.phase_summary(theta)["planet_flux_min"]
        return np.array([min(p_min, 0.0) / NONNEGATIVE_SCALE])

    def log_prior_batch(self, thetas) -> np.ndarray:
        """With ``nonnegative_planet``: ``-inf`` where the planet's flux goes negative
        somewhere in the orbit, else 0 (0 everywhere without it)."""
        thetas = np.atleast_2d(np.asarray(thetas, dtype=float))
        out = np.zeros(len(thetas))
        if self.nonnegative_planet:
            p_min = np.array([self.phase_summary(t)["planet_flux_min"] for t in thetas])
            out[p_min < 0.0] = -np.inf
        return out

    def describe(self) -> dict[str, Any]:
        """The model's settings, for results and logs, with the phase curve's own."""
        out = super().describe()
        out.update({"event": "phase-curve", "transit_fixed": dict(self.transit_fixed),
                    "transit_minus_eclipse_d": self.transit_minus_eclipse_d,
                    "transit_phase_deg": math.degrees(self.transit_phase_rad),
                    "exposure_s": self.exposure_s,
                    "n_subexposures": len(self._sub_offsets_d),
                    "aorkeys": list(self.aor_keys),
                    "nonnegative_planet": self.nonnegative_planet})
        return out
