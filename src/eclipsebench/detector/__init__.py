"""The IRAC detector: readout modes and constants, Fowler sampling and its noise.

The lowest layer of the package after :mod:`eclipsebench.errors`: the
simulator, photometry, the BCD reader, the configuration and the photon
limits all take their readout constants (Fowler number, wait ticks, sample
time, read noise, gain, FLUXCONV) and the Fowler noise model from here, and
this package imports none of them.
"""

from .constants import SUB_0P1S, SUB_2S, ReadoutMode, readout_mode
from .fowler import NOISE_MODELS, fowler_sample, group_charges

__all__ = ["SUB_0P1S", "SUB_2S", "ReadoutMode", "readout_mode", "NOISE_MODELS",
           "fowler_sample", "group_charges"]
