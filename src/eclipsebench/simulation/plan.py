"""Observation plans: epochs made of a "Pre" and a "Main" AOR, cubes, frames.

An epoch (Section 2.2 of Ingalls et al. 2016) is a short "Pre" AOR that lets
the pointing settle, a gap (the next PCRS peak-up), and the long "Main" AOR
that contains the eclipse (or, with ``observation.event = "transit"``, the
transit: :func:`transit_window_starts_bmjd`). With ``observation.event =
"phase-curve"`` an epoch is a whole phase curve: the "Pre" AOR, then Main AORs
of at most ``max_aor_hours`` each, a repointing between them, starting before
an eclipse (:func:`phase_curve_main_cubes`,
:func:`phase_curve_window_starts_bmjd`), as IRACSIM's exoplanet wrapper plans
one. PCRS peak-up places the star of *each* AOR at the
sweet spot ``(x0, y0)`` plus a Gaussian scatter. Times inside the simulator
are seconds since the start of the epoch's first exposure (all pointing terms
are phased from there, as in IRACSIM); files carry BMJD_TDB.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..astro.eclipse import EclipseShape
from ..astro.events import event_for
from ..astro.orbit import eclipse_time_bmjd, transit_time_bmjd
from ..config.simulation import ObservationSection
from ..errors import ConfigError
from ..seeding import rng

__all__ = ["AORPlan", "EpochPlan", "JD_OFFSET_BMJD", "epoch_start_times_bmjd", "plan_epoch",
           "plan_challenge", "SECONDS_PER_DAY", "transit_window_starts_bmjd",
           "phase_curve_main_cubes", "phase_curve_window_starts_bmjd", "eclipse_half_duration_d"]

SECONDS_PER_DAY = 86400.0
# The paper's tables give JD - 2455000; BMJD = JD - 2400000.5.
JD_OFFSET_BMJD = 54999.5
# Epochs beyond the configured start times are moved by up to +-1% of an orbit
# (a golden-ratio sequence), so they sample different orbital phases.
EXTRA_PHASE_SPREAD = 0.02
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


@dataclass(frozen=True)
class AORPlan:
    """One AOR: its key, start, cubes and the star's peak-up position.

    Attributes
    ----------
    epoch : int
        1-based epoch number.
    label : str
        ``"Pre"`` or ``"Main"`` (a phase curve's Main AORs: ``"Main1"``, ``"Main2"``, ...).
    aorkey : int
        The AOR key (``r<AORKEY>`` folder, ``AORKEY`` header).
    t0_s : float
        Start of the AOR's first exposure, seconds since the epoch start.
    n_cubes, frames_per_cube : int
        Cubes in the AOR and frames per cube.
    frame_interval_s, cube_interval_s : float
        Start-to-start spacing of frames inside a cube and of cubes.
    x0_px, y0_px : float
        The star's position after PCRS peak-up (0-based pixel coordinates).
    """

    epoch: int
    label: str
    aorkey: int
    t0_s: float
    n_cubes: int
    frames_per_cube: int
    frame_interval_s: float
    cube_interval_s: float
    x0_px: float
    y0_px: float

    @property
    def n_frames(self) -> int:
        """Frames in the AOR."""
        return self.n_cubes * self.frames_per_cube

    @property
    def duration_s(self) -> float:
        """From the first exposure's start to the last cube's end (s)."""
        return (self.n_cubes - 1) * self.cube_interval_s + self.frames_per_cube * self.frame_interval_s

    def cube_starts_s(self) -> np.ndarray:
        """Start of each cube's first integration, seconds since the epoch start."""
        return self.t0_s + self.cube_interval_s * np.arange(self.n_cubes)

    def frame_starts_s(self) -> np.ndarray:
        """(n_cubes, frames_per_cube) integration starts, seconds since the epoch start."""
        return (self.cube_starts_s()[:, None]
                + self.frame_interval_s * np.arange(self.frames_per_cube)[None, :])


@dataclass(frozen=True)
class EpochPlan:
    """One epoch: its start time (BMJD_TDB) and its AORs in time order."""

    epoch: int
    start_bmjd: float
    aors: tuple[AORPlan, ...]

    @property
    def duration_s(self) -> float:
        """From the first exposure to the end of the last cube (s)."""
        last = self.aors[-1]
        return last.t0_s + last.duration_s

    @property
    def n_frames(self) -> int:
        """Frames in the epoch."""
        return sum(a.n_frames for a in self.aors)

    def aor_starts_s(self) -> np.ndarray:
        """Start of each AOR, seconds since the epoch start (pointing resets)."""
        return np.array([a.t0_s for a in self.aors])

    def to_bmjd(self, t_s: np.ndarray | float) -> np.ndarray:
        """Convert seconds since the epoch start to BMJD_TDB."""
        return self.start_bmjd + np.asarray(t_s, dtype=float) / SECONDS_PER_DAY


def epoch_start_times_bmjd(start_times_jd: tuple[float, ...] | list[float], n_epochs: int,
                           period_days: float) -> np.ndarray:
    """Start times (BMJD_TDB) of ``n_epochs`` epochs.

    The first ``len(start_times_jd)`` epochs use the configured starts
    (JD - 2455000, Table 2 of the paper by default). Epoch ``n`` beyond them
    repeats configured start ``m = (n - 1) mod M`` in cycle
    ``c = (n - 1) // M``: ``start_m + c * K * P + P * u_c``, where ``K`` is the
    number of orbits that the configured starts span (rounded) plus one, so a
    cycle begins one orbit after the previous one ends, and
    ``u_c = 0.02 * (frac(c * 0.618...) - 0.5)`` moves each cycle by up to
    +-1% of an orbit (0.032 d = 46 min for XO-3b), so that every epoch sees the eclipse at a different
    orbital phase of the window.

    Parameters
    ----------
    start_times_jd : sequence of float
        Configured start times, JD - 2455000, increasing.
    n_epochs : int
        Number of epochs wanted (>= 1).
    period_days : float
        Orbital period (days).

    Returns
    -------
    numpy.ndarray
        ``n_epochs`` start times, BMJD_TDB.
    """
    base = np.asarray(start_times_jd, dtype=float) + JD_OFFSET_BMJD
    m_count = base.size
    index = np.arange(n_epochs)
    cycle = index // m_count
    span_orbits = math.floor((base[-1] - base[0]) / period_days + 0.5) + 1
    shift = EXTRA_PHASE_SPREAD * (np.mod(cycle * _GOLDEN, 1.0) - 0.5)
    shift[cycle == 0] = 0.0
    return base[index % m_count] + cycle * span_orbits * period_days + period_days * shift


def _aorkey(base: int, epoch: int, index: int, stride: int = 2) -> int:
    """``base + stride (epoch - 1) + index``: the AOR ``index`` (0 = Pre) of an epoch of
    ``stride`` AOR slots; ``stride = 2`` is Table 2's Pre/Main pair."""
    return base + stride * (epoch - 1) + index


def phase_curve_main_cubes(obs: ObservationSection, period_days: float) -> tuple[int, ...]:
    """Cubes of each Main AOR of a phase-curve epoch, in time order.

    As IRACSIM's exoplanet wrapper (``exoplanet_simulate.pro``) splits an
    observation: Main AORs of the longest whole number of cubes that fits in
    ``max_aor_hours``, then one AOR of what is left. The Main AORs hold
    ``round(duration / cube_interval_s)`` cubes, ``duration`` being
    ``phase_curve_duration_d`` (unset: ``period_days``), as the eclipse plan
    counts its cubes from the AOR durations.

    Parameters
    ----------
    obs : ObservationSection
    period_days : float
        The planet's orbital period (days).

    Examples
    --------
    >>> from eclipsebench.config.simulation import ObservationSection
    >>> cubes = phase_curve_main_cubes(ObservationSection(event="phase-curve"), 3.1915239)
    >>> cubes, sum(cubes)
    ((333, 333, 333, 333, 333, 333, 133), 2131)
    """
    duration_d = obs.phase_curve_duration_d or period_days
    total = max(1, round(duration_d * SECONDS_PER_DAY / obs.cube_interval_s))
    cube_s = obs.frames_per_cube * obs.frame_interval_s
    max_s = obs.max_aor_hours * 3600.0
    per_aor = math.floor((max_s - cube_s) / obs.cube_interval_s + 1e-9) + 1
    if per_aor < 1:
        raise ConfigError("observation.max_aor_hours", f"{obs.max_aor_hours} h holds no cube "
                          f"({cube_s:g} s)")
    n_full, rest = divmod(total, per_aor)
    return (per_aor,) * n_full + ((rest,) if rest else ())


def plan_epoch(obs: ObservationSection, epoch: int, start_bmjd: float, seed: int, *,
               main_cubes: tuple[int, ...] | None = None) -> EpochPlan:
    """The plan of one epoch: a "Pre" AOR (if ``pre_cubes`` > 0) and its Main AOR(s).

    Without ``main_cubes`` (eclipse and transit epochs) the epoch has one
    "Main" AOR of ``obs.main_cubes``; AORKEYs are ``aorkey_base + 2 (epoch - 1)``
    (Pre) and that plus one (Main), as in Table 2. With ``main_cubes`` (a
    phase curve, :func:`phase_curve_main_cubes`) the Main AORs ``"Main1"``,
    ``"Main2"``, ... follow one another, each after a gap of ``aor_gap_s``;
    an epoch has ``S = 1 + len(main_cubes)`` AOR slots and its keys are
    ``aorkey_base + S (epoch - 1) + i`` with ``i = 0`` for Pre (kept even
    without a Pre AOR) and ``i = k`` for Main ``k``: consecutive, as IRACSIM's
    wrapper increments its REQKEYs, and disjoint between epochs (every epoch
    has the same ``S``). Table 2's keys are the case ``S = 2``.

    Each AOR's peak-up position is ``(x0, y0)`` plus a Gaussian scatter of
    ``peakup_scatter_px`` per axis, drawn from the stream
    ``("simulate", epoch, "peakup")`` (row ``i`` of an ``(S, 2)`` draw, so
    the Pre and first Main AORs get the eclipse plan's numbers).

    Examples
    --------
    >>> from eclipsebench.config.simulation import ObservationSection
    >>> obs = ObservationSection(event="phase-curve")
    >>> plan = plan_epoch(obs, 2, 57000.0, 1, main_cubes=(333, 333, 10))
    >>> [(a.label, a.aorkey, a.n_cubes) for a in plan.aors]
    [('Pre', 20150004, 11), ('Main1', 20150005, 333), ('Main2', 20150006, 333), ('Main3', 20150007, 10)]
    """
    if main_cubes is None:
        specs = [("Pre", obs.pre_cubes, 0), ("Main", obs.main_cubes, 1)]
    else:
        specs = [("Pre", obs.pre_cubes, 0)] + [(f"Main{k}", int(n), k)
                                               for k, n in enumerate(main_cubes, start=1)]
    stride = len(specs)
    gen = rng(seed, "simulate", epoch, "peakup")
    scatter = gen.normal(0.0, 1.0, size=(stride, 2)) * obs.peakup_scatter_px
    aors = []
    t0 = 0.0
    for label, n_cubes, index in specs:
        if n_cubes == 0:
            continue
        aorkey = _aorkey(obs.aorkey_base, epoch, index, stride)
        if aorkey > 99_999_999:
            raise ConfigError("observation.aorkey_base", f"AORKEY {aorkey} has more than 8 digits")
        aor = AORPlan(epoch=epoch, label=label, aorkey=aorkey, t0_s=t0, n_cubes=n_cubes,
                      frames_per_cube=obs.frames_per_cube,
                      frame_interval_s=obs.frame_interval_s, cube_interval_s=obs.cube_interval_s,
                      x0_px=obs.x0_px + float(scatter[index, 0]),
                      y0_px=obs.y0_px + float(scatter[index, 1]))
        aors.append(aor)
        t0 = t0 + aor.duration_s + obs.aor_gap_s
    return EpochPlan(epoch=epoch, start_bmjd=float(start_bmjd), aors=tuple(aors))


def transit_window_starts_bmjd(starts_bmjd, duration_d: float, system) -> np.ndarray:
    """Window starts moved from each window's eclipse to the transit before it.

    A window ``[start, start + duration_d]`` that holds a mid-transit is kept.
    Any other is moved by ``t_tr - t_ecl``: ``t_ecl`` the eclipse nearest the
    window's middle, ``t_tr`` the transit before it (an eccentric orbit's
    transit is not half a period from its eclipse), so the transit takes the
    place in the window that the eclipse had.

    Parameters
    ----------
    starts_bmjd : array_like
        Window starts (BMJD_TDB), e.g. :func:`epoch_start_times_bmjd`.
    duration_d : float
        Window length (days).
    system : PlanetSystem
        The planet (its ephemeris and orbit).

    Examples
    --------
    >>> from eclipsebench.astro.catalogue import get_system
    >>> from eclipsebench.astro.orbit import eclipse_time_bmjd, transit_time_bmjd
    >>> xo3 = get_system("XO-3b (2015 challenge)")
    >>> t_ecl = eclipse_time_bmjd(xo3, 57234.5)
    >>> start = transit_window_starts_bmjd([t_ecl - 0.14], 0.37, xo3)[0]
    >>> round(float(transit_time_bmjd(xo3, start) - start), 6)
    0.14
    """
    out = []
    for start in np.asarray(starts_bmjd, dtype=float):
        mid = start + 0.5 * duration_d
        t_tr = float(transit_time_bmjd(system, mid))
        if start <= t_tr <= start + duration_d:
            out.append(float(start))
            continue
        t_ecl = float(eclipse_time_bmjd(system, mid))
        t_before = float(transit_time_bmjd(system, t_ecl - 0.5 * system.period_days))
        out.append(float(start + (t_before - t_ecl)))
    return np.array(out)


def eclipse_half_duration_d(system) -> float:
    """Half the time from first to last contact of the planet's secondary eclipse (days).

    Examples
    --------
    >>> from eclipsebench.astro.catalogue import get_system
    >>> round(24 * eclipse_half_duration_d(get_system("XO-3b (2015 challenge)")), 2)
    1.41
    """
    return 0.5 * EclipseShape(np.empty(0), system).duration_days


def phase_curve_window_starts_bmjd(starts_bmjd, system, *, lead_d: float,
                                   main_offset_d: float) -> np.ndarray:
    """Epoch starts that put a phase curve's first Main AOR ``lead_d`` before an ingress.

    For each configured start ``s`` the eclipse is the first one after it
    (the eclipse nearest ``s + P/2``); the epoch starts at
    ``t_ecl - T/2 - lead_d - main_offset_d``, with ``T/2``
    (:func:`eclipse_half_duration_d`) the time from first contact to
    mid-eclipse and ``main_offset_d`` the Pre AOR and its gap, so the first
    Main AOR begins ``lead_d`` before first contact and that eclipse is whole.
    (IRACSIM's wrapper starts "a number of hours before transit" or at an
    orbital phase; we start before an eclipse, the event the 2015 challenge's
    windows were built around.)

    Parameters
    ----------
    starts_bmjd : array_like
        Configured starts (BMJD_TDB), e.g. :func:`epoch_start_times_bmjd`.
    system : PlanetSystem
    lead_d : float
        Time of the first Main AOR before the first contact (days).
    main_offset_d : float
        Start of the first Main AOR after the epoch's start (days).

    Examples
    --------
    >>> from eclipsebench.astro.catalogue import get_system
    >>> xo3 = get_system("XO-3b (2015 challenge)")
    >>> start = phase_curve_window_starts_bmjd([57000.0], xo3, lead_d=2 / 24,
    ...                                        main_offset_d=0.02)[0]
    >>> t_ecl = eclipse_time_bmjd(xo3, start + 1.6)
    >>> round(float(24 * (t_ecl - eclipse_half_duration_d(xo3) - start - 0.02)), 6)
    2.0
    """
    half = eclipse_half_duration_d(system)
    out = []
    for start in np.asarray(starts_bmjd, dtype=float):
        t_ecl = float(eclipse_time_bmjd(system, start + 0.5 * system.period_days))
        out.append(t_ecl - half - lead_d - main_offset_d)
    return np.array(out)


def plan_challenge(obs: ObservationSection, n_epochs: int, period_days: float,
                   seed: int, *, system=None) -> list[EpochPlan]:
    """Plans of epochs ``1..n_epochs`` (see :func:`epoch_start_times_bmjd`).

    With ``obs.event = "transit"`` the windows are moved to the transits
    (:func:`transit_window_starts_bmjd`); with ``"phase-curve"`` each epoch is
    a whole phase curve (:func:`phase_curve_main_cubes`) starting before the
    first eclipse after its configured start
    (:func:`phase_curve_window_starts_bmjd`). Both need ``system``.
    """
    starts = epoch_start_times_bmjd(obs.start_times_jd, n_epochs, period_days)
    event = event_for(obs.event)
    if event.needs_orbit and system is None:
        raise ConfigError("observation.event", f"a {obs.event} plan needs the planet's orbit")
    if event.transit_windows:
        duration_d = plan_epoch(obs, 1, 0.0, seed).duration_s / SECONDS_PER_DAY
        starts = transit_window_starts_bmjd(starts, duration_d, system)
    main_cubes = None
    if event.whole_orbit:
        main_cubes = phase_curve_main_cubes(obs, period_days)
        probe = plan_epoch(obs, 1, 0.0, seed, main_cubes=main_cubes)
        first_main = next(a for a in probe.aors if a.label.startswith("Main"))
        starts = phase_curve_window_starts_bmjd(
            starts, system, lead_d=obs.phase_curve_lead_h / 24.0,
            main_offset_d=first_main.t0_s / SECONDS_PER_DAY)
    return [plan_epoch(obs, e + 1, float(starts[e]), seed, main_cubes=main_cubes)
            for e in range(n_epochs)]
