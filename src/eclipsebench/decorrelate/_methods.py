"""Imports every finished method module so that each registers itself."""

from . import bliss, kernel, pld  # noqa: F401,E402  (bliss, kr-data, kr-pmap, pld)
