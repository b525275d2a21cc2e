"""The two ways to compare methods: ``controlled`` and ``paper``.

``controlled``
    Every method shares the ``[reduce]`` settings: the astrophysical model
    (phase, ramp, eclipse shape), the centroid of the photometry table, the
    sampler and the error rule. Differences between methods are then the
    methods' own; this is the comparison the paper wished it had.
``paper``
    Each method as its team ran it for the 2015 Data Challenge (paper,
    Appendix B): its centroid, its phase and ramp models (fixed, or chosen by
    BIC among the team's candidates), its eclipse shape, its sampler and the
    error it reported. This is what the paper measured.

One :class:`PaperProfile` per registered method holds those choices and, per
cell, the sentence of Appendix B (or of the team's own papers) that justifies
it; ``docs/methods.md`` prints the same table, and a test checks that every
registered method has an entry. A method from a plugin adds its own with
:func:`register_paper_profile`.

Examples
--------
>>> p = paper_profile("pld")
>>> p.phases, p.reported_error
(('quadratic',), ('time_averaging',))
>>> paper_profile("bliss").phases
('flat', 'linear', 'quadratic', 'sinusoid')
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from ..config.reduce import PhaseModel, RampModel
from ..errors import InputError

__all__ = ["PROFILES", "PaperProfile", "paper_profile", "register_paper_profile",
           "centroid_columns", "CENTROID_COLUMNS", "profile_table_rows"]

#: The two comparisons (``[reduce] profile``, ``run.profiles``, ``--profile``).
PROFILES = ("controlled", "paper")

#: Photometry-table columns of each centroid (``docs/photometry.md``).
CENTROID_COLUMNS: dict[str, tuple[str, str]] = {
    "col": ("x_col", "y_col"),
    "gauss": ("x_gauss", "y_gauss"),
    "gauss-fixed": ("x_gfix", "y_gfix"),
}


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
        :data:`CENTROID_COLUMNS`). Pixel methods (ICA, PLD) do not use it
        beyond the aperture the photometry placed.
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
        quadrature as in the controlled profile.
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


_B1 = "App. B.1"
_SILENT = "Appendix B is silent; "

_PROFILES: dict[str, PaperProfile] = {
    "bliss": PaperProfile(
        team="H. Diamond-Lowe, K. Stevenson (POET)", centroid="gauss-fixed",
        phases=("flat", "linear", "quadratic", "sinusoid"), ramps=("none", "linear"),
        eclipse_shape="physical", sampler="mcmc", reported_error=("mcmc",),
        fit="least squares, then DE-MC",
        why={"centroid": f"{_B1}: 'Centroid positions were measured by fitting a 2D Gaussian "
                         "profile with fixed width'",
             "phase": f"{_B1}: 'flat, linear, quadratic, or sinusoidal phase variations' ... "
                      "'Acceptance of model parameters was decided by minimizing the BIC'",
             "ramp": f"{_B1}: 'a flat or possible linear detector ramp', chosen by BIC",
             "fit": f"{_B1}: 'A Differential Evolution Markov Chain (DE-MC) routine ... was used "
                    "to explore the phase space of parameters'",
             "error": f"{_B1}: DE-MC '... and estimate their uncertainties'"}),
    "gp": PaperProfile(
        team="T. Evans", centroid="col", phases=("linear",), ramps=("none",),
        eclipse_shape="physical", sampler="mcmc", reported_error=("mcmc",),
        fit="ML hyperparameters on 30 s bins, then MCMC with the kernel fixed",
        method_options={"bin_seconds": 30.0},
        why={"centroid": _SILENT + "Evans et al. (2015) not read here; the centre of light "
                                   "(the paper's Section 3.1 default)",
             "phase": "Sect. 5: 'eclipse fits using a linear (BLISS, GP, ICA, KR/Data) ... "
                      "phase curve'",
             "ramp": _SILENT + "none (B.2 lists no ramp among the parameters)",
             "fit": "App. B.2: 'maximum likelihood fit ... fluxes and centroids were binned ... "
                    "in groups of ~30 s'",
             "error": "App. B.2: 'MCMC with Metropolis-Hastings ... the covariance kernel "
                      "parameters and white noise variance were held fixed'"}),
    "ica": PaperProfile(
        team="G. Morello", centroid="col", phases=("linear",), ramps=("none",),
        eclipse_shape="physical", sampler="mcmc", reported_error=("mcmc",),
        fit="eclipse plus scaled components, adaptive-Metropolis MCMC",
        why={"centroid": "App. B.3: pixel light curves; no centroid enters the model",
             "phase": "App. B.3: 'an eclipse light curve model (including a linear phase "
                      "variation)'",
             "ramp": _SILENT + "none",
             "fit": "App. B.3: 'An Adaptive Metropolis MCMC algorithm with delayed rejection'",
             "error": "App. B.3: 'The final error bars were then increased to include the ICA "
                      "component separation error' (added in quadrature)"}),
    "kr-data": PaperProfile(
        team="I. Wong", centroid="col", phases=("linear",), ramps=("none",),
        eclipse_shape="physical", sampler="mcmc", reported_error=("prayer_bead", "mcmc"),
        fit="Levenberg-Marquardt", method_options={"k": 50},
        why={"centroid": "App. B.4: 'only the x and y centroids (as measured using the center of "
                         "light technique ...) were used in the kernel's distance metric'",
             "phase": "App. B.4: 'eclipse depth, time of mid-eclipse, and linear slope of phase "
                      "curve'",
             "ramp": _SILENT + "none (B.4 lists the fitted parameters without one)",
             "fit": "App. B.4: 'Levenberg-Marquardt (L-M) nonlinear least squares'",
             "error": "App. B.4: 'both a prayer-bead method and an MCMC routine ... reported the "
                      "largest uncertainty of the two'"}),
    "kr-pmap": PaperProfile(
        team="J. Krick, J. Ingalls", centroid="col", phases=("flat",), ramps=("none",),
        eclipse_shape="physical", sampler="leastsq", reported_error=("jacobian",),
        fit="Levenberg-Marquardt, Mandel & Agol shape", method_options={"k": 50},
        why={"centroid": "App. B.4: 'Euclidean distance in x and y centroid and noise pixels'; "
                         "Sect. 3.1 centre of light",
             "phase": "App. B.4: 'a Mandel & Agol light curve shape with no phase trend'",
             "ramp": _SILENT + "none",
             "fit": "App. B.4: 'using an L-M nonlinear least squares algorithm'",
             "error": "App. B.4: 'The uncertainties returned were solely the formal "
                      "uncertainties in the L-M fit'"}),
    "pld": PaperProfile(
        team="D. Deming", centroid="gauss", phases=("quadratic",), ramps=("none",),
        eclipse_shape="physical", sampler="leastsq", reported_error=("time_averaging",),
        fit="binned, Deming et al. 2015",
        why={"centroid": "App. B.5: '2D Gaussian centroiding ... only to determine where to "
                         "place the circular aperture, but not as a decorrelation variable'",
             "phase": "App. B.5: 'simultaneously with the pixel coefficients and a quadratic "
                      "phase curve'",
             "ramp": _SILENT + "none",
             "fit": "App. B.5; Deming et al. (2015) Sect. 3: fitted on binned data",
             "error": "App. B.5: 'error bars were estimated using the slope of the standard "
                      "deviation vs. bin size relationship ... to extrapolate to bins the width "
                      "of the eclipse duration'"}),
    "segpoly": PaperProfile(
        team="D. Buzasi", centroid="col", phases=("flat",), ramps=("none",),
        eclipse_shape="box", sampler="leastsq", reported_error=("jacobian",),
        fit="two-stage detrend, then box fit",
        why={"centroid": _SILENT + "the centre of light (Sect. 3.1 default)",
             "phase": "Sect. 5: 'a ... flat [KR/Pmap, SP(K2)] phase curve'",
             "ramp": _SILENT + "none",
             "fit": "App. B.6: 'a simple box function was used to fit the eclipse profile'",
             "error": "App. B.6: 'the uncertainties reported are formal fit errors'"}),
}

_SPCA_WHY = {
    "centroid": "Not a team of the paper (Appendix B is silent); Bell et al. (2021) re-scored "
                "the XO-3b eclipses with SPCA; we use the centre of light (Sect. 3.1 default)",
    "phase": "Appendix B is silent; the quadratic phase of the controlled profile (the "
             "challenge's phase curve is curved, Sect. 4.2)",
    "ramp": "Appendix B is silent; none",
    "fit": "SPCA fits with emcee (Bell et al. 2021), 64-frame bins (the method's default)",
    "error": "SPCA reports the posterior width",
}
for _name in ("poly2", "poly3", "poly4", "poly5", "pld-aper"):
    _PROFILES[_name] = PaperProfile(
        team="SPCA (Bell et al. 2021)", centroid="col", phases=("quadratic",), ramps=("none",),
        eclipse_shape="physical", sampler="mcmc", reported_error=("mcmc",),
        fit="emcee, 64-frame bins", why=dict(_SPCA_WHY))


def register_paper_profile(method: str, profile: PaperProfile) -> None:
    """Give a method (e.g. a plugin's) its paper-profile entry."""
    if not isinstance(profile, PaperProfile):
        raise TypeError(f"{profile!r} is not a PaperProfile")
    _PROFILES[method] = profile


def paper_profile(method: str) -> PaperProfile:
    """The paper-profile entry of ``method``; InputError if it has none.

    Examples
    --------
    >>> paper_profile("kr-pmap").reported_error
    ('jacobian',)
    """
    try:
        return _PROFILES[method]
    except KeyError:
        raise InputError(f"method '{method}': no paper profile (the team's pipeline is not "
                         "described; use --profile controlled, or register one with "
                         "eclipsebench.fit.profiles.register_paper_profile)") from None


def centroid_columns(table_columns, centroid: str) -> tuple[tuple[str, str], str]:
    """The (x, y) columns of ``centroid`` in a table, and a note when a fallback was used.

    The fixed-width Gaussian is in a photometry table only when the photometry
    computed it (``[photometry] gauss_width_px``, or ``centroid = "gauss-fixed"``);
    without it the free-width Gaussian stands in and the note says so.

    Examples
    --------
    >>> centroid_columns(["x", "y", "x_col", "y_col", "x_gauss", "y_gauss"], "gauss-fixed")
    (('x_gauss', 'y_gauss'), 'x_gfix/y_gfix not in the table: free-width Gaussian used')
    """
    names = set(table_columns)
    wanted = CENTROID_COLUMNS[centroid]
    if set(wanted) <= names:
        return wanted, ""
    if centroid == "gauss-fixed" and set(CENTROID_COLUMNS["gauss"]) <= names:
        return CENTROID_COLUMNS["gauss"], "x_gfix/y_gfix not in the table: free-width Gaussian used"
    if centroid == "col" and {"x", "y"} <= names:
        return ("x", "y"), "x_col/y_col not in the table: its x/y used"
    raise InputError(f"the photometry table has no {centroid} centroid columns "
                     f"({'/'.join(wanted)}) that the paper profile needs")


def profile_table_rows() -> list[dict[str, str]]:
    """One row per method with a paper profile, for ``docs/methods.md`` and the report."""
    centroid_words = {"col": "centre of light", "gauss": "2-D Gaussian",
                      "gauss-fixed": "2-D Gaussian, fixed width"}
    rows = []
    for name, p in _PROFILES.items():
        phase = p.phases[0] if len(p.phases) == 1 else "BIC among " + ", ".join(p.phases)
        ramp = p.ramps[0] if len(p.ramps) == 1 else "BIC among " + ", ".join(p.ramps)
        rows.append({"method": name, "team": p.team, "centroid": centroid_words[p.centroid],
                     "phase model": phase, "ramp": ramp, "fit": p.fit,
                     "reported error": " or ".join(p.reported_error)
                     + (" (the larger)" if len(p.reported_error) > 1 else "")})
    return rows


def profile_markdown() -> str:
    """The paper-profile table and, per method, the sentence behind each cell (Markdown).

    ``docs/methods.md`` holds this text verbatim (a test compares them).
    """
    rows = profile_table_rows()
    keys = ("method", "centroid", "phase model", "ramp", "fit", "reported error")
    lines = ["| " + " | ".join(keys) + " |", "|" + " --- |" * len(keys)]
    lines += ["| " + " | ".join(f"`{r[k]}`" if k == "method" else r[k] for k in keys) + " |"
              for r in rows]
    lines.append("")
    for name, p in _PROFILES.items():
        lines.append(f"- `{name}` ({p.team}):")
        for cell in ("centroid", "phase", "ramp", "fit", "error"):
            lines.append(f"  - {cell}: {p.why.get(cell, 'not stated')}")
    return "\n".join(lines) + "\n"
