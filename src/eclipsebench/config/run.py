"""``[challenge]`` and ``[run]``: what to run and where."""

from __future__ import annotations

from dataclasses import dataclass

from ..io.paths import SAFE_NAME, is_safe_name
from ..limits import MAX_BOOTSTRAP, MAX_EPOCHS, MAX_WORKERS, check_size
from .base import check


@dataclass(frozen=True)
class ChallengeSection:
    """Identity and size of a challenge: its name, seed and number of epochs."""

    name: str = "xo3b-2015"
    seed: int = 2015
    epochs: int = 10

    def validate(self) -> None:
        check(bool(self.name.strip()), "name", "a non-empty name")
        check(is_safe_name(self.name), "name",
              f"a name that can be a folder name ({SAFE_NAME.pattern}, at most 100 "
              f"characters), got {self.name!r}")
        check(self.seed >= 0, "seed", "a non-negative integer")
        check(self.epochs >= 1, "epochs", "at least 1 epoch")
        check_size("epochs", self.epochs, MAX_EPOCHS, "epochs", config=True)


@dataclass(frozen=True)
class RunSection:
    """How the runner executes and what it adds to the statistics.

    Attributes
    ----------
    methods : list of str
        Methods to run (empty: every registered method).
    workers : int
        1: in-process; N >= 2: a local Dask cluster of N processes.
    scheduler : str
        Must stay empty: an existing Dask scheduler receives the run's tasks
        (code), so it is named on the command line (``--scheduler``) or in
        the environment (``ECLIPSEBENCH_SCHEDULER``), never by a configuration
        file someone may hand you. Kept so that older files still read.
    empirical_photon_limit : bool
        Simulate systematics-free twins of every epoch (no pointing motion,
        the same noise seeds) and reduce them, for the empirical photon limit.
    photon_limit_method : str
        Method that reduces the twins (empty: the first method run).
    f_in : float
        Fraction of frames in eclipse for the analytic photon limit (0: from
        the eclipse geometry of the simulated epochs; the paper used 1/3).
    bootstrap : int
        Bootstrap resamples for the intervals on R, r and a (0: none).
    report : bool
        Write the report (figures, tables, index.html).
    lightcurve_epoch : int
        Epoch whose decorrelated light curves the report shows (the paper's
        5th; the last epoch when there are fewer).
    profiles : list of str
        The comparisons to run: ``controlled`` (every method with the shared
        ``[reduce]`` settings) and/or ``paper`` (each method as its team ran
        it; ``eclipsebench.fit.profiles``). The first is the summary's top level.
    """

    methods: tuple[str, ...] = ()  # empty: every registered method
    workers: int = 2
    scheduler: str = ""  # always empty: --scheduler or ECLIPSEBENCH_SCHEDULER name one
    empirical_photon_limit: bool = True
    photon_limit_method: str = ""
    f_in: float = 0.0
    bootstrap: int = 2000
    report: bool = True
    lightcurve_epoch: int = 5
    profiles: tuple[str, ...] = ("controlled", "paper")

    def validate(self) -> None:
        check(len(self.profiles) >= 1 and len(set(self.profiles)) == len(self.profiles)
              and all(p in ("controlled", "paper") for p in self.profiles), "profiles",
              'one or both of "controlled" and "paper", each once')
        check(not self.scheduler.strip(), "scheduler",
              "no scheduler in a configuration (it would receive the run's tasks); name one "
              "with --scheduler or the environment variable ECLIPSEBENCH_SCHEDULER")
        check(self.workers >= 1, "workers", "at least 1 worker")
        check_size("workers", self.workers, MAX_WORKERS, "workers", config=True)
        check(0.0 <= self.f_in < 1.0, "f_in", "0 (from the eclipse geometry) or a fraction in (0, 1)")
        check(self.bootstrap >= 0, "bootstrap", "a non-negative number of resamples")
        check_size("bootstrap", self.bootstrap, MAX_BOOTSTRAP, "resamples", config=True)
        check(self.lightcurve_epoch >= 1, "lightcurve_epoch", "an epoch number >= 1")
