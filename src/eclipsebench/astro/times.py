"""Time references: the BMJD offset and the start of the paper's simulated epoch 10.

Plain numbers, no imports: the command line's parser names them in its help
without loading numpy or scipy (:mod:`.orbit` and :mod:`.bias` re-export them).
"""

from __future__ import annotations

__all__ = ["BMJD_OFFSET", "EPOCH10_START_BMJD"]

BMJD_OFFSET = 2400000.5
"""BMJD = BJD - 2400000.5."""

EPOCH10_START_BMJD = 2234.8406 + 2455000.0 - BMJD_OFFSET
"""Start of the paper's simulated epoch 10 (Table 2: JD - 2455000 = 2234.8406) as BMJD."""
