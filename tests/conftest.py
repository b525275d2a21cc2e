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
