"""``[observation]``, ``[pointing]`` and ``[simulation]``: the IRAC simulator's inputs."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from .base import check


@dataclass(frozen=True)
class ObservationSection:
    """The observation plan of one epoch (Section 2.2 and Table 2 of the paper)."""

    pre_cubes: int = 11
    main_cubes: int = 233
    frames_per_cube: int = 64
    fowler: int = 8
    wait: int = 184
    sample_time_s: float = 0.01
    x0_px: float = 15.15
    y0_px: float = 15.20
    peakup_scatter_px: float = 0.04

    def validate(self) -> None:
        check(self.pre_cubes >= 0, "pre_cubes", "a non-negative number of cubes")
        check(self.main_cubes >= 1, "main_cubes", "at least 1 cube")
        check(self.frames_per_cube >= 1, "frames_per_cube", "at least 1 frame")
        check(self.fowler >= 1, "fowler", "a Fowler number >= 1")
        check(self.wait >= 0, "wait", "a non-negative number of wait ticks")
        check(self.sample_time_s > 0, "sample_time_s", "a positive sample time in s")
        check(2.0 <= self.x0_px <= 29.0, "x0_px", "a position on the 32x32 subarray (2-29 px)")
        check(2.0 <= self.y0_px <= 29.0, "y0_px", "a position on the 32x32 subarray (2-29 px)")
        check(self.peakup_scatter_px >= 0, "peakup_scatter_px", "a non-negative scatter in px")


@dataclass(frozen=True)
class SimulationSection:
    """Detector and noise model of the simulator (Appendix A.2-A.3)."""

    noise_model: Literal["physical", "iracsim2015"] = "physical"
    flux_aperture_e: float = 73246.0
    background_e_per_px: float = 4.0
    background_slope_per_day: float = 0.0
    read_noise_e: float = 9.4
    gain_e_per_dn: float = 3.71
    fluxconv: float = 0.1469
    subsamples: int = 10
    prf: str = "builtin"
    calibration_frames: int = 400000
    write_calibration: bool = True

    def validate(self) -> None:
        check(self.flux_aperture_e > 0, "flux_aperture_e", "a positive flux in electrons")
        check(self.background_e_per_px >= 0, "background_e_per_px", "a non-negative background")
        check(self.read_noise_e >= 0, "read_noise_e", "a non-negative read noise in electrons")
        check(self.gain_e_per_dn > 0, "gain_e_per_dn", "a positive gain")
        check(self.fluxconv > 0, "fluxconv", "a positive FLUXCONV")
        check(self.subsamples >= 1, "subsamples", "at least 1 sub-sample per Fowler sample")
        check(self.calibration_frames >= 0, "calibration_frames", "a non-negative count")
