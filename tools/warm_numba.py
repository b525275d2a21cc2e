"""Compile eclipsebench's numba kernels once, after installing, into numba's cache (issue 40).

Every kernel of the package is ``@njit(cache=True)``: compiled at its first
call and then kept beside its module (``__pycache__/*.nbi``, ``*.nbc``), so
later processes load it instead of compiling it. Right after an install the
cache is empty, and the first ``eclipsebench run``, ``photometry`` or
``reduce`` would compile the kernels it meets (in each Dask worker at once).
This script meets them all once, on a tiny observation in a temporary
folder: simulate one short epoch (with its KR/Pmap calibration set), measure
it, reduce it with every registered method by least squares and with BLISS
and KR/Data by MCMC. The Makefile's install step runs it; it writes nothing else.

Usage: ``python tools/warm_numba.py`` (prints the seconds it took).
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

#: One short epoch with an eclipse (the tests' small observation: 80 cubes of 16 frames).
SETS = ["observation.pre_cubes=1", "observation.frames_per_cube=16",
        "observation.main_cubes=80", "observation.cube_interval_s=220.0",
        "simulation.subsamples=2", "simulation.calibration_frames=4000"]


def main() -> int:
    t0 = time.perf_counter()
    import eclipsebench as eb
    from eclipsebench.astro.catalogue import system_for
    from eclipsebench.astro.orbit import eclipse_time_bmjd
    from eclipsebench.errors import InputError
    from eclipsebench.simulation.plan import JD_OFFSET_BMJD

    t_ecl = eclipse_time_bmjd(system_for(eb.load_config(overrides=SETS).system), 57205.8)
    cfg = eb.load_config(overrides=SETS + [
        "challenge.epochs=1", f"observation.start_times_jd=[{t_ecl - 0.12 - JD_OFFSET_BMJD:.6f}]"])
    with tempfile.TemporaryDirectory() as tmp:
        eb.simulate(Path(tmp) / "sim", config=cfg, workers=1)
        table = eb.measure(Path(tmp) / "sim", Path(tmp) / "phot", config=cfg)[0]
        for method in eb.methods():
            try:
                eb.reduce(table, method, config=cfg, sampler="leastsq", prayer_bead_shifts=0)
            except InputError:   # KR/Pmap: too few calibration frames here; no kernel of its own
                pass
        for method in ("bliss", "kr-data"):    # the kernels only their MCMC walkers meet
            eb.reduce(table, method, config=cfg, sampler="mcmc", prayer_bead_shifts=2)
    print(f"numba kernels compiled and cached in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
