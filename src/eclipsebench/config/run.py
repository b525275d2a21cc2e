"""``[challenge]`` and ``[run]``: what to run and where."""

from __future__ import annotations

from dataclasses import dataclass

from .base import check


@dataclass(frozen=True)
class ChallengeSection:
    """Identity and size of a challenge: its name, seed and number of epochs."""

    name: str = "xo3b-2015"
    seed: int = 2015
    epochs: int = 10

    def validate(self) -> None:
        check(bool(self.name.strip()), "name", "a non-empty name")
        check(self.seed >= 0, "seed", "a non-negative integer")
        check(self.epochs >= 1, "epochs", "at least 1 epoch")


@dataclass(frozen=True)
class RunSection:
    """How the runner executes: methods, workers, scheduler."""

    methods: tuple[str, ...] = ()  # empty: every registered method
    workers: int = 2
    scheduler: str = ""  # address of an existing Dask scheduler; empty: a local cluster

    def validate(self) -> None:
        check(self.workers >= 1, "workers", "at least 1 worker")
