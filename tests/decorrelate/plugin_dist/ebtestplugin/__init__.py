"""A method plugin as another package would ship it (used by the contract tests).

Registered through the entry point ``eclipsebench.methods: test-quadgain``
declared in ``ebtestplugin-0.1.dist-info/entry_points.txt`` beside it: a
multiplicative quadratic gain in (x, y), solved linearly for each ``astro``.
"""

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

import eclipsebench as eb
from eclipsebench.config import check


@dataclass(frozen=True)
class QuadGainOptions(eb.MethodOptions):
    """Options of ``test-quadgain``."""

    degree: int = 2

    def validate(self) -> None:
        check(1 <= self.degree <= 3, "degree", "an integer 1-3")


class QuadGain(eb.Systematics):
    """flux = astro * P(x, y), a polynomial of ``degree`` in the centroids."""

    name: ClassVar[str] = "test-quadgain"
    requires: ClassVar[tuple[str, ...]] = ("x", "y")
    Options: ClassVar[type] = QuadGainOptions
    description: ClassVar[str] = "test plugin: polynomial gain in (x, y)"

    def __init__(self, data, options: Any = None, *, context=None, **kwargs) -> None:
        super().__init__(data, options, context=context, **kwargs)
        dx = np.asarray(data.x, float) - np.mean(data.x)
        dy = np.asarray(data.y, float) - np.mean(data.y)
        terms = [dx**i * dy**j for i in range(self.options.degree + 1)
                 for j in range(self.options.degree + 1 - i)]
        self._design = np.column_stack(terms)
        w = 1.0 / np.asarray(data.flux_err, float)
        self._pinv_w = np.linalg.pinv(self._design * w[:, None]) * w[None, :]

    def predict(self, astro, theta=None):
        astro = np.asarray(astro, float)
        return astro * (self._design @ (self._pinv_w @ (self.data.flux / astro)))

    def diagnostics(self) -> dict:
        return {"n_terms": int(self._design.shape[1])}

    def n_effective_params(self) -> int:
        return int(self._design.shape[1])
