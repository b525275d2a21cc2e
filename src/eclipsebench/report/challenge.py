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
from ..io.pmap_files import load_calibration_table
from ..photometry.table import read_photometry
from ..progress import get_logger
from ..stats.challenge import good_frames

__all__ = ["centred_phase", "gain_map", "report_task", "plan_report_tasks"]

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


def report_task(cfg: Config, root: str, methods: list[str], epochs: list[int]) -> None:
    """Figures, tables and ``report/index.html`` (written last)."""
    # matplotlib (through .build): imported only when a report is asked for
    from .build import build_report

    layout = Layout(Path(root))
    summary = json.loads(layout.summary.read_text())
    profile = cfg.run.profiles[0]   # the summary's top level (a run may ask for the paper one only)
    depths = Table.read(layout.depths_of(profile), format="ascii.ecsv")
    system = system_for(cfg.system)
    photometry: dict[object, dict[str, Any]] = {}
    for e in epochs:
        t = read_photometry(layout.photometry(e))
        good = good_frames(t)
        photometry[e] = {"phase": centred_phase(np.asarray(t["time_bmjd"])[good], system),
                         **{k: np.asarray(t[k], float)[good] for k in _PHOTOMETRY_FIGURE_COLUMNS}}
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
    try:
        gains = gain_map(layout.calibration())
    except InputError as exc:
        log.warning("no gain map behind the centroids: %s", exc)
        gains = None
    notes = {"challenge": summary.get("challenge"), "seed": summary.get("seed"),
             "epochs": len(epochs), "methods": ", ".join(methods),
             "sigma_phot (analytic, Section 3.3)": _analytic_note(summary),
             "sigma_phot (empirical, no pointing motion)":
                 _ppm(summary.get("sigma_phot_ppm_empirical"))
                 + " (the SD of one method's depths on twins of the epochs whose star does not "
                   "move: photon noise and what the method adds; not used for r and a)",
             "true depth": _ppm(summary.get("truth_ppm"))}
    build_report(layout.report.parent, summary=summary, depths=depths,
                 truth_ppm=summary.get("truth_ppm"), photometry=photometry, lightcurves=curves,
                 lightcurve_epoch=lc_epoch, truth_curve=truth_curve, gain_map=gains,
                 title=f"eclipsebench: {summary.get('challenge')}", notes=notes)


def plan_report_tasks(cfg: Config, layout: Layout, methods: list[str], epochs: list[int], *,
                      after: tuple[str, ...]) -> list[Task]:
    """The one ``report`` task (``report/index.html`` last), after the statistics."""
    return [Task("report", "report", report_task, (cfg, str(layout.root), methods, epochs),
                 (layout.report,), tuple(after))]
