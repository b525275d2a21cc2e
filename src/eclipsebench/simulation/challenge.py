"""Simulate a whole data challenge: plans, pointing, cubes, truth, calibration set.

``simulate_challenge(config, out_dir)`` writes the folder described in
``docs/contracts.md``::

    DIR/config.toml, DIR/truth.ecsv, DIR/r<AORKEY>/ch<N>/bcd/*_bcd.fits (+ _bunc),
    DIR/lightcurves/epoch_NN.ecsv, DIR/calibration/pmap_calibration.fits

This module is the simulate *stage*: pure functions (:func:`simulate_aor`,
:func:`epoch_truth_row`, ...), the module-level task functions and the
planner :func:`plan_simulate_tasks`, which turns a configuration and a
challenge folder into engine tasks (:mod:`eclipsebench.engine.tasks`):
one per AOR, the calibration set, one per epoch (its light-curve table and
truth row) and ``truth.ecsv`` last. ``simulate_challenge`` runs them on the
engine, as ``eclipsebench run`` does among its other stages.

Every random stream is keyed by what it is for (``("simulate", epoch,
"pointing")``, ``("simulate", epoch, aorkey, expid, "photon")``, ...), so the
bytes depend on the seed only, never on the number of workers or the order.

Resuming: an AOR task writes its cubes, then ``DIR/.simstate/r<AORKEY>.npz``
(its per-frame truth) last; an epoch task writes its light-curve table, then
``DIR/.simstate/epoch_NN.json``. The engine's stamps (``.<name>.task.json``)
record the hashes of those files and of what they were made from; a rerun
redoes only what is missing or not whole.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

from ..config import Config, dump_toml, from_mapping, to_mapping
from ..config.base import load_toml
from ..engine.layout import SimulationLayout
from ..engine.tasks import check_outputs_inside, run_tasks
from ..errors import InputError
from ..io.atomic import write_text
from ..io.paths import check_links_inside
from .from_config import draw_epoch_pointing, light_curve_of
from .stage import challenge_plans, plan_simulate_tasks
from .star import make_star_imager

__all__ = ["simulate_challenge", "ChallengeResult"]


@dataclass
class ChallengeResult:
    """What :func:`simulate_challenge` did."""

    out_dir: Path
    epochs: int
    truth_rows: list[dict]
    files: int
    skipped_aors: int
    calibration: Path | None

    def to_dict(self) -> dict:
        """Summary for ``--json``."""
        return {"out_dir": str(self.out_dir), "epochs": self.epochs, "files": self.files,
                "truth_rows": len(self.truth_rows), "skipped_aors": self.skipped_aors,
                "calibration": None if self.calibration is None else str(self.calibration),
                "truth": self.truth_rows}


def simulate_challenge(cfg: Config, out_dir: str | os.PathLike[str], *, workers: int | None = None,
                       calibration: bool | None = None) -> ChallengeResult:
    """Simulate ``cfg.challenge.epochs`` epochs (and the calibration set) into ``out_dir``.

    Plans the simulate stage (:func:`plan_simulate_tasks`) and runs it on the
    task engine (:func:`eclipsebench.engine.tasks.run_tasks`).

    Parameters
    ----------
    cfg : Config
        The effective configuration (seed in ``challenge.seed``).
    out_dir : path
        The challenge folder; existing complete AORs and epochs are kept.
    workers : int, optional
        Worker processes (default ``run.workers``); 1 runs in this process.
    calibration : bool, optional
        Write the calibration-star set (default ``simulation.write_calibration``).
    """
    out = Path(out_dir)
    seed = cfg.challenge.seed
    workers = cfg.run.workers if workers is None else int(workers)
    calibration = cfg.simulation.write_calibration if calibration is None else calibration
    calibration = bool(calibration) and cfg.simulation.calibration_frames > 0
    light_curve_of(cfg)  # fail early on a bad [system] (and build L(t) once here)
    make_star_imager(cfg)  # ... on a bad PRF choice
    for epoch in range(1, cfg.challenge.epochs + 1):
        draw_epoch_pointing(cfg, epoch, seed)  # ... and on bad pointing ranges
    tasks = plan_simulate_tasks(cfg, out, calibration=calibration)
    check_links_inside(out)  # no output through a symbolic link out of --out
    check_outputs_inside(tasks, out)
    out.mkdir(parents=True, exist_ok=True)
    config_text = dump_toml(to_mapping(cfg))
    existing = SimulationLayout(out).config
    if existing.is_file() and existing.read_text() != config_text:
        # read back through the current schema: keys added since (with their
        # defaults) are no difference
        try:
            stored = from_mapping(Config, load_toml(existing))
        except InputError:
            stored = None
        if stored != cfg:
            raise InputError(f"--out {out}: holds a challenge simulated with a different "
                             "configuration (see its config.toml); choose another folder")
    write_text(existing, config_text)
    report = run_tasks(tasks, workers=workers, root=out)
    plans = challenge_plans(cfg)
    aor_keys = {f"simulate/r{a.aorkey}" for p in plans for a in p.aors}
    truth_rows = [json.loads(SimulationLayout(out).epoch_marker(p.epoch).read_text())
                  for p in plans]
    n_files = sum(2 * a.n_cubes for p in plans for a in p.aors)
    return ChallengeResult(out_dir=out, epochs=len(plans), truth_rows=truth_rows, files=n_files,
                           skipped_aors=sum(k in aor_keys for k in report.skipped),
                           calibration=SimulationLayout(out).calibration if calibration else None)
