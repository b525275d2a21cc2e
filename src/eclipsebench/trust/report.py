"""The answer of a trust run: ``trust.json``, ``trust.ecsv`` and the page.

:func:`collect` reads the real and twin results of a trust folder;
:func:`trust_summary` turns them into the answer (``eclipsebench.trust.score``);
:func:`score_task` writes the three files (the engine's last task), the page
with :mod:`eclipsebench.trust.page`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Table

from .. import __version__
from ..astro.events import event_for
from ..io.atomic import atomic_path, write_json
from ..photometry.table import read_table
from .collect import collect
from .layout import TrustLayout
from .score import (
    PHASE_QUANTITIES,
    mse_excess_sigma,
    near_equals,
    observation_statistics,
    phase_score,
    quote,
    ranking_resolution,
    recommend,
    recommendation_frequency,
    red_noise_check,
    score_methods,
    timing_score,
)

__all__ = ["trust_summary", "score_task", "ECSV_COLUMNS", "ECSV_TIME_COLUMNS",
           "ECSV_PHASE_COLUMNS", "table_provenance", "ranking_text"]

#: The per-method columns of ``trust.ecsv`` (ppm unless dimensionless).
ECSV_COLUMNS = ("bias_ppm", "sd_ppm", "rmse_ppm", "mean_err_ppm", "z_rms", "coverage_1sigma",
                "coverage_2sigma", "depth_ppm", "depth_err_ppm", "honest_err_ppm", "n_twins",
                "beta_red_real", "beta_red_twins_below", "recommended_frequency")
#: The mid-event time's columns of ``trust.ecsv`` (seconds), where the fits freed it.
ECSV_TIME_COLUMNS = ("t_bias_s", "t_sd_s", "t_rmse_s", "t_mean_err_s", "t_z_rms",
                     "t_coverage_1sigma", "t_err_s", "t_honest_err_s")

#: A whole phase curve's columns of ``trust.ecsv`` (its amplitude in ppm, its peak offset in
#: deg), where the twins carry one; NaN where a method's fits give no error.
ECSV_PHASE_COLUMNS = tuple(f"{name}_{stat}" for name, unit, _ in PHASE_QUANTITIES for stat in (
    f"bias_{unit}", f"sd_{unit}", f"rmse_{unit}", f"mean_err_{unit}", "z_rms",
    "coverage_1sigma", "coverage_2sigma", f"honest_err_{unit}")) + tuple(
    k for name, unit, _ in PHASE_QUANTITIES for k in (f"{name}_{unit}", f"{name}_err_{unit}"))


def trust_summary(settings: Mapping[str, Any], recipe: Mapping[str, Any], real: Mapping,
                  twins: Mapping, skipped: Mapping[str, str], failed: Mapping[str, int]
                  ) -> dict[str, Any]:
    """The answer: per-method statistics, the recommendation and what the twins were."""
    truth = float(recipe["depth_ppm"])
    scores = score_methods({m: t[:2] for m, t in twins.items()}, real, truth)
    for m, s in scores.items():
        beta = real[m].get("beta_red")
        s.update(red_noise_check(np.nan if beta is None else beta, twins[m][2]))
    for m, n in failed.items():
        if m in scores:
            scores[m]["n_twins_failed"] = n
    best, why = recommend(scores)
    resid = {m: dict(zip(t[3], np.asarray(t[0], float) - truth, strict=True))
             for m, t in twins.items()}
    if best is not None:
        for m, s in scores.items():
            s["mse_excess_sigma"] = (0.0 if m == best
                                     else mse_excess_sigma(resid[m], resid[best]))
    errors = {m: dict(zip(t[3], np.asarray(t[1], float), strict=True))
              for m, t in twins.items()}
    frequency = recommendation_frequency(resid, errors, seed=int(settings["seed"]))
    for m, s in scores.items():
        s["recommended_frequency"] = frequency.get(m, float("nan"))
    when = event_for(settings["reduce"]["event"]).time_prefix
    for m, s in scores.items():
        timing = timing_score(twins[m][4], twins[m][5], float(recipe["t_event_bmjd"]),
                              real[m].get(f"{when}_bmjd", np.nan),
                              np.nan if real[m].get(f"{when}_err_d") is None
                              else real[m][f"{when}_err_d"])
        if timing is not None:
            s.update(timing)
    phase_truth = {k: float(recipe[f"{name}_{unit}"]) for name, unit, _ in PHASE_QUANTITIES
                   if (k := f"{name}_{unit}") in recipe}
    if phase_truth:   # a whole phase curve: its amplitude and peak offset too
        for m, s in scores.items():
            for name, unit, angle in PHASE_QUANTITIES:
                value, err = f"{name}_{unit}", f"{name}_err_{unit}"
                found = phase_score(name, unit, twins[m][6][value], twins[m][6][err],
                                    phase_truth[value], real[m].get(value), real[m].get(err),
                                    angle=angle)
                if found is not None:
                    s.update(found)
    return {"quote": quote(scores, best), "methods": scores, "skipped": dict(skipped),
            "recommended": best, "recommended_frequency": frequency,
            "ranking": ranking_resolution(scores, resid, best, int(settings["n_twins"]),
                                          frequency),
            "recommended_because": why, "near_equals": near_equals(scores, resid, best),
            "n_twins": int(settings["n_twins"]),
            "twin_depth_ppm": truth, **{f"twin_{k}": v for k, v in phase_truth.items()},
            "system": settings["system"], "table": settings["table"],
            "seed": settings["seed"], "profile": settings["reduce"]["profile"],
            "sampler": settings["reduce"]["sampler"], "twins": {k: recipe.get(k) for k in (
                "event", "phase", "t_event_bmjd", "from_method", "flux_aperture_e",
                "motion_peak_px", "motion_rms_px", "calibration", "gain_model", "gain_fit",
                "blur_px", "sky_scatter", "background", "correlated_noise", "motion_bound")},
            "eclipsebench_version": __version__}


def table_provenance(meta: Mapping[str, Any]) -> dict[str, Any]:
    """What the real table's metadata say of where it came from: another pipeline's table
    (``source_table``), what was inferred to twin it (``inferred``: :func:`~eclipsebench.
    trust.observation.complete_table`), how its times were converted (``time_conversion``)."""
    out: dict[str, Any] = {}
    if meta.get("SOURCE"):
        out["source_table"] = str(meta["SOURCE"])
    if meta.get("INFERRED"):
        out["inferred"] = json.loads(meta["INFERRED"])
    if meta.get("TIMECONV"):
        out["time_conversion"] = str(meta["TIMECONV"])
    return out


def _ecsv(summary: Mapping[str, Any], path: Path) -> None:
    methods = list(summary["methods"])
    table = Table({"method": methods})
    for col in ECSV_COLUMNS:
        table[col] = [summary["methods"][m][col] for m in methods]
        if col.endswith("_ppm"):
            table[col].unit = "ppm"
    for col in ECSV_TIME_COLUMNS:
        table[col] = [summary["methods"][m].get(col, np.nan) for m in methods]
        if col.endswith("_s"):
            table[col].unit = "s"
    if any(f"twin_{name}_{unit}" in summary for name, unit, _ in PHASE_QUANTITIES):
        for col in ECSV_PHASE_COLUMNS:
            values = [summary["methods"][m].get(col) for m in methods]
            table[col] = [np.nan if v is None else v for v in values]
            for unit in ("ppm", "deg"):
                if col.endswith(f"_{unit}"):
                    table[col].unit = unit
    table.meta.update({"quote": summary["quote"]["text"],
                       "ranking": summary["ranking"]["text"],
                       "recommended": summary["recommended"], "n_twins": summary["n_twins"],
                       "twin_depth_ppm": summary["twin_depth_ppm"], "system": summary["system"],
                       "table": summary["table"]})
    table.meta.update({f"twin_{n}_{u}": summary[f"twin_{n}_{u}"] for n, u, _ in PHASE_QUANTITIES
                       if f"twin_{n}_{u}" in summary})
    with atomic_path(path) as tmp:
        table.write(tmp, format="ascii.ecsv")


def ranking_text(summary: Mapping[str, Any]) -> str:
    """The ranking's verdict with the bootstrap frequencies, for stdout and the page."""
    freq = summary.get("recommended_frequency") or {}
    shown = ", ".join(f"{m} {100 * f:.0f} %" for m, f in sorted(
        freq.items(), key=lambda kv: -kv[1]) if f > 0)
    return summary["ranking"]["text"] + (f"; recommended in bootstrap resamples of the twins: "
                                         f"{shown}" if shown else "")


def score_task(settings: Mapping[str, Any], methods: Sequence[str], root: str,
               command: str | None = None) -> None:
    """Write the page (:func:`eclipsebench.trust.page.write_page`, showing ``command``),
    ``trust.ecsv``, then ``trust.json`` (the engine's outputs, in order)."""
    # the page's figures (matplotlib): imported only when a page is drawn
    from .page import real_curves, write_page

    layout = TrustLayout(Path(root))
    recipe = json.loads(layout.recipe_json.read_text())
    real, twins, skipped, failed = collect(layout.root, methods, int(settings["n_twins"]),
                                           settings["reduce"]["event"])
    skipped = {**{m: json.loads(layout.real(m).read_text())["error"]
                  for m in settings["methods"] if m not in methods}, **skipped}
    summary = trust_summary(settings, recipe, real, twins, skipped, failed)
    real_table, twin = read_table(settings["table"]), read_table(layout.twin(1))
    summary["resemblance"] = {"real": observation_statistics(real_table),
                              "twin_001": observation_statistics(twin)}
    summary.update(table_provenance(real_table.meta))
    write_page(layout.report.parent, summary, twins=twins, curves=real_curves(layout, summary),
               real_table=real_table, twin_table=twin, command=command)
    _ecsv(summary, layout.table)
    write_json(layout.result, summary)
