"""trust (issue 26): the twins against the real epoch 1, its speed, and whether twins predict.

Three parts (``--part``):

``resemble``
    Real epoch 1 (``../shared/data/irac/real_xo3_eclipse1``) against
    ``--twins`` of its twins: median noise pixels, centroid rms in x and y,
    raw flux rms in 5-minute bins, residual rms after BLISS (least squares).
``speed``
    ``trust`` on real epoch 1 with ``--twins`` twins (default 50) and BLISS,
    GP, KR/Data, PLD, poly2 and SP(K2), ``--sampler leastsq``, 2 workers:
    wall time, and the task seconds of the simulation (recipe + twins) and of
    the reductions. Reference in the same script: one BLISS least-squares
    reduction of the real table (median of 3).
``window``
    ``--twins`` twins of real epoch 1 (default 10), each rendered twice with
    the same seed: only where its photometry reads (``trust``'s way,
    :func:`~eclipsebench.trust.twin.photometry_window`) and over the whole
    32 x 32 subarray (the noise draws differ). Per quantity (the
    resemblance statistics, the mean flux, background, flux error and the
    flux's frame-to-frame rms over good frames, the number of good frames)
    the mean over the twins of each way, their difference in standard
    errors of that difference, and the CPU seconds per twin of each way.
``gaussian``
    ``--twins`` twins of real epoch 1 (default 10), each rendered twice with
    the same seed (the same motion; the noise draws differ): with the twins'
    Gaussian photon noise (:data:`~eclipsebench.trust.twin.GAUSSIAN_SKEW`)
    and with the exact Poisson draws (``gaussian_skew=0``, twins before
    ``twin_model`` 6). Per quantity (``window``'s, the skewness of the flux
    about its running median over a cube, and the BLISS least-squares fit's
    ``beta_red`` and residual rms) the mean over the twins of each way,
    their difference in standard errors of that difference, and the CPU
    seconds per twin of each way (issue 40).
``table``
    another pipeline's table (issue 36): the real epoch-1 table cut to
    time_bmjd, flux and flux_err in an arbitrary unit, x and y (CSV), twinned
    beside the full table with the same seed: which methods are skipped, what
    was inferred, and the ratio of the BLISS and KR/Data twin RMSEs.
``predict``
    ``--epochs`` simulated challenge epochs (physical noise) treated as real:
    each epoch's table gets ``--twins`` twins reduced by BLISS, PLD and
    KR/Data; the twin-predicted RMSE of each method is set against that
    method's actual error on the epoch (its depth minus the epoch's truth).
    Prints the rms of (actual error / predicted RMSE) per method and whether
    the recommended method's actual errors are no worse than the median
    method's.

``phase-curve``
    The built-in ``xo3b-phase-curve`` challenge (one whole orbit, seed 2015;
    ``--set SECTION.KEY=VALUE`` changes its configuration, e.g. a sparse
    cadence for a quick run) simulated and measured, then ``trust --event
    phase-curve`` on its table with ``--twins`` twins (default 50) and BLISS,
    KR/Data and PLD (``--methods``), least squares: per method the depth,
    phase amplitude and peak offset over the twins (bias, RMSE, z_rms,
    coverage), the real fit's actual error against the simulator's truth in
    units of the twin RMSE, the task seconds of the simulation and the
    reductions and the CPU seconds of this process.

Command (what BENCHMARKS.md quotes): ``python bench/bench_trust.py --part
resemble --twins 4``, ``--part speed``, ``--part window --twins 10``,
``--part gaussian --twins 10``,
``--part predict --epochs 20 --twins 50``, ``--part phase-curve --twins 50``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import shutil
import statistics
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
REAL = (ROOT / ".." / "shared" / "data" / "irac" / "real_xo3_eclipse1").resolve()
SPEED_METHODS = ["bliss", "gp", "kr-data", "pld", "poly2", "segpoly"]
PREDICT_METHODS = ["bliss", "pld", "kr-data"]
PHASE_CURVE_METHODS = ["bliss", "kr-data", "pld"]


def _real_table(work: Path) -> Path:
    import eclipsebench as eb

    path = work / "real" / "epoch_01.fits"
    if not path.is_file():
        eb.measure(REAL, work / "real")
    return path


def _statistics(table, rms_ppm: float) -> dict[str, float]:
    from eclipsebench.trust.score import observation_statistics

    return {**observation_statistics(table), "bliss_residual_rms_ppm": float(rms_ppm)}


def resemble(work: Path, n_twins: int) -> None:
    import eclipsebench as eb
    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.config.photometry import PhotometrySection
    from eclipsebench.photometry.table import read_table
    from eclipsebench.trust.recipe import build_recipe
    from eclipsebench.trust.twin import twin_table

    path = _real_table(work)
    fit = eb.reduce(path, "bliss", sampler="leastsq", prayer_bead_shifts=0)
    recipe, info = build_recipe(str(path), get_system("XO-3b"), fit.to_dict(), fit.depth_ppm)
    real = _statistics(read_table(path), fit.rms_ppm)
    twins = []
    for i in range(1, n_twins + 1):
        t = twin_table(recipe, PhotometrySection(), seed=0, twin=i)
        twins.append(_statistics(t, eb.reduce(t, "bliss", system="XO-3b", sampler="leastsq",
                                              prayer_bead_shifts=0).rms_ppm))
    print(f"within-exposure motion {info['motion_rms_px']:.3f} px rms (jitter peak "
          f"{info['motion_peak_px']:.3f} px); calibration "
          f"{json.dumps(info['calibration'])}")
    print(f"| quantity | real epoch 1 | twins (mean of {n_twins}) | twins / real |")
    print("| --- | --- | --- | --- |")
    for key, value in real.items():
        mean = statistics.fmean(t[key] for t in twins)
        print(f"| {key} | {value:.4g} | {mean:.4g} | {mean / value:.3f} |")


def _real_recipe(work: Path):
    """``(recipe, photometry options, star)`` of real epoch 1's twins, from its BLISS fit."""
    import eclipsebench as eb
    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.trust.recipe import build_recipe, photometry_options
    from eclipsebench.trust.twin import twin_star

    path = _real_table(work)
    fit = eb.reduce(path, "bliss", sampler="leastsq", prayer_bead_shifts=0)
    recipe, _ = build_recipe(str(path), get_system("XO-3b"), fit.to_dict(), fit.depth_ppm)
    options = photometry_options(recipe.obs)
    return recipe, options, twin_star(recipe, options)


def window(work: Path, n_twins: int) -> None:
    from eclipsebench.trust.twin import photometry_window, twin_table

    recipe, options, star = _real_recipe(work)
    x, y = recipe.obs.track_px()
    print("windows (x0, y0, nx, ny) per AOR: " + ", ".join(
        str(photometry_window(x[r], y[r], options, (32, 32))) for r in recipe.obs.aors()))

    runs: dict[bool, list[dict[str, float]]] = {False: [], True: []}
    cpu = {False: 0.0, True: 0.0}
    for i in range(1, n_twins + 1):
        for whole in (False, True):
            c0 = time.process_time()
            table = twin_table(recipe, options, seed=0, twin=i, star=star, whole_frame=whole)
            cpu[whole] += time.process_time() - c0
            runs[whole].append(_twin_stats(table))
    print(f"CPU seconds per twin: window {cpu[False] / n_twins:.2f}, whole frame "
          f"{cpu[True] / n_twins:.2f}; ratio {cpu[True] / cpu[False]:.2f}")
    _compare(runs[False], runs[True], f"window (mean of {n_twins})", "whole frame")


def _twin_stats(table) -> dict[str, float]:
    """``window``'s and ``gaussian``'s statistics of one twin table's good frames."""
    from eclipsebench.trust.score import observation_statistics

    good = np.asarray(table["flag"]) == 0
    flux = np.asarray(table["flux"], float)[good]
    return {**observation_statistics(table), "flux_mean_e": float(flux.mean()),
            "flux_rms_frame_ppm": float(np.std(np.diff(flux)) / np.sqrt(2) / flux.mean() * 1e6),
            "background_mean_e": float(np.mean(np.asarray(table["background"])[good])),
            "flux_err_mean_e": float(np.mean(np.asarray(table["flux_err"])[good])),
            "good_frames": float(good.sum())}


def _compare(one: list[dict[str, float]], other: list[dict[str, float]], name_one: str,
             name_other: str) -> None:
    """Per quantity: the mean over the twins of each way and their difference in its SE, as
    two samples and paired (twin by twin: the two ways of a twin share its motion)."""
    print(f"| quantity | {name_one} | {name_other} | difference / its SE | paired |")
    print("| --- | --- | --- | --- | --- |")
    for key in one[0]:
        a = np.array([r[key] for r in one])
        b = np.array([r[key] for r in other])
        se = np.sqrt(a.var(ddof=1) / a.size + b.var(ddof=1) / b.size)
        se_paired = np.std(a - b, ddof=1) / np.sqrt(a.size)
        print(f"| {key} | {a.mean():.6g} | {b.mean():.6g} | "
              f"{(a.mean() - b.mean()) / se if se > 0 else 0.0:+.2f} | "
              f"{(a.mean() - b.mean()) / se_paired if se_paired > 0 else 0.0:+.2f} |")


def gaussian(work: Path, n_twins: int) -> None:
    """Issue 40: the twins' Gaussian photon noise against the exact Poisson draws."""
    import eclipsebench as eb
    from eclipsebench.photometry.clean import running_median
    from eclipsebench.trust.twin import GAUSSIAN_SKEW, twin_table

    recipe, options, star = _real_recipe(work)
    ways = {"gaussian": GAUSSIAN_SKEW, "exact": 0.0}
    runs: dict[str, list[dict[str, float]]] = {w: [] for w in ways}
    cpu = {w: 0.0 for w in ways}
    for i in range(1, n_twins + 1):
        for way, skew in ways.items():
            c0 = time.process_time()
            table = twin_table(recipe, options, seed=0, twin=i, star=star, gaussian_skew=skew)
            cpu[way] += time.process_time() - c0
            good = np.asarray(table["flag"]) == 0
            flux = np.asarray(table["flux"], float)
            resid = (flux - running_median(flux, 65, good))[good]
            resid = resid - resid.mean()
            bliss = eb.reduce(table, "bliss", system="XO-3b", sampler="leastsq",
                              prayer_bead_shifts=0)
            runs[way].append({**_twin_stats(table),
                              "flux_skewness": float(np.mean(resid**3) / np.std(resid) ** 3),
                              "bliss_beta_red": float(bliss.to_dict()["beta_red"]),
                              "bliss_rms_ppm": float(bliss.rms_ppm)})
    print(f"CPU seconds per twin (rendering and photometry): Gaussian {cpu['gaussian'] / n_twins:.2f},"
          f" exact {cpu['exact'] / n_twins:.2f}; ratio {cpu['gaussian'] / cpu['exact']:.2f}")
    _compare(runs["gaussian"], runs["exact"], f"Gaussian (mean of {n_twins})", "exact")


def speed(work: Path, n_twins: int, workers: int) -> None:
    import eclipsebench as eb

    path = _real_table(work)
    ref = []
    for _ in range(3):
        t0 = time.perf_counter()
        eb.reduce(path, "bliss", sampler="leastsq")
        ref.append(time.perf_counter() - t0)
    out = work / "speed"
    shutil.rmtree(out, ignore_errors=True)
    from eclipsebench.config import load_config
    from eclipsebench.trust.run import make_settings, run_trust

    cfg = load_config(None, ["reduce.sampler=\"leastsq\""])
    settings = make_settings(path, reduce=cfg.reduce, system_section=cfg.system,
                             methods=SPEED_METHODS, n_twins=n_twins)
    t0 = time.perf_counter()
    summary, report = run_trust(settings, out, workers=workers)
    wall = time.perf_counter() - t0
    stages = report.stage_seconds()
    sim = stages.get("recipe", 0.0) + stages.get("twin", 0.0)
    red = stages.get("real", 0.0) + stages.get("twin-reduce", 0.0)
    print(f"trust, real epoch 1, {n_twins} twins x {len(SPEED_METHODS)} methods, leastsq, "
          f"{workers} workers: wall {wall:.1f} s; task seconds: simulation {sim:.1f} "
          f"(recipe {stages.get('recipe', 0.0):.1f}), reductions {red:.1f}, score "
          f"{stages.get('score', 0.0):.1f}")
    print(f"reference: one BLISS least-squares reduction of the real table, median of 3: "
          f"{statistics.median(ref):.2f} s; ratio {wall / statistics.median(ref):.0f}")
    for m, s in summary["methods"].items():
        print(f"  {m:8s} depth {s['depth_ppm']:7.1f} honest {s['honest_err_ppm']:6.1f} bias "
              f"{s['bias_ppm']:7.1f} RMSE {s['rmse_ppm']:6.1f} z_rms {s['z_rms']:.2f} cov1 "
              f"{s['coverage_1sigma']:.2f}")
    print(f"  recommended {summary['recommended']}; skipped {summary['skipped']}")


def table(work: Path, n_twins: int, workers: int, tables: list[str]) -> None:
    """Issue 36: twins of another pipeline's table (time_bmjd, flux in arbitrary units,
    flux_err, x, y) against twins of the full photometry table, same seed. ``tables``: those
    twinned again; the other's result is read from its folder (made by the same twin model
    and as many twins, else refused)."""
    from astropy.table import Table

    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.config import load_config
    from eclipsebench.trust.run import run_trust, trust_settings
    from eclipsebench.trust.twin import TWIN_MODEL

    path = _real_table(work)
    full = Table.read(path)
    good = np.asarray(full["flag"]) == 0
    unit = 1.0 / 3737.0     # electrons to an arbitrary unit
    csv = work / "table" / "five_columns.csv"
    csv.parent.mkdir(parents=True, exist_ok=True)
    Table({"time_bmjd": full["time_bmjd"][good], "flux": full["flux"][good] * unit,
           "flux_err": full["flux_err"][good] * unit, "x": full["x"][good],
           "y": full["y"][good]}).write(csv, format="ascii.csv", overwrite=True)
    cfg = load_config(None, ["reduce.sampler=\"leastsq\""])
    rmse: dict[str, dict[str, float]] = {}
    for name, source, methods in (("full", path, ["bliss", "kr-data"]),
                                  ("csv", csv, ["bliss", "kr-data", "pld", "ica"])):
        out = work / "table" / name
        if name in tables:
            shutil.rmtree(out, ignore_errors=True)
            settings = trust_settings(source, out, reduce=cfg.reduce, system_section=cfg.system,
                                      system=get_system("XO-3b"), methods=methods,
                                      n_twins=n_twins, seed=1)
            summary, _ = run_trust(settings, out, workers=workers)
        else:
            summary = json.loads((out / "trust.json").read_text())
            made = json.loads((out / "trust_config.json").read_text())
            if made.get("twin_model") != TWIN_MODEL or made.get("n_twins") != n_twins:
                raise SystemExit(f"{out}: made with twin model {made.get('twin_model')} and "
                                 f"{made.get('n_twins')} twins, not {TWIN_MODEL} and {n_twins}: "
                                 f"twin it again (--tables {name})")
            print(f"{name}: read from {out} (twin model {TWIN_MODEL}, {n_twins} twins)")
        rmse[name] = {m: s["rmse_ppm"] for m, s in summary["methods"].items()}
        inferred = json.loads((out / "trust.json").read_text()).get("table", {})
        print(f"{name}: skipped {sorted(summary['skipped'])}; "
              + ", ".join(f"{m} RMSE {v:.1f} ppm" for m, v in rmse[name].items())
              + (f"; table {json.dumps(inferred)[:400]}" if name == "csv" else ""))
    for m in ("bliss", "kr-data"):
        print(f"{m}: twin RMSE of the five-column CSV / the full table = "
              f"{rmse['csv'][m]:.1f} / {rmse['full'][m]:.1f} = "
              f"{rmse['csv'][m] / rmse['full'][m]:.3f} (goal within 20 %)")


def predict(work: Path, n_epochs: int, n_twins: int, workers: int) -> None:
    from astropy.table import Table

    import eclipsebench as eb
    from eclipsebench.config import load_config
    from eclipsebench.trust.run import make_settings, run_trust

    cfg = eb.load_config(overrides=[f"challenge.epochs={n_epochs}", "challenge.seed=26"])
    sim, phot = work / "predict" / "sim", work / "predict" / "phot"
    eb.simulate(sim, config=cfg, workers=workers, calibration=False)
    if not (phot / f"epoch_{n_epochs:02d}.fits").is_file():
        eb.measure(sim, phot, config=cfg)
    truth = Table.read(sim / "truth.ecsv", format="ascii.ecsv")
    depth = {int(r["epoch"]): float(r["depth_ppm"]) for r in truth}
    rcfg = load_config(None, ["reduce.sampler=\"leastsq\""])
    ratios: dict[str, list[float]] = {m: [] for m in PREDICT_METHODS}
    redder: dict[str, list[bool]] = {m: [] for m in PREDICT_METHODS}
    rec_err, med_err = [], []
    n_near = 0
    for e in range(1, n_epochs + 1):
        table = phot / f"epoch_{e:02d}.fits"
        settings = make_settings(table, reduce=rcfg.reduce, system_section=rcfg.system,
                                 methods=PREDICT_METHODS, n_twins=n_twins, seed=e)
        summary, _ = run_trust(settings, work / "predict" / f"trust_{e:02d}", workers=workers)
        errors = {}
        for m, s in summary["methods"].items():
            errors[m] = abs(s["depth_ppm"] - depth[e])
            ratios[m].append((s["depth_ppm"] - depth[e]) / s["rmse_ppm"])
            redder[m].append(bool(s["redder_than_twins"]))
        if summary["recommended"] in errors:
            rec_err.append(errors[summary["recommended"]])
            med_err.append(float(np.median(list(errors.values()))))
            n_near += bool(summary.get("near_equals"))
        print(f"epoch {e:2d}: truth {depth[e]:.0f}; " + ", ".join(
            f"{m} {summary['methods'][m]['depth_ppm'] - depth[e]:+.0f} (RMSE "
            f"{summary['methods'][m]['rmse_ppm']:.0f})" for m in summary["methods"])
            + f"; recommended {summary['recommended']}"
            + (f" (near equals {', '.join(summary['near_equals'])})"
               if summary.get("near_equals") else ""), flush=True)
    # With n twins the predicted RMSE is itself estimated: if a method's twin errors are
    # N(0, s^2), n RMSE^2 / s^2 is chi^2 with n degrees of freedom, so even a perfect
    # prediction gives E[(error / RMSE)^2] = n / (n - 2) (1.25 for 10 twins).
    print(f"a perfect prediction from {n_twins} twins: rms {np.sqrt(n_twins / (n_twins - 2)):.2f} "
          "expected")
    boot = np.random.default_rng(0)
    for m, r in ratios.items():
        arr = np.asarray(r)
        draws = np.sqrt(np.mean(np.square(arr[boot.integers(0, len(arr), (2000, len(arr)))]),
                                axis=1))
        lo, hi = np.percentile(draws, [5, 95])
        print(f"{m}: rms(actual error / predicted RMSE) over {len(r)} epochs = "
              f"{float(np.sqrt(np.mean(np.square(arr)))):.2f} (bootstrap over epochs, 90 %: "
              f"{lo:.2f}-{hi:.2f})")
        flagged = np.asarray(redder[m])
        print(f"  epochs whose real residuals are redder than the twins' ({int(flagged.sum())}): "
              + ", ".join(f"rms {float(np.sqrt(np.mean(np.square(arr[sel])))):.2f} over "
                          f"{int(sel.sum())} {name}" for sel, name in
                          ((flagged, "flagged"), (~flagged, "others")) if sel.any()))
    if rec_err:
        diff = np.asarray(rec_err) - np.asarray(med_err)
        se = float(diff.std(ddof=1) / np.sqrt(diff.size)) if diff.size > 1 else float("nan")
        print(f"recommended method's mean |error| {np.mean(rec_err):.1f} ppm against the "
              f"median method's {np.mean(med_err):.1f} ppm over {len(rec_err)} epochs; the "
              f"twins could not tell it from another method (near_equals) on {n_near}; "
              f"difference {diff.mean():+.1f} +- {se:.1f} ppm (standard error over the epochs)")


def phase_curve(work: Path, n_twins: int, workers: int, sets: list[str],
                methods: list[str]) -> None:
    from astropy.table import Table

    import eclipsebench as eb
    from eclipsebench.config import load_config
    from eclipsebench.trust.run import make_settings, run_trust

    c0 = time.process_time()
    cfg = eb.load_config("xo3b-phase-curve", overrides=sets)
    tag = "full" if not sets else "set-" + hashlib.sha256("\n".join(sets).encode()).hexdigest()[:8]
    sim, phot = work / "phase_curve" / tag / "sim", work / "phase_curve" / tag / "phot"
    t0 = time.perf_counter()
    eb.simulate(sim, config=cfg, workers=workers, calibration=False)
    if not (phot / "epoch_01.fits").is_file():
        eb.measure(sim, phot, config=cfg)
    made = time.perf_counter() - t0
    truth = Table.read(sim / "truth.ecsv", format="ascii.ecsv")[0]
    table = phot / "epoch_01.fits"
    rcfg = load_config(None, ["reduce.sampler=\"leastsq\"", "reduce.event=\"phase-curve\""])
    settings = make_settings(table, reduce=rcfg.reduce, system_section=rcfg.system,
                             methods=methods, n_twins=n_twins)
    out = work / "phase_curve" / tag / f"trust_{n_twins}"
    t0 = time.perf_counter()
    summary, report = run_trust(settings, out, workers=workers)
    wall = time.perf_counter() - t0
    stages = report.stage_seconds()
    frames = len(Table.read(table))
    print(f"xo3b-phase-curve ({' '.join(sets) or 'as built in'}): {frames} frames, simulated "
          f"and measured in {made:.1f} s; trust --event phase-curve, {n_twins} twins x "
          f"{len(methods)} methods, leastsq, {workers} workers: wall {wall:.1f} s, task "
          f"seconds: simulation {stages.get('recipe', 0.0) + stages.get('twin', 0.0):.1f} "
          f"(recipe {stages.get('recipe', 0.0):.1f}), reductions "
          f"{stages.get('real', 0.0) + stages.get('twin-reduce', 0.0):.1f}, score "
          f"{stages.get('score', 0.0):.1f}; CPU of this process {time.process_time() - c0:.1f} s")
    # the simulator's truth as a fit of as many harmonics sees it (truth.ecsv: no tag for one,
    # _h2 for two): each method's error against the one its real fit chose
    print(f"simulator's truth: depth {truth['depth_ppm']:.1f} ppm; with one harmonic p(t_ecl) "
          f"{truth['harmonic_depth_ppm']:.1f}, amplitude {truth['phase_amplitude_ppm']:.1f} ppm, "
          f"offset {truth['phase_offset_deg']:+.1f} deg; with two "
          f"{truth['harmonic_depth_h2_ppm']:.1f}, {truth['phase_amplitude_h2_ppm']:.1f} ppm, "
          f"{truth['phase_offset_h2_deg']:+.1f} deg; injected in the twins (the first "
          f"method's real fit): depth {summary['twin_depth_ppm']:.1f}, amplitude "
          f"{summary['twin_phase_amplitude_ppm']:.1f}, offset "
          f"{summary['twin_phase_offset_deg']:+.1f}")
    print("| method | harmonics | quantity | real | honest error | twins' bias | RMSE | z_rms | cov1 "
          "| cov2 | real error / RMSE |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")

    def cell(v, fmt=".1f"):
        return "none" if v is None else format(v, fmt)

    for m, s in summary["methods"].items():
        phase = json.loads((out / "real" / f"{m}.json").read_text()).get("phase")
        tag = "_h2" if phase == "harmonic2" else ""
        for label, key, unit, true, angle in (
                ("depth (ppm)", "", "ppm", float(truth[f"harmonic_depth{tag}_ppm"]), False),
                ("amplitude (ppm)", "phase_amplitude_", "ppm",
                 float(truth[f"phase_amplitude{tag}_ppm"]), False),
                ("offset (deg)", "phase_offset_", "deg", float(truth[f"phase_offset{tag}_deg"]),
                 True)):
            value = s["depth_ppm" if not key else f"{key[:-1]}_{unit}"]
            rmse = s.get(f"{key}rmse_{unit}")
            if rmse is None:
                continue
            err = value - true
            if angle:
                err = (err + 180.0) % 360.0 - 180.0
            honest = s["honest_err_ppm" if not key else f"{key}honest_err_{unit}"]
            print(f"| {m} | {1 + (tag == '_h2')} | {label} | {value:.1f} | {cell(honest)} | "
                  f"{s[f'{key}bias_{unit}']:+.1f} | {rmse:.1f} | {cell(s[f'{key}z_rms'], '.2f')} "
                  f"| {cell(s[f'{key}coverage_1sigma'], '.2f')} | "
                  f"{cell(s[f'{key}coverage_2sigma'], '.2f')} | {err / rmse:+.2f} |")
    print(f"recommended {summary['recommended']}; {summary['ranking']['text']}; skipped "
          f"{summary['skipped']}")


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--part", choices=("resemble", "speed", "window", "gaussian", "table",
                                      "predict", "phase-curve"), default="resemble")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="SECTION.KEY=VALUE",
                   help="phase-curve: a change to the xo3b-phase-curve configuration")
    p.add_argument("--methods", default=",".join(PHASE_CURVE_METHODS),
                   help="phase-curve: the methods")
    p.add_argument("--tables", default="full,csv",
                   help="table: the tables twinned again (full, csv); the other is read back")
    p.add_argument("--twins", type=int, default=None)
    p.add_argument("--epochs", type=int, default=20)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--workdir", default="bench/results/trust")
    args = p.parse_args(argv)
    work = Path(args.workdir)
    work.mkdir(parents=True, exist_ok=True)
    print(f"# bench_trust --part {args.part}: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())},"
          f" {platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    if args.part not in ("predict", "phase-curve") and not REAL.is_dir():
        print("../shared/data/irac/real_xo3_eclipse1 is absent: skipped")
        return 0
    if args.part == "resemble":
        resemble(work, args.twins or 4)
    elif args.part == "speed":
        speed(work, args.twins or 50, args.workers)
    elif args.part == "window":
        window(work, args.twins or 10)
    elif args.part == "gaussian":
        gaussian(work, args.twins or 10)
    elif args.part == "table":
        table(work, args.twins or 20, args.workers, args.tables.split(","))
    elif args.part == "phase-curve":
        phase_curve(work, args.twins or 50, args.workers, args.sets, args.methods.split(","))
    else:
        predict(work, args.epochs, args.twins or 10, args.workers)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
