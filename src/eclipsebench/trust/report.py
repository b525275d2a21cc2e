"""The answer of a trust run: ``trust.json``, ``trust.ecsv`` and an HTML page with figures.

:func:`collect` reads the real and twin results of a trust folder;
:func:`trust_summary` turns them into the answer (``eclipsebench.trust.score``);
:func:`score_task` writes the three files (the engine's last task).
"""

from __future__ import annotations

import html
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Table

from .. import __version__
from ..io.atomic import atomic_path, write_json, write_text
from ..photometry.binning import bin_indices, bin_values
from ..photometry.table import read_table
from .layout import TrustLayout
from .score import (
    DISTINGUISHABLE_AT,
    PHASE_QUANTITIES,
    RECOMMEND_DRAWS,
    REDDER_THAN,
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

__all__ = ["collect", "trust_summary", "score_task", "ECSV_COLUMNS", "ECSV_TIME_COLUMNS",
           "ECSV_PHASE_COLUMNS", "phase_rows",
           "table_provenance", "ranking_text"]

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


def _load(path: Path) -> dict[str, Any]:
    return json.loads(Path(path).read_text())


#: A phase-curve result's keys that the twins' phase statistics read (value and error).
_PHASE_KEYS = tuple(k for name, unit, _ in PHASE_QUANTITIES
                    for k in (f"{name}_{unit}", f"{name}_err_{unit}"))


def collect(root: Path, methods: Sequence[str], n_twins: int, event: str = "eclipse"
            ) -> tuple[dict, dict, dict[str, str], dict[str, int]]:
    """Real results, twin ``(depths, errors, beta_red, twin numbers, mid-event times, their
    errors, phase quantities)`` per method (times in BMJD_TDB and days; the phase
    quantities ``{key: values}`` with the keys of :data:`~eclipsebench.trust.score.
    PHASE_QUANTITIES` and their errors, NaN where a result has none), skipped methods,
    failed twins."""
    when = "t_transit" if event == "transit" else "t_ecl"
    layout = TrustLayout(Path(root))
    real: dict = {}
    twins: dict = {}
    skipped: dict[str, str] = {}
    failed: dict[str, int] = {}
    for m in methods:
        data = _load(layout.real(m))
        if data.get("failed"):
            skipped[m] = data["error"]
            continue
        real[m] = data
        d, e, b, n, t, te = [], [], [], [], [], []
        phase: dict[str, list[float]] = {k: [] for k in _PHASE_KEYS}
        for i in range(1, n_twins + 1):
            res = _load(layout.twin_result(m, i))
            if res.get("failed") or not np.isfinite(res.get("depth_err_ppm") or np.nan):
                failed[m] = failed.get(m, 0) + 1
                continue
            d.append(res["depth_ppm"])
            e.append(res["depth_err_ppm"])
            b.append(np.nan if res.get("beta_red") is None else res["beta_red"])
            n.append(i)
            t.append(np.nan if res.get(f"{when}_bmjd") is None else res[f"{when}_bmjd"])
            te.append(np.nan if res.get(f"{when}_err_d") is None else res[f"{when}_err_d"])
            for key in _PHASE_KEYS:
                phase[key].append(np.nan if res.get(key) is None else res[key])
        if len(d) < 2:
            skipped[m] = f"{len(d)} of {n_twins} twins reduced: too few to score"
            del real[m]
            continue
        twins[m] = (d, e, b, n, t, te, phase)
    return real, twins, skipped, failed


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
    when = "t_transit" if settings["reduce"]["event"] == "transit" else "t_ecl"
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
                "blur_px", "sky_scatter", "background", "correlated_noise")},
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


def _noise_pixels_text(twins: Mapping[str, Any]) -> str:
    real = (twins.get("calibration") or {}).get("noise_pixels_real")
    return ("no noise pixels in the table: not calibrated" if real is None
            else f"median noise pixels {real:.2f} real")


def _provenance_html(summary: Mapping[str, Any]) -> str:
    esc = html.escape
    parts = []
    if summary.get("source_table"):
        parts.append(f"<p>Another pipeline's table, {esc(summary['source_table'])}, completed "
                     f"for the twins as {esc(summary['table'])}. Inferred:</p><ul>"
                     + "".join(f"<li>{esc(k)}: {esc(str(v))}</li>"
                               for k, v in (summary.get("inferred") or {}).items()) + "</ul>")
    if summary.get("time_conversion"):
        parts.append(f"<p>Times: {esc(summary['time_conversion'])}.</p>")
    return "".join(parts)


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


def _pyplot():
    """matplotlib's pyplot on the file backend (imported only when a page is drawn)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> None:
    """``fig`` as a PNG at ``path``, written atomically (a link made meanwhile is refused)."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)


def _figure_depths(summary, twins, path: Path) -> None:
    plt = _pyplot()
    methods = list(summary["methods"])
    fig, ax = plt.subplots(figsize=(max(5.0, 1.1 * len(methods) + 2), 4.0))
    jitter = np.random.default_rng(0)   # positions only: the figure's, not the results'
    for i, m in enumerate(methods):
        d = np.asarray(twins[m][0])
        ax.plot(i + 0.15 * jitter.uniform(-1, 1, d.size), d, ".", alpha=0.5, color="C0")
        s = summary["methods"][m]
        ax.errorbar(i + 0.35, s["depth_ppm"], yerr=s["honest_err_ppm"], fmt="s", color="C3",
                    label="real observation (honest error)" if i == 0 else None)
    ax.axhline(summary["twin_depth_ppm"], color="k", lw=1, label="depth injected in the twins")
    ax.set_xticks(range(len(methods)), methods, rotation=30, ha="right")
    ax.set_ylabel("eclipse depth (ppm)")
    ax.set_title(f"{summary['n_twins']} twins per method ({summary['profile']} profile)")
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def _figure_z(summary, twins, path: Path) -> None:
    plt = _pyplot()
    methods = list(summary["methods"])
    cols = min(4, len(methods))
    rows = int(np.ceil(len(methods) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.0 * cols, 2.4 * rows), squeeze=False)
    grid = np.linspace(-5, 5, 200)
    for ax, m in zip(axes.ravel(), methods, strict=False):
        d, e = (np.asarray(v) for v in twins[m][:2])
        z = (d - summary["twin_depth_ppm"]) / e
        ax.hist(np.clip(z, -5, 5), bins=np.linspace(-5, 5, 21), density=True, color="C0")
        ax.plot(grid, np.exp(-0.5 * grid**2) / np.sqrt(2 * np.pi), "k-", lw=1)
        ax.set_title(f"{m}: z_rms {summary['methods'][m]['z_rms']:.2f}", fontsize=9)
        ax.set_xlabel("(D - D_true) / sigma")
    for ax in axes.ravel()[len(methods):]:
        ax.axis("off")
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def _binned(time, values, width_d: float):
    """Mean time and median value of each ``width_d`` bin of at least 3 frames."""
    bins = bin_indices(time, width_days=width_d)
    centres, counts = bin_values(time, bins)
    order = np.argsort(bins, kind="stable")
    medians = np.array([np.median(v) for v in np.split(values[order], np.cumsum(
        counts.astype(int))[:-1])])
    keep = counts >= 3
    return centres[keep], medians[keep]


def _figure_twin(real_table, twin_table, path: Path) -> None:
    plt = _pyplot()
    fig, axes = plt.subplots(4, 1, figsize=(8.0, 8.0), sharex=True)
    for t, label, color in ((real_table, "real", "k"), (twin_table, "twin 1", "C1")):
        good = np.asarray(t["flag"]) == 0
        time = np.asarray(t["time_bmjd"])[good]
        for ax, col in zip(axes, ("flux", "x", "y", "noise_pixels"), strict=True):
            if col not in t.colnames:   # another pipeline's table without noise pixels
                continue
            v = np.asarray(t[col], float)[good]
            tb, vb = _binned(time, v / np.median(v) if col == "flux" else v, 5.0 / 1440)
            ax.plot(tb, vb, ".", ms=3, color=color, label=label)
    for ax, name in zip(axes, ("raw flux / median (5-min bins)", "x (px)", "y (px)",
                               "noise pixels"), strict=True):
        ax.set_ylabel(name, fontsize=8)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("BMJD_TDB")
    axes[0].set_title("the real observation beside one twin")
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def _html_table(head: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    esc = html.escape
    return ("<table><tr>" + "".join(f"<th>{esc(h)}</th>" for h in head) + "</tr>" + "".join(
        "<tr>" + "".join(f"<td>{esc(c)}</td>" for c in r) + "</tr>" for r in rows) + "</table>")


def ranking_text(summary: Mapping[str, Any]) -> str:
    """The ranking's verdict with the bootstrap frequencies, for stdout and the page."""
    freq = summary.get("recommended_frequency") or {}
    shown = ", ".join(f"{m} {100 * f:.0f} %" for m, f in sorted(
        freq.items(), key=lambda kv: -kv[1]) if f > 0)
    return summary["ranking"]["text"] + (f"; recommended in bootstrap resamples of the twins: "
                                         f"{shown}" if shown else "")


def _none_text(summary: Mapping[str, Any]) -> str:
    f = (summary.get("recommended_frequency") or {}).get("none")
    return "n/a" if f is None else f"{100 * f:.0f} %"


def _near_equals_text(summary: Mapping[str, Any]) -> str:
    """The sentence naming the methods the twins cannot tell from the recommended one."""
    near = summary.get("near_equals") or []
    if not near:
        return ""
    return (f" The twins cannot tell {', '.join(near)} from it (mean squared error within "
            f"{DISTINGUISHABLE_AT:g} paired standard errors): any of these.")


def _number(value: Any, fmt: str) -> str:
    """``value`` formatted, or "none" where a fit gave none."""
    return "none" if value is None else format(value, fmt)


def phase_rows(summary: Mapping[str, Any]) -> list[tuple[str, str, list[list[str]]]]:
    """A whole phase curve's statistics per quantity, for stdout and the page: ``(name,
    unit, rows)``, each row a method's real value, error, honest error, bias, SD, RMSE,
    mean error, z_rms and 1- and 2-sigma coverage as text ("none" where its fits gave no
    error); empty for an eclipse or a transit."""
    out = []
    for name, unit, _ in PHASE_QUANTITIES:
        if f"twin_{name}_{unit}" not in summary:
            continue
        rows = []
        for m, s in summary["methods"].items():
            if f"{name}_rmse_{unit}" not in s:
                continue
            rows.append([m, _number(s[f"{name}_{unit}"], ".1f"),
                         _number(s[f"{name}_err_{unit}"], ".1f"),
                         _number(s[f"{name}_honest_err_{unit}"], ".1f"),
                         _number(s[f"{name}_bias_{unit}"], ".1f"),
                         _number(s[f"{name}_sd_{unit}"], ".1f"),
                         _number(s[f"{name}_rmse_{unit}"], ".1f"),
                         _number(s[f"{name}_mean_err_{unit}"], ".1f"),
                         _number(s[f"{name}_z_rms"], ".2f"),
                         _number(s[f"{name}_coverage_1sigma"], ".2f"),
                         _number(s[f"{name}_coverage_2sigma"], ".2f")])
        out.append((name, unit, rows))
    return out


def _phase_html(summary: Mapping[str, Any]) -> str:
    """The page's section on a whole phase curve's amplitude and peak offset ("" for an
    eclipse or a transit)."""
    parts = []
    for name, unit, rows in phase_rows(summary):
        what = name.replace("_", " ")
        parts.append(f"<h3>{html.escape(what)} (injected {summary[f'twin_{name}_{unit}']:.1f} "
                     f"{unit})</h3>" + _html_table(
                         ["method", f"real ({unit})", f"error ({unit})",
                          f"honest error ({unit})", f"bias ({unit})", f"SD ({unit})",
                          f"RMSE ({unit})", f"mean error ({unit})", "z_rms",
                          "1-sigma coverage", "2-sigma coverage"], rows))
    if not parts:
        return ""
    return ("<h2>The phase curve</h2><p>The twins' phase-curve semi-amplitude and peak "
            "(hotspot) offset, east positive, of their harmonic fits against the injected "
            "ones (harmonic_summary of the real fit's harmonics): bias, scatter, coverage, "
            "and an honest error on the real value (its reported error times max(1, "
            "z_rms); none where the fits give no error).</p>" + "".join(parts))


def _html(summary: Mapping[str, Any], figures: Sequence[str]) -> str:
    esc = html.escape
    head = ["method", "depth (ppm)", "honest error (ppm)", "bias (ppm)", "SD (ppm)",
            "RMSE (ppm)", "mean error (ppm)", "z_rms", "1-sigma coverage", "2-sigma coverage",
            "recommended in (bootstrap)"]
    rows = []
    for m, s in summary["methods"].items():
        lo, hi = s["coverage_1sigma_interval"]
        rows.append([m, f"{s['depth_ppm']:.1f}", f"{s['honest_err_ppm']:.1f}",
                     f"{s['bias_ppm']:.1f}", f"{s['sd_ppm']:.1f}", f"{s['rmse_ppm']:.1f}",
                     f"{s['mean_err_ppm']:.1f}", f"{s['z_rms']:.2f}",
                     f"{s['coverage_1sigma']:.2f} ({lo:.2f}-{hi:.2f})",
                     f"{s['coverage_2sigma']:.2f}",
                     f"{100 * s.get('recommended_frequency', float('nan')):.0f} %"])
    table = _html_table(head, rows)
    timed = [(m, s) for m, s in summary["methods"].items() if "t_rmse_s" in s]
    timing = ("<h2>The mid-event time</h2><p>Over the twins whose fit freed it: the "
              "injected time's bias, scatter and coverage, and an honest error on the real "
              "time (its reported error times max(1, z_rms)).</p>" + _html_table(
                  ["method", "real time (BMJD_TDB)", "error (s)", "honest error (s)",
                   "bias (s)", "SD (s)", "RMSE (s)", "mean error (s)", "z_rms",
                   "1-sigma coverage"],
                  [[m, f"{s['t_event_bmjd']:.6f}", f"{s['t_err_s']:.1f}",
                    f"{s['t_honest_err_s']:.1f}", f"{s['t_bias_s']:.1f}", f"{s['t_sd_s']:.1f}",
                    f"{s['t_rmse_s']:.1f}", f"{s['t_mean_err_s']:.1f}", f"{s['t_z_rms']:.2f}",
                    f"{s['t_coverage_1sigma']:.2f}"] for m, s in timed])
              if timed else "")
    phase = _phase_html(summary)
    skipped = "".join(f"<li>{esc(m)}: {esc(r)}</li>" for m, r in summary["skipped"].items())
    like = summary.get("resemblance", {})
    resemblance = "".join(
        f"<tr><td>{esc(k)}</td><td>{v:.4g}</td><td>{like['twin_001'][k]:.4g}</td></tr>"
        for k, v in like.get("real", {}).items())
    tw = summary["twins"]
    redder = [m for m, s in summary["methods"].items() if s.get("redder_than_twins")]
    caution = (f"<p><b>Caution:</b> the real residuals of {esc(', '.join(redder))} are redder "
               f"(beta_red) than {REDDER_THAN:.0%} of the twins': they hold correlated noise "
               "the twins lack, so the twins' RMSE may under-predict the error.</p>"
               if redder else "")
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>How far to trust "
            f"{esc(summary['system'])}</title><style>body{{font-family:sans-serif;max-width:"
            f"1100px;margin:auto}}td,th{{padding:2px 8px;border-bottom:1px solid #ddd}}"
            f"img{{max-width:100%}}</style></head><body>"
            f"<h1>How far to trust the depth of {esc(summary['system'])}</h1>"
            f"<p style='font-size:130%'><b>Quote: {esc(summary['quote']['text'])}</b></p>"
            f"<p><b>{esc(ranking_text(summary))}</b></p>"
            f"<p>{esc(summary['table'])}: {summary['n_twins']} twins with a "
            f"{summary['twin_depth_ppm']:.1f} ppm {esc(str(tw['event']))} (the real depth of "
            f"{esc(str(tw['from_method']))}), reduced like the real table ({esc(summary['profile'])}"
            f" profile, sampler {esc(summary['sampler'])}). Recommended: <b>"
            f"{esc(str(summary['recommended']))}</b> ({esc(summary['recommended_because'])})."
            f"{esc(_near_equals_text(summary))}</p>"
            f"{table}<p>Honest error: the reported error times max(1, z_rms). Recommended in: "
            f"how often each method would be recommended over {RECOMMEND_DRAWS} bootstrap "
            f"resamples of the twins (none: {_none_text(summary)}). Twins: motion "
            f"within an exposure {tw['motion_rms_px']:.3f} px rms, the simulator's jitter with "
            f"a peak of {tw['motion_peak_px']:.3f} px per 131-s block ({_noise_pixels_text(tw)});"
            f" gain: "
            f"{esc(tw['gain_model'])}.</p>" + _provenance_html(summary) + caution
            + timing + phase + (f"<h2>Skipped</h2><ul>{skipped}</ul>" if skipped else "")
            + ("<h2>The real observation and twin 1</h2><table><tr><th>good frames</th>"
               f"<th>real</th><th>twin 1</th></tr>{resemblance}</table>" if resemblance else "")
            + "".join(f"<p><img src='{esc(f)}' alt='{esc(f)}'></p>" for f in figures)
            + "</body></html>")


def score_task(settings: Mapping[str, Any], methods: Sequence[str], root: str) -> None:
    """Write the report, ``trust.ecsv``, then ``trust.json`` (the engine's outputs, in order)."""
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
    folder = layout.report.parent
    folder.mkdir(parents=True, exist_ok=True)
    figures = ["depths.png", "z_scores.png", "twin.png"]
    if summary["methods"]:
        _figure_depths(summary, twins, folder / figures[0])
        _figure_z(summary, twins, folder / figures[1])
    else:
        figures = figures[2:]
    _figure_twin(real_table, twin, folder / "twin.png")
    write_text(layout.report, _html(summary, figures))
    _ecsv(summary, layout.table)
    write_json(layout.result, summary)
