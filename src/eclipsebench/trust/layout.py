"""Where each file of a trust run goes.

The folder of a trust run::

    DIR/trust_config.json              the settings (guards resume)
    DIR/eclipsebench.json              the folder's kind and its inputs by content
                                       (``eclipsebench.engine.folder``)
    DIR/run.lock                       held while a run works in DIR (every runner's lock)
    DIR/real/<method>.json (+.lc.ecsv) the real table reduced by each method (or why not)
    DIR/recipe.npz, DIR/recipe.json    what every twin shares (L(t), sky, motion, flux)
    DIR/twins/twin_NNN.fits            each twin's photometry table
    DIR/twins/<method>/twin_NNN.json   each twin reduced by each method
    DIR/trust.json, DIR/trust.ecsv     the answer (``eclipsebench.trust.score``)
    DIR/report/index.html              figures and the table
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..engine.folder import LOCK, MARKER

__all__ = ["TrustLayout"]


@dataclass(frozen=True)
class TrustLayout:
    """Where each file of a trust run goes (module docstring)."""

    root: Path

    @property
    def config(self) -> Path:
        return self.root / "trust_config.json"

    @property
    def lock(self) -> Path:
        return self.root / LOCK

    @property
    def marker(self) -> Path:
        return self.root / MARKER

    def real(self, method: str) -> Path:
        return self.root / "real" / f"{method}.json"

    @property
    def recipe_npz(self) -> Path:
        return self.root / "recipe.npz"

    @property
    def recipe_json(self) -> Path:
        return self.root / "recipe.json"

    def twin(self, i: int) -> Path:
        return self.root / "twins" / f"twin_{i:03d}.fits"

    def twin_result(self, method: str, i: int) -> Path:
        return self.root / "twins" / method / f"twin_{i:03d}.json"

    @property
    def result(self) -> Path:
        return self.root / "trust.json"

    @property
    def table(self) -> Path:
        return self.root / "trust.ecsv"

    @property
    def report(self) -> Path:
        return self.root / "report" / "index.html"
