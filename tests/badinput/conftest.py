"""Helpers for the bad-input tests: run the CLI, check the one-line error, snapshot folders."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from astropy.io import fits
from scipy.special import erf

from eclipsebench.cli import main

REAL = "real_xo3_peakup_46466816"
GAIN, EXPTIME, FLUXCONV = 3.71, 1.92, 0.1447


def run_cli(capsys, *argv) -> tuple[int, str, list[str]]:
    """Exit code, stdout and the stderr lines of ``eclipsebench ARGV``."""
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err.splitlines()


def assert_one_line(code: int, err: list[str], *names: str, exit_code: int = 2) -> None:
    """Exit ``exit_code``, exactly one stderr line naming each of ``names``, no traceback."""
    assert code == exit_code, err
    assert len(err) == 1, err
    assert "Traceback" not in err[0] and "internal error" not in err[0], err
    for name in names:
        assert str(name) in err[0], (name, err[0])


def snapshot(root: Path) -> set[str]:
    """Every path under ``root`` (files and folders), relative."""
    return {p.relative_to(root).as_posix() for p in root.rglob("*")}


def star_cube(n: int = 64, *, seed: int = 0, total: float = 7e4, bg: float = 5.0) -> np.ndarray:
    """``n`` frames (electrons) of a jittering integrated Gaussian star with photon noise."""
    rng = np.random.default_rng(seed)

    def edges(c: float) -> np.ndarray:
        e = (np.arange(33) - 0.5 - c) / (0.6 * np.sqrt(2.0))
        return np.diff(0.5 * erf(e))

    frames = [total * np.outer(edges(14.9 + 0.01 * rng.standard_normal()),
                               edges(15.2 + 0.01 * rng.standard_normal())) for _ in range(n)]
    return rng.poisson(np.stack(frames) + bg).astype(float)


def write_cube(folder: Path, cube_e: np.ndarray, *, expid: int = 0, bmjd: float | None = None,
               aorkey: int = 123456, **extra) -> Path:
    """A subarray BCD file of ``cube_e`` (electrons); cube k starts 130 s after cube k-1."""
    folder.mkdir(parents=True, exist_ok=True)
    h = fits.Header()
    values = dict(CHNLNUM=2, BMJD_OBS=57000.0 + expid * 130.0 / 86400 if bmjd is None else bmjd,
                  FRAMTIME=2.0, EXPTIME=EXPTIME, SAMPTIME=0.01, AFOWLNUM=8, AWAITPER=184,
                  GAIN=GAIN, FLUXCONV=FLUXCONV, RONOISE=9.4, BUNIT="MJy/sr", READMODE="SUB",
                  AORKEY=aorkey, EXPID=expid, DCENUM=0, TIMESYS="TDB")
    values.update(extra)
    for key, value in values.items():
        h[key] = value
    path = folder / f"SPITZER_I2_{aorkey}_{expid:04d}_0000_1_bcd.fits"
    fits.PrimaryHDU((cube_e * FLUXCONV / (GAIN * EXPTIME)).astype(np.float32),
                    header=h).writeto(path)
    return path


@pytest.fixture
def star_folder(tmp_path) -> Path:
    """Three synthetic cubes of one AOR (192 frames)."""
    folder = tmp_path / "bcd"
    for k in range(3):
        write_cube(folder, star_cube(64, seed=k), expid=k)
    return folder


@pytest.fixture
def real_cubes(shared_irac, tmp_path):
    """``copy(names)``: copy real XO-3 peak-up cubes (EXPIDs) into tmp_path/real; return paths."""
    folder = tmp_path / "real"
    folder.mkdir()

    def copy(expids=(0, 1, 2)) -> list[Path]:
        out = []
        for k in expids:
            name = f"SPITZER_I2_46466816_{k:04d}_0000_2_bcd.fits"
            shutil.copy(shared_irac / REAL / name, folder / name)
            out.append(folder / name)
        return out

    return copy


def xo3_table(path: Path, *, noise: float = 1e-3, seed: int = 0) -> Path:
    """A photometry table (contract columns) of an XO-3b epoch: flat flux times (1 + noise)."""
    from astropy.table import Table

    from eclipsebench.astro.catalogue import get_system
    from eclipsebench.astro.orbit import eclipse_time_bmjd

    t_ecl = eclipse_time_bmjd(get_system("XO-3b"), 57000.0)
    time = t_ecl + np.arange(-0.2, 0.17, 6.0 / 86400)
    n = len(time)
    rng = np.random.default_rng(seed)
    x = 15.0 + 0.05 * rng.standard_normal(n)
    y = 15.0 + 0.05 * rng.standard_normal(n)
    flux = 2e5 * (1.0 + noise * rng.standard_normal(n))
    Table({"time_bmjd": time, "aorkey": np.full(n, 20150001), "expid": np.arange(n) // 64,
           "frame": np.arange(n) % 64, "x": x, "y": y, "x_gauss": x, "y_gauss": y,
           "noise_pixels": np.full(n, 7.0), "width_x": np.full(n, 0.6),
           "width_y": np.full(n, 0.6), "background": np.full(n, 0.1), "flux": flux,
           "flux_err": np.full(n, 200.0), "flag": np.zeros(n, dtype=np.int32),
           "stamp3": np.broadcast_to(flux[:, None, None] / 9, (n, 3, 3)).copy(),
           "stamp5": np.broadcast_to(flux[:, None, None] / 25, (n, 5, 5)).copy()},
          meta={"EPOCH": 1, "SYSTEM": "XO-3b (2015 challenge)"}).write(path)
    return path


@pytest.fixture
def cli(capsys):
    """``cli(*argv) -> (code, stdout, stderr lines)``."""
    return lambda *argv: run_cli(capsys, *argv)


@pytest.fixture
def bad():
    """The helpers of this folder (tests import nothing from conftest under importlib mode)."""
    import types

    return types.SimpleNamespace(assert_one_line=assert_one_line, snapshot=snapshot,
                                 star_cube=star_cube, write_cube=write_cube,
                                 xo3_table=xo3_table)
