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
