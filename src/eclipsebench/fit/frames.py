"""Which frames of an epoch a fit uses: the settling AOR rule.

The paper's challenge observed each epoch as a 30-minute Pre AOR followed by
the 7.8-hour Main AOR (Section 2.1); the Pre AOR exists "to allow short term
pointing drift to settle", and the paper's frame count N = 14,912 = 233 x 64
is the Main AOR alone. So by default the reducer leaves out the frames of an
epoch's first AOR when it is short beside the others (:func:`settling_aor`),
and says how many; ``[reduce] settling_aor = "keep"`` fits them.
"""

from __future__ import annotations

import numpy as np

__all__ = ["settling_aor", "SETTLING_MAX_FRACTION"]

#: The first AOR is a settling AOR when its time span is at most this fraction of
#: the longest AOR's. The challenge's Pre AOR spans 0.06 of its Main AOR (11 of
#: 244 cubes); real Spitzer staring programmes used 20-30 min pre-AORs before
#: AORs of several hours, so any fraction between about 0.1 and 0.5 separates them.
SETTLING_MAX_FRACTION = 0.25


def settling_aor(time_bmjd: np.ndarray, aorkey: np.ndarray | None,
                 max_fraction: float = SETTLING_MAX_FRACTION) -> np.ndarray:
    """Mask of the frames of the epoch's settling AOR (all False when there is none).

    Parameters
    ----------
    time_bmjd : ndarray, shape (n,)
        Frame times.
    aorkey : ndarray, shape (n,) or None
        The AOR of each frame; None (a table without AORs) means one AOR.
    max_fraction : float
        The first AOR (by start time) is the settling AOR when the epoch has at
        least two AORs and its span is at most this fraction of the longest.

    Returns
    -------
    ndarray of bool, shape (n,)

    Examples
    --------
    >>> t = np.concatenate([np.linspace(0, 0.02, 10), np.linspace(0.03, 0.35, 100)])
    >>> aor = np.repeat([1, 2], [10, 100])
    >>> int(settling_aor(t, aor).sum())
    10
    >>> int(settling_aor(t, None).sum())
    0
    """
    time = np.asarray(time_bmjd, dtype=float)
    mask = np.zeros(len(time), dtype=bool)
    if aorkey is None:
        return mask
    aor = np.asarray(aorkey)
    keys = np.unique(aor)
    if len(keys) < 2:
        return mask
    starts = {k: time[aor == k].min() for k in keys}
    spans = {k: np.ptp(time[aor == k]) for k in keys}
    first = min(keys, key=lambda k: starts[k])
    if spans[first] <= max_fraction * max(spans.values()):
        mask = aor == first
    return mask
