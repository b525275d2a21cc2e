"""Benchmark: the full default ten-epoch XO-3b challenge, simulated and written.

156,160 subarray frames (10 epochs x 244 cubes x 64 frames) at 1 ms pointing
sub-sampling, 2 x 2,440 FITS files (~1.3 GB), truth, light curves and the
400,000-frame calibration set; reference: drawing 156,160 x 1,024 Poisson
variates with numpy (one per pixel and frame) in the same script.

Usage::

    .venv/bin/python bench/bench_simulate.py [--epochs K] [--workers N] [--repeats R]
                                             [--no-calibration] [--keep DIR]

Prints wall time, peak resident memory of this process and of its worker
processes (``resource.getrusage``), and the ratio to the reference.
"""

from __future__ import annotations

import argparse
import resource
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def cpu_seconds() -> float:
    """CPU time (user + system) of this process and its finished children."""
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def reference_poisson(n_frames: int, mean_e: float, repeats: int) -> tuple[float, float]:
    """Median wall and CPU seconds to draw n_frames x 1024 Poisson variates (4,096-frame chunks)."""
    times, cpus = [], []
    for r in range(repeats):
        g = np.random.default_rng(r)
        lam = np.full((4096, 1024), mean_e)
        t0 = time.perf_counter()
        c0 = time.process_time()
        done = 0
        while done < n_frames:
            n = min(4096, n_frames - done)
            g.poisson(lam[:n])
            done += n
        times.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return statistics.median(times), statistics.median(cpus)


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--epochs", type=int, default=10)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=1, help="runs of the full simulation")
    ap.add_argument("--no-calibration", action="store_true")
    ap.add_argument("--keep", metavar="DIR", help="write here and keep (default: a temp dir)")
    args = ap.parse_args(argv)

    from eclipsebench.config import load_config
    from eclipsebench.simulation.challenge import simulate_challenge
    from eclipsebench.simulation.from_config import light_curve_of
    from eclipsebench.simulation.star import make_star_imager

    cfg = load_config(None, [f"challenge.epochs={args.epochs}"])
    t0 = time.perf_counter()
    light_curve_of(cfg)
    make_star_imager(cfg)
    setup_s = time.perf_counter() - t0

    times, cpus = [], []
    n_frames = 0
    for _ in range(args.repeats):
        out = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bench_sim_"))
        if out.exists():
            shutil.rmtree(out)
        t0 = time.perf_counter()
        c0 = cpu_seconds()
        res = simulate_challenge(cfg, out, workers=args.workers,
                                 calibration=not args.no_calibration)
        times.append(time.perf_counter() - t0)
        cpus.append(cpu_seconds() - c0)
        n_frames = sum(r_["n_frames"] for r_ in res.truth_rows)
        size_gb = sum(p.stat().st_size for p in out.rglob("*") if p.is_file()) / 1e9
        if not args.keep:
            shutil.rmtree(out)
    sim_s = statistics.median(times)
    sim_cpu = statistics.median(cpus)
    ref_s, ref_cpu = reference_poisson(n_frames, 5.0, 3)
    load = __import__("os").getloadavg()[0]
    self_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    child_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(f"frames simulated        {n_frames}")
    print(f"files written           {res.files} cubes + truth, light curves"
          + ("" if args.no_calibration else ", calibration set") + f" ({size_gb:.2f} GB)")
    print(f"set-up (L(t), PRF)      {setup_s:.1f} s (once per process; not in the time below)")
    print(f"simulate + write        {sim_s:.1f} s (median of {len(times)}; workers={args.workers})")
    print(f"reference Poisson draws {ref_s:.1f} s for {n_frames} x 1024 variates (lambda = 5)")
    print(f"ratio (wall)             {sim_s / ref_s:.2f}")
    print(f"CPU, all processes      {sim_cpu:.1f} s (ideal wall on {args.workers} idle cores: "
          f"{sim_cpu / args.workers:.1f} s); reference CPU {ref_cpu:.1f} s, ratio "
          f"{sim_cpu / ref_cpu:.2f}")
    print(f"load average at the end {load:.1f}")
    print(f"peak RSS                main {self_mb:.0f} MB, largest worker {child_mb:.0f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
