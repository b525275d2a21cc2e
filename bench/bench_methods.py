"""Speed of the systematics methods: set-up time and predict() calls per second.

One synthetic epoch of 15,000 frames (a drifting, wobbling pointing track, a
7x7 stamp of a Gaussian PSF through an intra-pixel sensitivity, and a
calibration-star table of 200,000 frames for KR/Pmap). Every registered method
is built once (its parameter-independent set-up, timed) and then ``predict``
is called repeatedly with a slightly different eclipse curve each time, as a
fitter does. The reference is ``numpy.mean`` of 15,000 values in the same
process, so the ratio is comparable between machines.

Usage: ``python bench/bench_methods.py [--repeats 5] [--frames 15000]``
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _load_synthetic():
    """The test generator (tests/decorrelate/conftest.py), loaded as a plain module."""
    path = ROOT / "tests" / "decorrelate" / "conftest.py"
    spec = importlib.util.spec_from_file_location("_eb_decorrelate_synth", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def _rate(fn, *, min_time_s=0.3, repeats=5):
    """Median calls per second over ``repeats`` runs of at least ``min_time_s`` each."""
    rates = []
    for _ in range(repeats):
        n, t0 = 0, time.perf_counter()
        while True:
            fn(n)
            n += 1
            dt = time.perf_counter() - t0
            if dt >= min_time_s:
                break
        rates.append(n / dt)
    return float(np.median(rates))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--frames", type=int, default=15000)
    args = ap.parse_args(argv)

    from eclipsebench.decorrelate import available_methods, get_method

    synth = _load_synthetic()
    with tempfile.TemporaryDirectory() as tmp:
        synth.write_calibration_table(Path(tmp) / "calibration" / "pmap_calibration.fits")
        ep = synth.make_epoch(n_frames=args.frames, meta={"SIMDIR": tmp})
        time_bmjd = ep.data.time_bmjd
        curves = [synth.eclipse_curve(time_bmjd, ep.t_ecl_bmjd + 1e-4 * i, 1875.0 + i)
                  for i in range(16)]
        values = np.random.default_rng(0).random(args.frames)
        ref = _rate(lambda i: np.mean(values), repeats=args.repeats)
        print(f"frames: {args.frames}, repeats: {args.repeats} (medians)")
        print(f"{'reference np.mean':<22s} {ref:12.0f} calls/s")
        print(f"{'method':<22s} {'setup s':>8s} {'predict/s':>12s} {'ratio to ref':>13s} "
              f"{'ms/call':>8s}")
        for name in available_methods():
            cls = get_method(name)
            setups = []
            for _ in range(max(1, min(args.repeats, 3))):
                t0 = time.perf_counter()
                model = cls(ep.data)
                setups.append(time.perf_counter() - t0)
            theta = model.initial_params()
            rate = _rate(lambda i, m=model, th=theta: m.predict(curves[i % 16], th),
                         repeats=args.repeats)
            print(f"{name:<22s} {np.median(setups):8.3f} {rate:12.1f} {rate / ref:13.2e} "
                  f"{1e3 / rate:8.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
