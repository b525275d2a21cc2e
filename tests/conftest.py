"""Shared test fixtures: where the real IRAC reference files live."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED_IRAC = (ROOT / ".." / "shared" / "data" / "irac").resolve()


@pytest.fixture(scope="session")
def shared_irac() -> Path:
    """``../shared/data/irac`` (tests using it carry the ``shared_data`` marker)."""
    if not SHARED_IRAC.is_dir():
        pytest.skip("../shared/data/irac is not beside this checkout")
    return SHARED_IRAC


@pytest.fixture(scope="session")
def real_epoch1_table(shared_irac, tmp_path_factory) -> Path:
    """Our photometry (built-in settings) of real epoch 1 (``real_xo3_eclipse1``), as a FITS
    table written once per session."""
    from eclipsebench.api import measure

    out = tmp_path_factory.mktemp("real_epoch1")
    measure(shared_irac / "real_xo3_eclipse1", out)
    return out / "epoch_01.fits"


def simulate_eclipse_epoch(root: Path, sets: list[str], lead_d: float) -> Path:
    """Simulate one short epoch (configuration ``sets``) that starts ``lead_d`` days before an
    eclipse of the configured planet, measure it; the photometry table's path."""
    from eclipsebench.astro.catalogue import system_for
    from eclipsebench.astro.orbit import eclipse_time_bmjd
    from eclipsebench.cli import main
    from eclipsebench.config import load_config
    from eclipsebench.simulation.plan import JD_OFFSET_BMJD

    t_ecl = eclipse_time_bmjd(system_for(load_config(None, sets).system), 57205.8)
    sets = sets + [f"observation.start_times_jd=[{t_ecl - lead_d - JD_OFFSET_BMJD:.6f}]"]
    args = [a for s in sets for a in ("--set", s)]
    assert main(["simulate", "--out", str(root / "sim"), "--epochs", "1", "--no-calibration",
                 "--quiet", "--workers", "1", *args]) == 0
    assert main(["photometry", str(root / "sim"), "--out", str(root / "phot"), "--quiet"]) == 0
    return root / "phot" / "epoch_01.fits"


def real_epoch1_jd_utc(table, shared_irac: Path):
    """The times of a photometry table of real epoch 1 as JD_UTC at the observer (Spitzer),
    from the archive's own headers: each cube's ``MJD_OBS`` (UTC at Spitzer) less its
    ``BMJD_OBS`` moved to TDB, added to each frame's BMJD_TDB. Independent of
    ``astro/timescales.py``; also the observer (first header's ``SPTZR_X/Y/Z, MJD_OBS``)."""
    import numpy as np
    from astropy.io import fits
    from astropy.time import Time

    shift, observer = {}, None
    for f in sorted((shared_irac / "real_xo3_eclipse1").glob("r*/ch2/bcd/*_bcd.fits")):
        h = fits.getheader(f)
        bmjd_tdb = Time(h["BMJD_OBS"], format="mjd", scale="utc").tdb.mjd
        shift[(int(h["AORKEY"]), int(h["EXPID"]))] = h["MJD_OBS"] - bmjd_tdb
        if observer is None:
            observer = f"{h['SPTZR_X']},{h['SPTZR_Y']},{h['SPTZR_Z']},{h['MJD_OBS']}"
    keys = zip(np.asarray(table["aorkey"]), np.asarray(table["expid"]), strict=True)
    delta = np.array([shift[(int(a), int(e))] for a, e in keys])
    return np.asarray(table["time_bmjd"], float) + delta + 2400000.5, observer
