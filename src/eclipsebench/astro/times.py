"""Time references: the BMJD offset, the start of the paper's simulated epoch 10, time formats.

Plain numbers, no imports: the command line's parser names them in its help
without loading numpy or scipy (:mod:`.orbit` and :mod:`.bias` re-export them).
"""

from __future__ import annotations

__all__ = ["BMJD_OFFSET", "EPOCH10_START_BMJD", "TIME_FORMATS", "TIME_SCALES", "TIME_AT"]

BMJD_OFFSET = 2400000.5
"""BMJD = BJD - 2400000.5."""

EPOCH10_START_BMJD = 2234.8406 + 2455000.0 - BMJD_OFFSET
"""Start of the paper's simulated epoch 10 (Table 2: JD - 2455000 = 2234.8406) as BMJD."""

#: How a table may give its times (:mod:`.timescales`): ``format`` -> (the offset in days
#: subtracted to give an MJD-like count, whether the times are already barycentric).
TIME_FORMATS = {"bmjd": (0.0, True), "bjd": (BMJD_OFFSET, True), "mjd": (0.0, False),
                "jd": (BMJD_OFFSET, False)}
#: The time scales converted to TDB (astropy's names).
TIME_SCALES = ("utc", "tt", "tdb")
#: Where in its frame a time stamp lies.
TIME_AT = ("start", "mid", "end")
