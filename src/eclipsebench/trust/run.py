"""``trust``: twins of a real observation, reduced like it, scored; resumable on the engine.

The folder of a trust run is :class:`~eclipsebench.trust.layout.TrustLayout`.

Two passes on the engine (:func:`eclipsebench.engine.tasks.run_tasks`): the
real reductions first (a method that refuses the real table, such as a pixel
method without stamps or KR/Pmap without a map, is listed as skipped with its
reason), then the recipe, the twins, their reductions and the score. Every
random draw derives from the one seed: twin ``i``'s frames from
``rng(seed, "trust", "twin", i, cube, ...)``, its reductions from the seed
``spawn_ints(seed, "trust", "reduce")`` with epoch ``i``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Table

from ..astro.catalogue import PlanetSystem
from ..config.base import to_mapping
from ..config.reduce import ReduceSection
from ..decorrelate import get_method
from ..decorrelate.base import MethodOptions, parse_method_options
from ..engine.cluster import ClusterOptions, external_security
from ..engine.folder import Input, check_free_space, check_kind, claim, planet_input
from ..engine.lock import run_lock
from ..engine.tasks import RunReport, Task, check_outputs_inside, run_tasks
from ..errors import InputError
from ..fit import reduce as fit_reduce
from ..fit.result import result_ok, write_failure, write_result
from ..io.atomic import write_text
from ..io.digest import file_sha256, files_sha256
from ..io.paths import check_links_inside
from ..io.pmap_files import check_pmap_path
from ..limits import MAX_TWINS
from ..photometry.table import read_table, write_photometry
from ..progress import get_logger
from ..seeding import spawn_ints
from ..simulation.star import StarImager
from .layout import TrustLayout
from .observation import OBSERVATION_FILE, adopt_observation, completed_observation
from .recipe import (
    PILOT_TWIN,
    bounded_recipe,
    build_recipe,
    photometry_options,
    pilot_twin,
    read_recipe,
    write_recipe,
)
from .report import score_task
from .result import TrustResult, read_trust
from .twin import TWIN_MODEL, TwinRecipe, twin_star, twin_table

__all__ = ["TrustSettings", "make_settings", "trust_settings", "run_trust", "twin_batches",
           "MIN_TWINS", "MAX_TWINS", "TWINS_PER_TASK"]

#: Fewer twins give no coverage worth quoting (the upper bound is the stated limit).
MIN_TWINS = 10

log = get_logger("trust")


@dataclass(frozen=True)
class TrustSettings:
    """Everything a trust run depends on (its JSON guards a resumed folder)."""

    table: str
    system: PlanetSystem
    methods: tuple[str, ...]
    n_twins: int
    seed: int
    reduce: ReduceSection
    depth_ppm: float | None = None
    method_options: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    pmap: str | None = None
    #: Each method's options as resolved once by :func:`make_settings` (the
    #: configuration's table, the team's in the paper profile, ``method_options``).
    resolved_options: Mapping[str, MethodOptions] = field(default_factory=dict)
    #: The external inputs by content (the table, the planet's elements, the pixel map
    #: KR/Pmap and the twins would read), computed once by :func:`make_settings`.
    inputs: Mapping[str, Input] = field(default_factory=dict)
    #: Frames of the table (for the estimate of what the run writes).
    table_frames: int = 0
    #: The epoch number the real table's reductions record (its ``EPOCH``, else None),
    #: which their resume check expects (:func:`eclipsebench.fit.result.result_ok`).
    table_epoch: int | None = None

    @property
    def sources(self) -> tuple[str, ...]:
        """The inputs' digests, for the stamp of every task (they all read them)."""
        return tuple(self.inputs[k].sha256 for k in sorted(self.inputs))

    def describe(self) -> dict[str, Any]:
        """A JSON-able view (the guard and the result both record it)."""
        return {"table": self.table, "system": self.system.name, "methods": list(self.methods),
                "n_twins": self.n_twins, "seed": self.seed, "depth_ppm": self.depth_ppm,
                "reduce": to_mapping(self.reduce),
                "method_options": {k: dict(v) for k, v in self.method_options.items()},
                "pmap": self.pmap, "twin_model": TWIN_MODEL}


# ----------------------------------------------------------------------------- tasks
def _reduce(settings: TrustSettings, table, method: str, *, seed: int, epoch: int | None,
            extra_options: Mapping[str, Any] | None = None):
    """``method`` on ``table`` with its resolved options (``extra_options`` over them)."""
    options = parse_method_options(get_method(method), extra_options,
                                   base=settings.resolved_options[method])
    return fit_reduce.reduce_epoch(table, method, options=settings.reduce,
                                   system=settings.system, seed=seed, epoch=epoch,
                                   method_options=options, pmap=settings.pmap)


def real_task(settings: TrustSettings, method: str, out_path: str) -> None:
    """Reduce the real table with ``method``; a method that refuses it records why."""
    try:
        result = _reduce(settings, settings.table, method, seed=settings.seed, epoch=None)
    except InputError as exc:
        write_failure(out_path, method, settings.table_epoch, str(exc))
        return
    write_result(result, out_path)


def recipe_task(settings: TrustSettings, first: str, real_path: str, npz_path: str,
                json_path: str) -> None:
    """The twins' shared recipe from the first method's real fit (and the depth asked for),
    with the real correlated noise a pilot twin reduced by that method lacks."""
    fit = json.loads(Path(real_path).read_text())
    depth = settings.depth_ppm if settings.depth_ppm is not None else float(fit["depth_ppm"])
    if not depth > 0:
        raise InputError(f"{first}: the real depth is {depth:.1f} ppm; twins need a positive "
                         "depth to inject (give --depth PPM)")
    event = settings.reduce.event
    recipe, info = build_recipe(settings.table, settings.system, fit, depth, event,
                                settings.pmap)
    # the pilot's residuals at the least-squares solution: no sampling, no prayer bead
    quick = dataclasses.replace(settings, reduce=dataclasses.replace(
        settings.reduce, sampler="leastsq", prayer_bead_shifts=0))
    extra = shared_options(first, fit, settings.method_options.get(first, {}))

    def pilot_residuals(twin_recipe: TwinRecipe) -> tuple[np.ndarray, np.ndarray]:
        return _residuals(_reduce(quick, pilot_twin(twin_recipe, seed=settings.seed), first,
                                  seed=spawn_ints(settings.seed, "trust", "reduce")[0],
                                  epoch=PILOT_TWIN, extra_options=extra).lightcurve_table())

    real = Table.read(Path(real_path).with_suffix(".lc.ecsv"), format="ascii.ecsv")
    try:
        recipe, info = bounded_recipe(recipe, info, settings.pmap, _residuals(real),
                                      pilot_residuals)
    except InputError as exc:
        info = {**info, "correlated_noise": {"method": None, "why": f"pilot twin: {exc}"}}
    write_recipe(recipe, info, Path(npz_path), Path(json_path))


def _residuals(lightcurve: Table) -> tuple[np.ndarray, np.ndarray]:
    """``(time_bmjd, residual)`` of a result's light curve (``RESULT.lc.ecsv``)."""
    return (np.asarray(lightcurve["time_bmjd"], float),
            np.asarray(lightcurve["residual"], float))


#: Twins simulated per task: they share the recipe (read once per process) and the star
#: (its PRF tables and gain, built once per task), and are measured in memory.
TWINS_PER_TASK = 5

#: The recipe last read in this process, with its star: ``(key, recipe, star)``
#: (:func:`_recipe_and_star`).
_RECIPE_HELD: list[tuple[tuple, TwinRecipe, StarImager]] = []


def _recipe_and_star(table: str, npz_path: str, json_path: str
                     ) -> tuple[TwinRecipe, StarImager]:
    """The recipe of ``npz_path``/``json_path`` for ``table`` and the star its twins are
    rendered with (:func:`~eclipsebench.trust.twin.twin_star`: its PRF tables and gain,
    0.4 s to build), both made once per process.

    The real table is read again only when it is another file (path, inode, size or
    modification time) or the recipe's bytes changed, so a worker's twin tasks after
    its first do not reread it.
    """
    info = os.stat(table)
    key = (str(table), info.st_ino, info.st_size, info.st_mtime_ns,
           hashlib.sha256(Path(npz_path).read_bytes()).hexdigest(),
           hashlib.sha256(Path(json_path).read_bytes()).hexdigest())
    if _RECIPE_HELD and _RECIPE_HELD[0][0] == key:
        return _RECIPE_HELD[0][1], _RECIPE_HELD[0][2]
    recipe, _ = read_recipe(table, Path(npz_path), Path(json_path))
    star = twin_star(recipe, photometry_options(recipe.obs))
    _RECIPE_HELD[:] = [(key, recipe, star)]
    return recipe, star


def twin_batches(n_twins: int) -> list[tuple[int, ...]]:
    """Twins 1 to ``n_twins`` in tasks of :data:`TWINS_PER_TASK` (the last may hold fewer);
    a batch is the same whatever the number of twins asked once it is whole.

    Examples
    --------
    >>> twin_batches(12)
    [(1, 2, 3, 4, 5), (6, 7, 8, 9, 10), (11, 12)]
    """
    return [tuple(range(a, min(a + TWINS_PER_TASK, n_twins + 1)))
            for a in range(1, n_twins + 1, TWINS_PER_TASK)]


def twin_task(settings: TrustSettings, npz_path: str, json_path: str, twins: Sequence[int],
              out_paths: Sequence[str]) -> None:
    """Simulate and measure the twins ``twins`` in memory; write their photometry tables
    (``out_paths``, in order)."""
    recipe, star = _recipe_and_star(settings.table, npz_path, json_path)
    options = photometry_options(recipe.obs)
    for twin, out in zip(twins, out_paths, strict=True):
        write_photometry(twin_table(recipe, options, seed=settings.seed, twin=twin, star=star),
                         out)


def shared_options(method: str, real: Mapping[str, Any], asked: Mapping[str, Any]
                   ) -> dict[str, Any]:
    """What the twins take from the method's real fit: its fitted hyperparameters (GP's kernel),
    when its options have a ``hyperparameters`` field the user left unset and the class names
    their order (``hyperparameter_names``).

    Examples
    --------
    >>> real = {"diagnostics": {"hyperparameters": {"gp_ln_white": 0.1, "gp_ln_amp": -5.0,
    ...         "gp_ln_len_t": 3.0, "gp_ln_len_x": -2.0, "gp_ln_len_y": -2.5}}}
    >>> shared_options("gp", real, {})
    {'hyperparameters': [-5.0, -2.0, -2.5, 3.0, 0.1]}
    """
    cls = get_method(method)
    names = {f.name for f in dataclasses.fields(cls.Options)}
    order = getattr(cls, "hyperparameter_names", None)
    fitted = (real.get("diagnostics") or {}).get("hyperparameters")
    if "hyperparameters" in names and "hyperparameters" not in asked and order \
            and isinstance(fitted, Mapping) and set(order) <= set(fitted):
        return {"hyperparameters": [float(fitted[n]) for n in order]}
    return {}


def twin_reduce_task(settings: TrustSettings, method: str, twin: int, table_path: str,
                     real_path: str, out_path: str) -> None:
    """Reduce twin ``twin`` with ``method`` exactly as the real table was reduced."""
    real = json.loads(Path(real_path).read_text())
    extra = shared_options(method, real, settings.method_options.get(method, {}))
    seed = spawn_ints(settings.seed, "trust", "reduce")[0]
    try:
        result = _reduce(settings, table_path, method, seed=seed, epoch=twin,
                         extra_options=extra)
    except InputError as exc:
        write_failure(out_path, method, twin, str(exc))
        return
    write_result(result, out_path)


# ----------------------------------------------------------------------------- plans
def plan_real(settings: TrustSettings, layout: TrustLayout) -> list[Task]:
    """One task per method on the real table."""
    return [Task(f"real/{m}", "real", real_task, (settings, m, str(layout.real(m))),
                 (layout.real(m),), check=partial(result_ok, m, settings.table_epoch),
                 sources=settings.sources)
            for m in settings.methods]


def plan_twins(settings: TrustSettings, layout: TrustLayout, usable: Sequence[str],
               command: str | None = None) -> list[Task]:
    """The recipe, every twin and every twin's reduction by the usable methods, the score
    (its page shows ``command``)."""
    first = usable[0]
    tasks = [Task("recipe", "recipe", recipe_task,
                  (settings, first, str(layout.real(first)), str(layout.recipe_npz),
                   str(layout.recipe_json)), (layout.recipe_json, layout.recipe_npz),
                  (f"real/{first}",), sources=settings.sources)]
    results = []
    for batch in twin_batches(settings.n_twins):
        made = f"twin/{batch[0]:03d}-{batch[-1]:03d}"
        tasks.append(Task(made, "twin", twin_task,
                          (settings, str(layout.recipe_npz), str(layout.recipe_json), batch,
                           tuple(str(layout.twin(i)) for i in batch)),
                          tuple(layout.twin(i) for i in batch), ("recipe",),
                          sources=settings.sources))
        for i in batch:
            for m in usable:
                key = f"twin-reduce/{m}/{i:03d}"
                results.append(key)
                tasks.append(Task(key, "reduce", twin_reduce_task,
                                  (settings, m, i, str(layout.twin(i)), str(layout.real(m)),
                                   str(layout.twin_result(m, i))), (layout.twin_result(m, i),),
                                  (made, f"real/{m}"), check=partial(result_ok, m, i),
                                  sources=settings.sources))
    tasks.append(Task("score", "score", score_task,
                      (settings.describe(), list(usable), str(layout.root), command),
                      (layout.report, layout.table, layout.result),
                      ("recipe", *results, *(f"real/{m}" for m in settings.methods)),
                      sources=settings.sources))
    return tasks


def _guard(settings: TrustSettings, layout: TrustLayout) -> None:
    """Refuse a folder of other settings; another number of twins is the same run, resumed.

    Twin ``i`` depends on the seed and ``i`` only, so asking for more twins keeps
    the ones already made and reduced, and the score (whose inputs change) is
    redone over twins 1 to ``n_twins``.
    """
    described = settings.describe()
    text = json.dumps(described, sort_keys=True, indent=1)
    if layout.config.is_file():
        held = layout.config.read_text()
        if held == text:
            return
        try:
            before = json.loads(held)
        except ValueError:
            before = None
        if not isinstance(before, dict) or {**before, "n_twins": settings.n_twins} != described:
            raise InputError(f"{layout.root}: holds a trust run with other settings (see "
                             f"{layout.config.name}); use another --out or remove it")
        log.info("%s: %s twins asked where %s were; the twins made are kept", layout.root,
                 settings.n_twins, before.get("n_twins"))
    write_text(layout.config, text)


def usable_methods(settings: TrustSettings, layout: TrustLayout) -> tuple[list[str], dict]:
    """The methods whose real reduction succeeded, and ``{method: reason}`` for the others."""
    usable, skipped = [], {}
    for m in settings.methods:
        data = json.loads(layout.real(m).read_text())
        if data.get("failed"):
            skipped[m] = data.get("error", "failed")
        else:
            usable.append(m)
    return usable, skipped


#: Bytes of a reduction's light curve (``.lc.ecsv``) per frame of the table, a bound:
#: 103 measured on a 1,312-frame table (the JSON beside it adds a few kB).
LC_BYTES_PER_FRAME = 120
#: Bytes of a reduction's JSON result, a bound (2.1 kB measured).
RESULT_BYTES = 4096


def estimated_bytes(settings: TrustSettings, layout: TrustLayout, n_frames: int
                    ) -> tuple[int, str]:
    """What this invocation will write: the twins' tables not made yet (each about the real
    table's size) and their reductions by every method; ``(bytes, what it counts)``."""
    table_bytes = Path(settings.table).stat().st_size
    twins = [i for i in range(1, settings.n_twins + 1) if not layout.twin(i).is_file()]
    reductions = sum(not layout.twin_result(m, i).is_file() for m in settings.methods
                     for i in range(1, settings.n_twins + 1))
    total = (len(twins) * table_bytes
             + reductions * (n_frames * LC_BYTES_PER_FRAME + RESULT_BYTES))
    return total, (f"{len(twins)} twin tables of about {table_bytes} bytes and {reductions} "
                   "reductions")


def _written_by_trust(layout: TrustLayout) -> list[Path]:
    """Every path a trust run creates in its folder (the lock aside)."""
    return [layout.config, layout.marker, layout.real("x").parent, layout.recipe_npz,
            layout.recipe_json, layout.twin(1).parent, layout.result, layout.table,
            layout.report.parent]


def _undo(made: Sequence[Path]) -> None:
    """Remove what a refused first run made (``made``: paths that did not exist before it)."""
    for path in made:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink(missing_ok=True)


def run_trust(settings: TrustSettings, root: str | Path, *, workers: int = 1,
              scheduler: str | None = None, command: str | None = None
              ) -> tuple[TrustResult, RunReport]:
    """Run (or resume) a trust run in ``root``; return its answer and what ran (``command``:
    the command line or call shown on the page).

    A folder is refused in one line, before anything is written, when it holds
    another kind of run, when an input (the table, the planet's elements, the
    pixel map) changed since it was made, or when it holds a trust run of other
    settings (another number of twins is the same run, resumed). A run refused
    for its input before any twin was made (no method could reduce the table,
    a depth that cannot be injected) removes what it wrote, so the corrected
    command goes on in the same folder.

    Raises
    ------
    InputError
        As above; the message names the folder or the input and how to go on.
    EnvironmentFailure
        The estimate of what the run will write exceeds the free space.
    """
    layout = TrustLayout(Path(root))
    if layout.root.is_dir():   # no output through a symbolic link out of the folder
        check_kind(layout.root, "trust")
        check_links_inside(layout.root)
        check_outputs_inside(plan_real(settings, layout), layout.root)
    if scheduler:   # a tls:// scheduler's files loaded before the folder is made
        external_security(scheduler, ClusterOptions())
    needed, what = estimated_bytes(settings, layout, settings.table_frames)
    check_free_space(layout.root, needed, what)
    layout.root.mkdir(parents=True, exist_ok=True)
    with run_lock(layout.lock):
        ours = _written_by_trust(layout)
        if not layout.config.is_file():   # a new folder: only what this run makes is ours
            adopted = layout.root / OBSERVATION_FILE   # another pipeline's table, completed
            ours = [p for p in ours if not os.path.lexists(p)] + [adopted]
        claim(layout.root, "trust", settings.inputs, legacy_ok=False)
        _guard(settings, layout)
        try:
            first = run_tasks(plan_real(settings, layout), workers=1, root=layout.root)
            usable, skipped = usable_methods(settings, layout)
            if not usable:
                raise InputError(f"{settings.table}: no method could reduce the real table ("
                                 + "; ".join(f"{m}: {r}" for m, r in skipped.items()) + ")")
            tasks = plan_real(settings, layout) + plan_twins(settings, layout, usable, command)
            check_outputs_inside(tasks, layout.root)
            report = run_tasks(tasks, workers=workers, scheduler=scheduler, root=layout.root)
        except InputError:
            if not any(layout.twin(1).parent.glob("twin_*.fits")):
                _undo(ours)   # no twin made yet: the corrected command starts afresh
            raise
        report.ran = first.ran + report.ran
        return read_trust(layout.result), report


def make_settings(table: str | os.PathLike[str], *, reduce: ReduceSection, system: Any = None,
                  system_section: Any = None, methods: Sequence[str] | None = None,
                  n_twins: int = 50, depth_ppm: float | None = None, seed: int = 0,
                  method_options: Mapping[str, Mapping[str, Any]] | None = None,
                  pmap: str | None = None, hint: str = "--system NAME",
                  depth_name: str = "depth_ppm") -> TrustSettings:
    """Check every input of a trust run before any work; the settings it will run with.

    Raises
    ------
    InputError
        One line naming the argument: a missing or unreadable table, one that
        cannot be twinned (another pipeline's, fewer than 100 good frames or 2 cubes of
        2 good frames), a
        twin count outside 10-10,000, a depth that is not finite and positive or
        not below what a fit can return (named ``depth_name``,
        :func:`~eclipsebench.fit.model.depth_limit_ppm`),
        an unknown method, a whole phase curve (``reduce.event``) of a table
        without the column ``aorkey`` or with one AOR, a table naming no planet, or
        a ``pmap`` that holds no readable map.
    """
    from ..decorrelate import available_methods
    from ..decorrelate.base import unknown_methods
    from ..fit.model import AstroModel, depth_limit_ppm
    from ..fit.prepare import table_epoch
    from ..fit.target import system_of_table
    from ..io.pmap_files import find_pmap_path, pmap_files
    from .observation import check_several_aors, observation_from_table
    from .recipe import EVENTS, twin_map

    if isinstance(n_twins, bool) or not isinstance(n_twins, int) \
            or not MIN_TWINS <= n_twins <= MAX_TWINS:
        raise InputError(f"twins: expected an integer from {MIN_TWINS} to {MAX_TWINS}, got "
                         f"{n_twins!r}")
    if depth_ppm is not None and not (isinstance(depth_ppm, (int, float))
                                      and np.isfinite(depth_ppm) and depth_ppm > 0):
        raise InputError(f"{depth_name}: expected a finite depth > 0 in ppm, got {depth_ppm!r}")
    if reduce.event not in EVENTS:
        raise InputError(f"event {reduce.event!r}: twins are made of one eclipse or transit "
                         f"observation or a whole phase curve ({', '.join(EVENTS)})")
    deepest = depth_limit_ppm(reduce.event)
    if depth_ppm is not None and depth_ppm >= deepest:
        raise InputError(f"{depth_name}: {depth_ppm:g} ppm is beyond what a fit can return (a "
                         f"{reduce.event}'s depth is below {deepest:g} ppm, the bound of the "
                         "fit's parameter); expected a depth below it")
    chosen = tuple(methods) if methods else available_methods()
    if problem := unknown_methods(chosen):
        raise InputError(f"methods: {problem}")
    if len(set(chosen)) != len(chosen):
        raise InputError("methods: a method is named twice")
    if pmap is not None and str(pmap) != "":   # a device or a FIFO: refused before the table
        check_pmap_path(pmap)
    path = Path(table)
    if not path.is_file():
        raise InputError(f"{path}: no such photometry table")
    data = read_table(path)
    obs = observation_from_table(data, str(path))
    if AstroModel.event_class(reduce.event).whole_orbit:   # an offset per AOR: the AORs named
        check_several_aors(data, obs, str(path))
    twin_map(obs, pmap)   # a bad --pmap stops here
    planet = system_of_table(data.meta, system=system, section=system_section,
                             source=str(path), hint=hint)
    inputs = {"table": Input("table", f"the table {path.resolve()}", file_sha256(path)),
              "system": planet_input(planet)}
    try:   # the map KR/Pmap and the twins would read (--pmap, else the table's SIMDIR)
        map_path = find_pmap_path(pmap, data.meta, float(obs.time_bmjd[0]))
    except InputError:
        map_path = None
    if map_path is not None:
        inputs["pmap"] = Input("pmap", f"the pixel map {map_path}",
                               files_sha256(pmap_files(map_path)))
    options = {m: dict(v) for m, v in (method_options or {}).items()}
    for m in options:
        if m not in chosen:
            raise InputError(f"option for {m!r}: not one of the methods of this run")
    configured = fit_reduce.configured_method_options(reduce)
    resolved = {m: fit_reduce.resolve_method_options(m, reduce, options.get(m),
                                                     profile=reduce.profile,
                                                     configured=configured)
                for m in chosen}
    return TrustSettings(table=str(path.resolve()), system=planet, methods=chosen,
                         n_twins=int(n_twins), seed=int(seed), reduce=reduce,
                         depth_ppm=None if depth_ppm is None else float(depth_ppm),
                         method_options=options, pmap=pmap, resolved_options=resolved,
                         inputs=inputs, table_frames=int(obs.n_frames),
                         table_epoch=table_epoch(data))


def trust_settings(table, root, *, columns: Mapping[str, str] | None = None,
                   time_column: str | None = None, time_format: str | None = None,
                   time_options: Mapping[str, Any] | None = None, readout: str | None = None,
                   channel: int | None = None, labels: Mapping[str, str] | None = None,
                   **settings: Any):
    """The settings of a trust run of any table (``make_settings``' keywords in ``settings``).

    An ``eclipsebench photometry`` table is used as it is. Another pipeline's
    is completed (:func:`completed_observation`), checked with every other
    input on a temporary copy, and only then written to the trust folder
    (:func:`adopt_observation`): bad input writes nothing.
    """
    import tempfile
    from dataclasses import replace
    from pathlib import Path

    from ..io.pmap_files import check_pmap_path
    from ..photometry.table import write_photometry
    if settings.get("pmap") not in (None, ""):   # a device or a FIFO: refused before the table
        check_pmap_path(settings["pmap"])
    path = Path(table)
    if not path.is_file():
        raise InputError(f"{path}: no such photometry table")
    done = completed_observation(str(path), system=settings.get("system"),
                                 system_section=settings.get("system_section"),
                                 hint=settings.get("hint", "--system NAME"), columns=columns,
                                 time_column=time_column, time_format=time_format,
                                 time_options=time_options, readout=readout, channel=channel,
                                 labels=labels)
    if done is None:
        return make_settings(path, **settings)
    with tempfile.TemporaryDirectory() as tmp:
        probe = Path(tmp) / OBSERVATION_FILE
        write_photometry(done, probe)
        try:
            checked = make_settings(probe, **settings)
        except InputError as exc:   # named by the user's table, not the temporary copy
            raise InputError(str(exc).replace(str(probe), str(path))) from None
    return replace(checked, table=adopt_observation(done, root, write_photometry))
