"""Stated limits on every size that allocates memory or disk in proportion.

Each limit is a named constant, checked at the edge (configuration
validation, command-line parsing) before any work, so that a mistyped
``--epochs 1000000000`` is one line naming the key, the value and the limit
(exit code 2) instead of a ``MemoryError`` after minutes. The limits are far
above anything the paper or a Monte Carlo needs (the defaults in brackets)
and far below what would exhaust a login node.

=============================  ==============  ======================================
constant                       limit           what it bounds (default)
=============================  ==============  ======================================
``MAX_EPOCHS``                 1,000           ``challenge.epochs`` (10; 100 for a
                                               Monte Carlo)
``MAX_TWINS``                  10,000          digital twins of a trust run
                                               (``trust --twins``, 50)
``MAX_CUBES_PER_AOR``          100,000         ``observation.pre_cubes``,
                                               ``observation.main_cubes`` (11, 233)
``MAX_FRAMES_PER_CUBE``        4,096           ``observation.frames_per_cube`` (64)
``MAX_FRAMES_PER_EPOCH``       10,000,000      frames of one epoch (15,616)
``MAX_CALIBRATION_FRAMES``     10,000,000      ``simulation.calibration_frames``
                                               (400,000)
``MAX_MCMC_WALKERS``           2,000           ``reduce.mcmc_walkers``, ``--walkers`` (16)
``MAX_MCMC_WALKER_STEPS``      10,000,000      walkers x ``reduce.mcmc_steps`` and
                                               walkers x ``reduce.mcmc_block_steps``
                                               (16 x 5000)
``MAX_BOOTSTRAP``              1,000,000       ``run.bootstrap``, ``stats --bootstrap``
                                               (2,000)
``MAX_WORKERS``                256             ``run.workers``, ``--workers``: local
                                               processes (2)
``MAX_TEXT_FILE_BYTES``        16 MiB          a configuration or catalogue file
                                               (a few KiB)
``MAX_PMAP_FILE_BYTES``        2 GiB           one pixel-map file (``--pmap``: an SSC
                                               map file is 2 MB)
``MAX_TABLE_HEADER_BYTES``     1 MiB           the metadata (YAML header) of an ECSV
                                               table, also with its aliases
                                               expanded, and each metadata value
                                               written to a FITS header (a few KiB)
=============================  ==============  ======================================

A table's rows are counted before it is read whole (FITS ``NAXIS2``; CSV
and ECSV lines, streamed) and refused above ``MAX_FRAMES_PER_EPOCH``.
Configurations, catalogues and pixel maps must be regular files (not a
device such as ``/dev/zero``, not a FIFO) within their size limit.
"""

from __future__ import annotations

from .errors import ConfigError, InputError

__all__ = ["MAX_EPOCHS", "MAX_TWINS", "MAX_CUBES_PER_AOR", "MAX_FRAMES_PER_CUBE",
           "MAX_FRAMES_PER_EPOCH", "MAX_CALIBRATION_FRAMES", "MAX_MCMC_WALKERS",
           "MAX_MCMC_WALKER_STEPS", "MAX_BOOTSTRAP", "MAX_WORKERS", "MAX_TEXT_FILE_BYTES",
           "MAX_PMAP_FILE_BYTES", "MAX_TABLE_HEADER_BYTES", "size_problem", "check_size"]

#: Epochs of one challenge (``challenge.epochs``): each is about 140 MB of cubes.
MAX_EPOCHS = 1_000
#: Digital twins of a trust run (``trust --twins``; the value its command states).
MAX_TWINS = 10_000
#: Cubes (files) of one AOR, Pre or Main: each cube is about 256 KiB.
MAX_CUBES_PER_AOR = 100_000
#: Frames of one cube (a real IRAC subarray cube holds 64).
MAX_FRAMES_PER_CUBE = 4_096
#: Frames of one epoch (all its AORs): one photometry row each.
MAX_FRAMES_PER_EPOCH = 10_000_000
#: Frames of the KR/Pmap calibration-star set.
MAX_CALIBRATION_FRAMES = 10_000_000
#: MCMC walkers of one fit (the likelihood is evaluated for all of them at once).
MAX_MCMC_WALKERS = 2_000
#: Walkers x steps of one MCMC chain (the chain emcee keeps in memory).
MAX_MCMC_WALKER_STEPS = 10_000_000
#: Bootstrap resamples of the ensemble statistics.
MAX_BOOTSTRAP = 1_000_000
#: Worker processes of a local Dask cluster (each imports the package: ~300 MB).
MAX_WORKERS = 256
#: Bytes of one configuration or catalogue file (TOML text, read whole).
MAX_TEXT_FILE_BYTES = 16 * 2**20
#: Bytes of one pixel-map file (read whole): the KR/Pmap calibration set at
#: ``MAX_CALIBRATION_FRAMES`` rows of its columns is under 2 GiB.
MAX_PMAP_FILE_BYTES = 2 * 2**30
#: Bytes of an ECSV table's header (its YAML metadata and column list, parsed whole), also
#: once its YAML aliases are expanded; characters of one metadata value written as JSON.
MAX_TABLE_HEADER_BYTES = 2**20


def size_problem(value: int | float, limit: int, what: str = "") -> str:
    """The message of a size above its limit: the value, the limit, what is counted.

    Examples
    --------
    >>> size_problem(10**9, MAX_EPOCHS, "epochs")
    '1000000000 epochs is above the limit of 1000 (eclipsebench.limits)'
    """
    unit = f" {what}" if what else ""
    return f"{value}{unit} is above the limit of {limit} (eclipsebench.limits)"


def check_size(key: str, value: int | float, limit: int, what: str = "", *,
               config: bool = False) -> None:
    """Refuse ``value`` above ``limit`` in one line naming ``key``, the value and the limit.

    Parameters
    ----------
    key : str
        The option or configuration key, e.g. ``"--bootstrap"`` or ``"epochs"``.
    value : int or float
        The size asked for.
    limit : int
        The largest size allowed (one of this module's constants).
    what : str
        What is counted, e.g. ``"epochs"`` (shown after the value).
    config : bool
        Raise a :class:`~eclipsebench.errors.ConfigError` (for a section's
        ``validate``, which prefixes the section) instead of an InputError.

    Raises
    ------
    InputError
        ``value > limit`` (exit code 2 on the command line).

    Examples
    --------
    >>> check_size("--bootstrap", 2000, MAX_BOOTSTRAP)
    >>> check_size("--bootstrap", 10**12, MAX_BOOTSTRAP, "resamples")
    Traceback (most recent call last):
    ...
    eclipsebench.errors.InputError: --bootstrap: 1000000000000 resamples is above the limit of 1000000 (eclipsebench.limits)
    """
    if value > limit:
        problem = size_problem(value, limit, what)
        raise ConfigError(key, problem) if config else InputError(f"{key}: {problem}")
