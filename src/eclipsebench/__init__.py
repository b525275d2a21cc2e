"""eclipsebench: simulate, reduce and score Spitzer/IRAC eclipse photometry.

``import eclipsebench as eb`` gives the public API (``docs/api.md``):
:func:`eb.load_config`, :func:`eb.simulate`, :func:`eb.measure`,
:func:`eb.reduce`, :func:`eb.score`, :func:`eb.trust`, :func:`eb.run_challenge`,
:func:`eb.methods`, :func:`eb.method_class`, :func:`eb.read_result`,
:func:`eb.read_photometry`, and the base classes
:class:`eb.Systematics`, :class:`eb.MethodOptions`, :class:`eb.MethodContext`.
"""

#: The package version, read by pyproject.toml (``[tool.setuptools.dynamic]``);
#: CHANGELOG.md lists what each version changed.
__version__ = "0.2.0"

#: Public name -> the module that defines it.
_PUBLIC = {
    "load_config": "api", "methods": "api", "method_class": "api", "measure": "api",
    "reduce": "api", "simulate": "api", "run_challenge": "api", "score": "api", "trust": "api",
    "Systematics": "decorrelate.base", "MethodOptions": "decorrelate.base",
    "MethodContext": "decorrelate.base", "EpochData": "decorrelate.base",
    "EpochResult": "fit.result", "InputError": "errors",
    "read_result": "api", "read_photometry": "api",
}

__all__ = ["__version__", *_PUBLIC]


def __getattr__(name: str):
    # Loaded on first use (PEP 562): the API pulls in numba, scikit-learn and
    # astropy (about 2.5 s), which `eclipsebench --help` should not pay for.
    if name not in _PUBLIC:
        raise AttributeError(f"module 'eclipsebench' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(f".{_PUBLIC[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(__all__)
