"""The calibration-star data set for KR/Pmap (paper Appendix B.4, the warm "pmap" set).

A non-variable star observed in many short pointings spread over the
sweet-spot pixel with 0.1 s subarray frames (FN = 2, WT = 6, 0.01 s ticks),
through the same PRF, intra-pixel gain and Fowler noise as the challenge
(about 400,000 measurements by default, ``simulation.calibration_frames``).

Measured as the science frames are: every frame goes through the science
photometry itself, :func:`eclipsebench.photometry.measure.measure_stack`, with
the configuration's ``[photometry]`` section (brightest pixel, annulus,
centroid, noise pixels, aperture radius, background estimator, noise model;
by default the paper's 3-7 px annulus mean, 7x7 center of light, Eqs.
``x_centroid``/``y_centroid``/``noise_pixels``, and a 2.25 px aperture) and
the calibration frames' readout. KR/Pmap therefore trains on numbers made by
the same code, with the same settings, as the numbers it corrects.

Stamp size: only a square stamp about the star is simulated (400,000 full
32x32 frames would cost 3.5 times the pixels for nothing). Its half-width,
:func:`calibration_stamp_half_px`, is ``ceil(outer annulus radius) + 1`` px,
or more where the centroid box, the largest aperture (pixel corners included)
or the least-asymmetry window reach further: 8 px, a 17x17 stamp, for the
default photometry. The star sits within 0.5 px of the stamp's central pixel,
so its brightest pixel and its centroid lie within 1 px of it, and every pixel
of the annulus about either lies inside the stamp: no estimator sees the stamp
edge, as none sees the edge of a science frame (an 11x11 stamp, as before,
clipped the 3-7 px annulus to 3-5.4 px). The price: the Fowler noise draws of
2.4 times as many pixels (about 1.4 s instead of 0.5 s per 16,384-frame chunk
on this machine). The whole stamp gets the star and the sky at a constant rate,
as the pixels of a science frame outside its per-tick stamp do.

The result, ``DIR/calibration/pmap_calibration.fits``, has columns ``x``,
``y``, ``noise_pixels``, ``flux``, ``flux_err`` (electrons) plus the true
position and the background.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NamedTuple

import numpy as np
from astropy.table import Table

from ..config import Config
from ..config.detector import read_noise_of
from ..config.photometry import PhotometrySection
from ..detector.constants import SUB_0P1S, ReadoutMode
from ..io.atomic import atomic_path
from ..photometry.estimators import LSQ_GRID_HALF_PX, LSQ_WINDOW_PX
from ..photometry.measure import measure_stack
from ..seeding import rng
from .render import fowler_uniform
from .star import make_star_imager, prf_label

__all__ = ["write_calibration_set", "write_calibration_table", "simulate_calibration",
           "calibration_chunk", "calibration_frames", "measure_calibration_frames",
           "calibration_stamp_half_px", "CalibrationFrames", "concat_chunks", "n_chunks",
           "CHUNK_FRAMES", "FRAMES_PER_POINTING", "CALIBRATION_COLUMNS"]

CHUNK_FRAMES = 16384
FRAMES_PER_POINTING = 64
JITTER_PX = 0.01
CALIBRATION_FLUX_E = 40000.0
CALIBRATION_COLUMNS = ("x", "y", "noise_pixels", "flux", "flux_err", "x_true", "y_true",
                       "background")


class CalibrationFrames(NamedTuple):
    """Simulated calibration stamps before photometry.

    ``frames_e[n, a, b]`` is detector pixel ``(x0[n] + b, y0[n] + a)`` in
    electrons; the star's true position is ``(x_true[n], y_true[n])``.
    """

    frames_e: np.ndarray
    x0: np.ndarray
    y0: np.ndarray
    x_true: np.ndarray
    y_true: np.ndarray


def calibration_stamp_half_px(options: PhotometrySection) -> int:
    """Half-width (px) of the simulated calibration stamps (see the module notes).

    ``ceil(r_out) + 1`` for the annulus, raised where the centroid box, the
    largest aperture (pixel corners included) or the least-asymmetry window
    (plus 1 px) reach further; 8 for the default photometry.
    """
    r_max = max(max(options.radii_px), options.radius_px)
    reach_px = max(options.annulus_px[1], r_max + 0.5, options.box_px // 2,
                   LSQ_GRID_HALF_PX + LSQ_WINDOW_PX)
    return int(math.ceil(reach_px)) + 1


def calibration_frames(cfg: Config, chunk: int, n_total: int | None = None, *,
                       mode: ReadoutMode = SUB_0P1S,
                       flux_aperture_e: float = CALIBRATION_FLUX_E) -> CalibrationFrames:
    """Simulate frames ``chunk * 16384 ...`` of the calibration set (no photometry).

    Pointings of 64 frames are centred uniformly at random within a square of
    side ``simulation.calibration_box_px`` around the sweet-spot pixel centre
    (15, 15); frames scatter about their pointing by 0.01 px. Each frame is a
    stamp of :func:`calibration_stamp_half_px` about the star's nearest pixel
    with ``flux_aperture_e`` electrons in the ``simulation.aperture_radius_px``
    aperture, the sky, physical Fowler noise and read noise of ``mode`` (none
    of either with ``simulation.noise_model = "none"``: the noise-free
    Fowler sum).
    Streams: ``("simulate", "calibration", chunk, "positions"|"photon"|"read")``,
    so the output depends on the seed only, not on how chunks are spread over
    workers.
    """
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
    read_sigma_e = read_noise_of(cfg) * np.sqrt(2.0 / mode.fowler)

    g = rng(seed, "simulate", "calibration", chunk, "positions")
    n_point = -(-n // FRAMES_PER_POINTING)
    centres = 15.0 + sim.calibration_box_px * (g.random((n_point, 2)) - 0.5)
    pos = np.repeat(centres, FRAMES_PER_POINTING, axis=0)[:n]
    pos = pos + g.normal(0.0, JITTER_PX, size=pos.shape)
    x_true, y_true = pos[:, 0], pos[:, 1]
    half = calibration_stamp_half_px(cfg.photometry)
    stamps, x0, y0 = star.prf.render_stamp(x_true, y_true, half=half)
    rate = stamps * (e_per_unit / ticks_exp) + bg_per_tick
    if sim.noise_model == "none":
        # sum_i (S_i - P_i) / FN of a constant rate: FN + WT ticks' worth
        return CalibrationFrames(rate * ticks_exp, x0, y0, x_true, y_true)
    frames = fowler_uniform(rate, mode, rng(seed, "simulate", "calibration", chunk, "photon"))
    frames += rng(seed, "simulate", "calibration", chunk, "read").standard_normal(
        frames.shape) * read_sigma_e
    return CalibrationFrames(frames, x0, y0, x_true, y_true)


def measure_calibration_frames(cfg: Config, frames: CalibrationFrames, *,
                               mode: ReadoutMode = SUB_0P1S) -> dict[str, np.ndarray]:
    """Science photometry of calibration stamps: :func:`measure_stack` with ``cfg.photometry``.

    The brightest pixel is searched about the stamps' central pixel; the
    noise model uses the readout ``mode`` and :func:`read_noise_of` ``cfg``.

    Returns
    -------
    dict of ndarray
        :data:`CALIBRATION_COLUMNS`, positions in detector pixels.
    """
    half = frames.frames_e.shape[1] // 2
    m = measure_stack(frames.frames_e, guess_x=half, guess_y=half, options=cfg.photometry,
                      fowler=mode.fowler, wait=mode.wait, read_noise_e=read_noise_of(cfg))
    return {"x": frames.x0 + m["x"], "y": frames.y0 + m["y"],
            "noise_pixels": m["noise_pixels"], "flux": m["flux"], "flux_err": m["flux_err"],
            "x_true": frames.x_true, "y_true": frames.y_true, "background": m["background"]}


def calibration_chunk(cfg: Config, chunk: int, n_total: int | None = None, *,
                      mode: ReadoutMode = SUB_0P1S,
                      flux_aperture_e: float = CALIBRATION_FLUX_E) -> dict[str, np.ndarray]:
    """Simulate and measure frames ``chunk * 16384 ...`` of the calibration set.

    :func:`calibration_frames` then :func:`measure_calibration_frames`.
    """
    frames = calibration_frames(cfg, chunk, n_total, mode=mode, flux_aperture_e=flux_aperture_e)
    return measure_calibration_frames(cfg, frames, mode=mode)


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
    return {k: (np.concatenate([p[k] for p in parts]) if parts else np.zeros(0))
            for k in CALIBRATION_COLUMNS}


def write_calibration_set(cfg: Config, out_dir: str | Path) -> str:
    """Simulate the calibration set and write ``DIR/calibration/pmap_calibration.fits``."""
    return write_calibration_table(cfg, simulate_calibration(cfg), out_dir)


def write_calibration_table(cfg: Config, data: dict[str, np.ndarray], out_dir: str | Path) -> str:
    """Write measured calibration frames to ``DIR/calibration/pmap_calibration.fits``.

    The header records how they were measured (``[photometry]`` of ``cfg``).
    """
    opt = cfg.photometry
    table = Table({k: data[k] for k in CALIBRATION_COLUMNS})
    for k in ("x", "y", "x_true", "y_true"):
        table[k].unit = "pix"
    table.meta.update({"SIMSEED": cfg.challenge.seed, "NFRAMES": len(table),
                       "CHNLNUM": cfg.observation.channel,
                       "READMODE": "SUB 0.1s", "AFOWLNUM": SUB_0P1S.fowler,
                       "AWAITPER": SUB_0P1S.wait, "SAMPTIME": SUB_0P1S.sample_time_s,
                       "APRADIUS": opt.radius_px,
                       "ANNULUS": f"{opt.annulus_px[0]:g}-{opt.annulus_px[1]:g} px",
                       "BGEST": opt.background, "CENTROID": opt.centroid,
                       "STAMPPX": 2 * calibration_stamp_half_px(opt) + 1,
                       "FLUXAPE": CALIBRATION_FLUX_E,
                       "NOISEMOD": "none" if cfg.simulation.noise_model == "none" else "physical",
                       "SIMPRF": prf_label(cfg.simulation.prf), "BUNIT": "electrons per frame",
                       "SIMFLAT": cfg.simulation.flat_gain,
                       "COMMENT": "eclipsebench simulated calibration star for KR/Pmap"})
    path = Path(out_dir) / "calibration" / "pmap_calibration.fits"
    with atomic_path(path) as tmp:
        table.write(tmp, format="fits")
    return str(path)
