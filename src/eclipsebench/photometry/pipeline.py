"""BCD folders to per-epoch photometry tables (reading, cleaning, measuring, flagging).

This module orchestrates; the numbers come from the array functions of
:mod:`.measure` and :mod:`.clean`. One epoch at a time is held in memory
(about 130 MB for a 15,600-frame subarray epoch).
"""

from __future__ import annotations

import dataclasses
import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from astropy.table import Table

from .. import __version__
from ..config.base import from_mapping, to_mapping
from ..config.photometry import PhotometrySection
from ..errors import InputError
from ..io.bcd_read import (
    BcdCube,
    BcdInfo,
    Epoch,
    find_bcd_files,
    frame_times_bmjd,
    group_epochs,
    read_bcd,
    read_bcd_header,
)
from ..progress import get_logger
from .clean import (
    FLAG_BITS,
    flag_counts,
    frame_faults,
    keep_fault_reasons,
    nanmedian0,
    outliers,
    reject_cosmic_rays,
)
from .measure import measure_stack
from .table import make_table

__all__ = ["AorStack", "load_aor", "process_epoch", "find_simdir", "photometry_tables"]

_LOG = get_logger("photometry")
_RADIUS_COLUMN = re.compile(r"^flux_r\d+p\d\d$")
_X_COLUMNS = ("x", "x_col", "x_gauss", "x_gfix", "x_lsq", "peak_x")
_Y_COLUMNS = ("y", "y_col", "y_gauss", "y_gfix", "y_lsq", "peak_y")


@dataclass
class AorStack:
    """One AOR's frames in electrons, cut to a window about the star."""

    aorkey: int
    frames_e: np.ndarray       # (n, ny, nx) float32, electrons per pixel
    bad_mask: np.ndarray | None  # (n, ny, nx) bool: fatal bimsk bits
    time_bmjd: np.ndarray
    expid: np.ndarray
    dce: np.ndarray
    frame: np.ndarray
    first: np.ndarray          # bool: first frame of a subarray cube
    x_off: int                 # window origin in detector pixels
    y_off: int
    star_x: int                # brightest pixel of the median frame (window coordinates)
    star_y: int
    fowler: int
    wait: int
    read_noise_e: float
    files: list[Path]


def _brightest(image: np.ndarray) -> tuple[int, int] | None:
    finite = np.isfinite(image)
    if not finite.any():
        return None
    j, i = np.unravel_index(np.argmax(np.where(finite, image, -np.inf)), image.shape)
    return int(i), int(j)


def _median_frame(data: np.ndarray, valid: np.ndarray, most: int = 256) -> np.ndarray:
    """Median of up to ``most`` valid frames spread evenly over the AOR."""
    idx = np.flatnonzero(valid)
    if idx.size > most:
        idx = idx[np.linspace(0, idx.size - 1, most).round().astype(int)]
    return nanmedian0(data[idx])


def brightest_of_median(frames: np.ndarray, valid: np.ndarray) -> tuple[int, int] | None:
    """The brightest pixel ``(x, y)`` of the median of up to 256 valid frames: where the star
    is (None when no pixel is finite)."""
    return _brightest(_median_frame(frames, valid))


def load_aor(cubes: list[BcdCube], options: PhotometrySection) -> AorStack:
    """Stack one AOR's cubes (time order), convert to electrons, cut a window.

    Subarray frames are used whole; full-array frames are cut to a
    ``window_px`` square about the brightest pixel of the median frame.
    """
    infos = [c.info for c in cubes]
    # float32 like the files (7 significant digits; sums are done in float64 in the kernels)
    data = np.concatenate([c.data * np.float32(c.info.electrons_per_mjysr) for c in cubes])
    masks = None
    if all(c.mask is not None for c in cubes):
        masks = np.concatenate([(c.mask & int(options.bimsk_bits)) != 0 for c in cubes
                                if c.mask is not None])
    first = np.concatenate([(np.arange(i.n_frames) == 0) & i.subarray for i in infos])
    valid = ~first if options.drop_first_frame and (~first).any() else np.ones(first.size, bool)
    x_off = y_off = 0
    if not infos[0].subarray:
        guess = brightest_of_median(data, valid)
        if guess is not None:
            half = options.window_px // 2
            x_off = int(np.clip(guess[0] - half, 0, data.shape[2] - options.window_px))
            y_off = int(np.clip(guess[1] - half, 0, data.shape[1] - options.window_px))
        data = data[:, y_off:y_off + options.window_px, x_off:x_off + options.window_px]
        if masks is not None:
            masks = masks[:, y_off:y_off + options.window_px, x_off:x_off + options.window_px]
    if masks is not None:
        data[masks] = np.nan
    star = brightest_of_median(data, valid)
    if star is None:
        star = (data.shape[2] // 2, data.shape[1] // 2)
    return AorStack(
        aorkey=infos[0].aorkey, frames_e=data, bad_mask=masks,
        time_bmjd=np.concatenate([frame_times_bmjd(i) for i in infos]),
        expid=np.concatenate([np.full(i.n_frames, i.expid) for i in infos]),
        dce=np.concatenate([np.full(i.n_frames, i.dce) for i in infos]),
        frame=np.concatenate([np.arange(i.n_frames) for i in infos]),
        first=first, x_off=x_off, y_off=y_off, star_x=star[0], star_y=star[1],
        fowler=infos[0].fowler, wait=infos[0].wait, read_noise_e=infos[0].read_noise_e,
        files=[i.path for i in infos])


def _region(shape: tuple[int, int], x: int, y: int, radius: float) -> np.ndarray:
    jj, ii = np.mgrid[: shape[0], : shape[1]]
    return (ii - x) ** 2 + (jj - y) ** 2 <= radius**2


def measure_aor(stack: AorStack, options: PhotometrySection, *, stamp_x: int,
                stamp_y: int) -> dict[str, np.ndarray]:
    """Clean and measure one AOR; returns table columns in detector coordinates.

    Pixels that the cosmic-ray rejection replaces are replaced in
    ``stack.frames_e`` itself.
    """
    opt = options
    n, ny, nx = stack.frames_e.shape
    flag = np.zeros(n, dtype=np.int64)
    faults = frame_faults(stack.frames_e)  # no image: kept out of the neighbours' statistics
    if opt.drop_first_frame:
        flag[stack.first] |= FLAG_BITS["first_frame"]
    rmax = max(max(opt.radii_px), opt.radius_px)
    # the centroid box and the largest aperture when the star is within 1 px of its
    # usual pixel (pixel corners included)
    region = _region((ny, nx), stack.star_x, stack.star_y,
                     max((opt.box_px // 2 + 0.5) * np.sqrt(2.0), rmax + 0.75) + 1.0)
    frames = stack.frames_e
    if opt.cosmic_ray_window > 0:
        reach = int(np.ceil(opt.annulus_px[1])) + opt.search_px + 1
        y0, y1 = max(stack.star_y - reach, 0), min(stack.star_y + reach + 1, ny)
        x0, x1 = max(stack.star_x - reach, 0), min(stack.star_x + reach + 1, nx)
        cleaned, hits = reject_cosmic_rays(frames[:, y0:y1, x0:x1], opt.cosmic_ray_window,
                                           opt.cosmic_ray_sigma, valid=~stack.first & (faults == 0),
                                           read_var_e2=2.0 * stack.read_noise_e**2 / stack.fowler)
        if hits.any():
            frames[:, y0:y1, x0:x1] = cleaned  # the stack is ours: repair in place
            hit_region = (hits & region[None, y0:y1, x0:x1]).any(axis=(1, 2))
            flag[hit_region] |= FLAG_BITS["cosmic_ray"]
    has_nonfinite = ~np.isfinite(frames.reshape(n, -1)).all(axis=1)
    if stack.bad_mask is not None:
        flag[stack.bad_mask[:, region].any(axis=1)] |= FLAG_BITS["bimsk"]
    m = measure_stack(frames, guess_x=stack.star_x, guess_y=stack.star_y, stamp_x=stamp_x,
                      stamp_y=stamp_y, options=opt, fowler=stack.fowler, wait=stack.wait,
                      read_noise_e=stack.read_noise_e)
    # a non-finite pixel matters when it reached a measurement (box or apertures)
    rmax_name = max((k for k in m if _RADIUS_COLUMN.match(k)),
                    key=lambda k: float(k[6:].replace("p", ".")))
    reached = ~np.all([np.isfinite(m[k]) for k in ("x_col", "noise_pixels", "x_gauss",
                                                   rmax_name, "flux")], axis=0)
    flag[has_nonfinite & reached] |= FLAG_BITS["nonfinite"]
    key = ("x", "y", "flux", "flux_err", "background", "noise_pixels")
    bad = ~np.all([np.isfinite(m[k]) for k in key], axis=0) | ~(m["flux"] > 0)
    flag[bad & ((flag & FLAG_BITS["nonfinite"]) == 0)] |= FLAG_BITS["no_star"]
    failed = ~m["gauss_ok"]
    if opt.centroid == "gauss-fixed":
        failed |= ~m["gfix_ok"]
    elif opt.centroid == "lsq-asym":
        failed |= ~m["lsq_ok"]
    flag[failed & ~bad] |= FLAG_BITS["fit_failed"]
    flag = keep_fault_reasons(flag, faults)
    if opt.outlier_window > 0:
        ok = flag == 0
        # true pointing motion (drifts, excursions) moves both centroids alike; a bad
        # pixel or an unflagged hit pulls the center of light and the Gaussian apart
        cen = outliers(m["x_col"] - m["x_gauss"], opt.outlier_window, opt.outlier_sigma, ok) | \
            outliers(m["y_col"] - m["y_gauss"], opt.outlier_window, opt.outlier_sigma, ok)
        flag[cen & ok] |= FLAG_BITS["centroid_outlier"]
        flx = outliers(m["flux"], opt.outlier_window, opt.outlier_sigma, ok)
        flag[flx & ok] |= FLAG_BITS["flux_outlier"]
    for name in _X_COLUMNS:
        if name in m:
            m[name] = m[name] + stack.x_off
    for name in _Y_COLUMNS:
        if name in m:
            m[name] = m[name] + stack.y_off
    m.pop("gauss_ok")
    m.pop("gfix_ok", None)
    m.pop("lsq_ok", None)
    m.update({"time_bmjd": stack.time_bmjd, "aorkey": np.full(n, stack.aorkey),
              "expid": stack.expid, "dce": stack.dce, "frame": stack.frame, "flag": flag,
              "stamp_x": np.full(n, stamp_x + stack.x_off),
              "stamp_y": np.full(n, stamp_y + stack.y_off)})
    return m


def find_simdir(start: Path) -> Path | None:
    """The nearest folder at or above ``start`` holding ``truth.ecsv`` or ``calibration/``."""
    for folder in [start, *start.parents]:
        if (folder / "truth.ecsv").is_file() or (folder / "calibration").is_dir():
            return folder
    return None


def _relative(path: Path, root: Path) -> str:
    try:
        return path.resolve().relative_to(root.resolve()).as_posix()
    except ValueError:
        return path.resolve().as_posix()


def _observation_meta(info: BcdInfo) -> dict:
    """What the main AOR's header says of the target and the readout (``docs/contracts.md``).

    The target (``OBJECT``, ``RA_REF``, ``DEC_REF``, ``AORLABEL``, ``DATE_OBS``
    and a simulation's ``SYSTEM``) lets a reduction find the planet in the
    catalogue; the readout (Fowler number, wait, sample and frame times, gain,
    read noise) lets ``trust`` simulate twins of the observation.
    """
    return {**info.extra_target, "READMODE": "SUB" if info.subarray else "FULL",
            "AFOWLNUM": int(info.fowler), "AWAITPER": int(info.wait),
            "SAMPTIME": float(info.sample_time_s), "FRAMTIME": float(info.framtime_s),
            "EXPTIME": float(info.exptime_s), "FRMINTVL": float(info.frame_interval_s),
            "GAIN": float(info.gain), "FLUXCONV": float(info.fluxconv),
            "RONOISE": float(info.read_noise_e)}


def process_epoch(epoch: Epoch, options: PhotometrySection, *, input_root: Path,
                  on_file: Callable[[], None] | None = None) -> Table:
    """Read, clean and measure every AOR of ``epoch``; one table in time order."""
    stacks = []
    for aorkey in epoch.aorkeys:
        cubes = []
        for info in (f for f in epoch.files if f.aorkey == aorkey):
            cubes.append(read_bcd(info, mask=True))
            if on_file is not None:
                on_file()
        stacks.append(load_aor(cubes, options))
    main = max(stacks, key=lambda s: s.frames_e.shape[0])
    stamp_det = (main.star_x + main.x_off, main.star_y + main.y_off)
    parts = [measure_aor(s, options, stamp_x=stamp_det[0] - s.x_off, stamp_y=stamp_det[1] - s.y_off)
             for s in stacks]
    columns = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    order = np.argsort(columns["time_bmjd"], kind="stable")
    columns = {k: v[order] for k, v in columns.items()}
    infos = epoch.files
    meta = {
        "EB_VERSION": __version__,
        "EPOCH": int(epoch.number),
        "AORKEYS": [int(a) for a in epoch.aorkeys],
        "CHANNEL": int(infos[0].channel),
        "INPUTS": [_relative(i.path, input_root) for i in infos],
        "INROOT": str(input_root.resolve()),
        "OPTIONS": to_mapping(options),
        "CENTROID": options.centroid,
        "RADIUS": float(options.radius_px),
        "BGMETHOD": options.background,
        "TIMESYS": "TDB",
        "TIMEREF": "SOLARSYSTEM",
        "TIMEUNIT": "d",
        "FLAGBITS": dict(FLAG_BITS),
        "FLAGCNT": flag_counts(columns["flag"]),
        "NFRAMES": int(columns["flag"].size),
        "SIMULATE": bool(any(i.simulate for i in infos)),
        **_observation_meta(next(i for i in infos if i.aorkey == main.aorkey)),
    }
    if meta["SIMULATE"]:
        simdir = find_simdir(infos[0].path.resolve().parent)
        if simdir is not None:
            meta["SIMDIR"] = str(simdir)
    return make_table(columns, meta)


def photometry_tables(input_dir: str | os.PathLike, options: PhotometrySection, *,
                      channel: int | None = None,
                      progress: Callable[[int], Callable[[], None]] | None = None):
    """Yield ``(epoch, table)`` for every epoch found under ``input_dir``.

    ``progress(total_files)`` may return a callback called once per file read.
    """
    root = Path(input_dir)
    files = find_bcd_files(root, channel=channel)
    infos = [read_bcd_header(p) for p in files]
    epochs = group_epochs(infos, gap_days=options.epoch_gap_days)
    tick = progress(len(infos)) if progress is not None else None
    if not epochs:
        raise InputError(f"{root}: no epochs found")
    for epoch in epochs:
        _LOG.info("epoch %d: AORs %s, %d files", epoch.number, list(epoch.aorkeys),
                  len(epoch.files))
        yield epoch, process_epoch(epoch, options, input_root=root if root.is_dir() else
                                   root.parent, on_file=tick)


def replace_options(options: PhotometrySection, **changes) -> PhotometrySection:
    """A copy of ``options`` with ``changes`` applied and validated."""
    mapping = to_mapping(dataclasses.replace(options, **changes))
    return from_mapping(PhotometrySection, mapping, prefix="photometry")
