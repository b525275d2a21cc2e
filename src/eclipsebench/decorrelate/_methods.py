"""Imports every finished method module so that each registers itself."""

# bliss, kr-data, kr-pmap, pld; gp, ica, segpoly
from . import bliss, gp, ica, kernel, pld, pld_aper, poly, segpoly  # noqa: F401,E402
