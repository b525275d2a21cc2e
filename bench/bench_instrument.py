"""Benchmarks of the instrument kernels, each beside a numpy reference run in the same script.

Run from the project root::

    .venv/bin/python bench/bench_instrument.py [--repeat 3]

1. Pointing model: all 1 ms samples of a 9-hour epoch (32.4 million times,
   two axes) through ``PointingModel.offsets_grid`` in 64-frame cube chunks
   (128,512 samples); peak traced memory. Reference: drawing the same number
   of standard normals with numpy in the same chunks.
2. Fowler sampling: one 64-frame 32x32 cube of the 2 s subarray mode, the
   physical grouped kernel (FN Poisson draws per pixel), the literal per-tick
   kernel (n_max draws) and the iracsim2015 kernel. Reference: numpy drawing
   as many Poisson variates as the grouped kernel does.
3. PRF: ``render_taylor`` (13x13 stamps, value + 5 derivatives) for one epoch
   of frames (15,616) of the builtin PRF. Reference: numpy ``exp`` of the
   same number of stamp pixels (a Gaussian stamp).

Prints medians; the ratio to the reference is what counts.
"""

from __future__ import annotations

import argparse
import sys
import tracemalloc
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from _timing import median_seconds  # noqa: E402

from eclipsebench.detector import fowler as F  # noqa: E402
from eclipsebench.detector.constants import SUB_2S  # noqa: E402
from eclipsebench.instrument.pointing import PointingModel, draw_pointing_params  # noqa: E402
from eclipsebench.instrument.prf import BuiltinPRF  # noqa: E402

EPOCH_S = 9 * 3600.0
DT_S = 1e-3
CHUNK = 128_512


def bench_pointing(repeat):
    n_total = int(EPOCH_S / DT_S)

    def run():
        m = PointingModel(draw_pointing_params(np.random.default_rng(1)), duration_s=EPOCH_S,
                          dt_s=DT_S, rng=np.random.default_rng(2), aor_starts_s=(0.0, 1900.0))
        acc = 0.0
        for start in range(0, n_total, CHUNK):
            dx, dy = m.offsets_grid(start, min(CHUNK, n_total - start))
            acc += dx[0] + dy[0]
        return acc

    def ref():
        rng = np.random.default_rng(3)
        acc = 0.0
        for start in range(0, n_total, CHUNK):
            z = rng.standard_normal((2, min(CHUNK, n_total - start)))
            acc += z[0, 0]
        return acc

    t_model = median_seconds(run, repeat)
    t_ref = median_seconds(ref, repeat)
    tracemalloc.start()
    run()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return n_total, t_model, t_ref, peak


def bench_fowler(repeat):
    mode = SUB_2S
    shape = (64, 32, 32)
    q = np.full((mode.n_max,) + shape, 2.0)
    groups = F.group_charges(np.full((mode.n_max, 1), 2.0), mode)
    groups = np.broadcast_to(groups.reshape(mode.fowler, 1, 1, 1), (mode.fowler,) + shape).copy()
    reads = F.read_charges(np.full((mode.n_max, 1), 2.0), mode)
    reads = np.broadcast_to(reads.reshape(2 * mode.fowler, 1, 1, 1),
                            (2 * mode.fowler,) + shape).copy()
    rng = np.random.default_rng(4)
    t_grouped = median_seconds(lambda: F.fowler_sample(groups, mode, rng, 9.4, grouped=True), repeat)
    t_ticks = median_seconds(lambda: F.fowler_sample_ticks(q, mode, rng, 9.4), repeat)
    t_irac = median_seconds(lambda: F.fowler_sample_iracsim2015(reads, mode, rng, 16.8), repeat)
    t_ref = median_seconds(lambda: rng.poisson(groups), repeat)
    return int(groups.size), t_grouped, t_ticks, t_irac, t_ref


def bench_prf(repeat):
    prf = BuiltinPRF()
    n = 15_616
    rng = np.random.default_rng(5)
    x = 15.15 + 0.1 * rng.standard_normal(n)
    y = 15.2 + 0.1 * rng.standard_normal(n)
    prf.render_taylor(x[:4], y[:4])  # compile
    t_prf = median_seconds(lambda: prf.render_taylor(x, y, half=6), repeat)
    g = np.arange(-6, 7, dtype=float)

    def ref():
        u = (g[None, :] - (x - 15)[:, None]) ** 2
        v = (g[None, :] - (y - 15)[:, None]) ** 2
        return np.exp(-0.5 * (u[:, None, :] + v[:, :, None]))

    t_ref = median_seconds(ref, repeat)
    return n, t_prf, t_ref


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="instrument kernel benchmarks")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    n, t_m, t_r, peak = bench_pointing(args.repeat)
    print(f"pointing: {n:,} samples x 2 axes (9 h at 1 ms) in {t_m:.2f} s "
          f"({n / t_m / 1e6:.1f} M samples/s); reference numpy normals {t_r:.2f} s; "
          f"ratio {t_m / t_r:.2f}; peak traced memory {peak / 2**20:.0f} MiB")
    n, t_g, t_t, t_i, t_r = bench_fowler(args.repeat)
    print(f"fowler (one 64x32x32 cube, FN=8 WT=184): grouped physical {t_g * 1e3:.1f} ms, "
          f"per-tick physical {t_t * 1e3:.1f} ms, iracsim2015 {t_i * 1e3:.1f} ms; "
          f"reference numpy poisson of the same {n:,} variates {t_r * 1e3:.1f} ms; "
          f"ratios {t_g / t_r:.2f} / {t_t / t_r:.2f} / {t_i / t_r:.2f}")
    n, t_p, t_r = bench_prf(args.repeat)
    print(f"prf render_taylor: {n:,} frames x 13x13 x 6 in {t_p:.2f} s; reference numpy "
          f"Gaussian stamps {t_r:.2f} s; ratio {t_p / t_r:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
