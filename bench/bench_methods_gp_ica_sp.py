"""Speed of ``reduce_epoch`` for the GP, ICA and SP(K2) methods, with uncertainties.

The epoch is the one of ``bench/bench_reduce.py`` (15,000 frames of XO-3b,
8.8 h, catalogue eclipse, quadratic phase curve, drifting and wobbling
pointing through a smooth intra-pixel gain, 5x5 Gaussian-PSF stamps, 0.3 %
white noise per frame), built by that script's functions so the numbers sit
beside its table. Each method is fitted with the defaults (least squares,
Jacobian x beta_red, 16-shift prayer bead, ICA separation error); ``--mcmc``
adds emcee (32 walkers, up to 2000 steps, autocorrelation check). The
reference, timed in the same process, is one batman secondary-eclipse light
curve of the same frames (the ratio is comparable between machines).
Everything runs on one core (BLAS, OpenMP and numba threads set to 1).

``--recovery`` also fits noiseless copies with and without the gain and
prints depth minus truth (physical eclipse shape for all three methods; the
SP(K2) default box shape separately).

Usage: ``python bench/bench_methods_gp_ica_sp.py [--repeats 3] [--mcmc] [--recovery]``
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

METHODS = ("gp", "ica", "segpoly")


def _bench_reduce():
    path = Path(__file__).resolve().with_name("bench_reduce.py")
    spec = importlib.util.spec_from_file_location("_eb_bench_reduce", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--frames", type=int, default=15000)
    ap.add_argument("--mcmc", action="store_true", help="also time least squares + emcee")
    ap.add_argument("--recovery", action="store_true", help="noiseless depth recovery")
    ap.add_argument("--methods", nargs="*", default=list(METHODS))
    args = ap.parse_args(argv)

    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.config.reduce import ReduceSection
    from eclipsebench.fit.reduce import reduce_epoch

    br = _bench_reduce()
    system = get_system("XO-3b")
    truth_ppm = br.DEPTH * 1e6
    with tempfile.TemporaryDirectory() as tmp:
        table = br.make_table(system, n_frames=args.frames, simdir=tmp)
        ref = br.batman_reference(system, np.asarray(table["time_bmjd"]), args.repeats)
        print(f"frames: {args.frames}, repeats: {args.repeats} (medians), one core")
        print(f"reference: one batman secondary-eclipse light curve = {ref * 1e3:.3f} ms")
        print(f"{'method':<8s} {'sampler':<8s} {'time s':>8s} {'x batman':>10s} "
              f"{'depth-true':>11s} {'err ppm':>8s} {'err from':>22s} {'beta':>6s} {'n':>6s}")
        samplers = ["leastsq"] + (["mcmc"] if args.mcmc else [])
        for name in args.methods:
            for sampler in samplers:
                opts = ReduceSection(sampler=sampler)
                times, res = [], None
                for _ in range(args.repeats if sampler == "leastsq" else 1):
                    t0 = time.perf_counter()
                    res = reduce_epoch(table, name, options=opts, seed=1)
                    times.append(time.perf_counter() - t0)
                dt = float(np.median(times))
                extra = ""
                if res.depth_err_separation_ppm:
                    extra = f"  (separation {res.depth_err_separation_ppm:.1f} ppm)"
                print(f"{name:<8s} {sampler:<8s} {dt:8.2f} {dt / ref:10.3g} "
                      f"{res.depth_ppm - truth_ppm:11.1f} {res.depth_err_ppm:8.1f} "
                      f"{res.depth_err_method:>22s} {res.beta_red:6.2f} {res.n_frames:6d}{extra}",
                      flush=True)
        if args.recovery:
            print("\nnoiseless recovery (quadratic phase, leastsq, no prayer bead): "
                  "depth - truth, ppm")
            sys_tab = br.make_table(system, n_frames=args.frames, noise=0.0, simdir=tmp)
            flat_tab = br.make_table(system, n_frames=args.frames, noise=0.0,
                                     systematics=False, simdir=tmp)
            for name in args.methods:
                shapes = ["physical"] + (["auto"] if name == "segpoly" else [])
                for shape in shapes:
                    opts = ReduceSection(prayer_bead_shifts=0, eclipse_shape=shape)
                    a = reduce_epoch(sys_tab, name, options=opts).depth_ppm - truth_ppm
                    b = reduce_epoch(flat_tab, name, options=opts).depth_ppm - truth_ppm
                    label = f"{name} ({'box' if shape == 'auto' else shape})"
                    print(f"{label:<20s} with systematics {a:8.2f}   without {b:8.2f}",
                          flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
