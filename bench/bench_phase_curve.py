"""Benchmark: whole phase-curve round trips and BLISS speed (issue 17, points 2-3).

For each seed: the built-in configuration ``xo3b-phase-curve`` (one whole
orbit of the 2015 challenge's XO-3b, 2 s subarray frames in AORs of at most
12 h after a 30-minute Pre AOR, ``physical`` noise) is simulated, measured
with the default photometry and reduced with ``reduce --event phase-curve``
by each method with the first- and with the second-harmonic phase curve (one
shared systematics model, a flux offset per AOR), and the BIC's pick between
the two is marked. The eclipse depth is compared with the true depth, the
phase amplitude (semi-amplitude) and the hotspot offset with the truth of the
same harmonic order (``truth.ecsv``: the reducer's model fitted to the
noiseless L(t), :func:`eclipsebench.astro.phase_curves.fit_harmonic_light_curve`).

Speed: the reduction of each seed is timed as ``eclipsebench reduce`` runs
it (least squares and the default errors); ``--speed N`` also times BLISS
N more times on the first seed's table with the default ``--phase bic``
(both harmonic orders fitted) on one core (BLAS, OpenMP and numba one
thread) and prints the median, for the "140,000 frames in at most 2
minutes" line of the issue.

Usage::

    .venv/bin/python bench/bench_phase_curve.py [--seed N ...] [--method NAME ...]
        [--speed N] [--keep DIR]

Prints one JSON line per seed and method, then a Markdown table and, per
method and quantity, how many seeds lie within 2 sigma of the truth.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from astropy.table import Table  # noqa: E402

from eclipsebench.cli import main as cli  # noqa: E402

DEFAULT_SEEDS = (1, 2, 3, 4, 5)
DEFAULT_METHODS = ("bliss", "poly2")
#: The phase models fitted, with the suffix of their truth columns in truth.ecsv.
PHASES = (("harmonic1", ""), ("harmonic2", "_h2"))
#: (result key, error key, truth column, unit) of each compared quantity.
QUANTITIES = (("depth_ppm", "depth_err_ppm", "depth_ppm", "ppm"),
              ("phase_amplitude_ppm", "phase_amplitude_err_ppm", "phase_amplitude_ppm", "ppm"),
              ("phase_offset_deg", "phase_offset_err_deg", "phase_offset_deg", "deg"))
ONE_CORE = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
            "NUMBA_NUM_THREADS": "1"}


def reduce_seconds(table: Path, method: str, out: Path, phase: str = "harmonic1") -> float:
    """Wall time of one ``eclipsebench reduce --event phase-curve`` in a one-core process."""
    env = {**os.environ, **ONE_CORE}
    exe = Path(sys.executable).with_name("eclipsebench")
    t0 = time.perf_counter()
    subprocess.run([str(exe), "reduce", str(table), "--method", method, "--event",
                    "phase-curve", "--phase", phase, "--out", str(out), "--quiet"],
                   check=True, env=env)
    return time.perf_counter() - t0


def run_seed(seed: int, methods: list[str], root: Path) -> list[dict]:
    """Simulate, measure and reduce one whole phase curve; one row per method and phase model.

    A folder kept from an earlier run (``--keep``) is reduced again without
    simulating and measuring it anew.
    """
    times = {}
    table = root / "phot" / "epoch_01.fits"
    if not table.is_file():
        t0 = time.perf_counter()
        assert cli(["simulate", "xo3b-phase-curve", "--out", str(root / "sim"), "--seed",
                    str(seed), "--no-calibration", "--quiet", "--workers", "2"]) == 0
        times["simulate_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        assert cli(["photometry", str(root / "sim"), "--out", str(root / "phot"),
                    "--quiet"]) == 0
        times["photometry_s"] = time.perf_counter() - t0
    truth = Table.read(root / "sim" / "truth.ecsv", format="ascii.ecsv")[0]
    rows = []
    for method in methods:
        for phase, tag in PHASES:
            out = root / f"{method}_{phase}.json"
            reduce_s = reduce_seconds(table, method, out, phase)
            res = json.loads(out.read_text())
            row = {"seed": seed, "method": method, "phase": phase, "frames": res["n_frames"],
                   **{k: round(v, 1) for k, v in times.items()}, "reduce_s": round(reduce_s, 1),
                   "bic": round(float(res["bic"]), 1), "err_from": res.get("depth_err_method")}
            for key, err_key, truth_key, _ in QUANTITIES:
                # the eclipse depth against the true depth; the phase curve against the
                # truth of the same harmonic order
                true_key = truth_key if key == "depth_ppm" else truth_key.replace(
                    "_ppm", f"{tag}_ppm").replace("_deg", f"{tag}_deg")
                value, err, true = float(res[key]), float(res[err_key]), float(truth[true_key])
                diff = value - true
                if key == "phase_offset_deg":
                    diff = (diff + 180.0) % 360.0 - 180.0
                row.update({key: round(value, 2), err_key: round(err, 2),
                            f"{key}_true": round(true, 2), f"{key}_z": round(diff / err, 2)})
            row["nightside_flux_ppm"] = round(float(res["nightside_flux_ppm"]), 1)
            row["nightside_flux_err_ppm"] = round(float(res["nightside_flux_err_ppm"]), 1)
            rows.append(row)
        pair = [r for r in rows if r["method"] == method]
        best = min(pair, key=lambda r: r["bic"])
        for r in pair:
            r["bic_preferred"] = r is best
    return rows


def summary(rows: list[dict]) -> list[str]:
    """The Markdown table and the acceptance line of each method."""
    lines = ["| method | phase | BIC pick | seed | frames | depth (ppm) | truth | amplitude (ppm) "
             "| truth | offset (deg) | truth | nightside (ppm) | reduce (s) |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        lines.append(
            f"| {r['method']} | {r['phase']} | {'yes' if r['bic_preferred'] else ''} | "
            f"{r['seed']} | {r['frames']} | "
            f"{r['depth_ppm']:.0f} +- {r['depth_err_ppm']:.0f} | {r['depth_ppm_true']:.0f} | "
            f"{r['phase_amplitude_ppm']:.0f} +- {r['phase_amplitude_err_ppm']:.0f} | "
            f"{r['phase_amplitude_ppm_true']:.0f} | "
            f"{r['phase_offset_deg']:.1f} +- {r['phase_offset_err_deg']:.1f} | "
            f"{r['phase_offset_deg_true']:.1f} | "
            f"{r['nightside_flux_ppm']:.0f} +- {r['nightside_flux_err_ppm']:.0f} | "
            f"{r['reduce_s']:.0f} |")
    lines.append("")
    groups = [(m, p) for m in dict.fromkeys(r["method"] for r in rows)
              for p in dict.fromkeys(r["phase"] for r in rows)]
    groups += [(m, "BIC's pick") for m in dict.fromkeys(r["method"] for r in rows)]
    for method, phase in groups:
        sel = [r for r in rows if r["method"] == method
               and (r["phase"] == phase or (phase == "BIC's pick" and r["bic_preferred"]))]
        parts = []
        for key, _, _, _ in QUANTITIES:
            z = np.array([r[f"{key}_z"] for r in sel])
            parts.append(f"{key} {int(np.sum(np.abs(z) < 2.0))}/{len(sel)} within 2 sigma "
                         f"(mean z {np.mean(z):+.2f})")
        lines.append(f"{method}, {phase}: " + "; ".join(parts))
    return lines


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, action="append")
    ap.add_argument("--method", action="append")
    ap.add_argument("--speed", type=int, default=0,
                    help="time BLISS this many more times on the first seed (one core)")
    ap.add_argument("--keep", type=Path, help="keep the folders here")
    args = ap.parse_args(argv)
    methods = args.method or list(DEFAULT_METHODS)
    rows = []
    for i, seed in enumerate(args.seed or DEFAULT_SEEDS):
        root = Path(tempfile.mkdtemp(prefix=f"bench_phase_curve_{seed}_")) if args.keep is None \
            else args.keep / f"seed_{seed}"
        try:
            for row in run_seed(seed, methods, root):
                print(json.dumps(row), flush=True)
                rows.append(row)
            if i == 0 and args.speed > 0:
                table = root / "phot" / "epoch_01.fits"
                runs = [reduce_seconds(table, "bliss", root / "speed.json", "bic")
                        for _ in range(args.speed)]
                print(json.dumps({"speed": "bliss, --phase bic (the default)",
                                  "frames": rows[0]["frames"],
                                  "seconds": [round(s, 1) for s in runs],
                                  "median_s": round(float(np.median(runs)), 1)}), flush=True)
        finally:
            if args.keep is None:
                shutil.rmtree(root, ignore_errors=True)
    print("\n".join(summary(rows)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
