"""Benchmark: channel 1 and the readout modes, simulated, measured and reduced with BLISS.

Scenarios (issue 16 points 3 and 4), one epoch each, the eclipse 0.14 d after
the window's start:

``ch1_2s``
    ``observation.channel = 1``, the default 2 s subarray epoch (11 + 233 cubes
    of 64 frames: 15,616 frames).
``ch1_0p1s``
    channel 1, ``readout = sub_0p1s`` (FN 2, WT 6), 64-frame cubes every
    8.4 s, as many cubes as ``--cubes-0p1s`` (default 400: 25,600 frames).
``full_2s``
    channel 2, ``readout = full_2s`` (FN 4, WT 2, 0.2 s ticks), one 256 x 256
    frame every ``--full-cadence`` s (default 30) with the star at (60.4, 190.7).

Usage::

    .venv/bin/python bench/bench_channels.py [--scenario NAME ...] [--seed N ...] [--keep DIR]

Prints, per scenario and seed: frames, wall time of simulate / photometry /
reduce, the BLISS depth and its error against the truth, chi2_red, and the
median noise pixels and aperture flux of the good frames.
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

from eclipsebench.astro.catalogue import system_for  # noqa: E402
from eclipsebench.astro.orbit import eclipse_time_bmjd  # noqa: E402
from eclipsebench.cli import main as cli  # noqa: E402
from eclipsebench.config import load_config  # noqa: E402
from eclipsebench.photometry.table import read_photometry  # noqa: E402
from eclipsebench.simulation.plan import JD_OFFSET_BMJD  # noqa: E402


def scenarios(args) -> dict[str, list[str]]:
    return {
        "ch1_2s": ["observation.channel=1", "observation.main_cubes=233"],
        "ch1_0p1s": ["observation.channel=1", "observation.readout=sub_0p1s",
                     "observation.pre_cubes=10", f"observation.main_cubes={args.cubes_0p1s}",
                     f"observation.cube_interval_s={30150.0 / args.cubes_0p1s:.3f}"],
        "full_2s": ["observation.readout=full_2s", "observation.x0_px=60.4",
                    "observation.y0_px=190.7", "observation.pre_cubes=20",
                    f"observation.main_cubes={int(30150 / args.full_cadence)}",
                    f"observation.cube_interval_s={args.full_cadence}"],
    }


def window(sets: list[str]) -> str:
    system = system_for(load_config(None, sets).system)
    t_ecl = eclipse_time_bmjd(system, 57205.8)
    return f"observation.start_times_jd=[{t_ecl - 0.14 - JD_OFFSET_BMJD:.6f}]"


def run(name: str, sets: list[str], seed: int, root: Path) -> dict:
    sets = sets + [window(sets)]
    flags = [a for s in sets for a in ("--set", s)]
    times = {}
    t0 = time.perf_counter()
    assert cli(["simulate", "--out", str(root / "sim"), "--epochs", "1", "--seed", str(seed),
                "--no-calibration", "--quiet", "--workers", "1", *flags]) == 0
    times["simulate"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    assert cli(["photometry", str(root / "sim"), "--out", str(root / "phot"), "--quiet"]) == 0
    times["photometry"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    out = root / "bliss.json"
    assert cli(["reduce", str(root / "phot" / "epoch_01.fits"), "--method", "bliss", "--out",
                str(out), "--quiet"]) == 0
    times["reduce"] = time.perf_counter() - t0
    res = json.loads(out.read_text())
    truth = Table.read(root / "sim" / "truth.ecsv", format="ascii.ecsv")[0]
    table = read_photometry(root / "phot" / "epoch_01.fits")
    good = np.asarray(table["flag"]) == 0
    return {"scenario": name, "seed": seed, "frames": len(table), "good": int(good.sum()),
            **{f"{k}_s": round(v, 1) for k, v in times.items()},
            "depth_ppm": round(res["depth_ppm"], 1), "err_ppm": round(res["depth_err_ppm"], 1),
            "true_ppm": float(truth["depth_ppm"]),
            "z": round((res["depth_ppm"] - truth["depth_ppm"]) / res["depth_err_ppm"], 2),
            "chi2_red": round(res.get("chi2_red", float("nan")), 3),
            "noise_pixels": round(float(np.median(table["noise_pixels"][good])), 3),
            "flux_e": round(float(np.median(table["flux"][good])), 1)}


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", action="append", choices=("ch1_2s", "ch1_0p1s", "full_2s"))
    ap.add_argument("--seed", type=int, action="append")
    ap.add_argument("--cubes-0p1s", type=int, default=400)
    ap.add_argument("--full-cadence", type=float, default=30.0)
    ap.add_argument("--keep", type=Path, help="keep the folders here")
    args = ap.parse_args(argv)
    table = scenarios(args)
    for name in args.scenario or list(table):
        for seed in args.seed or [2015]:
            root = Path(tempfile.mkdtemp(prefix=f"bench_{name}_")) if args.keep is None \
                else args.keep / f"{name}_{seed}"
            try:
                print(json.dumps(run(name, table[name], seed, root)), flush=True)
            finally:
                if args.keep is None:
                    shutil.rmtree(root, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
