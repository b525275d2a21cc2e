"""``[reduce]``: the shared astrophysical model and the fitter."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from .base import check


@dataclass(frozen=True)
class ReduceSection:
    """Options shared by every decorrelation method.

    One astrophysical model (eclipse, phase curve, optional ramp) is shared by
    all methods so that they differ only in their systematics model.
    """

    phase: Literal["flat", "linear", "quadratic", "sinusoid"] = "quadratic"
    ramp: Literal["none", "linear", "exponential"] = "none"
    sampler: Literal["leastsq", "mcmc"] = "leastsq"
    mcmc_walkers: int = 32
    mcmc_steps: int = 2000

    def validate(self) -> None:
        check(self.mcmc_walkers >= 4 and self.mcmc_walkers % 2 == 0, "mcmc_walkers",
              "an even number of walkers >= 4")
        check(self.mcmc_steps >= 100, "mcmc_steps", "at least 100 steps")
