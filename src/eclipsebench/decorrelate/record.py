"""One record per method: its label, its fitter policy, its paper profile, its docs anchor.

A method's facts that are not code live here, registered with its class
(``Systematics.record``), so that nothing outside the method's module and the
registry branches on a method's name:

* :class:`FitterPolicy`: how the shared fitter treats the method (its MCMC
  move, whether the prayer bead applies, whether its likelihood models the
  white noise, whether it draws random numbers, whether ``with_flux`` equals
  a fresh build);
* :class:`PaperProfile`: how its team ran it for the 2015 Data Challenge
  (paper, Appendix B; the teams' table is the data file
  ``eclipsebench/data/paper_teams.toml``, read by :func:`team_profile`),
  which the ``paper`` profile reproduces, including the
  one statement of the error its authors reported (``reported_error``, also
  what ``[reduce] error_rule = "method"`` reports). A method without one (a
  plugin, say) runs in the ``paper`` profile as in the ``controlled`` one;
* a label (the paper's name of the method, e.g. ``"KR/Data"``) and the anchor
  of its section in ``docs/methods.md``.

Examples
--------
>>> from eclipsebench.decorrelate import get_method
>>> rec = get_method("pld").record
>>> rec.label, rec.paper.reported_error, rec.paper.phases
('PLD', ('time_averaging',), ('quadratic',))
>>> MethodRecord().paper is None
True
"""

from __future__ import annotations

import dataclasses
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Any, Literal

from ..config.reduce import PhaseModel, RampModel

__all__ = ["FitterPolicy", "PaperProfile", "MethodRecord", "heading_anchor", "team_profile"]


@dataclass(frozen=True)
class FitterPolicy:
    """How the shared fitter treats a method.

    Attributes
    ----------
    preferred_move : {"de", "stretch"}
        The emcee move of the method's MCMC: ``"de"`` (differential evolution,
        ter Braak 2006; the DE-MC of the BLISS team, and the move that mixes
        fastest here: integrated autocorrelation times of 11-14 steps against
        38-55 for the stretch move, docs/benchmarks-history.md "mcmc") or
        ``"stretch"`` (emcee's affine-invariant move, Goodman & Weare 2010).
        Both sample the same posterior.
    use_prayer_bead : bool
        Whether the prayer-bead error applies. A method whose model follows
        the correlated noise itself (a GP's conditional mean) leaves residuals
        that are not the noise the bead should shift, and may set this to
        False (its errors then come from the Jacobian and MCMC).
    likelihood_models_noise : bool
        Whether ``log_likelihood`` models the white noise itself (GP's fitted
        noise term); otherwise the fitter rescales the flux errors to
        chi2_red = 1.
    stochastic : bool
        Whether the method draws random numbers (its result then depends on
        the seed).
    with_flux_rebuilds : bool
        Whether ``with_flux`` equals a fresh build on the new fluxes. A method
        whose data-derived state is a fixed pre-processing step (SP(K2)'s
        detrend) may keep it on refits and set this to False.
    """

    preferred_move: Literal["de", "stretch"] = "de"
    use_prayer_bead: bool = True
    likelihood_models_noise: bool = False
    stochastic: bool = False
    with_flux_rebuilds: bool = True


@dataclass(frozen=True)
class PaperProfile:
    """One team's pipeline choices (paper, Appendix B) for one method.

    Attributes
    ----------
    team : str
        Who ran it for the 2015 challenge (or whose pipeline it is).
    centroid : {"col", "gauss", "gauss-fixed"}
        The centroid the method regresses on: centre of light, 2-D Gaussian
        with free width, 2-D Gaussian with fixed width (columns in
        :data:`eclipsebench.fit.profiles.CENTROID_COLUMNS`). Pixel methods
        (ICA, PLD) do not use it beyond the aperture the photometry placed.
    phases : tuple of str
        Phase-curve models; more than one: the one of least BIC is used.
    ramps : tuple of str
        Ramp models; more than one: chosen by BIC together with the phase.
    eclipse_shape : {"physical", "box"}
        The eclipse profile fitted.
    sampler : {"leastsq", "mcmc"}
        Whether the team sampled a posterior.
    reported_error : tuple of str
        The depth errors the team reported; the largest is reported
        (estimate names of the fit: ``jacobian`` (formal), ``jacobian_beta``,
        ``prayer_bead``, ``mcmc``, or a method's own such as ``time_averaging``).
        A method's ``extra_depth_variance`` (ICA's separation error) is added in
        quadrature as in the controlled profile. The same errors are reported
        in the controlled profile under ``[reduce] error_rule = "method"``.
    fit : str
        How the team fitted, in words (the table's "fit" column).
    method_options : Mapping
        Options of the method that the team's pipeline sets.
    why : Mapping
        Per column (``centroid``, ``phase``, ``ramp``, ``fit``, ``error``): the
        paper's sentence, or where Appendix B is silent, what we chose and why.
    """

    team: str
    centroid: Literal["col", "gauss", "gauss-fixed"]
    phases: tuple[PhaseModel, ...]
    ramps: tuple[RampModel, ...]
    eclipse_shape: Literal["physical", "box"]
    sampler: Literal["leastsq", "mcmc"]
    reported_error: tuple[str, ...]
    fit: str
    method_options: Mapping[str, Any] = field(default_factory=dict)
    why: Mapping[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class MethodRecord:
    """A method's facts beside its code, registered with its class (``cls.record``).

    Attributes
    ----------
    label : str
        The method's name in the paper's tables (``"KR/Data"``), or another
        display name; empty: the registry name.
    policy : FitterPolicy
        How the shared fitter treats the method.
    paper : PaperProfile or None
        Its team's pipeline for the ``paper`` profile; None: the method runs
        in the ``paper`` profile as in the ``controlled`` one.
    docs_anchor : str
        The anchor of its section in ``docs/methods.md``. A class that
        declares its own record and leaves this empty gets the anchor of the
        heading ``LABEL (`name`)`` when it is registered (:func:`heading_anchor`);
        a class without a record of its own has none.
    in_paper : bool
        Whether the method is one of the paper's seven (its rows of Tables 3
        and 4 are then looked up under ``label``).
    """

    label: str = ""
    policy: FitterPolicy = field(default_factory=FitterPolicy)
    paper: PaperProfile | None = None
    docs_anchor: str = ""
    in_paper: bool = False


def heading_anchor(heading: str) -> str:
    """The anchor MyST makes of a Markdown heading (``myst_heading_anchors``, GitHub's rule).

    Lower case; characters other than letters, digits, ``-``, ``_`` and spaces
    dropped; each space a ``-``.

    Examples
    --------
    >>> heading_anchor("KR/Data (`kr-data`)")
    'krdata-kr-data'
    >>> heading_anchor("SP(K2) (`segpoly`)")
    'spk2-segpoly'
    """
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


@cache
def _teams() -> dict[str, Any]:
    text = resources.files("eclipsebench.data").joinpath("paper_teams.toml").read_text("utf-8")
    return tomllib.loads(text)


def team_profile(name: str) -> PaperProfile:
    """The paper profile ``name`` of ``eclipsebench/data/paper_teams.toml`` (Appendix B).

    Examples
    --------
    >>> p = team_profile("pld")
    >>> p.team, p.centroid, p.reported_error
    ('D. Deming', 'gauss', ('time_averaging',))
    """
    entry = dict(_teams()[name])
    names = {f.name for f in dataclasses.fields(PaperProfile)}
    if not set(entry) <= names:   # a typo in the package's own data: a bug, said loudly
        raise KeyError(f"paper_teams.toml [{name}]: unknown keys {sorted(set(entry) - names)}")
    values: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v for k, v in entry.items()}
    return PaperProfile(**values)
