"""Where a challenge run (``make run``) spends its time (issue 40).

Two views of a finished run folder:

1. its ``timings.ecsv`` summed per stage and method (task seconds, the share of
   all task seconds), with the run's wall time and the last tasks (the tail
   that one worker runs alone);
2. with ``--profile-epoch N``: every reduction of epoch ``N`` (each method,
   both profiles, as the run's planner makes them), run again in this process,
   single-threaded, under cProfile, into a scratch folder: the CPU seconds of
   each task and the ``--top`` entries by internal time and by cumulative time.

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


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("run", type=Path, help="a finished run folder (eclipsebench run --out)")
    p.add_argument("--profile-epoch", type=int, default=None,
                   help="also profile every reduction of this epoch (default: timings only)")
    p.add_argument("--top", type=int, default=25)
    args = p.parse_args(argv)
    stage_split(args.run)
    if args.profile_epoch is not None:
        profile_reductions(args.run, args.profile_epoch, args.top)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
