"""The run folder of ``eclipsebench run``: the one place that says where each file goes.

::

    DIR/run_config.toml                    the configuration of the run (guards resume)
    DIR/eclipsebench.json                  the folder's kind and its inputs by content (.folder)
    DIR/run.lock                           held (pid) while a run works in DIR
    DIR/simulation/                        the simulated challenge (docs/contracts.md)
    DIR/simulation_flat/                   its systematics-free twin (empirical photon limit)
    DIR/photometry[_flat]/epoch_NN.fits    one photometry table per epoch
    DIR/results[_flat]/<method>/epoch_NN.json (+ .lc.ecsv)   one reduction per epoch x method
                                           (the controlled profile)
    DIR/results_paper/<method>/epoch_NN.json (+ .lc.ecsv)    the same in the paper profile
    DIR/joint/<method>[_chN].json          a campaign's joint fit of every epoch (one depth)
    DIR/depths.ecsv                        method, epoch, depth_ppm, error_ppm (controlled)
    DIR/depths_paper.ecsv                  the same in the paper profile
    DIR/summary.json                       statistics + photon limits + truth + seed + config
    DIR/report/index.html                  figures and tables
    DIR/timings.ecsv                       when, where and how long each task of the
                                           last invocation ran (not part of the results)

Beside each task's last output the engine keeps the task's stamp,
``.<name>.task.json`` (:mod:`.engine`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..io.paths import check_name
from .folder import LOCK, MARKER

__all__ = ["Layout", "SimulationLayout", "STATE_DIR"]

#: The simulated challenge's resume state: each AOR's truth and each epoch's truth row.
STATE_DIR = ".simstate"


@dataclass(frozen=True)
class Layout:
    """Where each task of a run writes (see the module docstring)."""

    root: Path

    def sim(self, flat: bool = False) -> Path:
        return self.root / ("simulation_flat" if flat else "simulation")

    def photometry(self, epoch: int, flat: bool = False) -> Path:
        return self.root / ("photometry_flat" if flat else "photometry") / f"epoch_{epoch:02d}.fits"

    def result(self, method: str, epoch: int, flat: bool = False,
               profile: str = "controlled") -> Path:
        check_name("method", method)  # one path component: never out of the run folder
        folder = "results_flat" if flat else "results"
        if profile != "controlled":
            folder += f"_{profile}"
        return self.root / folder / method / f"epoch_{epoch:02d}.json"

    def result_lightcurve(self, method: str, epoch: int, flat: bool = False,
                          profile: str = "controlled") -> Path:
        """The decorrelated light curve written beside a result."""
        return self.result(method, epoch, flat, profile).with_suffix(".lc.ecsv")

    def truth(self, flat: bool = False) -> Path:
        return SimulationLayout(self.sim(flat)).truth

    def truth_lightcurve(self, epoch: int, flat: bool = False) -> Path:
        return SimulationLayout(self.sim(flat)).epoch_lightcurve(epoch)

    def calibration(self) -> Path:
        return SimulationLayout(self.sim()).calibration

    def joint(self, name: str) -> Path:
        """A campaign's joint fit of one method over its epochs (``name``: the method, with
        ``_chN`` when the campaign has several channels)."""
        check_name("method", name)
        return self.root / "joint" / f"{name}.json"

    @property
    def depths(self) -> Path:
        return self.depths_of("controlled")

    def depths_of(self, profile: str) -> Path:
        """The depth table of one profile (``depths.ecsv`` for the controlled one)."""
        return self.root / ("depths.ecsv" if profile == "controlled" else f"depths_{profile}.ecsv")

    @property
    def summary(self) -> Path:
        return self.root / "summary.json"

    @property
    def timings(self) -> Path:
        return self.root / "timings.ecsv"

    @property
    def report(self) -> Path:
        return self.root / "report" / "index.html"

    @property
    def run_config(self) -> Path:
        return self.root / "run_config.toml"

    @property
    def lock(self) -> Path:
        return self.root / LOCK

    @property
    def marker(self) -> Path:
        return self.root / MARKER


@dataclass(frozen=True)
class SimulationLayout:
    """Where each file of a simulated challenge goes (``docs/contracts.md``): the folder
    ``eclipsebench simulate --out DIR`` writes, and a run's ``DIR/simulation``::

        DIR/config.toml                        the configuration simulated
        DIR/truth.ecsv                         one row per epoch (written last)
        DIR/lightcurves/epoch_NN.ecsv          the true L(t) and position per frame
        DIR/calibration/pmap_calibration.fits  the KR/Pmap calibration-star set
        DIR/.simstate/r<AORKEY>.npz            an AOR's per-frame truth, after its cubes
        DIR/.simstate/epoch_NN.json            an epoch's truth row, after its light curve

    The cubes' own paths are :func:`eclipsebench.io.bcd_write.bcd_path`'s.

    Examples
    --------
    >>> SimulationLayout(Path("sim")).epoch_marker(3).as_posix()
    'sim/.simstate/epoch_03.json'
    """

    root: Path

    def __post_init__(self) -> None:
        object.__setattr__(self, "root", Path(self.root))

    @property
    def config(self) -> Path:
        return self.root / "config.toml"

    @property
    def truth(self) -> Path:
        return self.root / "truth.ecsv"

    @property
    def calibration(self) -> Path:
        return self.root / "calibration" / "pmap_calibration.fits"

    def epoch_lightcurve(self, epoch: int) -> Path:
        return self.root / "lightcurves" / f"epoch_{epoch:02d}.ecsv"

    def aor_state(self, aorkey: int) -> Path:
        return self.root / STATE_DIR / f"r{aorkey}.npz"

    def epoch_marker(self, epoch: int) -> Path:
        return self.root / STATE_DIR / f"epoch_{epoch:02d}.json"
