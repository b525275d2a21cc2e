"""Benchmark: transit round trips (issue 17 point 1, the transit line of its acceptance).

For each seed: one simulated epoch of the 2015 challenge's XO-3b planned
around the transit (``observation.event = "transit"``: the first Table 2
window moved from its eclipse to the transit before it; 11 + 233 cubes of 64
two-second frames, 15,616 frames, ``physical`` noise), measured with the
default photometry and reduced with ``reduce --event transit`` by each method
(Rp/R* and the mid-transit time free; a/R*, b and the limb darkening fixed to
the catalogue, which is what the simulator used; default quadratic phase
model and error rule). Rp/R* is compared with the truth (``truth.ecsv``
``rp_rs``).

Usage::

    .venv/bin/python bench/bench_transit.py [--seed N ...] [--method NAME ...] [--keep DIR]

Prints one JSON line per seed and method, then a Markdown table and the
acceptance summary per method: how many seeds have Rp/R* within 2 sigma of
the truth, and the mean bias in units of the mean error (and of the error
of the mean, sigma / sqrt(n)).
"""

from __future__ import annotations

import argparse
import json
import shutil
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
DEFAULT_METHODS = ("bliss", "pld")


def run_seed(seed: int, methods: list[str], root: Path) -> list[dict]:
    """Simulate, measure and reduce one transit epoch; one row per method."""
    times = {}
    t0 = time.perf_counter()
    assert cli(["simulate", "--out", str(root / "sim"), "--epochs", "1", "--seed", str(seed),
                "--no-calibration", "--quiet", "--workers", "1",
                "--set", "observation.event=transit"]) == 0
    times["simulate_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    assert cli(["photometry", str(root / "sim"), "--out", str(root / "phot"), "--quiet"]) == 0
    times["photometry_s"] = time.perf_counter() - t0
    truth = Table.read(root / "sim" / "truth.ecsv", format="ascii.ecsv")[0]
    rows = []
    for method in methods:
        out = root / f"{method}.json"
        t0 = time.perf_counter()
        assert cli(["reduce", str(root / "phot" / "epoch_01.fits"), "--method", method,
                    "--event", "transit", "--out", str(out), "--quiet"]) == 0
        reduce_s = time.perf_counter() - t0
        res = json.loads(out.read_text())
        rp, err = res["rp_rs"], res["rp_rs_err"]
        rows.append({
            "seed": seed, "method": method, "frames": res["n_frames"],
            **{k: round(v, 1) for k, v in times.items()}, "reduce_s": round(reduce_s, 1),
            "rp_rs": round(rp, 6), "rp_rs_err": round(err, 6),
            "rp_rs_true": float(truth["rp_rs"]),
            "z": round((rp - float(truth["rp_rs"])) / err, 2),
            "transit_depth_ppm": round(res["transit_depth_ppm"], 1),
            "transit_depth_err_ppm": round(res["transit_depth_err_ppm"], 1),
            "t_transit_offset_s": round((res["t_transit_bmjd"] - float(truth["t_transit_bmjd"]))
                                        * 86400.0, 1),
            "t_transit_err_s": round(res["t_transit_err_d"] * 86400.0, 1),
            "err_from": res["depth_err_method"], "beta_red": round(res["beta_red"], 2),
            "chi2_red": round(res["chi2_red"], 3)})
    return rows


def summary(rows: list[dict]) -> list[str]:
    """The Markdown table and the acceptance line of each method."""
    lines = ["| method | seed | Rp/R* | error | (fit - truth) / error | depth (ppm) | "
             "t - truth (s) | reduce (s) |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        lines.append(f"| {r['method']} | {r['seed']} | {r['rp_rs']:.5f} | {r['rp_rs_err']:.5f} | "
                     f"{r['z']:+.2f} | {r['transit_depth_ppm']:.0f} +- "
                     f"{r['transit_depth_err_ppm']:.0f} | {r['t_transit_offset_s']:+.0f} +- "
                     f"{r['t_transit_err_s']:.0f} | {r['reduce_s']:.1f} |")
    lines.append("")
    for method in dict.fromkeys(r["method"] for r in rows):
        sel = [r for r in rows if r["method"] == method]
        diff = np.array([r["rp_rs"] - r["rp_rs_true"] for r in sel])
        err = np.array([r["rp_rs_err"] for r in sel])
        within = int(np.sum(np.abs(diff / err) < 2.0))
        bias = float(np.mean(diff))
        lines.append(f"{method}: {within} of {len(sel)} within 2 sigma; mean bias "
                     f"{bias:+.6f} = {bias / np.mean(err):+.2f} x mean error "
                     f"({np.mean(err):.6f}) = {bias / (np.mean(err) / np.sqrt(len(sel))):+.2f} "
                     "x error of the mean")
    return lines


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, action="append")
    ap.add_argument("--method", action="append")
    ap.add_argument("--keep", type=Path, help="keep the folders here")
    args = ap.parse_args(argv)
    methods = args.method or list(DEFAULT_METHODS)
    rows = []
    for seed in args.seed or DEFAULT_SEEDS:
        root = Path(tempfile.mkdtemp(prefix=f"bench_transit_{seed}_")) if args.keep is None \
            else args.keep / f"seed_{seed}"
        try:
            for row in run_seed(seed, methods, root):
                print(json.dumps(row), flush=True)
                rows.append(row)
        finally:
            if args.keep is None:
                shutil.rmtree(root, ignore_errors=True)
    print("\n".join(summary(rows)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
