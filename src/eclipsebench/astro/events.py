"""The events an epoch observes and a fit models: one class each, carrying the facts callers
branch on.

An :class:`Event` says what is particular to the secondary eclipse (:class:`Eclipse`),
the transit (:class:`Transit`) or a whole phase curve (:class:`PhaseCurve`): the key of
its time in a result file, the conjunction its time is at (and which conjunctions its
window holds), its size parameter of a depth, what a result's printout adds for it, and
what the rest of the package offers it (a joint fit over epochs, a run's scoring, the
analytic photon limit, the default sampler). Callers ask the event
(``event_for(options.event).time_key``) instead of comparing its name; the fitted
models (:mod:`eclipsebench.fit.model`, one class per event) and the simulator's
plans read the same objects.

Plain classes, no numpy at import: the configuration (which the command line's parser
loads) checks its event settings with them. Adding an event: docs/architecture.md,
"Where to add".
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

from ..errors import InputError

__all__ = ["Event", "Eclipse", "Transit", "PhaseCurve", "EVENT_CLASSES", "event_for"]

#: The suffixes of an event's three time keys in a result (value, error, prediction).
_TIME_SUFFIXES = ("_bmjd", "_err_d", "_predicted_bmjd")


class Event:
    """What one event is, for every caller that would otherwise compare its name.

    The class attributes are the facts; an instance carries no state (``event_for``
    returns one per event).
    """

    #: The event's name: ``[reduce] event``, ``observation.event``, ``--event``.
    name: ClassVar[str] = ""
    #: The conjunction the event's time marks (``"eclipse"``: superior, ``"transit"``:
    #: inferior), as :func:`eclipsebench.astro.orbit.conjunction_time_bmjd` takes it; also
    #: the noun of the time in a printout ("the eclipse's mid-time").
    conjunction: ClassVar[str] = "eclipse"
    #: The conjunctions one epoch's window holds (a simulation warns about a missing one).
    observed: ClassVar[tuple[str, ...]] = ("eclipse",)
    #: Whether the epoch spans a whole orbit over several AORs (a phase curve's harmonic
    #: models, AOR offsets, its window from before the first eclipse).
    whole_orbit: ClassVar[bool] = False
    #: Whether simulating or fitting the event needs the planet's orbit (a catalogue system).
    needs_orbit: ClassVar[bool] = False
    #: Whether a simulated epoch's window, configured about an eclipse, is moved to the
    #: transit before it (:func:`eclipsebench.simulation.plan.transit_window_starts_bmjd`).
    transit_windows: ClassVar[bool] = False
    #: The sampler ``[reduce] sampler = "auto"`` stands for.
    default_sampler: ClassVar[str] = "mcmc"
    #: Whether several epochs share one fitted depth in a joint fit (``reduce_joint``).
    joint_fit: ClassVar[bool] = False
    #: Whether a campaign fits a group of its epochs together (a joint fit, or one fit of
    #: a phase curve's frames).
    campaign_group: ClassVar[bool] = False
    #: Whether a challenge run (``eclipsebench run``) scores it against the truth, and a
    #: campaign gives its analytic photon limit (Section 3.3: an eclipse's).
    scored: ClassVar[bool] = False
    #: The ``[reduce]`` keys that may be true only with this event.
    own_settings: ClassVar[tuple[str, ...]] = ()
    #: The prefix of the event's time keys in a result (``t_ecl_bmjd``, ``t_ecl_err_d``,
    #: ``t_ecl_predicted_bmjd``), its model's time parameter's.
    time_prefix: ClassVar[str] = "t_ecl"

    @property
    def time_key(self) -> str:
        """The key of the event's fitted time: its model's parameter and its result's key."""
        return self.time_prefix + "_bmjd"

    @property
    def observes_transit(self) -> bool:
        """Whether an epoch's window holds a transit (its truth then has the transit's)."""
        return "transit" in self.observed

    @property
    def mid_label(self) -> str:
        """The event's time in a figure's axis label: ``mid-eclipse`` or ``mid-transit``."""
        return "mid-" + self.conjunction

    @property
    def replaced_time_keys(self) -> tuple[str, ...]:
        """The eclipse's time keys a result of this event leaves out (its detail carries its
        own, under :attr:`time_prefix`): none for an eclipse or a phase curve."""
        if self.time_prefix == Event.time_prefix:
            return ()
        return tuple("t_ecl" + s for s in _TIME_SUFFIXES)

    def size_from_depth(self, depth_ppm: float) -> float:
        """The event's size parameter (its model's ``names[0]``) of a depth in ppm: the
        depth as a fraction (an eclipse's, a phase curve's)."""
        return depth_ppm * 1e-6

    def detail_lines(self, result: Mapping[str, Any]) -> list[str]:
        """What a result's text printout adds for the event (a result's ``to_dict()``)."""
        return []

    def __repr__(self) -> str:
        return f"event_for({self.name!r})"


class Eclipse(Event):
    """The secondary eclipse: its depth, the paper's event (every method, run and score)."""

    name = "eclipse"
    joint_fit = True
    campaign_group = True
    scored = True


class Transit(Event):
    """The transit: Rp/R* and batman's limb darkening, its time the mid-transit."""

    name = "transit"
    conjunction = "transit"
    time_prefix = "t_transit"
    observed = ("transit",)
    needs_orbit = True
    transit_windows = True

    def size_from_depth(self, depth_ppm: float) -> float:
        """Rp/R* of a geometric depth ``rp_rs^2`` in ppm (the inverse of the transit model's
        ``depth_ppm``)."""
        return math.sqrt(depth_ppm * 1e-6)

    def detail_lines(self, result: Mapping[str, Any]) -> list[str]:
        """Rp/R* as fitted."""
        return [f"rp_rs         {result['rp_rs']:.5f} +- {result['rp_rs_err']:.5f} "
                "(depth = rp_rs^2)"]


class PhaseCurve(Event):
    """A whole phase curve over several AORs: eclipses, transits and the harmonic phase
    variation; its time an eclipse's."""

    name = "phase-curve"
    observed = ("eclipse", "transit")
    whole_orbit = True
    needs_orbit = True
    default_sampler = "leastsq"
    campaign_group = True
    own_settings = ("systematics_per_aor", "nonnegative_planet")

    def detail_lines(self, result: Mapping[str, Any]) -> list[str]:
        """The amplitude, hotspot offset, night side and Rp/R*."""
        return [
            f"amplitude     {result['phase_amplitude_ppm']:.1f} +- "
            f"{result['phase_amplitude_err_ppm']:.1f} ppm (semi-amplitude)",
            f"offset        {result['phase_offset_deg']:.1f} +- "
            f"{result['phase_offset_err_deg']:.1f} deg (hotspot, east positive)",
            f"night side    {result['nightside_flux_ppm']:.1f} +- "
            f"{result['nightside_flux_err_ppm']:.1f} ppm; minimum "
            f"{result['planet_flux_min_ppm']:.1f} ppm"
            + (" (NEGATIVE)" if result.get("planet_flux_negative") else ""),
            f"rp_rs         {result['rp_rs']:.5f} +- {result['rp_rs_err']:.5f}"]


#: Every event by its name, in the order the command line offers them.
EVENT_CLASSES: dict[str, type[Event]] = {cls.name: cls for cls in (Eclipse, Transit, PhaseCurve)}
_INSTANCES = {name: cls() for name, cls in EVENT_CLASSES.items()}


def event_for(name: str | None) -> Event:
    """The :class:`Event` named ``name``; None (a result that names none): the eclipse.

    Examples
    --------
    >>> event_for("transit").time_key, event_for(None).time_key
    ('t_transit_bmjd', 't_ecl_bmjd')
    >>> round(event_for("transit").size_from_depth(10000.0), 6)
    0.1
    """
    if name is None:
        return _INSTANCES["eclipse"]
    try:
        return _INSTANCES[name]
    except (KeyError, TypeError):
        raise InputError(f"event {name!r}: expected one of {', '.join(EVENT_CLASSES)}") from None
