"""Compile eclipsebench's numba kernels once, after installing, into numba's cache (issue 40).

Every kernel of the package is ``@njit(cache=True)``: compiled at its first
call and then kept beside its module (``__pycache__/*.nbi``, ``*.nbc``), so
later processes load it instead of compiling it. Right after an install the
cache is empty, and the first ``eclipsebench run``, ``photometry`` or
``reduce`` would compile the kernels it meets (in each Dask worker at once).
This script meets them all once, on a tiny observation in a temporary
folder: simulate one short epoch (with its KR/Pmap calibration set), measure
it, reduce it with every registered method by least squares and with BLISS
and KR/Data by MCMC, render and measure one ``trust`` twin of it, and call the
public photometry estimators (:mod:`eclipsebench.photometry.estimators`,
:mod:`eclipsebench.photometry.overlap`) that the pipeline's fused kernel does
not. The Makefile's install step runs it; it writes nothing else.

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
        warm_trust_twin(table)
    warm_estimators()
    warm_eclipse_table()
    print(f"numba kernels compiled and cached in {time.perf_counter() - t0:.0f} s")
    return 0


def warm_trust_twin(table) -> None:
    """One twin of ``table`` with motion within its exposures: the twins' own kernels (the
    motion's tick moments, the windowed rendering)."""
    import numpy as np

    from eclipsebench.trust.observation import observation_from_table
    from eclipsebench.trust.recipe import photometry_options
    from eclipsebench.trust.twin import make_recipe, twin_table

    obs = observation_from_table(table, "the warm-up's table")
    options = photometry_options(obs)
    recipe = make_recipe(obs, np.ones(obs.n_frames), radius_px=options.radius_px,
                         motion_peak_px=0.1)
    twin_table(recipe, options, seed=0, twin=1)


def warm_estimators() -> None:
    """The public estimators, each its own compiled stack (float64 frames, as they convert)."""
    import numpy as np

    from eclipsebench.photometry import estimators
    from eclipsebench.photometry.overlap import circle_overlap_grid, pixel_overlap

    frames = np.random.default_rng(0).normal(100.0, 1.0, (4, 32, 32))
    frames[:, 15:18, 15:18] += 1000.0
    estimators.brightest_pixel(frames)
    x, y = estimators.centroid_col(frames)[:2]
    estimators.annulus_background(frames, x, y)
    estimators.aperture_sums(frames, x, y, [2.0, 3.0])
    estimators.centroid_gauss(frames)
    estimators.centroid_lsq_asym(frames)
    circle_overlap_grid((21, 21), 10.3, 9.8, 3.0)
    pixel_overlap(-0.5, 0.5, -0.5, 0.5, 1.0)



def warm_eclipse_table() -> None:
    """The physical eclipse shape's table at times other than the data's (a binned fit's)."""
    import numpy as np

    from eclipsebench.fit.model.kernels import _interp_table, _search_table

    xp = np.linspace(-0.1, 0.1, 9)
    _interp_table(np.zeros((2, 3)), _search_table(xp, np.abs(xp)))


if __name__ == "__main__":
    sys.exit(main())
