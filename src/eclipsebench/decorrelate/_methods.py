"""Imports every finished method module so that each registers itself."""

# bliss, kr-data, kr-pmap, pld; segpoly
from . import bliss, kernel, pld, segpoly  # noqa: F401,E402
