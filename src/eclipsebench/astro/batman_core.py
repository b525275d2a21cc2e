"""batman's two compiled routines, called directly: the package's one use of batman's private API;
and batman itself, imported without its compiler probe.

:mod:`eclipsebench.astro.eclipse` uses batman's public ``TransitModel`` to
tabulate an event's shape once. The fit's transit model
(:class:`eclipsebench.fit.model.AstroModel`) evaluates the transit
thousands of times per second with the orbit fixed or free, where building a
``TransitModel`` per call (it re-derives the geometry and its integration
settings each time) costs more than the curve itself. It therefore calls the
two C routines that ``TransitModel.light_curve`` calls, ``_rsky`` (the sky
separation of the orbit) and ``_quadratic_ld`` (Mandel & Agol's quadratic
limb darkening), through the two functions below, so that a change of
batman's private API touches this module only; a test checks them against
``batman.TransitModel`` (``tests/fit/test_transit.py``).

batman's ``transitmodel`` imports its ``openmp`` module, which imports
``distutils`` at import time only to compile a test program when a model
asks for more than one thread (eclipsebench never does). With setuptools
installed, ``distutils`` is setuptools' own, and importing it imports
setuptools and ``pkg_resources``: 0.12 CPU s of every command that fits
(issue 40). Every module of the package imports batman from here
(:data:`TransitModel`, :data:`TransitParams`), and this module puts a
stand-in for ``batman.openmp`` in place first, whose ``detect`` runs the
real probe (batman's own file) when it is called.
"""

from __future__ import annotations

import importlib.util
import sys
import types
from pathlib import Path

import numpy as np


def _detect_openmp() -> bool:
    """batman's own ``openmp.detect()``, loaded from its file on the first call."""
    path = Path(sys.modules["batman"].__file__ or "").with_name("openmp.py")
    spec = importlib.util.spec_from_file_location("batman._openmp_probe", path)
    if spec is None or spec.loader is None:
        return False
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return bool(module.detect())


def _defer_openmp_probe() -> None:
    """A stand-in for ``batman.openmp`` (its ``detect`` the real one, loaded when called), set
    before batman is first imported in this process."""
    if "batman" in sys.modules or "batman.openmp" in sys.modules:
        return
    stand_in = types.ModuleType("batman.openmp", "batman's OpenMP probe, loaded when called "
                                "(eclipsebench.astro.batman_core)")
    stand_in.detect = _detect_openmp  # type: ignore[attr-defined]
    stand_in.__all__ = ["detect"]  # type: ignore[attr-defined]
    sys.modules["batman.openmp"] = stand_in


_defer_openmp_probe()

from batman import TransitModel, TransitParams, _quadratic_ld, _rsky  # noqa: E402

__all__ = ["sky_separation", "quadratic_transit", "TransitModel", "TransitParams"]


def sky_separation(time: np.ndarray, t0: float, period_d: float, a_rs: float, inc_rad: float,
                   ecc: float, omega_rad: float) -> np.ndarray:
    """batman's ``rsky``: planet-star separation (stellar radii; 100 behind the star) at ``time``.

    ``t0`` is batman's time of inferior conjunction, in the units of ``time`` and ``period_d``.
    """
    return _rsky._rsky(time, t0, period_d, a_rs, inc_rad, ecc, omega_rad, 1, 1)


def quadratic_transit(separation: np.ndarray, rp_rs: float, u1: float, u2: float) -> np.ndarray:
    """batman's quadratic limb-darkened transit (1 out of transit) at the separations given."""
    return _quadratic_ld._quadratic_ld(separation, rp_rs, u1, u2, 1)
