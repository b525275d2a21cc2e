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

Each method's :class:`~eclipsebench.decorrelate.record.PaperProfile` sits in
its record (``cls.record.paper``, in the method's module) with, per cell, the
sentence of Appendix B (or of the team's own papers) that justifies it;
``docs/methods.md`` prints the same table (:func:`profile_markdown`). A method
without one (a plugin, unless it sets its record's ``paper`` or calls
:func:`register_paper_profile`) runs in the paper profile as in the controlled
one.

Examples
--------
>>> p = paper_profile("pld")
>>> p.phases, p.reported_error
(('quadratic',), ('time_averaging',))
>>> paper_profile("bliss").phases
('flat', 'linear', 'quadratic', 'sinusoid')
"""

from __future__ import annotations

from dataclasses import replace

from ..decorrelate.base import available_methods, get_method
from ..decorrelate.record import PaperProfile
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


def register_paper_profile(method: str, profile: PaperProfile) -> None:
    """Give a registered method (e.g. a plugin's) its team's pipeline (its record's ``paper``)."""
    if not isinstance(profile, PaperProfile):
        raise TypeError(f"{profile!r} is not a PaperProfile")
    cls = get_method(method)
    cls.record = replace(cls.record, paper=profile)


def paper_profile(method: str) -> PaperProfile | None:
    """The team's pipeline of ``method`` (its record's ``paper``); None: run as controlled.

    Examples
    --------
    >>> paper_profile("kr-pmap").reported_error
    ('jacobian',)
    """
    return get_method(method).record.paper


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


def _paper_profiles() -> list[tuple[str, PaperProfile]]:
    """(name, profile) of every registered method with a team's pipeline, in registry order."""
    out = []
    for name in available_methods():
        paper = get_method(name).record.paper
        if paper is not None:
            out.append((name, paper))
    return out


def profile_table_rows() -> list[dict[str, str]]:
    """One row per method with a paper profile, for ``docs/methods.md`` and the report."""
    centroid_words = {"col": "centre of light", "gauss": "2-D Gaussian",
                      "gauss-fixed": "2-D Gaussian, fixed width"}
    rows = []
    for name, p in _paper_profiles():
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
    for name, p in _paper_profiles():
        lines.append(f"- `{name}` ({p.team}):")
        for cell in ("centroid", "phase", "ramp", "fit", "error"):
            lines.append(f"  - {cell}: {p.why.get(cell, 'not stated')}")
    return "\n".join(lines) + "\n"
