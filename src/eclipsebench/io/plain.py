"""The one JSON encoder: any result as plain JSON types.

Every file, digest and ``--json`` printout the package writes goes through
:func:`json_safe` (result files, summaries, the CLI's stdout, content
digests), so a value is spelt the same wherever it appears: mappings become
dicts with string keys, tuples, lists and arrays become lists, numpy scalars
Python numbers, and a non-finite float (which JSON lacks) ``null``, kept
(``nonfinite="keep"``, for an object read back before it is written) or its
``repr`` (``"repr"``, for a digest that must tell NaN from infinity).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Literal

__all__ = ["json_safe"]

Nonfinite = Literal["null", "keep", "repr"]


def json_safe(obj: Any, *, nonfinite: Nonfinite = "null") -> Any:
    """A copy of ``obj`` in plain JSON types.

    Parameters
    ----------
    obj : any
        Mappings, sequences, numpy arrays and scalars, numbers, strings, None
        (anything else is returned as it is).
    nonfinite : {"null", "keep", "repr"}
        What a NaN or an infinity becomes: None (valid JSON, stable bytes;
        the default), itself, or ``repr`` of it (``'nan'``, ``'inf'``).

    Examples
    --------
    >>> import numpy as np
    >>> json_safe({1: (np.float64(2.5), float("nan")), "a": np.arange(2)})
    {'1': [2.5, None], 'a': [0, 1]}
    >>> json_safe([float("inf")], nonfinite="repr"), json_safe([float("nan")], nonfinite="keep")
    (['inf'], [nan])
    """
    if isinstance(obj, Mapping):
        return {str(k): json_safe(v, nonfinite=nonfinite) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v, nonfinite=nonfinite) for v in obj]
    if callable(getattr(obj, "tolist", None)) and not isinstance(obj, (str, bytes)):
        # a numpy array (a list) or scalar (a Python number), astropy's Column too
        return json_safe(obj.tolist(), nonfinite=nonfinite)
    if isinstance(obj, float) and not math.isfinite(obj):
        return None if nonfinite == "null" else repr(obj) if nonfinite == "repr" else obj
    return obj
