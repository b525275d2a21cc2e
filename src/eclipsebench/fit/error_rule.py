"""The error rule: from the fit's depth-error estimates to the reported error and its name.

A pure function of the estimates (no fit, no method): ``docs/fitting.md``,
"Depth errors". The estimates are the fit's shared three (``jacobian_beta``:
the Jacobian error times ``max(1, beta_red)``; ``prayer_bead``; ``mcmc``: the
posterior's half-width), the formal ``jacobian`` error, and a method's own
(PLD's ``time_averaging``). Which one is reported:

* a list of names given by the caller (the paper profile: the team's), the
  largest of them;
* otherwise ``error_rule = "method"``: the names the method's authors reported
  (its record's paper profile), where it has them;
* otherwise ``error_rule = "posterior"`` with a posterior sampled: ``mcmc``;
* otherwise the largest of the shared three.

A method's extra depth variance (ICA's separation error) is then added in
quadrature, and ``+separation`` to the name.

Examples
--------
>>> shared = {"jacobian_beta": 80e-6, "prayer_bead": 95e-6, "mcmc": None}
>>> reported_depth_error(shared, error_rule="largest")
(9.5e-05, 'prayer_bead')
>>> reported_depth_error(shared, jacobian=70e-6, reported=("jacobian",), error_rule="largest")
(7e-05, 'jacobian')
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ..errors import InputError

__all__ = ["largest_estimate", "reported_depth_error", "check_reported_error", "ZERO_ERROR_PPM"]


def largest_estimate(estimates: Mapping[str, float | None]) -> tuple[float, str]:
    """The largest finite estimate and its name; ``(nan, "none")`` when there is none."""
    usable = {k: v for k, v in estimates.items() if v is not None and np.isfinite(v)}
    if not usable:
        return float("nan"), "none"
    name = max(usable, key=lambda k: usable[k])
    return float(usable[name]), name


def reported_depth_error(shared: Mapping[str, float | None], *, error_rule: str,
                         jacobian: float | None = None,
                         own: Mapping[str, float] | None = None,
                         reported: tuple[str, ...] | None = None,
                         authors: tuple[str, ...] | None = None, sampled: bool = False,
                         errors: bool = True, separation_var: float = 0.0,
                         method: str = "") -> tuple[float, str]:
    """The reported depth error (fraction) and the name of its estimate.

    Parameters
    ----------
    shared : Mapping
        ``jacobian_beta``, ``prayer_bead`` and ``mcmc`` (None where not computed).
    error_rule : {"posterior", "largest", "method"}
        ``[reduce] error_rule``.
    jacobian : float, optional
        The formal least-squares error (a team may report it).
    own : Mapping, optional
        The method's own estimates by name.
    reported : tuple of str, optional
        Names to report, the largest of them (the paper profile's team errors);
        overrides the rule.
    authors : tuple of str, optional
        The names the method's authors reported (its paper profile), for
        ``error_rule = "method"``.
    sampled : bool
        Whether a posterior was sampled (``mcmc`` is then in ``shared``).
    errors : bool
        False: errors were not computed beyond the shared three (a model
        comparison fit); only the largest of those is given.
    separation_var : float
        A variance the fit cannot see (ICA's separation), added in quadrature.
    method : str
        The method's name, for the message when a named estimate is missing.

    Raises
    ------
    InputError
        A named estimate was not computed.
    """
    depth_err, name = largest_estimate(shared)
    if reported is None and error_rule == "method":
        reported = authors
    if reported is None and error_rule == "posterior" and sampled:
        reported = ("mcmc",)
    if errors and reported is not None:
        every = {"jacobian": jacobian, **shared, **dict(own or {})}
        depth_err, name = largest_estimate({k: every.get(k) for k in reported})
        if not np.isfinite(depth_err):
            raise InputError(f"method '{method}': its reported error "
                             f"'{' or '.join(reported)}' was not computed")
    if separation_var > 0:
        depth_err = float(np.hypot(depth_err, np.sqrt(separation_var)))
        name += "+separation"
    return depth_err, name


#: A depth error below this (1e-12 of the flux: rounding) is zero, never a result.
ZERO_ERROR_PPM = 1e-6


def check_reported_error(depth_ppm: float, depth_err_ppm: float | None, *, method: str,
                         source: str) -> None:
    """Refuse a depth whose reported error is zero or not finite: it is not a result.

    A constant flux, or a fit that the data do not constrain, gives an error
    of zero (to rounding) or NaN; a depth quoted with it would claim infinite
    precision. ``eb.reduce`` and ``eclipsebench reduce`` both refuse it here.

    Raises
    ------
    InputError
        One line naming ``source`` (the table), the method, the depth and the error.

    Examples
    --------
    >>> check_reported_error(1875.0, 42.0, method="bliss", source="epoch_01.fits")
    >>> check_reported_error(0.0, 2e-9, method="bliss", source="epoch_01.fits")
    Traceback (most recent call last):
    ...
    eclipsebench.errors.InputError: epoch_01.fits: the bliss fit gives depth 0.0 +- 2e-09 ppm: a zero or non-finite error is not a result (constant flux or a degenerate fit); nothing written
    """
    if depth_err_ppm is None or not math.isfinite(depth_err_ppm) \
            or depth_err_ppm < ZERO_ERROR_PPM:
        shown = "no" if depth_err_ppm is None else f"{depth_err_ppm:.3g}"
        raise InputError(f"{source}: the {method} fit gives depth {depth_ppm:.1f} +- "
                         f"{shown} ppm: a zero or non-finite error is not a result "
                         "(constant flux or a degenerate fit); nothing written")
