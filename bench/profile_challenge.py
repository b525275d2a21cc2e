"""Where a challenge run (``make run``) spends its time (issue 40).

Two views of a finished run folder:

1. its ``timings.ecsv`` summed per stage and method (task seconds, the share of
   all task seconds), with the run's wall time and the last tasks (the tail
   that one worker runs alone);
2. with ``--profile-epoch N``: every reduction of epoch ``N`` (each method,
   both profiles, as the run's planner makes them), run again in this process,
   single-threaded, under cProfile, into a scratch folder: the CPU seconds of
   each task and the ``--top`` entries by internal time and by cumulative time.

3. with ``--against BEFORE``: the science of the run against another run of the
   same configuration (issue 40: a speed-up must not move it): per profile and
   method, accuracy ``a`` and the RMSE with BEFORE's bootstrap interval (68 %,
   ``a_lo``/``a_hi`` of its ``summary.json``; RMSE = sigma_phot / a), whether the
   new value lies inside, and the largest depth difference.

Usage: ``python bench/profile_challenge.py runs/xo3b-2015-seed2015-10ep
--profile-epoch 1 --top 25`` (the run folder is only read).
"""

from __future__ import annotations

import argparse
import collections
import cProfile
import io
import pstats
import sys
import tempfile
import time
from pathlib import Path


def stage_split(run: Path) -> None:
    import numpy as np
    from astropy.table import Table

    t = Table.read(run / "timings.ecsv", format="ascii.ecsv")
    seconds: dict[str, float] = collections.defaultdict(float)
    count: collections.Counter[str] = collections.Counter()
    for key, s in zip(t["key"], t["seconds"], strict=True):
        parts = str(key).split("/")
        stage = parts[0] + (f" {parts[1]}" if parts[0].startswith("reduce") else "")
        seconds[stage] += float(s)
        count[stage] += 1
    total = sum(seconds.values())
    print(f"{run}: wall {t.meta.get('wall_s', float('nan')):.1f} s, {len(t)} tasks, "
          f"{total:.1f} task seconds ({t.meta.get('executor', '')})")
    print("| stage | task seconds | tasks | share |")
    print("| --- | ---: | ---: | ---: |")
    for stage, s in sorted(seconds.items(), key=lambda kv: -kv[1]):
        print(f"| {stage} | {s:.1f} | {count[stage]} | {100 * s / total:.1f} % |")
    end = np.asarray(t["start_s"]) + np.asarray(t["seconds"])
    print("last tasks: " + ", ".join(f"{t['key'][i]} ({t['seconds'][i]:.1f} s from "
                                     f"{t['start_s'][i]:.0f} s)" for i in np.argsort(end)[-4:]))


def profile_reductions(run: Path, epoch: int, top: int) -> None:
    import numba
    from threadpoolctl import threadpool_limits

    from eclipsebench.challenge.reduce_stage import plan_reduce_tasks
    from eclipsebench.config import load_config
    from eclipsebench.decorrelate import available_methods
    from eclipsebench.engine.layout import Layout

    cfg = load_config(str(run / "run_config.toml"), [])
    methods = list(cfg.run.methods) or list(available_methods())
    table = str(Layout(run).photometry(epoch, False))
    numba.set_num_threads(1)
    prof = cProfile.Profile()
    total = 0.0
    with tempfile.TemporaryDirectory() as tmp, threadpool_limits(1):
        scratch = Layout(Path(tmp))
        tasks = [task for profile in cfg.run.profiles
                 for task in plan_reduce_tasks(cfg, scratch, [epoch], methods, profile=profile)]
        for task in tasks:
            args = list(task.args)
            args[1] = table            # the run's photometry; results go to the scratch folder
            c0 = time.process_time()
            prof.enable()
            task.func(*args)
            prof.disable()
            dt = time.process_time() - c0
            total += dt
            print(f"{task.key:40s} {dt:7.2f} cpu s", flush=True)
    print(f"{len(tasks)} reductions of epoch {epoch}: {total:.1f} cpu s")
    for order in ("tottime", "cumulative"):
        out = io.StringIO()
        pstats.Stats(prof, stream=out).sort_stats(order).print_stats(top)
        print(out.getvalue())


def _depths(path: Path, method: str) -> dict[int, float]:
    from astropy.table import Table

    t = Table.read(path, format="ascii.ecsv")
    return {int(e): float(d) for m, e, d in zip(t["method"], t["epoch"], t["depth_ppm"],
                                                strict=True) if m == method}


def science_against(run: Path, before: Path) -> int:
    """Print the science table of ``run`` against ``before``; the count of values outside."""
    import json

    new, old = (json.loads((r / "summary.json").read_text()) for r in (run, before))
    outside = 0
    print(f"science of {run} against {before} (68 % bootstrap intervals of the latter)")
    print("| profile | method | a before [interval] | a after | RMSE before [interval] | "
          "RMSE after | largest depth change (ppm) | inside |")
    print("| --- | --- | --- | ---: | --- | ---: | ---: | --- |")
    for profile, group in old["profiles"].items():
        sigma = group["sigma_phot_ppm"]
        for method, m in group["methods"].items():
            n = new["profiles"][profile]["methods"][method]
            rmse_lo, rmse_hi = sigma / m["a_hi"], sigma / m["a_lo"]
            table = "depths.ecsv" if profile == "controlled" else f"depths_{profile}.ecsv"
            depths_old, depths_new = (_depths(r / table, method) for r in (before, run))
            change = max((abs(depths_new[e] - v) for e, v in depths_old.items()
                          if e in depths_new), default=float("nan"))
            inside = (m["a_lo"] <= n["a"] <= m["a_hi"]) and (rmse_lo <= n["RMSE"] <= rmse_hi)
            outside += not inside
            print(f"| {profile} | {method} | {m['a']:.3f} [{m['a_lo']:.3f}, {m['a_hi']:.3f}] | "
                  f"{n['a']:.3f} | {m['RMSE']:.1f} [{rmse_lo:.1f}, {rmse_hi:.1f}] | "
                  f"{n['RMSE']:.1f} | {change:.1f} | {'yes' if inside else 'NO'} |")
        print(f"| {profile} | average a | {group['average']['a']:.4f} | "
              f"{new['profiles'][profile]['average']['a']:.4f} | | | | |")
    print(f"{outside} value pairs outside their interval")
    return outside


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("run", type=Path, help="a finished run folder (eclipsebench run --out)")
    p.add_argument("--profile-epoch", type=int, default=None,
                   help="also profile every reduction of this epoch (default: timings only)")
    p.add_argument("--top", type=int, default=25)
    p.add_argument("--against", type=Path, default=None,
                   help="another run folder of the same configuration: compare the science")
    args = p.parse_args(argv)
    if args.against is not None:
        return 1 if science_against(args.run, args.against) else 0
    stage_split(args.run)
    if args.profile_epoch is not None:
        profile_reductions(args.run, args.profile_epoch, args.top)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
