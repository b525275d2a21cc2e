"""The telescope: pointing model, PRFs and the intra-pixel gain (paper Appendix A).

Pure kernels on arrays. Modules:

- :mod:`.pointing`: :class:`PointingParams`, :class:`PointingRanges`,
  :func:`draw_pointing_params`, :class:`PointingModel`.
- :mod:`.prf`: :class:`BuiltinPRF`, :class:`IrsaPRF`, the gain polynomial,
  flux scaling helpers; measured with :mod:`eclipsebench.photometry`.

The detector (readout modes, constants, Fowler sampling) is
:mod:`eclipsebench.detector`.
"""

from .pointing import PointingModel, PointingParams, PointingRanges, draw_pointing_params
from .prf import PRF, BuiltinPRF, IrsaPRF, electrons_per_second_scale

__all__ = ["PointingModel", "PointingParams", "PointingRanges", "draw_pointing_params", "PRF",
           "BuiltinPRF", "IrsaPRF", "electrons_per_second_scale"]
