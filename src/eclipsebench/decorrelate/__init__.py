"""Correlated-noise (systematics) models, one module per method, one registry.

Importing this package imports every method module, which registers itself;
:func:`get_method` and :func:`available_methods` are the only ways the rest of
the package finds a method by name.
"""

from .base import EpochData, Systematics, available_methods, get_method, register

__all__ = ["EpochData", "Systematics", "available_methods", "get_method", "register"]

# Method modules register themselves on import; list each one here when it is complete.
from . import _methods  # noqa: E402,F401
