"""eclipsebench: simulate, reduce and score Spitzer/IRAC eclipse photometry.

``import eclipsebench as eb`` gives the public API (``docs/api.md``):
:func:`eb.load_config`, :func:`eb.simulate`, :func:`eb.measure`,
:func:`eb.reduce`, :func:`eb.compare_phases`, :func:`eb.score`, :func:`eb.trust`, :func:`eb.run_challenge`,
:func:`eb.campaign`,
:func:`eb.methods`, :func:`eb.method_class`, :func:`eb.read_result`,
:func:`eb.read_photometry`, and the base classes
:class:`eb.Systematics`, :class:`eb.MethodOptions`, :class:`eb.MethodContext`.
"""

import sys
import types

#: The package version, read by pyproject.toml (``[tool.setuptools.dynamic]``);
#: CHANGELOG.md lists what each version changed.
__version__ = "0.2.0"

#: Public name -> the module that defines it.
_PUBLIC = {
    "load_config": "api", "methods": "api", "method_class": "api", "measure": "api",
    "reduce": "api", "simulate": "api", "run_challenge": "api", "campaign": "api",
    "score": "api", "trust": "api", "compare_phases": "api",
    "Systematics": "decorrelate.base", "MethodOptions": "decorrelate.base",
    "MethodContext": "decorrelate.base", "EpochData": "decorrelate.base",
    "EpochResult": "fit.result", "InputError": "errors",
    "read_result": "api", "read_photometry": "api",
}

__all__ = ["__version__", *_PUBLIC]


class _SubpackageFunction:
    """An API function that shares its name with a subpackage (``eb.trust``).

    Calling it calls the API function; its other attributes are the
    subpackage's, so ``import eclipsebench.trust.result as r`` still works.
    """

    def __init__(self, function, package: str):
        self.__wrapped__ = function
        self.__doc__ = function.__doc__
        self.__name__ = function.__name__
        self.__qualname__ = function.__qualname__
        self._package = package

    def __call__(self, *args, **kwargs):
        return self.__wrapped__(*args, **kwargs)

    def __getattr__(self, name: str):
        import importlib

        return getattr(importlib.import_module(self._package), name)

    def __repr__(self) -> str:
        return f"<function eclipsebench.{self.__name__}>"


class _Package(types.ModuleType):
    """The package module: an API name is never replaced by the subpackage of that name.

    Importing a subpackage binds it on its parent (``import eclipsebench.trust.result``
    sets ``eclipsebench.trust`` to the subpackage), which hid the function
    ``eb.trust`` after any call that loaded the trust code. The subpackage stays in
    ``sys.modules``, where ``import`` finds it; the attribute stays the API's.
    """

    def __setattr__(self, name: str, value) -> None:
        if name in _PUBLIC and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


def __getattr__(name: str):
    # Loaded on first use (PEP 562): the API pulls in numba, scikit-learn and
    # astropy (about 2.5 s), which `eclipsebench --help` should not pay for.
    if name not in _PUBLIC:
        raise AttributeError(f"module 'eclipsebench' has no attribute {name!r}")
    import importlib
    import importlib.util

    value = getattr(importlib.import_module(f".{_PUBLIC[name]}", __name__), name)
    if importlib.util.find_spec(f"{__name__}.{name}") is not None:   # a subpackage's name
        value = _SubpackageFunction(value, f"{__name__}.{name}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(__all__)
