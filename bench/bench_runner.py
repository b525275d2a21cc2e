"""Wall time of the whole challenge with 1 and 2 Dask workers (issue 8).

Runs ``eclipsebench run`` (the default XO-3b challenge unless options say
otherwise) into fresh folders, first with ``--workers 1`` (the reference:
in-process, synchronous), then with ``--workers 2`` (a LocalCluster of two
processes), and prints the wall times, the speed-up, the task seconds per
stage and how busy each worker was (from the run's ``timings.ecsv`` data).
Each configuration runs ``--repeats`` times (default 1: a full run takes
minutes) and the median is reported. The two runs must give the same
``summary.json`` bytes; the script says whether they do.

    python bench/bench_runner.py                    # the default challenge
    python bench/bench_runner.py --epochs 3 --set observation.frames_per_cube=8
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import tempfile
import time
from pathlib import Path

from eclipsebench.challenge.runner import run_challenge
from eclipsebench.config import load_config


def one_run(cfg, workers: int, root: Path) -> tuple[float, dict, bytes]:
    if root.exists():
        shutil.rmtree(root)
    t0 = time.perf_counter()
    _, report = run_challenge(cfg, root, workers=workers)
    wall = time.perf_counter() - t0
    busy: dict[str, float] = {}
    for t in report.timeline:
        busy[t.worker] = busy.get(t.worker, 0.0) + t.seconds
    print(f"  workers={workers} run in {root.name}: wall {wall:.1f} s, task seconds "
          f"{sum(busy.values()):.1f}, busy per worker "
          + ", ".join(f"{b / report.wall_s:.0%}" for b in busy.values()), flush=True)
    return wall, report.stage_seconds(), (root / "summary.json").read_bytes()


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--epochs", type=int)
    p.add_argument("--repeats", type=int, default=1)
    p.add_argument("--set", dest="overrides", action="append", default=[])
    p.add_argument("--keep", metavar="DIR", help="keep the run folders under DIR")
    args = p.parse_args()
    overrides = list(args.overrides)
    if args.epochs:
        overrides.append(f"challenge.epochs={args.epochs}")
    cfg = load_config(None, overrides)
    base = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bench_runner_"))
    results = {}
    for workers in (1, 2):
        walls, stages, summaries = [], None, set()
        for i in range(args.repeats):
            wall, stages, summary = one_run(cfg, workers, base / f"w{workers}_{i}")
            walls.append(wall)
            summaries.add(summary)
        results[workers] = (statistics.median(walls), stages, summaries)
        print(f"workers={workers}: median wall {results[workers][0]:.1f} s over {args.repeats} "
              f"run(s); task seconds per stage: "
              + json.dumps({k: round(v, 1) for k, v in stages.items()}), flush=True)
    w1, w2 = results[1][0], results[2][0]
    same = results[1][2] == results[2][2] and len(results[1][2]) == 1
    print(f"speed-up 1 -> 2 workers: {w1 / w2:.2f}x (reference: the 1-worker run)")
    print(f"summary.json identical for 1 and 2 workers: {same}")
    if not args.keep:
        shutil.rmtree(base, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
