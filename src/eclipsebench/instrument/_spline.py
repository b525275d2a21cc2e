"""Cubic B-spline evaluation of a tabulated PRF, with derivatives (numba kernels).

A table ``T[j, i]`` samples a function ``C(dy, dx)`` at
``dx = (i - cx) / os``, ``dy = (j - cy) / os``. :func:`spline_coefficients`
turns it into cubic B-spline coefficients once; the kernels then evaluate the
image of a star at ``(x, y)`` as ``V[py, px] = C(py - y, px - x)`` on stamps
of pixels, and the derivatives with respect to the star position
(``dV/dx = -os dC/dtx``, ``d2V/dx2 = os^2 d2C/dtx2``, ...).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy import ndimage

PAD = 4
PAD_F = float(PAD)


def spline_coefficients(table: np.ndarray) -> np.ndarray:
    """Zero-pad ``table`` by :data:`PAD` samples and prefilter it for cubic B-splines."""
    padded = np.pad(np.asarray(table, dtype=float), PAD)
    return ndimage.spline_filter(padded, order=3, mode="grid-constant")


@njit(cache=True, inline="always")
def _weights(f, w, dw, d2w):
    g = 1.0 - f
    w[0] = g * g * g / 6.0
    w[1] = (3.0 * f * f * f - 6.0 * f * f + 4.0) / 6.0
    w[2] = (-3.0 * f * f * f + 3.0 * f * f + 3.0 * f + 1.0) / 6.0
    w[3] = f * f * f / 6.0
    dw[0] = -0.5 * g * g
    dw[1] = 1.5 * f * f - 2.0 * f
    dw[2] = -1.5 * f * f + f + 0.5
    dw[3] = 0.5 * f * f
    d2w[0] = g
    d2w[1] = 3.0 * f - 2.0
    d2w[2] = -3.0 * f + 1.0
    d2w[3] = f


@njit(cache=True, fastmath=True)
def stamps_kernel(coef, cx, cy, os, xs, ys, x0, y0, ny, nx, order, out):
    """Evaluate stamps. ``out`` has shape (n, 6 if order == 2 else 3 if order == 1 else 1, ny, nx):
    value, d/dx, d/dy, d2/dx2, d2/dxdy, d2/dy2 with respect to the star position.

    ``cx, cy`` are table-index coordinates of offset 0 in the *unpadded* table.
    Pixel ``(x0[n] + b, y0[n] + a)`` goes to ``out[n, :, a, b]``.
    """
    n = xs.shape[0]
    ty_max = coef.shape[0] - 2
    tx_max = coef.shape[1] - 2
    wx = np.empty((nx, 4))
    dwx = np.empty((nx, 4))
    d2wx = np.empty((nx, 4))
    ixs = np.empty(nx, np.int64)
    okx = np.empty(nx, np.bool_)
    wy = np.empty(4)
    dwy = np.empty(4)
    d2wy = np.empty(4)
    nq = out.shape[1]
    for k in range(n):
        for b in range(nx):
            tx = cx + PAD_F + os * (x0[k] + b - xs[k])
            okx[b] = tx >= 1.0 and tx < tx_max
            if okx[b]:
                ix = int(np.floor(tx))
                ixs[b] = ix - 1
                _weights(tx - ix, wx[b], dwx[b], d2wx[b])
        for a in range(ny):
            ty = cy + PAD_F + os * (y0[k] + a - ys[k])
            if ty < 1.0 or ty >= ty_max:
                for q in range(nq):
                    for b in range(nx):
                        out[k, q, a, b] = 0.0
                continue
            iy = int(np.floor(ty))
            _weights(ty - iy, wy, dwy, d2wy)
            for b in range(nx):
                if not okx[b]:
                    for q in range(nq):
                        out[k, q, a, b] = 0.0
                    continue
                i0 = ixs[b]
                v = 0.0
                vx = 0.0
                vy = 0.0
                vxx = 0.0
                vxy = 0.0
                vyy = 0.0
                for jj in range(4):
                    row = iy - 1 + jj
                    c0 = coef[row, i0]
                    c1 = coef[row, i0 + 1]
                    c2 = coef[row, i0 + 2]
                    c3 = coef[row, i0 + 3]
                    s0 = wx[b, 0] * c0 + wx[b, 1] * c1 + wx[b, 2] * c2 + wx[b, 3] * c3
                    v += wy[jj] * s0
                    if order >= 1:
                        s1 = dwx[b, 0] * c0 + dwx[b, 1] * c1 + dwx[b, 2] * c2 + dwx[b, 3] * c3
                        vx += wy[jj] * s1
                        vy += dwy[jj] * s0
                        if order >= 2:
                            s2 = (d2wx[b, 0] * c0 + d2wx[b, 1] * c1 + d2wx[b, 2] * c2
                                  + d2wx[b, 3] * c3)
                            vxx += wy[jj] * s2
                            vxy += dwy[jj] * s1
                            vyy += d2wy[jj] * s0
                out[k, 0, a, b] = v
                if order >= 1:
                    out[k, 1, a, b] = -os * vx
                    out[k, 2, a, b] = -os * vy
                if order >= 2:
                    out[k, 3, a, b] = os * os * vxx
                    out[k, 4, a, b] = os * os * vxy
                    out[k, 5, a, b] = os * os * vyy
