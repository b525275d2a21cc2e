"""The result of a fit: one epoch's (:class:`EpochResult`) and a joint fit's
(:class:`JointResult`), each with its own ``to_dict`` / ``from_dict``, their files,
their text and HTML summaries and their figures.

- :mod:`.epoch`: :class:`EpochResult`, its schema and light-curve table;
- :mod:`.joint`: :class:`JointResult`;
- :mod:`.files`: the paths beside a ``RESULT.json``, the one writer
  (:func:`write_result`), the one reader (:func:`read_result`) and the resume
  rule (:func:`result_ok`);
- :mod:`.display`: the text and HTML summaries of any result class;
- :mod:`.plot`: an epoch's figures (matplotlib, imported when a figure is made).

This package keeps the public names: import from here.
"""

from __future__ import annotations

from .epoch import LIGHTCURVE_COLUMNS, EpochResult, bic_data, lightcurve_errors
from .files import (
    chain_path,
    lightcurve_path,
    read_result,
    result_ok,
    write_failure,
    write_result,
)
from .joint import JointResult

__all__ = ["EpochResult", "lightcurve_errors", "lightcurve_path", "chain_path",
           "read_result", "bic_data", "JointResult", "write_result", "write_failure",
           "result_ok", "LIGHTCURVE_COLUMNS"]
