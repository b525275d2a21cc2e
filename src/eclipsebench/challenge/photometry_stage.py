"""The photometry stage of a run: one photometry table per simulated epoch.

:func:`plan_photometry_tasks` turns a configuration, the run folder
(:class:`eclipsebench.engine.layout.Layout`) and the epochs' observing plans into engine tasks
``photometry[_flat]/epoch_NN``; :func:`photometry_task` runs the photometry
package's pure pipeline (:func:`eclipsebench.photometry.pipeline.process_epoch`)
on one epoch's AOR folders. (Its home is here because ``photometry/`` has no
knowledge of run folders; it could move there as ``photometry/stage.py``.)
"""

from __future__ import annotations

from pathlib import Path

from ..config import Config
from ..engine.layout import Layout
from ..engine.tasks import Task
from ..io.bcd_read import find_bcd_files, group_epochs, read_bcd_header
from ..photometry.pipeline import process_epoch
from ..photometry.table import read_photometry, write_photometry
from ..simulation.plan import EpochPlan

__all__ = ["photometry_key", "photometry_task", "plan_photometry_tasks", "PHOTOMETRY_COLUMNS"]

#: Columns the later stages read from a photometry table.
PHOTOMETRY_COLUMNS = ("time_bmjd", "flux", "background", "x", "y", "noise_pixels")


def photometry_key(epoch: int, flat: bool = False) -> str:
    """The task key of one epoch's photometry."""
    return f"photometry{'_flat' if flat else ''}/epoch_{epoch:02d}"


def photometry_task(cfg: Config, sim_dir: str, epoch: int, aorkeys: list[int],
                    out_path: str) -> None:
    """Photometry of one simulated epoch (its AOR folders) into ``out_path``."""
    root = Path(sim_dir)
    files = [p for a in aorkeys for p in find_bcd_files(root / f"r{a}")]
    epochs = group_epochs([read_bcd_header(p) for p in files],
                          gap_days=cfg.photometry.epoch_gap_days)
    if len(epochs) != 1 or epochs[0].number != epoch:
        raise RuntimeError(f"AORs {aorkeys} of epoch {epoch} were grouped as epochs "
                           f"{[e.number for e in epochs]}")
    write_photometry(process_epoch(epochs[0], cfg.photometry, input_root=root), out_path)


def photometry_table_ok(path: Path) -> bool:
    """Resume check: the table reads and has the columns the later stages use."""
    table = read_photometry(path)
    return len(table) > 0 and all(c in table.colnames for c in PHOTOMETRY_COLUMNS)


def plan_photometry_tasks(cfg: Config, layout: Layout, plans: list[EpochPlan], *,
                          flat: bool = False, after: tuple[str, ...] = ()) -> list[Task]:
    """One photometry task per epoch of ``plans``, reading ``layout.sim(flat)``.

    ``after``: the keys of the tasks that write the simulated cubes (the
    simulate stage's ``truth`` task).
    """
    sim = layout.sim(flat)
    tasks = []
    for plan in plans:
        out = layout.photometry(plan.epoch, flat)
        tasks.append(Task(photometry_key(plan.epoch, flat), "photometry", photometry_task,
                          (cfg, str(sim), plan.epoch, [a.aorkey for a in plan.aors], str(out)),
                          (out,), tuple(after), check=photometry_table_ok))
    return tasks
