"""The report stage of a run: figures, tables and ``report/index.html``.

Pure functions (:func:`centred_phase`, :func:`gain_map`), the task function
:func:`report_task` (reads the run folder, hands arrays to
:func:`eclipsebench.report.build.build_report`) and the planner
:func:`plan_report_tasks`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Table

from ..astro.catalogue import system_for
from ..astro.orbit import orbital_phase
from ..config import Config
from ..decorrelate.kernel import pmap_gain
from ..engine.layout import Layout
from ..engine.tasks import Task
from ..errors import InputError
from ..io.atomic import write_text
from ..io.pmap_files import load_calibration_table
from ..photometry.table import read_photometry
from ..progress import get_logger
from ..stats.challenge import good_frames
from ..stats.compare import group_by_method
from .page import page_folder, relative

__all__ = ["centred_phase", "gain_map", "figures_task", "report_task",
           "plan_photometry_figures_task", "plan_report_tasks"]

log = get_logger("challenge")

#: Photometry columns shown by the centroid and photometry figures.
_PHOTOMETRY_FIGURE_COLUMNS = ("x", "y", "noise_pixels", "background", "flux")


def centred_phase(time_bmjd, system) -> np.ndarray:
    """Orbital phase since mid-transit, in (-0.5, 0.5] (the eclipse near +0.5 -> -0.5)."""
    p = np.asarray(orbital_phase(np.asarray(time_bmjd, float), system))
    return np.where(p > 0.5, p - 1.0, p)


def gain_map(calibration: Path, *, n: int = 41, k: int = 50):
    """The intra-pixel gain around the sweet spot from the calibration star (KR, as Fig. 2).

    Returns ``(x, y, gain)`` on an ``n x n`` grid spanning the 1-99 percentiles
    of the calibration centroids, or None without a calibration file.
    """
    if not Path(calibration).is_file():
        return None
    cal = load_calibration_table(calibration)
    gx = np.linspace(float(np.percentile(cal.x, 1)), float(np.percentile(cal.x, 99)), n)
    gy = np.linspace(float(np.percentile(cal.y, 1)), float(np.percentile(cal.y, 99)), n)
    xx, yy = np.meshgrid(gx, gy)
    gain = pmap_gain(cal, xx.ravel(), yy.ravel(), None, k=k, scales=np.ones(2))
    return gx, gy, gain.reshape(xx.shape)


def _ppm(v) -> str:
    return "n/a" if v is None else f"{v:.1f} ppm"


def _analytic_note(summary: dict) -> str:
    """The analytic photon limit with the inputs that make it differ from the README's 64.5 ppm."""
    text = _ppm(summary.get("sigma_phot_ppm_analytic"))
    inputs = (summary.get("photon_limit") or {}).get("analytic") or {}
    if not inputs:
        return text
    return (f"{text}, used for r and a: Eq. photon_noise on this run's own photometry (S/N "
            f"{inputs['snr_single']:.0f} per frame, N = {inputs['frames']:.0f} frames per epoch, "
            f"f_in = {inputs['f_in']:.3f} from each epoch's eclipse geometry, D = "
            f"{inputs['depth_ppm']:.0f} ppm). The README's 64.5 ppm is the same equation on the "
            "paper's simulated-data inputs (S/N 268, N = 15232, f_in = 1/3); the paper prints "
            "53 ppm, which its equation does not give (docs/scoring.md, 'The photon limit in a "
            "run')")


def _photometry_inputs(cfg: Config, layout: Layout, epochs: list[int]):
    """Each epoch's good frames for the centroid and photometry figures, and the gain map."""
    system = system_for(cfg.system)
    photometry: dict[object, dict[str, Any]] = {}
    for e in epochs:
        t = read_photometry(layout.photometry(e))
        good = good_frames(t)
        photometry[e] = {"phase": centred_phase(np.asarray(t["time_bmjd"])[good], system),
                         **{k: np.asarray(t[k], float)[good] for k in _PHOTOMETRY_FIGURE_COLUMNS}}
    try:
        gains = gain_map(layout.calibration())
    except InputError as exc:
        log.warning("no gain map behind the centroids: %s", exc)
        gains = None
    return photometry, gains


def _result_inputs(cfg: Config, layout: Layout, methods: list[str], epochs: list[int]):
    """The summary, the profile the figures show, its depths and one epoch's light curves."""
    summary = json.loads(layout.summary.read_text())
    profile = cfg.run.profiles[0]   # the summary's top level (a run may ask for the paper one only)
    depths = Table.read(layout.depths_of(profile), format="ascii.ecsv")
    system = system_for(cfg.system)
    lc_epoch = min(cfg.run.lightcurve_epoch, max(epochs))
    curves = {}
    for m in methods:
        path = layout.result_lightcurve(m, lc_epoch, profile=profile)
        if path.is_file():
            lc = Table.read(path, format="ascii.ecsv")
            curves[m] = {"phase": centred_phase(lc["time_bmjd"], system),
                         "flux_corrected": np.asarray(lc["flux_corrected"], float),
                         "astro_model": np.asarray(lc["astro_model"], float)}
    truth_curve = None
    truth_lc = layout.truth_lightcurve(lc_epoch)
    if truth_lc.is_file():
        t = Table.read(truth_lc, format="ascii.ecsv")
        truth_curve = (centred_phase(t["time_bmjd"], system), np.asarray(t["flux_true"], float))
    return summary, profile, depths, {"truth_ppm": summary.get("truth_ppm"),
                                      "lightcurves": curves, "lightcurve_epoch": lc_epoch,
                                      "truth_curve": truth_curve}


#: The figures of a run's statistics drawn by the first of the two tasks that draw them (the
#: others by the second): the mean/difference plots between methods take as long as the rest.
FIRST_RESULT_FIGURES = ("method_differences", "repeatability_reliability")


def figures_task(cfg: Config, root: str, methods: list[str], epochs: list[int], part: str,
                 out_path: str) -> None:
    """Draw one part of a run's figures into its report folder (``part``: ``photometry``,
    ``results-1`` or ``results-2``) and record them (``out_path``: name, caption, files, in
    the page's order, and what was not drawn) for :func:`report_task`."""
    # matplotlib (through .build): imported only when a report is asked for
    from .build import draw_planned, plan_photometry_figures, plan_result_figures

    layout = Layout(Path(root))
    dest = page_folder(layout.report.parent)
    if part == "photometry":
        planned, skipped = plan_photometry_figures(*_photometry_inputs(cfg, layout, epochs))
        position = {name: i for i, (name, _, _) in enumerate(planned)}
    else:
        summary, profile, depths, inputs = _result_inputs(cfg, layout, methods, epochs)
        planned, skipped = plan_result_figures(
            summary, group_by_method(depths, list(summary["methods"])), profile, **inputs)
        position = {name: i for i, (name, _, _) in enumerate(planned)}
        first = part == "results-1"
        planned = [p for p in planned if (p[0] in FIRST_RESULT_FIGURES) == first]
        skipped = skipped if first else []
    items = draw_planned(dest, planned)
    record = {"figures": [[position[name], name, caption, [relative(f, dest) for f in files]]
                          for name, caption, files in items], "not_drawn": skipped}
    write_text(Path(out_path), json.dumps(record, indent=1) + "\n")


def report_task(cfg: Config, root: str, methods: list[str], epochs: list[int],
                drawn: list[str]) -> None:
    """Tables and ``report/index.html`` (written last) with the figures that
    :func:`figures_task` drew (its records ``drawn``, in the page's order)."""
    # matplotlib (through .build): imported only when a report is asked for
    from .build import build_report

    layout = Layout(Path(root))
    summary, profile, depths, inputs = _result_inputs(cfg, layout, methods, epochs)
    dest = layout.report.parent
    placed, not_drawn = [], []
    for part, path in enumerate(drawn):
        record = json.loads(Path(path).read_text())
        placed += [((part > 0, at), (name, caption, [dest / f for f in files]))
                   for at, name, caption, files in record["figures"]]
        not_drawn += record["not_drawn"]
    figures = [item for _, item in sorted(placed, key=lambda p: p[0])]
    notes = {"challenge": summary.get("challenge"), "seed": summary.get("seed"),
             "epochs": len(epochs), "methods": ", ".join(methods),
             "sigma_phot (analytic, Section 3.3)": _analytic_note(summary),
             "sigma_phot (empirical, no pointing motion)":
                 _ppm(summary.get("sigma_phot_ppm_empirical"))
                 + " (the SD of one method's depths on twins of the epochs whose star does not "
                   "move: photon noise and what the method adds; not used for r and a)",
             "true depth": _ppm(summary.get("truth_ppm"))}
    build_report(dest, summary=summary, depths=depths, truth_ppm=inputs["truth_ppm"],
                 title=f"eclipsebench: {summary.get('challenge')}", notes=notes,
                 profile=profile, drawn=(figures, not_drawn))


#: The parts of a run's figures, each drawn by a task of its own.
FIGURE_PARTS = ("photometry", "results-1", "results-2")


def _record(layout: Layout, part: str) -> Path:
    """Where :func:`figures_task` records the figures of ``part``."""
    return layout.report.parent / f"figures-{part}.json"


def plan_photometry_figures_task(cfg: Config, layout: Layout, epochs: list[int], *,
                                 after: tuple[str, ...]) -> list[Task]:
    """The centroid and photometry figures, drawn as soon as the photometry is measured
    (planned beside it: the engine's priority is the plan's order)."""
    return [Task("report/figures-photometry", "report", figures_task,
                 (cfg, str(layout.root), [], epochs, "photometry",
                  str(_record(layout, "photometry"))),
                 (_record(layout, "photometry"),), tuple(after))]


def plan_report_tasks(cfg: Config, layout: Layout, methods: list[str], epochs: list[int], *,
                      after: tuple[str, ...]) -> list[Task]:
    """The figures of the statistics in two tasks beside each other, then ``report`` (the
    tables and ``report/index.html``, last) with those and the photometry's
    (:func:`plan_photometry_figures_task`)."""
    tasks = [Task(f"report/figures-{part}", "report", figures_task,
                  (cfg, str(layout.root), methods, epochs, part, str(_record(layout, part))),
                  (_record(layout, part),), tuple(after))
             for part in FIGURE_PARTS[1:]]
    return tasks + [Task("report", "report", report_task,
                         (cfg, str(layout.root), methods, epochs,
                          [str(_record(layout, p)) for p in FIGURE_PARTS]),
                         (layout.report,),
                         (*after, "report/figures-photometry", *(t.key for t in tasks)))]
