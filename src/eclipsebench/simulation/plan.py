"""Observation plans: epochs made of a "Pre" and a "Main" AOR, cubes, frames.

An epoch (Section 2.2 of Ingalls et al. 2016) is a short "Pre" AOR that lets
the pointing settle, a gap (the next PCRS peak-up), and the long "Main" AOR
that contains the eclipse (or, with ``observation.event = "transit"``, the
transit: :func:`transit_window_starts_bmjd`). PCRS peak-up places the star of *each* AOR at the
sweet spot ``(x0, y0)`` plus a Gaussian scatter. Times inside the simulator
are seconds since the start of the epoch's first exposure (all pointing terms
are phased from there, as in IRACSIM); files carry BMJD_TDB.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..astro.orbit import eclipse_time_bmjd, transit_time_bmjd
from ..config.simulation import ObservationSection
from ..errors import ConfigError
from ..seeding import rng

__all__ = ["AORPlan", "EpochPlan", "JD_OFFSET_BMJD", "epoch_start_times_bmjd", "plan_epoch",
           "plan_challenge", "SECONDS_PER_DAY", "transit_window_starts_bmjd"]

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
        ``"Pre"`` or ``"Main"``.
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


def _aorkey(base: int, epoch: int, main: bool) -> int:
    return base + 2 * (epoch - 1) + (1 if main else 0)


def plan_epoch(obs: ObservationSection, epoch: int, start_bmjd: float, seed: int) -> EpochPlan:
    """The plan of one epoch: a "Pre" AOR (if ``pre_cubes`` > 0) and a "Main" AOR.

    AORKEYs are ``aorkey_base + 2 (epoch - 1)`` (Pre) and that plus one
    (Main), as in Table 2. Each AOR's peak-up position is ``(x0, y0)`` plus a
    Gaussian scatter of ``peakup_scatter_px`` per axis, drawn from the stream
    ``("simulate", epoch, "peakup")``.
    """
    gen = rng(seed, "simulate", epoch, "peakup")
    scatter = gen.normal(0.0, 1.0, size=(2, 2)) * obs.peakup_scatter_px
    aors = []
    t0 = 0.0
    specs = [("Pre", obs.pre_cubes, False), ("Main", obs.main_cubes, True)]
    for i, (label, n_cubes, main) in enumerate(specs):
        if n_cubes == 0:
            continue
        aorkey = _aorkey(obs.aorkey_base, epoch, main)
        if aorkey > 99_999_999:
            raise ConfigError("observation.aorkey_base", f"AORKEY {aorkey} has more than 8 digits")
        aor = AORPlan(epoch=epoch, label=label, aorkey=aorkey, t0_s=t0, n_cubes=n_cubes,
                      frames_per_cube=obs.frames_per_cube,
                      frame_interval_s=obs.frame_interval_s, cube_interval_s=obs.cube_interval_s,
                      x0_px=obs.x0_px + float(scatter[i, 0]),
                      y0_px=obs.y0_px + float(scatter[i, 1]))
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


def plan_challenge(obs: ObservationSection, n_epochs: int, period_days: float,
                   seed: int, *, system=None) -> list[EpochPlan]:
    """Plans of epochs ``1..n_epochs`` (see :func:`epoch_start_times_bmjd`).

    With ``obs.event = "transit"`` the windows are moved to the transits
    (:func:`transit_window_starts_bmjd`; ``system`` is then required).
    """
    starts = epoch_start_times_bmjd(obs.start_times_jd, n_epochs, period_days)
    if obs.event == "transit":
        if system is None:
            raise ConfigError("observation.event", "a transit plan needs the planet's orbit")
        duration_d = plan_epoch(obs, 1, 0.0, seed).duration_s / SECONDS_PER_DAY
        starts = transit_window_starts_bmjd(starts, duration_d, system)
    return [plan_epoch(obs, e + 1, float(starts[e]), seed) for e in range(n_epochs)]
