"""Spitzer/IRAC channel-2 (4.5 um) constants and readout modes.

Values come from the paper (Appendix A, Section 3.3), the IRACSIM code the
2015 data challenge used, and the header of a real channel-2 subarray BCD
(AOR 46466816: ``AFOWLNUM = 8``, ``AWAITPER = 184``, ``SAMPTIME = 0.01``,
``FRAMTIME = 2.0``, ``EXPTIME = 1.92``, ``GAIN = 3.71``, ``RONOISE = 9.4``).

Readout timing (paper Appendix A.3): a frame is ``n_max = 2 FN + WT`` sample
intervals of ``dt`` seconds; the integration time is ``t_int = n_max dt`` and
the exposure time (pedestal i to signal i) is ``t_exp = (FN + WT) dt``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from eclipsebench.errors import InputError

if TYPE_CHECKING:  # annotations only: the configuration package imports this module
    from eclipsebench.config import Config

__all__ = [
    "PIXEL_SCALE_ARCSEC", "PIXEL_SCALE_X_ARCSEC", "PIXEL_SCALE_Y_ARCSEC", "PIXEL_SOLID_ANGLE_SR",
    "GAIN_E_PER_DN", "FLUXCONV_WARM_CH2", "FLUXCONV_HEADER_XO3", "READ_NOISE_E",
    "READ_NOISE_IRACSIM2015_E", "WAVELENGTH_UM", "BAND_UM", "TELESCOPE_DIAMETER_M",
    "SUBARRAY_SHAPE", "SUBARRAY_ORIGIN_FULL", "SWEET_SPOT_PX", "ReadoutMode",
    "SUB_2S", "SUB_0P4S", "SUB_0P1S", "SUB_0P02S", "FULL_2S", "FULL_6S", "FULL_12S",
    "FULL_30S", "FULL_100S", "READOUT_MODES", "readout_mode", "read_noise_per_read_e",
    "read_noise_of",
]

#: Nominal IRAC pixel scale (arcsec per pixel); the brief's 1.2".
PIXEL_SCALE_ARCSEC = 1.2
#: Channel-2 pixel scales that IRACSIM writes (PXSCAL1, PXSCAL2), arcsec.
PIXEL_SCALE_X_ARCSEC = 1.21641835430637
PIXEL_SCALE_Y_ARCSEC = 1.21585676679388
#: Solid angle of one channel-2 pixel (sr), from the IRACSIM scales.
PIXEL_SOLID_ANGLE_SR = PIXEL_SCALE_X_ARCSEC * PIXEL_SCALE_Y_ARCSEC / 206264.80624709636**2
#: Electrons per DN (header GAIN).
GAIN_E_PER_DN = 3.71
#: Warm channel-2 FLUXCONV (MJy/sr per DN/s) used by IRACSIM and the issue.
FLUXCONV_WARM_CH2 = 0.1469
#: The FLUXCONV that the real S19.2 pipeline wrote into AOR 46466816's header.
FLUXCONV_HEADER_XO3 = 0.1447
#: Read noise per read (e): the header RONOISE, used by the physical model.
READ_NOISE_E = 9.4
#: Read noise per read that IRACSIM used for channel 2 (e).
READ_NOISE_IRACSIM2015_E = 16.8
#: Centre wavelength and band edges of channel 2 (um).
WAVELENGTH_UM = 4.5
BAND_UM = (4.0, 5.0)
#: Spitzer primary mirror diameter (m).
TELESCOPE_DIAMETER_M = 0.85
#: Subarray shape (ny, nx) and the 0-based full-array pixel of subarray pixel (0, 0) as (x, y).
SUBARRAY_SHAPE = (32, 32)
SUBARRAY_ORIGIN_FULL = (8, 216)
#: The channel-2 subarray sweet-spot pixel (x, y), 0-based.
SWEET_SPOT_PX = (15, 15)


@dataclass(frozen=True)
class ReadoutMode:
    """One IRAC readout mode (Fowler sampling parameters).

    Parameters
    ----------
    name : str
        Label such as ``"sub_2s"``.
    fowler : int
        Fowler number FN (pedestal reads = signal reads), >= 1.
    wait : int
        Wait ticks WT between the last pedestal and the first signal read, >= 0.
    sample_time_s : float
        Sample (clock tick) time Delta t in seconds: 0.01 subarray, 0.2 full array.
    frame_time_s : float
        The nominal frame time (header FRAMTIME), seconds.
    subarray : bool
        True for 32x32 subarray readout (64 frames per file).
    """

    name: str
    fowler: int
    wait: int
    sample_time_s: float
    frame_time_s: float
    subarray: bool = True

    def __post_init__(self):
        if int(self.fowler) != self.fowler or self.fowler < 1:
            raise InputError(f"readout mode {self.name!r} fowler: expected an integer >= 1, "
                             f"got {self.fowler}")
        if int(self.wait) != self.wait or self.wait < 0:
            raise InputError(f"readout mode {self.name!r} wait: expected an integer >= 0, "
                             f"got {self.wait}")
        if not self.sample_time_s > 0:
            raise InputError(f"readout mode {self.name!r} sample_time_s: expected a positive "
                             f"time in s, got {self.sample_time_s}")

    @property
    def n_max(self) -> int:
        """Sample intervals per frame, ``2 FN + WT``."""
        return 2 * self.fowler + self.wait

    @property
    def t_int_s(self) -> float:
        """Integration time ``n_max dt`` (s)."""
        return self.n_max * self.sample_time_s

    @property
    def t_exp_s(self) -> float:
        """Exposure time ``(FN + WT) dt`` (s), the header EXPTIME."""
        return (self.fowler + self.wait) * self.sample_time_s

    @property
    def frames_per_file(self) -> int:
        """64 for subarray cubes, 1 for full-array images."""
        return 64 if self.subarray else 1

    @property
    def shape(self) -> tuple[int, int]:
        """Image shape (ny, nx)."""
        return SUBARRAY_SHAPE if self.subarray else (256, 256)


#: 2 s subarray (the XO-3 data): FN=8, WT=184, dt=0.01 s -> t_int 2.00 s, t_exp 1.92 s.
SUB_2S = ReadoutMode("sub_2s", 8, 184, 0.01, 2.0, True)
#: 0.4 s subarray: t_exp 0.36 s.
SUB_0P4S = ReadoutMode("sub_0p4s", 4, 32, 0.01, 0.4, True)
#: 0.1 s subarray (the pmap calibration frames): FN=2, WT=6 -> t_int 0.10 s, t_exp 0.08 s.
SUB_0P1S = ReadoutMode("sub_0p1s", 2, 6, 0.01, 0.1, True)
#: 0.02 s subarray: FN=1, WT=0, t_exp 0.01 s.
SUB_0P02S = ReadoutMode("sub_0p02s", 1, 0, 0.01, 0.02, True)
#: Full-array modes, 0.2 s samples; exposure times 1.2, 4.4, 10.4, 26.8, 96.8 s.
FULL_2S = ReadoutMode("full_2s", 4, 2, 0.2, 2.0, False)
FULL_6S = ReadoutMode("full_6s", 8, 14, 0.2, 6.0, False)
FULL_12S = ReadoutMode("full_12s", 8, 44, 0.2, 12.0, False)
FULL_30S = ReadoutMode("full_30s", 16, 118, 0.2, 30.0, False)
FULL_100S = ReadoutMode("full_100s", 16, 468, 0.2, 100.0, False)

READOUT_MODES = {m.name: m for m in (SUB_2S, SUB_0P4S, SUB_0P1S, SUB_0P02S, FULL_2S, FULL_6S,
                                     FULL_12S, FULL_30S, FULL_100S)}


def readout_mode(name: str) -> ReadoutMode:
    """The predefined :class:`ReadoutMode` called ``name`` (e.g. ``"sub_2s"``)."""
    try:
        return READOUT_MODES[name]
    except KeyError:
        raise InputError(f"readout mode: expected one of {sorted(READOUT_MODES)}, "
                         f"got {name!r}") from None


def read_noise_per_read_e(noise_model: str, read_noise_e: float | None = None) -> float:
    """Read noise per read (electrons) of a simulation noise model.

    Parameters
    ----------
    noise_model : {"physical", "iracsim2015"}
        ``"iracsim2015"`` uses IRACSIM's :data:`READ_NOISE_IRACSIM2015_E`
        (16.8 e); any other model the header value :data:`READ_NOISE_E` (9.4 e).
    read_noise_e : float, optional
        An explicit value, returned as is.
    """
    if read_noise_e is not None:
        return float(read_noise_e)
    return READ_NOISE_IRACSIM2015_E if noise_model == "iracsim2015" else READ_NOISE_E


def read_noise_of(cfg: Config) -> float:
    """Read noise per read of a configuration: ``simulation.read_noise_e``, or the model's own.

    See :func:`read_noise_per_read_e`; only ``cfg.simulation.noise_model`` and
    ``cfg.simulation.read_noise_e`` are read.
    """
    return read_noise_per_read_e(cfg.simulation.noise_model, cfg.simulation.read_noise_e)
