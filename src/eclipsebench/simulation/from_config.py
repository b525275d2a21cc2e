"""The challenge configuration as the simulator's objects: the planet at the channel's
wavelength, L(t), the readout, the frame model, the pointing and the target.
"""

from __future__ import annotations

import math
from dataclasses import fields, replace

import numpy as np

from ..astro.catalogue import system_for
from ..astro.lightcurve import LightCurve, cached_light_curve
from ..astro.thermal import DEFAULT_WAVELENGTH_UM
from ..config import Config
from ..config.detector import noise_factor_of, read_noise_of
from ..detector.constants import ReadoutMode, channel_constants
from ..errors import ConfigError, InputError
from ..instrument.pointing import (
    ParamRange,
    PointingParams,
    PointingRanges,
    draw_pointing_params,
)
from ..io.header_template import XO3_DEC_DEG, XO3_RA_DEG
from ..seeding import rng
from .plan import epoch_start_times_bmjd, plan_epoch
from .render import FrameModel

__all__ = ['challenge_epoch_times_bmjd', 'system_of', 'light_curve_of', 'readout_from_config', 'frame_model_from_config', 'pointing_ranges_from_config', 'draw_epoch_pointing', 'target_of']

def system_of(cfg: Config):
    """``cfg.system`` for the channel observed.

    The ``[system]`` default ``wavelength_um`` (4.5095 um, IRACSIM's for
    channel 2) becomes channel 1's effective wavelength (3.551 um, IRAC
    Instrument Handbook Table 2.2) when ``observation.channel = 1``; any other
    value is kept.
    """
    system = cfg.system
    if cfg.observation.channel == 1 and math.isclose(system.wavelength_um, DEFAULT_WAVELENGTH_UM):
        system = replace(system, wavelength_um=channel_constants(1).effective_wavelength_um)
    return system


def light_curve_of(cfg: Config) -> LightCurve:
    """L(t) of ``cfg.system`` at the channel's wavelength (:func:`system_of`; the one
    per-process cache, :func:`cached_light_curve`)."""
    return cached_light_curve(system_of(cfg))


def readout_from_config(cfg: Config) -> ReadoutMode:
    """The :class:`ReadoutMode` of ``[observation]`` (``readout``, or ``"custom"``)."""
    return cfg.observation.readout_mode()


def frame_model_from_config(cfg: Config) -> FrameModel:
    """The :class:`FrameModel` of a configuration."""
    sim = cfg.simulation
    mode = readout_from_config(cfg)
    return FrameModel(mode=mode, noise_model=sim.noise_model,
                      read_noise_e=read_noise_of(cfg), noise_factor=noise_factor_of(cfg),
                      subsamples=sim.subsamples,
                      stamp_px=sim.stamp_px, shape=mode.shape)


def pointing_ranges_from_config(cfg: Config) -> PointingRanges:
    """Table 5's ranges with the ``simulation.pointing_ranges`` overrides applied.

    Each override is ``"name=C:value"``, ``"name=U:lo:hi"`` or ``"name=G:lo:hi"``
    with ``name`` a :class:`~eclipsebench.instrument.pointing.PointingRanges` field.
    """
    key = "simulation.pointing_ranges"
    names = {f.name for f in fields(PointingRanges)}
    changes: dict[str, ParamRange] = {}
    for text in cfg.simulation.pointing_ranges:
        name, sep, spec = text.partition("=")
        name = name.strip()
        if not sep or name not in names:
            raise ConfigError(key, f"{text!r}: expected name=KIND:values with name one of "
                                   + ", ".join(sorted(names)))
        parts = spec.strip().split(":")
        kind = parts[0].upper()
        try:
            values = [float(v) for v in parts[1:]]
        except ValueError:
            raise ConfigError(key, f"{text!r}: values must be numbers") from None
        if kind == "C" and len(values) == 1:
            changes[name] = ParamRange("C", values[0])
        elif kind in ("U", "G") and len(values) == 2 and values[0] <= values[1]:
            default = getattr(PointingRanges(), name)
            limits = default.limits if kind == "G" else None
            changes[name] = ParamRange(kind, values[0], values[1], limits)
        else:
            raise ConfigError(key, f"{text!r}: expected C:value, U:lo:hi or G:lo:hi (lo <= hi)")
    return PointingRanges(**{**{f.name: getattr(PointingRanges(), f.name)
                                for f in fields(PointingRanges)}, **changes})


def draw_epoch_pointing(cfg: Config, epoch: int, seed: int) -> PointingParams:
    """The pointing parameters of ``epoch`` (stream ``("simulate", epoch, "pointing")``)."""
    try:
        return draw_pointing_params(rng(seed, "simulate", epoch, "pointing"),
                                    pointing_ranges_from_config(cfg))
    except ConfigError:
        raise
    except InputError as exc:
        raise ConfigError("simulation.pointing_ranges", str(exc)) from None


def target_of(cfg: Config) -> tuple[float, float, str]:
    """RA, Dec (deg) and OBJECT of the target: XO-3's unless the catalogue knows better."""
    system = system_for(cfg.system)
    ra = getattr(system, "ra_deg", None)
    dec = getattr(system, "dec_deg", None)
    # the star: the planet's name without a qualifier ("XO-3b (2015 challenge)") or its letter
    name = system.name.split("(", 1)[0].strip()
    name = name[:-1] if name.endswith("b") else name
    if ra is None or dec is None:
        ra, dec = XO3_RA_DEG, XO3_DEC_DEG
    return float(ra), float(dec), name.rstrip()


def challenge_epoch_times_bmjd(epoch: int, cfg: Config | None = None, *,
                               label: str = "epoch") -> np.ndarray:
    """Mid-frame times (BMJD_TDB) of every frame of one epoch of a challenge.

    The frames the simulator renders for that epoch (both AORs, Table 2's
    start times; :func:`eclipsebench.simulation.plan.plan_epoch`), each at
    the centre of its Fowler weights, where the simulator evaluates L(t).

    Parameters
    ----------
    epoch : int
        1 to ``cfg.challenge.epochs``.
    cfg : Config, optional
        Default: the built-in challenge.
    label : str
        How an error names ``epoch`` (``eclipsebench lightcurve`` passes ``--epoch``).

    Examples
    --------
    >>> t = challenge_epoch_times_bmjd(10)
    >>> t.size, round(float(t[0]), 4), round(float(t[-1] - t[0]) * 24, 2)
    (15616, 57234.3406, 8.85)
    """
    cfg = cfg if cfg is not None else Config()
    if not 1 <= epoch <= cfg.challenge.epochs:
        raise InputError(f"{label}: expected an epoch of the challenge, 1-{cfg.challenge.epochs}, "
                         f"got {epoch}")
    obs = cfg.observation
    period = system_for(cfg.system).period_days
    start = float(epoch_start_times_bmjd(obs.start_times_jd, epoch, period)[epoch - 1])
    plan = plan_epoch(obs, epoch, start, cfg.challenge.seed)
    # as simulate_aor: time_bmjd at the centre of the Fowler weights, (2 FN + WT + 1)/2 ticks
    tick_mid_s = 0.5 * (2 * obs.fowler + obs.wait + 1) * obs.sample_time_s
    return np.concatenate([plan.to_bmjd(a.frame_starts_s().ravel() + tick_mid_s)
                           for a in plan.aors])
