"""campaign (issue 38): against ``run`` on the same epochs, and against separate ``reduce`` calls.

Parts (``--part``):

``run``
    ``eclipsebench run`` on the built-in challenge (``--epochs`` epochs,
    least squares, ``--methods``, the controlled profile) and then
    ``eclipsebench campaign`` over that run's photometry tables only (no
    truth): the per-method depths and the Table 3 statistics side by side,
    and the largest difference of each.
``speed``
    A campaign of the same tables x methods with least squares on
    ``--workers`` workers, against the same reductions run as separate
    ``eclipsebench reduce`` commands one after another (each a new process),
    in one script: the wall times and their ratio (goal: at most 0.5).

Example: ``python bench/bench_campaign.py --part run --epochs 10 --workdir /tmp/bc`` then
``python bench/bench_campaign.py --part speed --workdir /tmp/bc`` (it reuses the run's
tables).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

METHODS = ["bliss", "gp", "kr-data", "pld", "poly2", "segpoly"]
#: The Table 3 statistics compared between ``run`` and ``campaign`` (per method).
STATISTICS = ("D_mean", "sigma_mean", "SD", "sigma_orig", "f_dis", "sigma_tot", "R")


def _cli(*argv: str) -> None:
    subprocess.run([sys.executable, "-m", "eclipsebench", *argv], check=True,
                   stdout=subprocess.DEVNULL)


def _campaign(tables: list[str], out: Path, methods: list[str], workers: int) -> float:
    """``eclipsebench campaign`` of ``tables`` (least squares, controlled): its wall seconds."""
    t0 = time.perf_counter()
    _cli("campaign", *tables, "--out", str(out), "--workers", str(workers), "--quiet",
         "--sampler", "leastsq", "--profiles", "controlled", "--methods", ",".join(methods),
         "--system", "XO-3b (2015 challenge)")
    return time.perf_counter() - t0


def _sets(epochs: int, methods: list[str]) -> list[str]:
    items = [f"challenge.epochs={epochs}", 'reduce.sampler="leastsq"',
             'run.profiles=["controlled"]', f"run.methods={json.dumps(methods)}"]
    return [a for item in items for a in ("--set", item)]


def _stats(summary: dict) -> dict[str, dict[str, float]]:
    """Per-method Table 3 statistics of a run's summary (``methods``) or a campaign's (its
    controlled profile's one channel group)."""
    if "profiles" in summary and "channels" in summary["profiles"].get("controlled", {}):
        groups = summary["profiles"]["controlled"]["channels"]
        methods = next(iter(groups.values()))["methods"]
    else:
        methods = summary["methods"]
    return {m: {k: float(v[k]) for k in STATISTICS if isinstance(v.get(k), (int, float))}
            for m, v in methods.items()}


def part_run(work: Path, epochs: int, methods: list[str], workers: int) -> None:
    from astropy.table import Table

    run_dir, camp_dir = work / "run", work / "campaign"
    t0 = time.perf_counter()
    _cli("run", "--out", str(run_dir), "--workers", str(workers), "--quiet",
         *_sets(epochs, methods), "--set", "run.report=false")
    run_s = time.perf_counter() - t0
    tables = sorted(str(p) for p in (run_dir / "photometry").glob("epoch_*.fits"))
    shutil.rmtree(camp_dir, ignore_errors=True)
    camp_s = _campaign(tables, camp_dir, methods, workers)
    print(f"run {run_s:.0f} s, campaign {camp_s:.0f} s ({epochs} epochs x {len(methods)} "
          f"methods, least squares, {workers} workers)")
    a = Table.read(run_dir / "depths.ecsv", format="ascii.ecsv")
    b = Table.read(camp_dir / "depths.ecsv", format="ascii.ecsv")
    key = {(str(r["method"]), int(r["epoch"])): float(r["depth_ppm"]) for r in a}
    diffs = [abs(float(r["depth_ppm"]) - key[(str(r["method"]), int(r["epoch"]))])
             for r in b if (str(r["method"]), int(r["epoch"])) in key]
    print(f"depths compared: {len(diffs)} of {len(a)}; largest |run - campaign| "
          f"{max(diffs) if diffs else float('nan'):.3g} ppm")
    sa = _stats(json.loads((run_dir / "summary.json").read_text()))
    sb = _stats(json.loads((camp_dir / "summary.json").read_text()))
    print("| method | " + " | ".join(STATISTICS) + " | largest |run - campaign| |")
    print("| --- " * (len(STATISTICS) + 2) + "|")
    for m in methods:
        if m not in sa or m not in sb:
            print(f"| {m} | not in both summaries |")
            continue
        gap = max((abs(sa[m][k] - sb[m][k]) for k in STATISTICS if k in sa[m] and k in sb[m]),
                  default=float("nan"))
        print(f"| {m} | " + " | ".join(f"{sa[m].get(k, float('nan')):.4g}" for k in STATISTICS)
              + f" | {gap:.3g} |")


def part_speed(work: Path, methods: list[str], workers: int) -> None:
    tables = sorted(str(p) for p in (work / "run" / "photometry").glob("epoch_*.fits"))
    if not tables:
        raise SystemExit(f"no tables in {work / 'run' / 'photometry'}: run --part run first")
    out = work / "speed_campaign"
    shutil.rmtree(out, ignore_errors=True)
    campaign_s = _campaign(tables, out, methods, workers)
    single = work / "speed_reduce"
    shutil.rmtree(single, ignore_errors=True)
    single.mkdir(parents=True)
    t0 = time.perf_counter()
    for table in tables:
        for m in methods:
            _cli("reduce", table, "--method", m, "--sampler", "leastsq", "--quiet",
                 "--system", "XO-3b (2015 challenge)",
                 "--out", str(single / f"{Path(table).stem}_{m}.json"))
    separate_s = time.perf_counter() - t0
    n = len(tables) * len(methods)
    print(f"campaign, {len(tables)} epochs x {len(methods)} methods, least squares, "
          f"{workers} workers: {campaign_s:.1f} s wall (the joint fits and statistics "
          f"included)")
    print(f"the same {n} reductions as separate `eclipsebench reduce` commands one after "
          f"another: {separate_s:.1f} s wall")
    print(f"ratio campaign / separate: {campaign_s / separate_s:.2f} (goal at most 0.5)")


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--part", choices=("run", "speed"), default="run")
    p.add_argument("--epochs", type=int, default=10)
    p.add_argument("--methods", default=",".join(METHODS))
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--workdir", default="bench/results/campaign")
    args = p.parse_args(argv)
    work = Path(args.workdir)
    work.mkdir(parents=True, exist_ok=True)
    print(f"# bench_campaign --part {args.part}: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"
          f", {platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    methods = args.methods.split(",")
    if args.part == "run":
        part_run(work, args.epochs, methods, args.workers)
    else:
        part_speed(work, methods, args.workers)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
