"""The detector values a configuration gives: its own, or the channel's and readout mode's.

:mod:`eclipsebench.detector.constants` holds the values and takes them as
arguments; this module reads the keys of ``[simulation]`` and
``[observation]`` that override them (the detector package knows nothing of
the configuration's schema).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..detector.constants import (
    NOISE_FACTOR_IRACSIM2015,
    SUB_2S,
    ReadoutMode,
    channel_constants,
    read_noise_per_read_e,
)

if TYPE_CHECKING:  # annotations only: the package's __init__ imports the sections
    from . import Config

__all__ = ["read_noise_of", "noise_factor_of", "gain_of", "fluxconv_of"]


def _observation(cfg: Config) -> tuple[int, ReadoutMode]:
    obs = getattr(cfg, "observation", None)
    if obs is None or not hasattr(obs, "readout_mode"):
        return 2, SUB_2S
    return int(obs.channel), obs.readout_mode()


def read_noise_of(cfg: Config) -> float:
    """Read noise per read of a configuration: ``simulation.read_noise_e``, or the model's own.

    See :func:`read_noise_per_read_e`, with the channel and readout mode of
    ``cfg.observation``.
    """
    channel, mode = _observation(cfg)
    return read_noise_per_read_e(cfg.simulation.noise_model, cfg.simulation.read_noise_e,
                                 channel=channel, mode=mode)


def noise_factor_of(cfg: Config) -> float:
    """IRACSIM's ``NOISE_FACTOR`` of a configuration: ``simulation.noise_factor``, or its default.

    Unset, it is :data:`NOISE_FACTOR_IRACSIM2015` for ``noise_model =
    "iracsim2015"`` and 1 otherwise (the key applies to ``iracsim2015`` only).

    Examples
    --------
    >>> from eclipsebench.config import load_config
    >>> noise_factor_of(load_config(None, ["simulation.noise_model=iracsim2015"]))
    0.907
    >>> noise_factor_of(load_config(None, []))
    1.0
    """
    value = cfg.simulation.noise_factor
    if value is not None:
        return float(value)
    return NOISE_FACTOR_IRACSIM2015 if cfg.simulation.noise_model == "iracsim2015" else 1.0


def gain_of(cfg: Config) -> float:
    """``simulation.gain_e_per_dn``, or the header GAIN of ``observation.channel`` when unset."""
    value = cfg.simulation.gain_e_per_dn
    return float(value) if value is not None else channel_constants(_observation(cfg)[0]).gain_e_per_dn


def fluxconv_of(cfg: Config) -> float:
    """``simulation.fluxconv``, or the warm FLUXCONV of ``observation.channel`` when unset."""
    value = cfg.simulation.fluxconv
    return float(value) if value is not None else channel_constants(_observation(cfg)[0]).fluxconv
