"""Depth recovery of every registered method on noise-free simulated epochs (issue 13).

Epochs of the default challenge (seed 2015) simulated without photon, read
or background noise (``simulation.noise_model = "none"``): the pointing
(Table 5 draws, jitter, drift), the intra-pixel gain and the eclipse are
kept. Their photometry is reduced by every registered method with the
controlled profile's defaults but least squares (no MCMC, no prayer bead:
with no noise there is nothing to sample), KR/Pmap with the simulated
calibration set, the Pre AOR out of the fit by the settling rule. Printed:
depth minus truth per method and epoch (truth from the simulation's
``truth.ecsv``; the quadratic phase model's own bias on this light curve is
-1.8 ppm, Section 4.2), the largest miss over the epochs, the frames of
the first epoch fitted and dropped by reason, and the median wall seconds
of a fit.

Usage: ``python bench/bench_noise_free.py [--epochs N] [--workdir DIR]
[--methods bliss pld] [--option kr-data.use_noise_pixels=true ...]
[--set 'simulation.pointing_ranges=["a_j_px=C:0"]' ...]`` (``--workdir``
keeps the simulation and photometry for a second run, so give each
``--set`` its own workdir; a workdir made with fewer epochs is simulated
again; ``--option`` sets a method's option, the value read as TOML; ``--set``
changes the simulation's configuration beside the noise model).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

WITHIN_PPM = 20.0


def prepare(workdir: Path, epochs: int,
            overrides: tuple[str, ...] = ()) -> tuple[list[Path], list[float]]:
    """Simulate and measure the noise-free epochs once; their tables and true depths."""
    from astropy.table import Table

    import eclipsebench as eb

    tables = [workdir / "phot" / f"epoch_{e:02d}.fits" for e in range(1, epochs + 1)]
    truth_file = workdir / "sim" / "truth.ecsv"
    if not (truth_file.is_file() and len(Table.read(truth_file)) >= epochs
            and all(t.is_file() for t in tables)):
        cfg = eb.load_config(overrides=["simulation.noise_model=\"none\"", *overrides])
        eb.simulate(workdir / "sim", config=cfg, seed=2015, epochs=epochs, workers=1)
        eb.measure(workdir / "sim", workdir / "phot", config=cfg)
    truth = Table.read(truth_file)
    depth_by_epoch = {int(e): float(d) for e, d in zip(truth["epoch"], truth["depth_ppm"],
                                                       strict=True)}
    return tables, [depth_by_epoch[e] for e in range(1, epochs + 1)]


def method_options(pairs: list[str]) -> dict[str, dict]:
    """``["kr-data.use_noise_pixels=true"]`` -> ``{"kr-data": {"use_noise_pixels": True}}``."""
    import tomllib

    out: dict[str, dict] = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        method, dot, name = key.partition(".")
        if not (sep and dot and method and name):
            raise SystemExit(f"--option {pair!r}: expected METHOD.OPTION=VALUE")
        out.setdefault(method, {})[name] = tomllib.loads(f"v = {value}")["v"]
    return out


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--epochs", type=int, default=1)
    parser.add_argument("--workdir", type=Path, default=None)
    parser.add_argument("--methods", nargs="*", default=None)
    parser.add_argument("--option", action="append", default=[])
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    args = parser.parse_args(argv)
    options = method_options(args.option)
    if not 1 <= args.epochs <= 10:
        parser.error("--epochs: expected 1-10 (the default challenge's epochs)")
    import numpy as np

    import eclipsebench as eb

    with tempfile.TemporaryDirectory() as tmp:
        workdir = args.workdir or Path(tmp)
        workdir.mkdir(parents=True, exist_ok=True)
        tables, truths = prepare(workdir, args.epochs, tuple(args.overrides))
        heads = " | ".join(f"epoch {e}" for e in range(1, args.epochs + 1))
        print(f"| method | depth minus truth (ppm): {heads} | largest miss (ppm) | "
              "frames fitted (epoch 1) | dropped (epoch 1) | median seconds |")
        print("| --- " * (args.epochs + 5) + "|")
        misses = []
        for method in args.methods or eb.methods():
            diffs, seconds, first = [], [], None
            for table, truth in zip(tables, truths, strict=True):
                start = time.perf_counter()
                result = eb.reduce(table, method, sampler="leastsq", prayer_bead_shifts=0,
                                   options=options.get(method))
                seconds.append(time.perf_counter() - start)
                diffs.append(result.depth_ppm - truth)
                first = first or result
            dropped = ", ".join(f"{k.replace('_', ' ')} {v}"
                                for k, v in first.n_frames_dropped.items() if v)
            worst = max(diffs, key=abs)
            cells = " | ".join(f"{d:+.1f}" for d in diffs)
            label = method + "".join(f", {k}={v}" for k, v in options.get(method, {}).items())
            print(f"| {label} | {cells} | {worst:+.1f} | {first.n_frames} | {dropped} | "
                  f"{np.median(seconds):.1f} |", flush=True)
            if abs(worst) > WITHIN_PPM:
                misses.append(method)
        print(f"\nwithin {WITHIN_PPM:.0f} ppm on every epoch: all but {', '.join(misses)}"
              if misses else f"\nwithin {WITHIN_PPM:.0f} ppm on every epoch: every method")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
