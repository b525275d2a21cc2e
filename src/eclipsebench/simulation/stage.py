"""The simulate stage: the challenge's engine tasks (one per AOR, the calibration set, one per
epoch, ``truth.ecsv`` last), their resume checks, the plans and the bytes they write.
"""

from __future__ import annotations

import json
from functools import partial
from pathlib import Path

from astropy.table import Table

from ..astro.catalogue import system_for
from ..astro.events import event_for
from ..astro.orbit import conjunction_time_bmjd
from ..config import Config, dump_toml, to_mapping
from ..engine.layout import SimulationLayout
from ..engine.tasks import Task
from ..errors import InputError
from ..io.atomic import write_text
from ..io.bcd_write import bcd_path, bunc_path
from ..progress import get_logger
from .aor import simulate_aor
from .calibration import write_calibration_set
from .from_config import light_curve_of, readout_from_config
from .plan import SECONDS_PER_DAY, EpochPlan, plan_challenge
from .truth import TRUTH_COLUMNS, write_epoch, write_truth

__all__ = ['challenge_plans', 'plan_simulate_tasks', 'simulated_bytes', 'CUBE_HEADER_BYTES', 'simulate_aor_task', 'calibration_task', 'epoch_task', 'truth_task']

log = get_logger("simulate")


# Module-level so that Dask can ship them to worker processes.
def simulate_aor_task(cfg: Config, plan: EpochPlan, aor_index: int, out_dir: str,
                      seed: int) -> None:
    """Render and write one AOR (:func:`simulate_aor`) with the process's cached L(t)."""
    try:
        simulate_aor(cfg, plan, aor_index, out_dir, seed, light_curve=light_curve_of(cfg))
    except InputError as exc:  # ConfigError/DataError do not survive pickling
        raise InputError(str(exc)) from None


def calibration_task(cfg: Config, out_dir: str) -> None:
    """The KR/Pmap calibration-star set (``DIR/calibration/pmap_calibration.fits``)."""
    try:
        write_calibration_set(cfg, out_dir)
    except InputError as exc:  # ConfigError/DataError do not survive pickling
        raise InputError(str(exc)) from None


def epoch_task(cfg: Config, plan: EpochPlan, out_dir: str, seed: int) -> None:
    """One epoch's light-curve table and truth row, once its AORs are on disk."""
    write_epoch(cfg, plan, Path(out_dir), light_curve_of(cfg), seed)


def truth_task(cfg: Config, out_dir: str, epochs: list[int]) -> None:
    """``config.toml`` and ``truth.ecsv`` (last) from the epochs' truth rows."""
    out = Path(out_dir)
    write_text(SimulationLayout(out).config, dump_toml(to_mapping(cfg)))
    write_truth([json.loads(SimulationLayout(out).epoch_marker(e).read_text()) for e in epochs],
                out)


def _cubes_exist(out_dir: str, aorkey: int, n_cubes: int, *outputs: Path,
                 channel: int = 2) -> bool:
    """Check of an AOR task: every cube its truth marker stands for is on disk."""
    return all(bcd_path(Path(out_dir), aorkey, c, channel).is_file()
               and bunc_path(Path(out_dir), aorkey, c, channel).is_file()
               for c in range(n_cubes))


def _epoch_row_ok(epoch: int, lightcurve: Path, marker: Path) -> bool:
    """Check of an epoch task: the truth row parses and is this epoch's."""
    row = json.loads(Path(marker).read_text())
    return isinstance(row, dict) and row.get("epoch") == epoch and "t_ecl_bmjd" in row


def _truth_ok(config: Path, truth: Path) -> bool:
    """Check of the truth task: ``truth.ecsv`` reads and has its columns."""
    table = Table.read(truth, format="ascii.ecsv")
    return all(c in table.colnames for c in TRUTH_COLUMNS)


#: A simulated cube's FITS header: three 2880-byte blocks (measured on ``AorWriter``'s).
CUBE_HEADER_BYTES = 3 * 2880


def simulated_bytes(cfg: Config) -> int:
    """Bytes of the BCD and BUNC cubes a simulation of ``cfg`` writes (the calibration set,
    light curves and truth, a few MB, aside): each cube's float32 frames padded to FITS
    blocks, and its header."""
    ny, nx = readout_from_config(cfg).shape
    system = system_for(cfg.system)
    total = 0
    for plan in plan_challenge(cfg.observation, cfg.challenge.epochs, system.period_days,
                               cfg.challenge.seed, system=system):  # challenge_plans, unwarned
        for aor in plan.aors:
            data = aor.frames_per_cube * ny * nx * 4
            total += 2 * aor.n_cubes * (data + (-data) % 2880 + CUBE_HEADER_BYTES)
    return total


def challenge_plans(cfg: Config) -> list[EpochPlan]:
    """The observing plans of every epoch (:func:`.plan.plan_challenge`).

    An epoch whose frames hold no eclipse of the planet (another planet with
    the XO-3b challenge's start times, say) is planned, since a simulation
    without an eclipse has its uses (noise and pointing studies), but a warning
    names it and ``observation.start_times_jd``; its truth row has no eclipse
    time (NaN). With ``observation.event = "transit"`` the windows are moved to
    the transits (:func:`.plan.transit_window_starts_bmjd`) and the warning is
    about an epoch without a transit; a phase curve (``"phase-curve"``,
    :func:`.plan.phase_curve_main_cubes`) is warned about when it lacks either.
    """
    system = system_for(cfg.system)
    event = event_for(cfg.observation.event)
    plans = plan_challenge(cfg.observation, cfg.challenge.epochs, system.period_days,
                           cfg.challenge.seed, system=system)
    for plan in plans:
        t0 = plan.start_bmjd
        t1 = t0 + plan.duration_s / SECONDS_PER_DAY
        for name in event.observed:
            t_event = float(conjunction_time_bmjd(system, 0.5 * (t0 + t1), name))
            if not t0 <= t_event <= t1:
                log.warning("epoch %d (%.4f-%.4f BMJD) holds no %s of %s (the nearest is at "
                            "%.4f BMJD): set observation.start_times_jd (JD - 2455000) a few "
                            "hours before its %ss to simulate one", plan.epoch, t0, t1, name,
                            system.name, t_event, name)
    return plans


def plan_simulate_tasks(cfg: Config, out_dir: str | Path, *, calibration: bool | None = None,
                        prefix: str = "simulate") -> list[Task]:
    """The simulate stage's tasks for the challenge folder ``out_dir``.

    Keys: ``<prefix>/r<AORKEY>`` (the longest AORs first: keeps every worker
    busy), ``<prefix>/calibration``, ``<prefix>/epoch_NN`` and
    ``<prefix>/truth`` (``truth.ecsv``; the task later stages depend on).

    Parameters
    ----------
    cfg : Config
    out_dir : path
        The challenge folder (``docs/contracts.md``).
    calibration : bool, optional
        Write the calibration-star set (default ``simulation.write_calibration``;
        never when ``simulation.calibration_frames`` is 0).
    prefix : str
        Key prefix (the run's systematics-free twin uses ``simulate_flat``).
    """
    out = Path(out_dir)
    paths = SimulationLayout(out)
    seed = cfg.challenge.seed
    calibration = cfg.simulation.write_calibration if calibration is None else calibration
    calibration = bool(calibration) and cfg.simulation.calibration_frames > 0
    plans = challenge_plans(cfg)
    tasks: list[Task] = []
    aors = sorted(((plan, i) for plan in plans for i in range(len(plan.aors))),
                  key=lambda pi: -pi[0].aors[pi[1]].n_cubes)
    for plan, i in aors:
        aor = plan.aors[i]
        tasks.append(Task(f"{prefix}/r{aor.aorkey}", "simulate", simulate_aor_task,
                          (cfg, plan, i, str(out), seed), (paths.aor_state(aor.aorkey),),
                          check=partial(_cubes_exist, str(out), aor.aorkey, aor.n_cubes,
                                        channel=cfg.observation.channel)))
    truth_deps = []
    if calibration:
        tasks.append(Task(f"{prefix}/calibration", "simulate", calibration_task, (cfg, str(out)),
                          (paths.calibration,)))
        truth_deps.append(f"{prefix}/calibration")
    for plan in plans:
        key = f"{prefix}/epoch_{plan.epoch:02d}"
        tasks.append(Task(key, "simulate", epoch_task, (cfg, plan, str(out), seed),
                          (paths.epoch_lightcurve(plan.epoch), paths.epoch_marker(plan.epoch)),
                          tuple(f"{prefix}/r{a.aorkey}" for a in plan.aors),
                          check=partial(_epoch_row_ok, plan.epoch)))
        truth_deps.append(key)
    tasks.append(Task(f"{prefix}/truth", "simulate", truth_task,
                      (cfg, str(out), [p.epoch for p in plans]),
                      (paths.config, paths.truth), tuple(truth_deps),
                      check=_truth_ok))
    return tasks
