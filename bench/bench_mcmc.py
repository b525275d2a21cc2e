"""MCMC seconds per method (issue 14): emcee on the profiled likelihood, beside least squares.

For every registered method, on two 15,000-frame epochs:

* the synthetic XO-3b epoch of ``bench_reduce.py`` (same generator, seed and
  calibration-star table for KR/Pmap);
* the real XO-3b epoch 1 (``../shared/data/irac/real_xo3_eclipse1/``): its
  photometry is measured once with the default ``[photometry]`` settings
  (``eclipsebench photometry``) and kept in a cache file (``--real-table``);
  KR/Pmap uses the SSC map ``../shared/data/irac/pmap_ch2``.

Each method is reduced as ``eclipsebench reduce`` does, with the default
``[reduce]`` settings (quadratic phase, 16 walkers) except the step cap
(``--max-steps``, 20,000, so that a chain can reach 50 tau): once with
``sampler = "leastsq"`` (the least squares with its errors: Jacobian x
beta_red and the 16-shift prayer bead), once with ``sampler = "mcmc"`` and no
prayer bead. The MCMC seconds are those spent inside ``run_mcmc`` (the least
squares it starts from is not counted); steps, walkers, burn-in, the largest
autocorrelation time after burn-in and N/tau (the chain after burn-in over
tau) come from its result. Times are medians of ``--repeats`` runs; BLAS,
OpenMP and numba run on one thread (one core). ``--move de`` or ``stretch``
overrides each method's ``preferred_move`` to compare the two.

Usage: ``python bench/bench_mcmc.py [--repeats 3] [--methods bliss pld] [--epochs sim real]
[--move preferred|de|stretch] [--real-table PATH]``
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
REAL = (ROOT / ".." / "shared" / "data" / "irac" / "real_xo3_eclipse1").resolve()
REAL_PMAP = (ROOT / ".." / "shared" / "data" / "irac" / "pmap_ch2").resolve()
DEFAULT_CACHE = Path(tempfile.gettempdir()) / "eclipsebench_bench" / "real_xo3_eclipse1_epoch1.fits"


def real_table(path: Path, refresh: bool):
    """The real epoch 1's photometry table: read from ``path``, or measured and written there."""
    from eclipsebench.photometry.table import read_table, write_photometry

    if path.is_file() and not refresh:
        print(f"real epoch 1: photometry table {path} (cached; --refresh-real measures again)")
        return read_table(path)
    from eclipsebench.config import load_config
    from eclipsebench.photometry.pipeline import photometry_tables

    if not REAL.is_dir():
        raise SystemExit(f"{REAL}: the real epoch is not beside this checkout")
    t0 = time.perf_counter()
    _, table = next(photometry_tables(REAL, load_config(None).photometry))
    path.parent.mkdir(parents=True, exist_ok=True)
    write_photometry(table, path)
    print(f"real epoch 1: photometry measured in {time.perf_counter() - t0:.0f} s -> {path}")
    return read_table(path)


class TimedMcmc:
    """Wraps ``run_mcmc`` as ``reduce`` calls it: keeps its seconds and result, may set the move."""

    def __init__(self, run_mcmc, move: str | None):
        self.run_mcmc = run_mcmc
        self.move = move
        self.seconds: list[float] = []
        self.result = None

    def __call__(self, *args, **kwargs):
        if self.move is not None:
            kwargs["move"] = self.move
        t0 = time.perf_counter()
        self.result = self.run_mcmc(*args, **kwargs)
        self.seconds.append(time.perf_counter() - t0)
        return self.result


def bench_method(table, name, *, repeats, max_steps, move, resources):
    import eclipsebench.fit.epoch_fit as fit_module  # where the epoch's fit calls run_mcmc
    import eclipsebench.fit.reduce as reduce_module
    from eclipsebench.config.reduce import ReduceSection

    lsq_opts = ReduceSection(sampler="leastsq")
    mcmc_opts = ReduceSection(sampler="mcmc", prayer_bead_shifts=0, mcmc_steps=max_steps)
    lsq_s, lsq = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        lsq = reduce_module.reduce_epoch(table, name, options=lsq_opts, seed=1, resources=resources)
        lsq_s.append(time.perf_counter() - t0)
    timer = TimedMcmc(fit_module.run_mcmc, move)
    original = fit_module.run_mcmc
    fit_module.run_mcmc = timer
    try:
        for _ in range(repeats):
            res = reduce_module.reduce_epoch(table, name, options=mcmc_opts, seed=1,
                                             resources=resources)
    finally:
        fit_module.run_mcmc = original
    mc = timer.result
    return {"method": name, "lsq_s": statistics.median(lsq_s),
            "mcmc_s": statistics.median(timer.seconds), "move": mc.move,
            "steps": mc.n_steps, "walkers": mc.n_walkers, "burn_in": mc.burn_in,
            "tau_max": float(np.max(mc.tau)), "n_over_tau": mc.n_over_tau,
            "converged": mc.converged, "acceptance": mc.acceptance,
            "depth_lsq": lsq.depth_ppm, "err_lsq": lsq.depth_err_ppm,
            "err_lsq_from": lsq.depth_err_method,
            "depth_mcmc": res.mcmc["depth_median_ppm"],   # the posterior median
            "err_mcmc": res.depth_err_mcmc_ppm, "n_points": res.n_points}


def print_row(r):
    print(f"| {r['method']} | {r['lsq_s']:.2f} | {r['mcmc_s']:.2f} | {r['move']} | {r['steps']} "
          f"| {r['walkers']} | {r['burn_in']} | {r['tau_max']:.1f} | {r['n_over_tau']:.0f} "
          f"| {r['acceptance']:.2f} | {r['depth_lsq']:.0f} +- {r['err_lsq']:.0f} ({r['err_lsq_from']}) "
          f"| {r['depth_mcmc']:.0f} +- {r['err_mcmc']:.0f} |", flush=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--methods", nargs="*", default=None)
    ap.add_argument("--epochs", nargs="*", default=None, choices=["sim", "real"],
                    help="default: both, the real one when ../shared/data/irac is present")
    ap.add_argument("--move", default="preferred", choices=["preferred", "de", "stretch"])
    ap.add_argument("--max-steps", type=int, default=20000)
    ap.add_argument("--real-table", type=Path, default=DEFAULT_CACHE)
    ap.add_argument("--refresh-real", action="store_true")
    args = ap.parse_args(argv)

    sys.path.insert(0, str(HERE))
    import bench_reduce

    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.decorrelate import available_methods

    methods = args.methods or list(available_methods())
    if args.epochs is None:
        args.epochs = ["sim"] + (["real"] if REAL.is_dir() else [])
    move = None if args.move == "preferred" else args.move
    print(f"one core; repeats {args.repeats} (medians); load average at start "
          f"{' '.join(f'{v:.2f}' for v in os.getloadavg())}; move: {args.move}; "
          f"step cap {args.max_steps}")
    with tempfile.TemporaryDirectory() as tmp:
        epochs = []
        if "sim" in args.epochs:
            bench_reduce.write_calibration(Path(tmp))
            epochs.append(("simulated (bench_reduce.py, 15,000 frames)",
                           bench_reduce.make_table(get_system("XO-3b"), simdir=tmp), None))
        if "real" in args.epochs:
            epochs.append(("real epoch 1 (../shared/data/irac/real_xo3_eclipse1)",
                           real_table(args.real_table, args.refresh_real), str(REAL_PMAP)))
        for label, table, pmap in epochs:
            print(f"\n{label}\n")
            print("| method | least squares with errors (s) | MCMC (s) | move | steps | walkers "
                  "| burn-in | tau_max | N/tau | acceptance | least squares depth (ppm) "
                  "| MCMC median +- half-width (ppm) |")
            print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
            for name in methods:
                resources = {"pmap": pmap} if pmap and name == "kr-pmap" else None
                print_row(bench_method(table, name, repeats=args.repeats,
                                       max_steps=args.max_steps, move=move,
                                       resources=resources))
    print(f"\nload average at the end {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
