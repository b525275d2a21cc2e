"""Speed of L(t): 10^6 samples against a bare batman call on the same times.

Run: ``python bench/bench_lightcurve.py`` (also part of ``make bench``).
"""

from __future__ import annotations

import time

import batman
import numpy as np
from _timing import median_seconds

from eclipsebench.astro.bias import epoch_times
from eclipsebench.astro.catalogue import get_system
from eclipsebench.astro.eclipse import EclipseShape
from eclipsebench.astro.lightcurve import light_curve_function

N = 1_000_000
REPEAT = 7


def median_time(fn, repeat=REPEAT):
    return median_seconds(fn, repeat, warmup=True)


def main() -> None:
    s = get_system("XO-3b")
    light_curve_function(s, n_time=64)  # numba compile / cache load outside the timing
    t0 = time.perf_counter()
    lc = light_curve_function(s)
    build = time.perf_counter() - t0
    # 10^6 samples spanning two orbits (both eclipses and transits inside)
    t = 57234.0 + np.linspace(0.0, 2 * s.period_days, N)
    ours = median_time(lambda: lc(t))

    p = batman.TransitParams()
    p.t0, p.t_secondary, p.per, p.rp, p.a = 57234.5, 57234.5, s.period_days, s.rp_rs, s.a_rs
    p.inc, p.ecc, p.w, p.fp = s.inc_deg, s.ecc, s.omega_deg, 1875e-6
    p.u, p.limb_dark = [], "uniform"
    m_sec = batman.TransitModel(p, t, transittype="secondary")
    bat_sec = median_time(lambda: m_sec.light_curve(p))
    bat_sec_geom = median_time(
        lambda: batman.TransitModel(p, t, transittype="secondary").light_curve(p))
    q = batman.TransitParams()
    for k in ("t0", "per", "rp", "a", "inc", "ecc", "w"):
        setattr(q, k, getattr(p, k))
    q.u, q.limb_dark = list(s.ld_quadratic), "quadratic"
    m_tr = batman.TransitModel(q, t)
    bat_tr = median_time(lambda: m_tr.light_curve(q))

    frames = epoch_times()
    shape = EclipseShape(frames, s)
    t_ecl = lc.t_eclipse_bmjd
    per_call = median_time(lambda: [shape.visible_fraction(t_ecl + 1e-6 * k) for k in range(100)])

    print(f"light curve build (thermal model, tables), XO-3b challenge: {build:.2f} s")
    print(f"L(t), 10^6 samples:                         {ours * 1e3:7.1f} ms  (goal < 500 ms)")
    print(f"bare batman secondary, geometry cached:     {bat_sec * 1e3:7.1f} ms  "
          f"(ratio {ours / bat_sec:.2f})")
    print(f"bare batman secondary incl. geometry:       {bat_sec_geom * 1e3:7.1f} ms  "
          f"(ratio {ours / bat_sec_geom:.2f})")
    print(f"bare batman quadratic transit, same times:  {bat_tr * 1e3:7.1f} ms  "
          f"(ratio {ours / bat_tr:.2f})")
    print(f"EclipseShape.visible_fraction, {frames.size} frames: {per_call / 100 * 1e3:.3f} ms "
          "per call (fit inner loop)")


if __name__ == "__main__":
    main()
