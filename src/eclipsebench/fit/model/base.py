"""What every event's astrophysical model shares: :class:`AstroModel`, their base.

The model is built per event, one subclass each: :class:`~.eclipse.EclipseModel`
(``event="eclipse"``), :class:`~.transit.TransitModel` (``"transit"``) and
:class:`~.phase_curve.PhaseCurveModel` (``"phase-curve"``), each composed
with a phase term and a ramp (:mod:`.parts`). ``AstroModel(..., event=...)``
builds the event's subclass (``__new__`` picks it by its ``event``), so every
caller keeps one constructor; import it from :mod:`eclipsebench.fit.model`, which loads
every event's module.

The base holds the times, the parameter names and their scales, the checks of
the settings and of the parameter count, the bounds and starting values that
every event shares (the size, the event's time, the ramp), the eclipse's depth
conversions and the Gaussian priors (which an event overrides where it
differs), and the description of the settings. Each event's class fills in
its setup, ``visible_fraction``, ``stellar_flux`` and the model itself
(``_model``), the base's abstract methods. Typed code builds a model with
:meth:`AstroModel.build` (a type checker refuses to call an abstract class);
``AstroModel(...)`` gives the same object.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ...astro.events import Event, event_for
from ...errors import InputError
from ..names import ECLIPSE_SHAPES, EVENTS, PHASE_MODELS, RAMP_MODELS
from .parts import (
    DEPTH_BOUNDS,
    PHASE_TERMS,
    RAMPS,
    SCALES,
    VisibleFraction,
    known_period,
)
from .settings import EclipseSettings, OwnSettings

__all__ = ["AstroModel", "EventSettings"]


@dataclass(frozen=True)
class EventSettings:
    """What :class:`AstroModel` hands to its event's setup: the keywords every event may
    read (``shape``, ``period_d``, ``box_duration_d``) and the event's own settings
    (``own``, :mod:`.settings`)."""

    shape: VisibleFraction | None
    period_d: float | None
    box_duration_d: float | None
    own: Any


class AstroModel(ABC):
    """The astrophysical model of one event at fixed times: ``AstroModel(...)`` builds the
    event's subclass.

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
    event : {"eclipse", "transit", "phase-curve"}
        The event fitted: :class:`~.eclipse.EclipseModel`,
        :class:`~.transit.TransitModel` or
        :class:`~.phase_curve.PhaseCurveModel`. A transit needs
        ``system`` (its orbit) and ignores ``eclipse_shape``, ``shape`` and
        ``box_duration_d``. A whole phase curve (``phase`` "harmonic1" or
        "harmonic2") needs ``system`` and the physical eclipse shape. A
        subclass called directly models its own event (``event`` may be left
        out).
    settings : EclipseSettings, TransitSettings or PhaseCurveSettings, optional
        The event's own settings (:mod:`.settings`: a transit's free
        parameters, priors and limb darkening; a phase curve's limb darkening,
        AOR offsets, exposure and non-negative planet); default: the event's
        class with its defaults. Another event's settings are refused.

    Examples
    --------
    >>> import numpy as np
    >>> from eclipsebench.fit.model import AstroModel
    >>> class Flat:  # a planet that is always fully visible
    ...     def visible_fraction(self, t_ecl_bmjd):
    ...         return np.ones(3)
    >>> m = AstroModel(np.array([0.0, 0.1, 0.2]), None, phase="flat", shape=Flat())
    >>> type(m).__name__, m.event, m.names
    ('EclipseModel', 'eclipse', ('depth', 't_ecl_bmjd'))
    >>> m(np.array([0.002, 0.1]))
    array([1.002, 1.002, 1.002])

    A transit of the 2015 challenge's XO-3b, limb darkening free:

    >>> from eclipsebench.astro.catalogue import get_system
    >>> xo3 = get_system("XO-3b (2015 challenge)")
    >>> t = xo3.t_transit_bmjd + np.linspace(-0.1, 0.1, 5)
    >>> from eclipsebench.fit.model import TransitSettings
    >>> tr = AstroModel(t, xo3, phase="flat", event="transit",
    ...                 settings=TransitSettings(free=("q1", "q2")))
    >>> tr.names
    ('rp_rs', 't_transit_bmjd', 'q1', 'q2')
    >>> tr(tr.initial()).round(5).tolist()
    [1.0, 0.99487, 0.99167, 0.99488, 1.0]
    >>> round(tr.depth_ppm(0.0906), 2)
    8208.36
    """

    #: The event a subclass models (``event``), which also labels its results.
    event: ClassVar[str] = ""
    #: The phase models the event offers.
    phase_models: ClassVar[tuple[str, ...]] = PHASE_MODELS
    #: The class of the event's own settings (:mod:`.settings`), given as ``settings``.
    settings_class: ClassVar[type[OwnSettings]] = EclipseSettings
    #: Each event's subclass, registered as it is defined (:meth:`__init_subclass__`).
    _event_classes: ClassVar[dict[str, type[AstroModel]]] = {}
    #: The facts of the event that callers branch on (:mod:`eclipsebench.astro.events`):
    #: its time key, conjunction, size of a depth...; set from ``event`` as a subclass is
    #: defined.
    facts: ClassVar[Event]
    #: Whether the event spans a whole orbit over several AORs: a flux offset per AOR after
    #: the first (from the table's ``aorkey``) and a harmonic phase curve that
    #: :meth:`phase_summary` summarises (a phase curve's; not an eclipse's or a transit's).
    #: The event's fact (:attr:`facts`), set with it.
    whole_orbit: ClassVar[bool] = False
    #: A phase curve's AORs in time order (:attr:`n_aor` offsets after the first); none
    #: for the other events.
    aor_keys: tuple = ()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Register a subclass that names its own ``event`` (not one that inherits it), with
        that event's facts."""
        super().__init_subclass__(**kwargs)
        if cls.__dict__.get("event"):
            cls.facts = event_for(cls.event)
            cls.whole_orbit = cls.facts.whole_orbit
            AstroModel._event_classes[cls.event] = cls

    @staticmethod
    def event_class(event: str | None) -> type[AstroModel]:
        """The model class of ``event`` (None: the eclipse's)."""
        event = "eclipse" if event is None else event
        if event not in EVENTS:
            raise InputError(f"--event {event!r}: expected one of {', '.join(EVENTS)}")
        if event not in AstroModel._event_classes:
            raise InputError(f"event {event!r}: its model is not loaded (import AstroModel "
                             "from eclipsebench.fit.model)")
        return AstroModel._event_classes[event]

    @classmethod
    def build(cls, *args: Any, event: str | None = None, **kwargs: Any) -> AstroModel:
        """The model of ``event``: what ``AstroModel(..., event=...)`` gives, in a form a
        type checker accepts (the base is abstract)."""
        return AstroModel.event_class(event)(*args, event=event, **kwargs)

    def __new__(cls, *args: Any, event: str | None = None, **kwargs: Any) -> AstroModel:
        """The event's subclass when called as ``AstroModel(...)``, else ``cls`` itself."""
        if cls is not AstroModel:
            return super().__new__(cls)
        return super().__new__(AstroModel.event_class(event))

    def __init__(self, time_bmjd, system: Any = None, *, phase: str = "quadratic",
                 ramp: str = "none", eclipse_shape: str = "physical",
                 shape: VisibleFraction | None = None, period_d: float | None = None,
                 box_duration_d: float | None = None, event: str | None = None,
                 settings: OwnSettings | None = None) -> None:
        if event is not None and event != self.event:
            raise InputError(f"event {event!r}: {type(self).__name__} models event "
                             f"'{self.event}'")
        if phase not in self.phase_models:
            raise InputError(f"--phase {phase!r}: expected one of {', '.join(self.phase_models)} "
                             f"(event '{self.event}')")
        if ramp not in RAMP_MODELS:
            raise InputError(f"--ramp {ramp!r}: expected one of {', '.join(RAMP_MODELS)}")
        own = self.settings_class() if settings is None else settings
        if not isinstance(own, self.settings_class):
            raise InputError(f"{type(own).__name__}: the settings of another event; event "
                             f"'{self.event}' takes {self.settings_class.__name__}")
        if eclipse_shape not in ECLIPSE_SHAPES:
            raise InputError(f"eclipse_shape {eclipse_shape!r}: expected one of "
                             f"{', '.join(ECLIPSE_SHAPES)}")
        self.time_bmjd = np.ascontiguousarray(time_bmjd, dtype=float)
        if self.time_bmjd.ndim != 1 or len(self.time_bmjd) < 2:
            raise InputError("time_bmjd: expected at least two times")
        self.system = system
        self.phase = phase
        self.ramp = ramp
        #: The phase model's p(t) and the ramp's R(t) (:mod:`.parts`).
        self.phase_term = PHASE_TERMS[phase]
        self.ramp_term = RAMPS[ramp]
        self.n_phase = len(self.phase_term.names)
        self.n_ramp = len(self.ramp_term.names)
        self.eclipse_shape = eclipse_shape
        self.t_start_bmjd = float(self.time_bmjd.min())
        self.t_stop_bmjd = float(self.time_bmjd.max())
        #: Time since the first frame, the ramp's argument.
        self._since_start = self.time_bmjd - self.t_start_bmjd
        self.n_shape = 0          # parameters between the event's time and the phase's
        self.priors: dict[str, tuple[float, float]] = {}
        self.n_priors = 0
        self.n_aor = 0            # a phase curve's AOR offsets
        self.exposure_d = float(np.median(np.diff(np.sort(self.time_bmjd))))
        if not self.exposure_d > 0:
            raise InputError("time_bmjd: the frames do not advance in time")
        self.box_duration_d: float | None = None
        self.period_d: float | None = None
        self.shape: VisibleFraction | None = None
        self.names: tuple[str, ...] = ()
        self._setup(system, EventSettings(shape, period_d, box_duration_d, own))

    @abstractmethod
    def _setup(self, system: Any, settings: EventSettings) -> None:
        """The event's own settings, its geometry and its parameter names."""

    def __len__(self) -> int:
        return len(self.names)

    def _period(self) -> float:
        """The orbital period (days); the events and phase models that use it require it."""
        return known_period(self.period_d)

    @property
    def _ramp_at(self) -> int:
        """Index of the ramp's first parameter (after the size, the time, the event's
        shape parameters and the phase coefficients)."""
        return 2 + self.n_shape + self.n_phase

    @property
    def scales(self) -> np.ndarray:
        """Typical magnitude of each parameter (finite-difference steps, MCMC ball)."""
        return np.array([SCALES["aor_offset" if n.startswith("aor_offset_") else n]
                         for n in self.names])

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds (also the MCMC's uniform prior).

        The depth lies in (-0.1, 0.1); the eclipse centre inside the time span
        of the data; an exponential ramp has amplitude in (-0.2, 0.2) and a
        timescale between one frame and the time span. A transit's Rp/R* lies
        in [0, 0.5], its mid-time inside the data, a/R* in [1.5, 200], b in
        [0, 1.5] and q1, q2 in [0, 1]. A phase curve's eclipse time lies
        within half a period of the data (its first eclipse may precede them),
        its Rp/R* in [0, 0.5] and each AOR offset in (-0.5, 0.5).
        """
        lo = np.full(len(self.names), -np.inf)
        hi = np.full(len(self.names), np.inf)
        lo[0], hi[0] = DEPTH_BOUNDS
        lo[1], hi[1] = self.t_start_bmjd, self.t_stop_bmjd
        self._bound_event(lo, hi)
        self.ramp_term.bound(lo, hi, self._ramp_at, self.exposure_d,
                             self.t_stop_bmjd - self.t_start_bmjd)
        return lo, hi

    def _bound_event(self, lo: np.ndarray, hi: np.ndarray) -> None:
        """Set the event's own bounds in place (default: none)."""
        return None   # a hook: nothing to do by default

    def initial(self, *, depth: float | None = None, t_event_bmjd: float | None = None,
                rp_rs: float | None = None) -> np.ndarray:
        """Starting parameters: no phase variation or ramp, and

        - an eclipse: ``depth`` (default 1e-3) at ``t_event_bmjd`` (mid-eclipse);
        - a transit: ``rp_rs`` (default the catalogue's) at ``t_event_bmjd``
          (mid-transit), free a_rs, b, q1, q2 at their prior means or else
          their fixed values;
        - a phase curve: ``depth`` at ``t_event_bmjd`` (an eclipse within half a
          period of the data), the catalogue's ``rp_rs``, no phase variation,
          AOR offsets 0.

        The time defaults to the middle of the data.
        """
        if t_event_bmjd is None:
            t_event_bmjd = 0.5 * (self.t_start_bmjd + self.t_stop_bmjd)
        self._check_event_time(t_event_bmjd)
        theta = np.zeros(len(self.names))
        self._start_event(theta, depth=depth, rp_rs=rp_rs)
        theta[1] = t_event_bmjd
        self.ramp_term.start(theta, self._ramp_at, self.t_stop_bmjd - self.t_start_bmjd)
        return theta

    def _check_event_time(self, t_bmjd: float) -> None:
        """Refuse a starting event time outside the data."""
        if not self.t_start_bmjd <= t_bmjd <= self.t_stop_bmjd:
            raise InputError(f"{self.event} time {t_bmjd:.5f} BMJD lies outside the data "
                             f"({self.t_start_bmjd:.5f}-{self.t_stop_bmjd:.5f})")

    def _start_event(self, theta: np.ndarray, *, depth: float | None,
                     rp_rs: float | None) -> None:
        """Set the event's starting size (and shape parameters) in place (default: the
        depth, 1e-3 unless given)."""
        theta[0] = 1e-3 if depth is None else depth

    # ------------------------------------------------------------------ the model's parts
    @abstractmethod
    def visible_fraction(self, t_event_bmjd: float) -> np.ndarray:
        """v(t) about the event time: 1 = planet fully visible, 0 = fully eclipsed."""

    @abstractmethod
    def stellar_flux(self, theta) -> np.ndarray:
        """T(t), the star's flux in transit (1 outside)."""

    def planet(self, theta) -> np.ndarray:
        """p(t), the planet-to-star flux ratio; p(t_ecl) = depth for every phase model."""
        return self._planet_at(np.asarray(theta, dtype=float), self.time_bmjd)

    def _planet_level(self, theta: np.ndarray) -> float:
        """p at the event's time: the depth (an eclipse's and a phase curve's)."""
        return theta[0]

    def _planet_at(self, theta: np.ndarray, time: np.ndarray) -> np.ndarray:
        """p(t) at ``time``: the phase term about the event's time ``theta[1]``."""
        k = 2 + self.n_shape
        return self.phase_term.value(self._planet_level(theta), theta[k:k + self.n_phase],
                                     time - theta[1], self.period_d)

    def ramp_factor(self, theta) -> np.ndarray:
        """R(t), the multiplicative ramp (1 when ``ramp="none"``)."""
        r = np.asarray(theta, dtype=float)[self._ramp_at:]
        return self.ramp_term.factor(r, self._since_start)

    def _with_ramp(self, flux: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """``flux`` times R(t) of ``theta``, in place (``flux`` itself without a ramp)."""
        return self.ramp_term.apply(flux, theta[self._ramp_at:], self._since_start)

    def aor_factor(self, theta) -> np.ndarray:
        """O(t), a phase curve's AOR offsets: 1 throughout (no offsets)."""
        return np.ones_like(self.time_bmjd)

    def phase_summary(self, theta) -> dict[str, float]:
        """What the literature reports of the fitted phase curve (a phase curve only)."""
        raise InputError("phase_summary: the model is not a whole phase curve")

    # ------------------------------------------------------------------ evaluation
    def __call__(self, theta) -> np.ndarray:
        """A(t), normalised to 1 = the star alone (the event's formula: its class)."""
        theta = np.asarray(theta, dtype=float)
        if len(theta) != len(self.names):
            raise ValueError(f"expected {len(self.names)} parameters {self.names}, "
                             f"got {len(theta)}")
        return self._model(theta)

    @abstractmethod
    def _model(self, theta: np.ndarray) -> np.ndarray:
        """A(t) of a parameter vector of the right length."""

    def batch(self, thetas) -> np.ndarray:
        """The model of every row of ``thetas`` at once: shape (m, n) (the MCMC's call).

        Each row equals ``self(theta)``: the same arithmetic, element by
        element. An eclipse is computed for all rows at once
        (:meth:`.eclipse.EclipseModel.batch`); a transit or a phase
        curve row by row (:meth:`__call__`).

        Parameters
        ----------
        thetas : array_like, shape (m, len(names))

        Examples
        --------
        >>> import numpy as np
        >>> from eclipsebench.fit.model import AstroModel
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
        return self._rows(thetas)

    def _rows(self, thetas: np.ndarray) -> np.ndarray:
        """The model of every row (checked): by default :meth:`__call__` of each."""
        return np.stack([self(theta) for theta in thetas])

    # ------------------------------------------------------------------ the event's depth
    def depth_ppm(self, size: float) -> float:
        """The event's depth (ppm) of its size parameter ``names[0]``.

        An eclipse's size is its depth (``size * 1e6``); a transit's is Rp/R*,
        whose depth is the geometric ``rp_rs^2 * 1e6`` (the limb-darkened flux
        drop at mid-transit is deeper).
        """
        return float(size * 1e6)

    def depth_error_ppm(self, size: float, error: float) -> float:
        """An error of the size parameter as an error of the depth (ppm), to first order."""
        return float(error * 1e6)

    def size_per_depth(self, size: float) -> float:
        """d size / d depth at ``size``: 1 for an eclipse, ``1 / (2 rp_rs)`` for a transit."""
        return 1.0

    def depth_difference_ppm(self, lower: float, upper: float) -> float:
        """``depth(upper) - depth(lower)`` in ppm (a posterior interval's side)."""
        return float((upper - lower) * 1e6)

    @classmethod
    def depth_limit_ppm(cls) -> float:
        """The deepest event (ppm) a fit can return: the depth of its size's upper bound
        (an eclipse's and a phase curve's ``DEPTH_BOUNDS[1]``)."""
        return float(DEPTH_BOUNDS[1] * 1e6)

    def event_detail(self, size: float, size_err: float, t_bmjd: float, t_err_d: float,
                     t_predicted_bmjd: float) -> dict[str, Any]:
        """The result's ``event_detail`` of the fitted size, the event's time and their
        errors: none for an eclipse (a transit's: its Rp/R* and its times under their own
        names; a whole phase curve's summary is
        :func:`~eclipsebench.fit.epoch_fit.phase_curve_detail`)."""
        return {}

    # ------------------------------------------------------------------ priors
    def prior_residuals(self, theta) -> np.ndarray:
        """``(value - mean) / sigma`` of each Gaussian prior (empty without priors)."""
        theta = np.asarray(theta, dtype=float)
        return np.array([(theta[self.names.index(n)] - mu) / sigma
                         for n, (mu, sigma) in self.priors.items()])

    def log_prior_batch(self, thetas) -> np.ndarray:
        """``-0.5 sum(prior residuals^2)`` of every row (0 without priors)."""
        thetas = np.atleast_2d(np.asarray(thetas, dtype=float))
        out = np.zeros(len(thetas))
        for n, (mu, sigma) in self.priors.items():
            out -= 0.5 * ((thetas[:, self.names.index(n)] - mu) / sigma) ** 2
        return out

    def describe(self) -> dict[str, Any]:
        """The model's settings, for results and logs (an event adds its own)."""
        return {"phase": self.phase, "ramp": self.ramp, "eclipse_shape": self.eclipse_shape,
                "box_duration_d": self.box_duration_d, "period_d": self.period_d}
