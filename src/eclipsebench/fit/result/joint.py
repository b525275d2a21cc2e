"""The result of a joint fit of several epochs (one common depth): :class:`JointResult`.

:func:`eclipsebench.fit.joint.reduce_joint` returns it; ``to_dict()`` is what
its ``RESULT.json`` holds (``"joint": true``) and :meth:`JointResult.from_dict`
reads it back.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from ... import __version__
from ...errors import InputError
from .display import html_repr, text_repr

__all__ = ["JointResult"]


@dataclass(frozen=True)
class JointResult:
    """One depth common to several epochs; every other parameter per epoch."""

    method: str
    epochs: tuple[int | None, ...]
    depth_ppm: float
    depth_err_ppm: float
    depth_err_jacobian_ppm: float
    beta_red: float
    chi2_red: float
    bic: float
    aic: float
    k: int
    n_points: int
    phase: str
    converged: bool
    t_ecl_bmjd: tuple[float, ...]
    per_epoch: tuple[dict[str, Any], ...]

    @property
    def depth_combined_ppm(self) -> float:
        """Inverse-variance mean of the epochs' depths fitted alone."""
        w = 1.0 / np.array([e["depth_alone_err_ppm"] for e in self.per_epoch]) ** 2
        return float(np.sum(w * [e["depth_alone_ppm"] for e in self.per_epoch]) / np.sum(w))

    @property
    def depth_combined_err_ppm(self) -> float:
        """``1 / sqrt(sum 1 / sigma_i^2)`` of the epochs' errors fitted alone."""
        w = 1.0 / np.array([e["depth_alone_err_ppm"] for e in self.per_epoch]) ** 2
        return float(1.0 / np.sqrt(np.sum(w)))

    def to_dict(self) -> dict[str, Any]:
        """The result as JSON-ready data (:meth:`from_dict` reads it back); with its BIC's
        points (every epoch's, summed; bins for a binned method) and the software version."""
        return {"method": self.method, "joint": True, "epochs": list(self.epochs),
                "depth_ppm": self.depth_ppm,
                "depth_combined_ppm": self.depth_combined_ppm,
                "depth_combined_err_ppm": self.depth_combined_err_ppm,
                "depth_err_ppm": self.depth_err_ppm,
                "depth_err_jacobian_ppm": self.depth_err_jacobian_ppm,
                "beta_red": self.beta_red, "chi2_red": self.chi2_red, "bic": self.bic,
                "aic": self.aic, "k": self.k, "n_points": self.n_points, "phase": self.phase,
                "converged": self.converged, "t_ecl_bmjd": list(self.t_ecl_bmjd),
                "per_epoch": list(self.per_epoch), "bic_n_points": self.n_points,
                "bic_data": f"{self.n_points} points of {len(self.epochs)} epochs",
                "eclipsebench_version": __version__}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: object = "joint result"
                  ) -> JointResult:
        """The result :meth:`to_dict` wrote; InputError naming ``source`` when a field is
        missing."""
        try:
            kw = {f.name: data[f.name] for f in fields(cls)}
        except KeyError as exc:
            raise InputError(f"{source}: not a joint result (no {exc})") from None
        for name in ("epochs", "t_ecl_bmjd", "per_epoch"):
            kw[name] = tuple(kw[name])
        for name in ("beta_red", "chi2_red", "bic", "aic"):
            kw[name] = math.nan if kw[name] is None else kw[name]
        return cls(**kw)

    def _shown(self) -> dict[str, Any]:
        """The fields :func:`~eclipsebench.fit.result.display.text_repr` and
        :func:`~eclipsebench.fit.result.display.html_repr` show."""
        return {"method": self.method, "epoch": ", ".join(str(e) for e in self.epochs),
                "depth_ppm": self.depth_ppm, "depth_err_ppm": self.depth_err_ppm,
                "combined_ppm": self.depth_combined_ppm, "beta_red": self.beta_red,
                "chi2_red": self.chi2_red,
                "BIC": f"{self.bic:.1f} on {self.n_points} points",
                "phase": self.phase, "converged": self.converged}

    def __repr__(self) -> str:
        return text_repr("JointResult", self._shown())

    def _repr_html_(self) -> str:
        return html_repr("JointResult", self._shown())
