"""The telescope and detector: IRAC channel-2 constants, pointing model, PRFs, Fowler sampling.

Pure kernels on arrays (paper Appendix A). Modules:

- :mod:`.constants`: readout modes (:class:`ReadoutMode`) and detector constants.
- :mod:`.pointing`: :class:`PointingParams`, :class:`PointingRanges`,
  :func:`draw_pointing_params`, :class:`PointingModel`.
- :mod:`.prf`: :class:`BuiltinPRF`, :class:`IrsaPRF`, flux scaling helpers.
- :mod:`.fowler`: :func:`fowler_sample` and unit conversions.
"""

from .constants import SUB_0P1S, SUB_2S, ReadoutMode, readout_mode
from .fowler import NOISE_MODELS, fowler_sample, group_charges
from .pointing import PointingModel, PointingParams, PointingRanges, draw_pointing_params
from .prf import PRF, BuiltinPRF, IrsaPRF, electrons_per_second_scale

__all__ = ["SUB_0P1S", "SUB_2S", "ReadoutMode", "readout_mode", "NOISE_MODELS",
           "fowler_sample", "group_charges", "PointingModel", "PointingParams",
           "PointingRanges", "draw_pointing_params", "PRF", "BuiltinPRF", "IrsaPRF",
           "electrons_per_second_scale"]
