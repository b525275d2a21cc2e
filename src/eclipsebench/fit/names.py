"""The names ``reduce`` offers: events, phase and ramp models, eclipse shapes, time formats.

Plain tuples and dicts, no imports but ``typing`` and the plain :mod:`eclipsebench.astro.times`:
the command line's parser offers them as choices without loading the fitter (numba, batman,
astropy).
:mod:`.model` and :mod:`.data` re-export them.
"""

from __future__ import annotations

from typing import Literal

# ``time_format`` -> (offset in days, already barycentric?); the ``time_scale`` and
# ``time_at`` choices: :mod:`eclipsebench.astro.timescales` converts them.
from ..astro.times import TIME_AT, TIME_FORMATS, TIME_SCALES

__all__ = ["PHASE_MODELS", "PHASE_CURVE_MODELS", "RAMP_MODELS", "ECLIPSE_SHAPES", "EVENTS",
           "TIME_FORMATS", "TIME_SCALES", "TIME_AT"]

PHASE_MODELS = ("flat", "linear", "quadratic", "sinusoid")
#: The phase models of a whole phase curve (``event="phase-curve"``): the first harmonic,
#: or the first and second (:func:`eclipsebench.astro.phase_curves.harmonic_curve`).
PHASE_CURVE_MODELS: tuple[Literal["harmonic1", "harmonic2"], ...] = ("harmonic1", "harmonic2")
RAMP_MODELS = ("none", "linear", "exponential")
ECLIPSE_SHAPES = ("physical", "box")
EVENTS = ("eclipse", "transit", "phase-curve")
