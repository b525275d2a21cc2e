"""The IRAC detector: readout modes and constants, Fowler sampling and its noise.

The lowest layer of the package after :mod:`eclipsebench.errors`: the
simulator, photometry, the BCD reader, the configuration and the photon
limits all take their readout constants (Fowler number, wait ticks, sample
time, read noise, gain, FLUXCONV) and the Fowler noise model from here, and
this package imports none of them.
"""

from .constants import SUB_0P1S, SUB_2S, ReadoutMode, readout_mode

__all__ = ["SUB_0P1S", "SUB_2S", "ReadoutMode", "readout_mode", "NOISE_MODELS",
           "fowler_sample", "group_charges"]

#: Names of :mod:`.fowler` (numpy, numba), loaded on first use (PEP 562) so the
#: constants alone import nothing heavy (the command line's parser reads them).
_FOWLER = ("NOISE_MODELS", "fowler_sample", "group_charges")


def __getattr__(name: str):
    if name not in _FOWLER:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from . import fowler

    return getattr(fowler, name)
