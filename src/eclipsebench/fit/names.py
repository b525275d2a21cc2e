"""The names ``reduce`` offers: events, phase and ramp models, eclipse shapes, time formats.

Plain tuples and one dict, no imports but ``typing``: the command line's parser offers them
as choices without loading the fitter (numba, batman, astropy).
:mod:`.astro_model` and :mod:`.data` re-export them.
"""

from __future__ import annotations

from typing import Literal

__all__ = ["PHASE_MODELS", "PHASE_CURVE_MODELS", "RAMP_MODELS", "ECLIPSE_SHAPES", "EVENTS",
           "TIME_FORMATS"]

PHASE_MODELS = ("flat", "linear", "quadratic", "sinusoid")
#: The phase models of a whole phase curve (``event="phase-curve"``): the first harmonic,
#: or the first and second (:func:`eclipsebench.astro.phase_curves.harmonic_curve`).
PHASE_CURVE_MODELS: tuple[Literal["harmonic1", "harmonic2"], ...] = ("harmonic1", "harmonic2")
RAMP_MODELS = ("none", "linear", "exponential")
ECLIPSE_SHAPES = ("physical", "box")
EVENTS = ("eclipse", "transit", "phase-curve")
#: ``time_format`` -> the offset (days) subtracted to give BMJD. Every format is read as
#: a BJD_TDB-based count: no time-scale or barycentric conversion is made.
TIME_FORMATS = {"bmjd": 0.0, "mjd": 0.0, "bjd": 2400000.5, "jd": 2400000.5}
