"""``[observation]`` and ``[simulation]``: the IRAC simulator's inputs.

The defaults reproduce the synthetic half of the 2015 IRAC data challenge
(Section 2.3, Table 2 ``sim_xo3meas`` and Appendix A of Ingalls et al. 2016),
with the flux and background levels measured on the real "Pre" AOR of XO-3
(AORKEY 46466816) and the paper's Section 3.3 numbers.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Literal

from ..detector.constants import (
    READOUT_MODES,
    SUB_2S,
    ReadoutMode,
    channel_constants,
    cube_interval_default_s,
    frame_interval_default_s,
)
from ..errors import ConfigError
from ..limits import (
    MAX_CALIBRATION_FRAMES,
    MAX_CUBES_PER_AOR,
    MAX_FRAMES_PER_CUBE,
    MAX_FRAMES_PER_EPOCH,
    check_size,
)
from .base import check

# Table 2 (sim_xo3meas) of the paper: start of the first exposure of each
# simulated epoch's "Pre" AOR, JD - 2455000.
TABLE2_START_TIMES_JD = (2206.1459, 2209.2927, 2212.5079, 2215.7214, 2218.9047,
                         2222.0547, 2225.2356, 2228.4898, 2231.6296, 2234.8406)

SUBARRAY_PX = 32
FULL_ARRAY_PX = 256
#: Readout choices: the predefined modes plus ``"custom"`` (subarray with the
#: ``fowler``/``wait``/``sample_time_s`` keys).
READOUT_CHOICES = (*READOUT_MODES, "custom")
#: Durations of the 2015 challenge's AORs, kept in every readout mode:
#: 11 and 233 cubes of the 2 s subarray every 129.4 s.
PRE_AOR_S = 11 * 129.4
MAIN_AOR_S = 233 * 129.4


@dataclass(frozen=True)
class ObservationSection:
    """The observation plan of one epoch (Section 2.2 and Table 2 of the paper).

    An epoch is a "Pre" AOR of ``pre_cubes`` cubes, a gap of ``aor_gap_s``
    (the PCRS peak-up of the next AOR), and a "Main" AOR of ``main_cubes``
    cubes. A cube holds ``frames_per_cube`` frames whose integrations start
    every ``frame_interval_s``; cubes start every ``cube_interval_s`` (129.4 s
    between consecutive ``BMJD_OBS`` in the real cubes of AOR 46466816).
    ``start_times_jd`` (JD - 2455000) are the epochs' first exposures; epochs
    beyond the list continue on later orbits (see ``docs/simulate.md``).

    ``channel`` (1 = 3.6 um, 2 = 4.5 um) and ``readout`` (a predefined mode,
    :data:`~eclipsebench.detector.constants.READOUT_MODES`, or ``"custom"``)
    choose the detector. Keys left unset take the readout's values: FN, WT and
    tick of the mode; 64 frames per cube on the subarray, one 256 x 256 frame
    per file on the full array; frames every ``t_int + 0.008`` s (IRACSIM);
    files every :func:`~eclipsebench.detector.constants.cube_interval_default_s`;
    as many cubes as fill the 2015 challenge's AOR durations (11 and 233
    cubes of 2 s frames); the star at the channel's peak-up target
    (:class:`~eclipsebench.detector.constants.ChannelConstants`). A key given
    with a named readout must agree with it (``"custom"`` takes any FN, WT and
    tick on the subarray, with the 2 s subarray's values for those unset).

    ``event`` (``"eclipse"``, ``"transit"`` or ``"phase-curve"``) is what each
    epoch observes: with ``"transit"`` an epoch whose window holds no transit is
    moved by the time from its eclipse to the transit before it, so the transit
    sits where the eclipse sat (the default start times are the 2015 challenge's
    eclipse windows); a window that already holds a transit is kept.

    With ``"phase-curve"`` an epoch is a whole phase curve, planned as IRACSIM's
    exoplanet wrapper plans one (``exoplanet_simulate.pro``): the "Pre" AOR of
    ``pre_cubes``, then Main AORs of at most ``max_aor_hours`` (12 h) each that
    together last ``phase_curve_duration_d`` (unset: one orbital period; their
    cubes are ``round(duration / cube_interval_s)``, ``main_cubes`` is not
    used), each after a repointing of ``aor_gap_s`` with its own PCRS peak-up.
    The first Main AOR starts ``phase_curve_lead_h`` (2 h) before the first
    contact of the first eclipse after the configured start, so that eclipse is
    whole (see ``docs/simulate.md``).
    """

    channel: int = 2
    readout: str = "sub_2s"
    pre_cubes: int = None  # type: ignore[assignment]  # unset: derived in __post_init__
    main_cubes: int = None  # type: ignore[assignment]  # unset: derived in __post_init__
    frames_per_cube: int = None  # type: ignore[assignment]  # unset: derived in __post_init__
    fowler: int = None  # type: ignore[assignment]  # unset: derived in __post_init__
    wait: int = None  # type: ignore[assignment]  # unset: derived in __post_init__
    sample_time_s: float = None  # type: ignore[assignment]  # unset: derived in __post_init__
    frame_interval_s: float = None  # type: ignore[assignment]  # unset: derived in __post_init__
    cube_interval_s: float = None  # type: ignore[assignment]  # unset: derived in __post_init__
    aor_gap_s: float = 300.0
    start_times_jd: tuple[float, ...] = TABLE2_START_TIMES_JD
    aorkey_base: int = 20150000
    x0_px: float = None  # type: ignore[assignment]  # unset: derived in __post_init__
    y0_px: float = None  # type: ignore[assignment]  # unset: derived in __post_init__
    peakup_scatter_px: float = 0.04
    event: Literal["eclipse", "transit", "phase-curve"] = "eclipse"
    phase_curve_duration_d: float | None = None  # unset: one orbital period
    phase_curve_lead_h: float = 2.0
    max_aor_hours: float = 12.0

    def __post_init__(self):
        if self.channel not in (1, 2):
            raise ConfigError("observation.channel", f"expected 1 (3.6 um) or 2 (4.5 um), "
                                                     f"got {self.channel!r}")
        if self.readout not in READOUT_CHOICES:
            raise ConfigError("observation.readout", "expected one of "
                              + ", ".join(READOUT_CHOICES) + f", got {self.readout!r}")
        named = READOUT_MODES.get(self.readout)
        base = named if named is not None else SUB_2S
        # the checks of validate() that the defaults below need, on the values given
        for key, ok, expected in (("fowler", lambda v: v >= 1, "a Fowler number >= 1"),
                                  ("wait", lambda v: v >= 0, "a non-negative number of wait ticks"),
                                  ("sample_time_s", lambda v: v > 0,
                                   "a positive sample time in s")):
            given = getattr(self, key)
            check(given is None or ok(given), f"observation.{key}", expected)
        for key, value in (("fowler", base.fowler), ("wait", base.wait),
                           ("sample_time_s", base.sample_time_s)):
            given = getattr(self, key)
            if given is None:
                object.__setattr__(self, key, value)
            elif named is not None and not math.isclose(float(given), float(value)):
                raise ConfigError(f"observation.{key}", f"{given} disagrees with readout "
                                  f"{self.readout!r} ({key} = {value}); leave it unset or "
                                  "choose readout = 'custom'")
        mode = self.readout_mode()
        if self.frames_per_cube is None:
            object.__setattr__(self, "frames_per_cube", mode.frames_per_file)
        if self.frame_interval_s is None:
            object.__setattr__(self, "frame_interval_s", frame_interval_default_s(mode))
        if self.cube_interval_s is None:
            object.__setattr__(self, "cube_interval_s", cube_interval_default_s(mode))
        for key, duration_s, least in (("pre_cubes", PRE_AOR_S, 0), ("main_cubes", MAIN_AOR_S, 1)):
            if getattr(self, key) is None:
                object.__setattr__(self, key, max(least, round(duration_s / self.cube_interval_s)))
        target = channel_constants(self.channel).target_px(mode.subarray)
        for key, value in (("x0_px", target[0]), ("y0_px", target[1])):
            if getattr(self, key) is None:
                object.__setattr__(self, key, value)

    def readout_mode(self) -> ReadoutMode:
        """The :class:`~eclipsebench.detector.constants.ReadoutMode` of ``readout``.

        ``"custom"`` is a subarray mode named ``"configured"`` with the
        section's FN, WT and tick.
        """
        named = READOUT_MODES.get(self.readout)
        if named is not None:
            return named
        t_int = (2 * self.fowler + self.wait) * self.sample_time_s
        return ReadoutMode("configured", self.fowler, self.wait, self.sample_time_s,
                           round(t_int, 6), True)

    @property
    def array_px(self) -> int:
        """Side of the array: 32 (subarray) or 256 (full array)."""
        return SUBARRAY_PX if self.readout_mode().subarray else FULL_ARRAY_PX

    def validate(self) -> None:
        check(self.pre_cubes >= 0, "pre_cubes", "a non-negative number of cubes")
        check(self.main_cubes >= 1, "main_cubes", "at least 1 cube")
        check(self.frames_per_cube >= 1, "frames_per_cube", "at least 1 frame")
        for key in ("pre_cubes", "main_cubes"):
            check_size(key, getattr(self, key), MAX_CUBES_PER_AOR, "cubes", config=True)
        check_size("frames_per_cube", self.frames_per_cube, MAX_FRAMES_PER_CUBE, "frames",
                   config=True)
        check_size("main_cubes", (self.pre_cubes + self.main_cubes) * self.frames_per_cube,
                   MAX_FRAMES_PER_EPOCH, "frames per epoch", config=True)
        check(self.fowler >= 1, "fowler", "a Fowler number >= 1")
        check(self.wait >= 0, "wait", "a non-negative number of wait ticks")
        check(self.sample_time_s > 0, "sample_time_s", "a positive sample time in s")
        mode = self.readout_mode()
        check(mode.subarray or self.frames_per_cube == 1, "frames_per_cube",
              f"1 frame per file for the full-array readout {self.readout!r}")
        t_int_s = (2 * self.fowler + self.wait) * self.sample_time_s
        check(self.frame_interval_s >= t_int_s - 1e-9, "frame_interval_s",
              f"at least the integration time (2 FN + WT) x sample_time = {t_int_s:g} s")
        check(self.cube_interval_s >= self.frames_per_cube * self.frame_interval_s - 1e-9,
              "cube_interval_s", "at least frames_per_cube x frame_interval_s")
        check(self.aor_gap_s >= 0, "aor_gap_s", "a non-negative gap in s")
        check(len(self.start_times_jd) >= 1 and all(math.isfinite(t) for t in self.start_times_jd),
              "start_times_jd", "a non-empty list of start times (JD - 2455000)")
        check(all(b > a for a, b in itertools.pairwise(self.start_times_jd)),
              "start_times_jd", "start times in increasing order")
        check(0 <= self.aorkey_base <= 99_999_000, "aorkey_base", "an AORKEY of at most 8 digits")
        side = self.array_px
        where = "the 32x32 subarray" if side == SUBARRAY_PX else "the 256x256 array"
        check(2.0 <= self.x0_px <= side - 3.0, "x0_px", f"a position on {where} (2-{side - 3} px)")
        check(2.0 <= self.y0_px <= side - 3.0, "y0_px", f"a position on {where} (2-{side - 3} px)")
        check(0 <= self.peakup_scatter_px <= 1.0, "peakup_scatter_px",
              "a scatter between 0 and 1 px")
        check(self.phase_curve_duration_d is None
              or (math.isfinite(self.phase_curve_duration_d)
                  and 0 < self.phase_curve_duration_d <= 100.0),
              "phase_curve_duration_d", "a duration in days, 0 < d <= 100 (unset: one orbit)")
        check(math.isfinite(self.phase_curve_lead_h) and 0 <= self.phase_curve_lead_h <= 48.0,
              "phase_curve_lead_h", "hours before the first eclipse's ingress, 0-48")
        cube_h = self.frames_per_cube * self.frame_interval_s / 3600.0
        check(math.isfinite(self.max_aor_hours) and cube_h <= self.max_aor_hours <= 1000.0,
              "max_aor_hours", f"an AOR length in hours that holds at least one cube "
                               f"({cube_h:.3g} h) and is at most 1000 h")


@dataclass(frozen=True)
class SimulationSection:
    """Detector, source and noise model of the simulator (Appendix A.2-A.3).

    ``flux_aperture_e`` is the star's background-free flux in the r = 2.25 px
    aperture per frame (electrons accumulated over EXPTIME; the paper's
    simulated mean is 73,246 e). ``background_e_per_px`` is the sky per pixel
    and frame (about 5 e far from the star in the real cubes of AOR
    46466816); ``background_slope_per_day`` its fractional change per day.
    ``pointing_motion = false`` holds the star at its peak-up position and
    ``flat_gain = true`` switches off the intra-pixel gain: twins with these
    switches changed draw from the same photon and read-noise streams in the
    same order. ``pointing_ranges`` overrides entries of Table 5
    (``"name=C:value"``, ``"name=U:lo:hi"``, ``"name=G:lo:hi"``).

    ``noise_model``: ``"physical"`` (independent Poisson increments per tick),
    ``"iracsim2015"`` (the 2015 challenge's frames: IRACSIM's compounding
    Poisson noise, 16.8 e per read, both scaled by ``noise_factor``, IRACSIM's
    ``NOISE_FACTOR``, 0.907 unless set, from the public 2015 cube's aperture
    scatter; and the background level of that cube, ``background_e_per_px``
    being the sky it put under its PRFs; see ``docs/simulate.md``) or
    ``"none"`` (noise-free frames: no photon, read or background noise;
    pointing, gain and eclipse kept).
    """

    noise_model: Literal["physical", "iracsim2015", "none"] = "physical"
    flux_aperture_e: float = 73246.0
    aperture_radius_px: float = 2.25
    background_e_per_px: float = 55.4  # 881 e in the r = 2.25 px aperture (paper Sec. 3.3)
    background_reference: Literal["annulus", "sky"] = "annulus"
    background_slope_per_day: float = 0.0
    read_noise_e: float | None = None  # unset: the channel's RONOISE (physical) / IRACSIM's
    noise_factor: float | None = None  # iracsim2015 only; unset: the public 2015 cube's 0.907
    gain_e_per_dn: float | None = None  # unset: the channel's header GAIN (3.71 / 3.7)
    fluxconv: float | None = None  # unset: the channel's warm FLUXCONV (0.1469 / 0.1253)
    subsamples: int = 10
    prf: str = "builtin"
    stamp_px: int = 13
    pointing_motion: bool = True
    pointing_ranges: tuple[str, ...] = ()  # Table 5 overrides: "a_sd_px=U:0:0.5", "a_j_px=C:0.02"
    flat_gain: bool = False
    calibration_frames: int = 400000
    write_calibration: bool = True
    calibration_box_px: float = 1.0

    def validate(self) -> None:
        check(math.isfinite(self.flux_aperture_e) and self.flux_aperture_e > 0,
              "flux_aperture_e", "a positive flux in electrons")
        check(0.5 <= self.aperture_radius_px <= 6.0, "aperture_radius_px",
              "an aperture radius in 0.5-6 px")
        check(math.isfinite(self.background_e_per_px) and self.background_e_per_px >= 0,
              "background_e_per_px", "a non-negative background in electrons per pixel")
        check(math.isfinite(self.background_slope_per_day) and abs(self.background_slope_per_day) < 10,
              "background_slope_per_day", "a fractional slope per day with |slope| < 10")
        check(self.read_noise_e is None or self.read_noise_e >= 0, "read_noise_e",
              "a non-negative read noise in electrons")
        check(self.noise_factor is None or (math.isfinite(self.noise_factor)
                                            and 0 < self.noise_factor <= 10), "noise_factor",
              "a positive factor on IRACSIM's noise (at most 10)")
        check(self.noise_factor is None or self.noise_model == "iracsim2015", "noise_factor",
              "no value unless noise_model = 'iracsim2015' (IRACSIM's NOISE_FACTOR)")
        check(self.gain_e_per_dn is None or self.gain_e_per_dn > 0, "gain_e_per_dn",
              "a positive gain")
        check(self.fluxconv is None or self.fluxconv > 0, "fluxconv", "a positive FLUXCONV")
        check(1 <= self.subsamples <= 100, "subsamples",
              "between 1 and 100 sub-samples per Fowler sample")
        check(bool(self.prf.strip()), "prf", "'builtin', 'irsa' or a folder of IRSA PRF files")
        check(5 <= self.stamp_px <= SUBARRAY_PX and self.stamp_px % 2 == 1, "stamp_px",
              "an odd stamp size between 5 and 31 px")
        check(self.calibration_frames >= 0, "calibration_frames", "a non-negative count")
        check_size("calibration_frames", self.calibration_frames, MAX_CALIBRATION_FRAMES,
                   "frames", config=True)
        check(0 < self.calibration_box_px <= 3.0, "calibration_box_px",
              "a positive box width (px) over which calibration pointings are spread")
