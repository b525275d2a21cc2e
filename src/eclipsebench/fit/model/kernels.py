"""The compiled kernels of the eclipse model's batch (``AstroModel.batch``).

:func:`_astro_rows` evaluates the eclipse model of many parameter rows in one
compiled pass over the frames; :func:`_interp_table` is :func:`numpy.interp`
of the physical eclipse shape's table with an O(1) search. Both repeat the
expressions of the numpy code, in the same order, so the values are
identical (the eclipse model of :mod:`eclipsebench.fit.model` calls them; the names
keep their leading underscore: they are that model's internals, not an API).
"""

from __future__ import annotations

import numpy as np

from ...jit import lazy_njit


def _search_table(xp: np.ndarray, fp: np.ndarray) -> tuple:
    """``(xp, fp, slopes, start, step, index)`` for :func:`_interp_table`.

    ``index[k]`` is the last ``j`` with ``xp[j] <= start + k * step`` on a
    uniform grid whose step is the smallest spacing of ``xp`` (so a cell
    holds at most one table point); ``slopes`` are :func:`numpy.interp`'s.
    """
    step = float(np.min(np.diff(xp)))
    cells = np.arange(int(np.ceil((xp[-1] - xp[0]) / step)) + 2)
    index = np.searchsorted(xp, xp[0] + cells * step, side="right") - 1
    slopes = (fp[1:] - fp[:-1]) / (xp[1:] - xp[:-1])
    return (np.ascontiguousarray(xp), np.ascontiguousarray(fp), slopes, float(xp[0]), step,
            np.clip(index, 0, len(xp) - 2).astype(np.int64))


#: Placeholder table arguments of :func:`_astro_rows` for the box eclipse.
_NO_TABLE = (np.zeros(2), np.ones(2), np.zeros(1), 0.0, 1.0, np.zeros(1, dtype=np.int64))


@lazy_njit(cache=True)
def _astro_rows(time, thetas, phase_code, ramp_at, t_start, box, box_half, exposure,
                xp, fp, slopes, start, step, index, ordered):  # pragma: no cover - compiled
    """``AstroModel.__call__`` of every row of ``thetas``, one compiled pass per row.

    A compiled copy of :mod:`eclipsebench.astro.phase_curves` (flat, linear,
    quadratic; held equal by a test). The expressions are those of :meth:`AstroModel.planet`,
    :func:`box_visible_fraction` (``box``) or :func:`_interp_table` (the
    physical shape's table), and :meth:`AstroModel.ramp_factor` (linear ramp
    when ``ramp_at >= 0``), in the same order, so each value is the same.

    With the physical shape, times in order (``ordered``: non-decreasing, so
    the offsets ``time - t_ecl`` are too) and a finite eclipse time, a row is
    two passes: ``1 + p`` (the planet wholly visible, ``1.0 * p`` is ``p``) at
    every frame, a loop without branches that the compiler vectorises, then
    the frames inside the table, found by bisection, get the table's value.
    There the first guess of ``j`` is the offset times the table's mean
    density of points (the shape's table is a uniform grid in geometric time,
    so nearly uniform in ``dt``: the guess is right or one point off) and the
    search that follows corrects it, so each ``j``, and each value, is the
    same: 0.27 ms instead of 0.45 ms for 8 rows of 15,600 frames, a third of
    them inside the 2.8-hour table (the MCMC's step in ``eclipsebench run``).
    Other times, the box or a non-finite eclipse time take a second loop with
    the table's test at every frame. Either way the planet's ``p`` is computed
    once per frame, in the first pass, and read back.
    """
    m, n = thetas.shape[0], len(time)
    out = np.empty((m, n))
    planet = np.empty(n)   # a row's p = depth + phase terms, at every frame
    last = len(xp) - 1
    cells = len(index) - 1
    for i in range(m):
        depth, t_ecl = thetas[i, 0], thetas[i, 1]
        c0 = thetas[i, 2] if phase_code >= 1 else 0.0
        c1 = thetas[i, 3] if phase_code == 2 else 0.0
        slope = thetas[i, ramp_at] if ramp_at >= 0 else 0.0
        for k in range(n):   # p and 1 + p everywhere: a loop the compiler vectorises
            dt = time[k] - t_ecl
            if phase_code == 0:
                p = depth
            elif phase_code == 1:
                p = depth + c0 * dt
            else:
                p = depth + dt * (c0 + c1 * dt)
            planet[k] = p
            out[i, k] = 1.0 + p
        if ordered and not box and abs(t_ecl) < np.inf:   # then the table's frames
            per_point = last / (xp[last] - xp[0])   # table points per day, on average
            lo, hi = 0, n   # k0: the first frame with time - t_ecl >= xp[0]
            while lo < hi:
                mid = (lo + hi) // 2
                if time[mid] - t_ecl < xp[0]:
                    lo = mid + 1
                else:
                    hi = mid
            k0 = lo
            hi = n          # k1: the first frame with time - t_ecl > xp[last]
            while lo < hi:
                mid = (lo + hi) // 2
                if time[mid] - t_ecl <= xp[last]:
                    lo = mid + 1
                else:
                    hi = mid
            for k in range(k0, lo):
                dt = time[k] - t_ecl
                p = planet[k]
                if dt == xp[last]:
                    v = fp[last]
                else:
                    j = min(max(int((dt - xp[0]) * per_point), 0), last - 1)
                    while j > 0 and xp[j] > dt:
                        j -= 1
                    while j < last - 1 and xp[j + 1] <= dt:
                        j += 1
                    v = fp[j] if xp[j] == dt else slopes[j] * (dt - xp[j]) + fp[j]
                out[i, k] = 1.0 + v * p
            if ramp_at >= 0:   # the same product, stored and multiplied
                for k in range(n):
                    out[i, k] = out[i, k] * (1.0 + slope * (time[k] - t_start))
            continue
        for k in range(n):
            dt = time[k] - t_ecl
            p = planet[k]
            if box:
                v = min(max((abs(dt) - box_half) / exposure + 0.5, 0.0), 1.0)
            elif dt < xp[0] or dt > xp[last]:
                v = 1.0
            elif dt == xp[last]:
                v = fp[last]
            else:   # j: the last table point at or below dt (uniform index, then corrected)
                j = index[min(max(int((dt - start) / step), 0), cells)]
                while j > 0 and xp[j] > dt:
                    j -= 1
                while j < last - 1 and xp[j + 1] <= dt:
                    j += 1
                v = fp[j] if xp[j] == dt else slopes[j] * (dt - xp[j]) + fp[j]
            f = 1.0 + v * p
            if ramp_at >= 0:
                f = f * (1.0 + slope * (time[k] - t_start))
            out[i, k] = f
    return out


def _interp_table(x: np.ndarray, table: tuple) -> np.ndarray:
    """``numpy.interp(x, xp, fp, left=1, right=1)`` of a 2-D ``x``, with an O(1) search.

    Same formula as numpy's (``slope[j] * (x - xp[j]) + fp[j]``, ``fp[j]``
    where ``x == xp[j]``, ``fp[-1]`` at the last point), so the values are
    identical; ``j`` comes from the uniform index of :func:`_search_table`.
    """
    xp, fp, slopes, start, step, index = table
    return _interp_rows(np.ascontiguousarray(x, dtype=float), xp, fp, slopes, start, step, index)


@lazy_njit(cache=True)
def _interp_rows(x, xp, fp, slopes, start, step, index):  # pragma: no cover - compiled
    m, n = x.shape
    out = np.empty((m, n))
    last = len(xp) - 1
    cells = len(index) - 1
    for i in range(m):
        for k in range(n):
            xv = x[i, k]
            if xv < xp[0] or xv > xp[last]:
                out[i, k] = 1.0
            elif xv == xp[last]:
                out[i, k] = fp[last]
            else:
                j = index[min(max(int((xv - start) / step), 0), cells)]
                while j > 0 and xp[j] > xv:
                    j -= 1
                while j < last - 1 and xp[j + 1] <= xv:
                    j += 1
                out[i, k] = fp[j] if xp[j] == xv else slopes[j] * (xv - xp[j]) + fp[j]
    return out
