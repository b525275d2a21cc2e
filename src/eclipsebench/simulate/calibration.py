"""The calibration-star data set for KR/Pmap (paper Appendix B.4, the warm "pmap" set).

A non-variable star observed in many short pointings spread over the
sweet-spot pixel with 0.1 s subarray frames (FN = 2, WT = 6, 0.01 s ticks),
through the same PRF, intra-pixel gain and Fowler noise as the challenge
(about 400,000 measurements by default, ``simulation.calibration_frames``).
Each measurement is reduced as the paper's photometry does: background from
the 3-7 px annulus, center-of-light centroid over 7x7 pixels (Eqs.
``x_centroid``/``y_centroid``), noise pixels over the same box (Eq.
``noise_pixels``), and a 2.25 px aperture. The result,
``DIR/calibration/pmap_calibration.fits``, has columns ``x``, ``y``,
``noise_pixels``, ``flux``, ``flux_err`` (electrons) plus the true position
and the background.

Speed: only an 11x11 stamp around the star is simulated (the annulus is the
part of 3-7 px that lies inside it, radii 3 to ~5.4 px); the photometry here
is a small vectorised numpy version of the photometry stage's (to be unified
with :mod:`eclipsebench.photometry` later).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..config import Config
from ..instrument.constants import SUB_0P1S, ReadoutMode
from ..instrument.fowler import fowler_weights
from ..io.atomic import atomic_path
from ..seeding import rng
from .render import fowler_uniform
from .star import make_star_imager, prf_label

__all__ = ["write_calibration_set", "write_calibration_table", "simulate_calibration",
           "calibration_chunk", "concat_chunks", "n_chunks", "measure_stamps",
           "aperture_weight_table", "CHUNK_FRAMES", "STAMP_HALF", "FRAMES_PER_POINTING"]

CHUNK_FRAMES = 16384
FRAMES_PER_POINTING = 64
STAMP_HALF = 5
BOX_HALF = 3
JITTER_PX = 0.01
CALIBRATION_FLUX_E = 40000.0


def aperture_weight_table(radius_px: float, half: int = BOX_HALF, step_px: float = 0.01
                          ) -> tuple[np.ndarray, float]:
    """Exact pixel overlaps of a circle on a grid of centre offsets, for interpolation.

    Returns ``(table, step)`` with ``table[iy, ix]`` the (2 half + 1)^2 overlap
    weights of a circle of ``radius_px`` centred at offset
    ``(-0.5 + ix step, -0.5 + iy step)`` from the box's central pixel.
    """
    from photutils.geometry import circular_overlap_grid

    n_off = int(round(1.0 / step_px)) + 1
    offs = -0.5 + step_px * np.arange(n_off)
    size = 2 * half + 1
    table = np.empty((n_off, n_off, size, size))
    for iy, oy in enumerate(offs):
        for ix, ox in enumerate(offs):
            table[iy, ix] = circular_overlap_grid(-half - 0.5 - ox, half + 0.5 - ox,
                                                  -half - 0.5 - oy, half + 0.5 - oy,
                                                  size, size, radius_px, 1, 1)
    return table, step_px


def _interp_weights(table: np.ndarray, step: float, ox: np.ndarray, oy: np.ndarray
                    ) -> np.ndarray:
    """Bilinear interpolation of :func:`aperture_weight_table` at offsets (ox, oy)."""
    n = table.shape[0]
    u = np.clip((ox + 0.5) / step, 0, n - 1 - 1e-9)
    v = np.clip((oy + 0.5) / step, 0, n - 1 - 1e-9)
    i = u.astype(int)
    j = v.astype(int)
    fu = (u - i)[:, None, None]
    fv = (v - j)[:, None, None]
    return ((1 - fu) * (1 - fv) * table[j, i] + fu * (1 - fv) * table[j, i + 1]
            + (1 - fu) * fv * table[j + 1, i] + fu * fv * table[j + 1, i + 1])


def measure_stamps(stamps_e: np.ndarray, *, radius_px: float, annulus_px: tuple[float, float],
                   var_per_e: float, read_var_e2: float, weight_table=None
                   ) -> dict[str, np.ndarray]:
    """Photometry of star stamps centred on the star's nearest pixel.

    Parameters
    ----------
    stamps_e : ndarray, shape (n, 2h + 1, 2h + 1)
        Images in electrons; the central pixel is the star's nearest pixel.
    radius_px : float
        Aperture radius.
    annulus_px : (float, float)
        Background annulus radii about the central pixel (clipped to the stamp).
    var_per_e, read_var_e2 : float
        Pixel variance model ``var = var_per_e max(e, 0) + read_var_e2``.
    weight_table : tuple, optional
        :func:`aperture_weight_table` for ``radius_px`` (computed if absent).

    Returns
    -------
    dict of ndarray
        ``x_off``, ``y_off`` (centroid relative to the central pixel),
        ``noise_pixels``, ``flux``, ``flux_err``, ``background`` (e per px).
    """
    n, size, _ = stamps_e.shape
    h = size // 2
    yy, xx = np.mgrid[-h:h + 1, -h:h + 1]
    r = np.hypot(xx, yy)
    ann = (r >= annulus_px[0]) & (r <= annulus_px[1])
    n_ann = int(ann.sum())
    bg = stamps_e[:, ann].mean(axis=1)
    sub = stamps_e - bg[:, None, None]
    box = sub[:, h - BOX_HALF:h + BOX_HALF + 1, h - BOX_HALF:h + BOX_HALF + 1]
    k = np.arange(-BOX_HALF, BOX_HALF + 1, dtype=float)
    tot = box.sum(axis=(1, 2))
    # Eqs. x_centroid, y_centroid over the 7x7 box
    x_off = (box.sum(axis=1) * k).sum(axis=1) / tot
    y_off = (box.sum(axis=2) * k).sum(axis=1) / tot
    # Eq. noise_pixels over the same box
    npix = tot**2 / (box**2).sum(axis=(1, 2))
    table, step = weight_table if weight_table is not None else aperture_weight_table(radius_px)
    w = _interp_weights(table, step, x_off, y_off)
    raw = stamps_e[:, h - BOX_HALF:h + BOX_HALF + 1, h - BOX_HALF:h + BOX_HALF + 1]
    area = w.sum(axis=(1, 2))
    flux = (w * box).sum(axis=(1, 2))
    var_pix = var_per_e * np.clip(raw, 0.0, None) + read_var_e2
    var_bg = (var_per_e * np.clip(bg, 0.0, None) + read_var_e2) / n_ann
    flux_err = np.sqrt((w**2 * var_pix).sum(axis=(1, 2)) + area**2 * var_bg)
    return {"x_off": x_off, "y_off": y_off, "noise_pixels": npix, "flux": flux,
            "flux_err": flux_err, "background": bg}


def calibration_chunk(cfg: Config, chunk: int, n_total: int | None = None, *,
                      mode: ReadoutMode = SUB_0P1S,
                      flux_aperture_e: float = CALIBRATION_FLUX_E) -> dict[str, np.ndarray]:
    """Simulate and measure frames ``chunk * 16384 ...`` of the calibration set.

    Pointings of 64 frames are centred uniformly at random within a square of
    side ``simulation.calibration_box_px`` around the sweet-spot pixel centre
    (15, 15); frames scatter about their pointing by 0.01 px. Streams:
    ``("simulate", "calibration", chunk, "positions"|"photon"|"read")``, so the
    output depends on the seed only, not on how chunks are spread over workers.
    """
    from ..simulate.challenge import read_noise_of

    sim = cfg.simulation
    seed = cfg.challenge.seed
    n_total = sim.calibration_frames if n_total is None else int(n_total)
    n = min(CHUNK_FRAMES, n_total - chunk * CHUNK_FRAMES)
    star = make_star_imager(cfg)
    e_per_unit = star.electrons_per_unit(flux_aperture_e)
    ticks_exp = mode.fowler + mode.wait
    sky_e = star.sky_e_per_px(sim.background_e_per_px, sim.flux_aperture_e,
                              sim.background_reference)
    obs = cfg.observation
    bg_per_tick = sky_e * mode.t_exp_s / ((obs.fowler + obs.wait) * obs.sample_time_s) / ticks_exp
    read_sigma = read_noise_of(cfg) * np.sqrt(2.0 / mode.fowler)
    w = fowler_weights(mode).astype(float)
    var_per_e = float((w**2).sum() / (mode.fowler**2 * ticks_exp))
    table = _weight_table(sim.aperture_radius_px)

    g = rng(seed, "simulate", "calibration", chunk, "positions")
    n_point = -(-n // FRAMES_PER_POINTING)
    centres = 15.0 + sim.calibration_box_px * (g.random((n_point, 2)) - 0.5)
    pos = np.repeat(centres, FRAMES_PER_POINTING, axis=0)[:n]
    pos = pos + g.normal(0.0, JITTER_PX, size=pos.shape)
    x_true, y_true = pos[:, 0], pos[:, 1]
    stamps, x0, y0 = star.prf.render_stamp(x_true, y_true, half=STAMP_HALF)
    rate = stamps * (e_per_unit / ticks_exp) + bg_per_tick
    frames = fowler_uniform(rate, mode, rng(seed, "simulate", "calibration", chunk, "photon"))
    frames += rng(seed, "simulate", "calibration", chunk, "read").standard_normal(
        frames.shape) * read_sigma
    m = measure_stamps(frames, radius_px=sim.aperture_radius_px, annulus_px=(3.0, 7.0),
                       var_per_e=var_per_e, read_var_e2=read_sigma**2, weight_table=table)
    return {"x": x0 + STAMP_HALF + m["x_off"], "y": y0 + STAMP_HALF + m["y_off"],
            "noise_pixels": m["noise_pixels"], "flux": m["flux"], "flux_err": m["flux_err"],
            "x_true": x_true, "y_true": y_true, "background": m["background"]}


_TABLES: dict[float, tuple[np.ndarray, float]] = {}


def _weight_table(radius_px: float) -> tuple[np.ndarray, float]:
    table = _TABLES.get(radius_px)
    if table is None:
        table = _TABLES[radius_px] = aperture_weight_table(radius_px)
    return table


def n_chunks(cfg: Config, n_total: int | None = None) -> int:
    """Chunks of 16,384 frames in the calibration set."""
    n_total = cfg.simulation.calibration_frames if n_total is None else int(n_total)
    return -(-n_total // CHUNK_FRAMES)


def simulate_calibration(cfg: Config, *, n_frames: int | None = None) -> dict[str, np.ndarray]:
    """The whole calibration set in this process (see :func:`calibration_chunk`)."""
    parts = [calibration_chunk(cfg, c, n_frames) for c in range(n_chunks(cfg, n_frames))]
    return concat_chunks(parts)


def concat_chunks(parts: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Concatenate chunk results (in chunk order)."""
    keys = ("x", "y", "noise_pixels", "flux", "flux_err", "x_true", "y_true", "background")
    return {k: (np.concatenate([p[k] for p in parts]) if parts else np.zeros(0)) for k in keys}


def write_calibration_set(cfg: Config, out_dir: str | Path) -> str:
    """Simulate the calibration set and write ``DIR/calibration/pmap_calibration.fits``."""
    return write_calibration_table(cfg, simulate_calibration(cfg), out_dir)


def write_calibration_table(cfg: Config, data: dict[str, np.ndarray], out_dir: str | Path) -> str:
    """Write measured calibration frames to ``DIR/calibration/pmap_calibration.fits``."""
    from astropy.table import Table

    table = Table({k: data[k] for k in ("x", "y", "noise_pixels", "flux", "flux_err",
                                        "x_true", "y_true", "background")})
    for k in ("x", "y", "x_true", "y_true"):
        table[k].unit = "pix"
    table.meta.update({"SIMSEED": cfg.challenge.seed, "NFRAMES": len(table),
                       "READMODE": "SUB 0.1s", "AFOWLNUM": SUB_0P1S.fowler,
                       "AWAITPER": SUB_0P1S.wait, "SAMPTIME": SUB_0P1S.sample_time_s,
                       "APRADIUS": cfg.simulation.aperture_radius_px,
                       "ANNULUS": "3-7 px (clipped to 11x11 stamp)",
                       "FLUXAPE": CALIBRATION_FLUX_E, "NOISEMOD": "physical",
                       "SIMPRF": prf_label(cfg.simulation.prf), "BUNIT": "electrons per frame",
                       "SIMFLAT": cfg.simulation.flat_gain,
                       "COMMENT": "eclipsebench simulated calibration star for KR/Pmap"})
    path = Path(out_dir) / "calibration" / "pmap_calibration.fits"
    with atomic_path(path) as tmp:
        table.write(tmp, format="fits")
    return str(path)
