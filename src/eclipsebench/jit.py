"""Numba kernels compiled (or loaded from numba's cache) at their first call, not at import.

Importing numba costs about 0.3 s of CPU. A command that never calls a kernel
(``reduce --sampler leastsq`` of most methods) should not pay it (issue 40's
start-up goal), so a module whose kernels are called from Python marks them
with :func:`lazy_njit` instead of ``numba.njit``: the decorator only remembers
the function, and the first call imports numba and compiles it with the same
options. numba's cache keys on the function's file, name and first line, so the
compiled code cached by ``tools/warm_numba.py`` is the one loaded.

A kernel that another kernel calls must be a real numba function when the
caller compiles: such modules (:mod:`eclipsebench.photometry.kernels`) keep
``numba.njit``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["lazy_njit"]


class LazyKernel:
    """A function to be compiled by ``numba.njit(**options)`` when first called.

    Examples
    --------
    >>> @lazy_njit(cache=False)
    ... def twice(x):
    ...     return 2.0 * x
    >>> twice.dispatcher is None
    True
    >>> twice(1.5), twice.dispatcher is not None
    (3.0, True)
    """

    def __init__(self, py_func: Callable, options: dict[str, Any]):
        self.py_func = py_func
        self.options = options
        self.dispatcher: Any = None
        self.__name__ = py_func.__name__
        self.__qualname__ = py_func.__qualname__
        self.__doc__ = py_func.__doc__
        self.__module__ = py_func.__module__
        self.__wrapped__ = py_func

    def compiled(self):
        """The numba dispatcher (numba imported and the function compiled or loaded)."""
        if self.dispatcher is None:
            from numba import njit

            self.dispatcher = njit(**self.options)(self.py_func)
        return self.dispatcher

    def __call__(self, *args):
        return self.compiled()(*args)


def lazy_njit(**options) -> Callable[[Callable], LazyKernel]:
    """``numba.njit(**options)``, applied at the function's first call (:class:`LazyKernel`)."""
    def wrap(py_func: Callable) -> LazyKernel:
        return LazyKernel(py_func, options)
    return wrap
