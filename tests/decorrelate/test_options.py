"""Method options: checked when made, resolved once at the edge, passed down as that object.

An options instance takes each value as its field's type and runs its range
checks when it is made, so a method takes the instance it is given as it is
(no second parse); the edge merges the configuration's table, the paper
team's options and the command line's in that order, once (issue 27).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from eclipsebench.config.reduce import ReduceSection
from eclipsebench.decorrelate.base import EpochData, parse_method_options
from eclipsebench.decorrelate.bliss import Bliss, BlissOptions
from eclipsebench.decorrelate.gp import GpOptions
from eclipsebench.decorrelate.kernel import KrDataOptions
from eclipsebench.errors import ConfigError, InputError
from eclipsebench.fit.prepare import configured_method_options, resolve_method_options


def _data(n: int = 400) -> EpochData:
    g = np.random.default_rng(3)
    return EpochData(time_bmjd=np.arange(n) / 1440.0, flux=1e5 + 30 * g.standard_normal(n),
                     flux_err=np.full(n, 30.0), x=15.0 + 0.05 * g.standard_normal(n),
                     y=15.0 + 0.05 * g.standard_normal(n))


def test_an_options_instance_is_checked_when_it_is_made():
    assert BlissOptions(knot_spacing_px=[1, 2]).knot_spacing_px == (1.0, 2.0)
    with pytest.raises(ConfigError, match="knot_spacing_px"):
        BlissOptions(knot_spacing_px=float("inf"))   # once bliss_setup's own check
    with pytest.raises(ConfigError, match="'k': expected an integer"):
        KrDataOptions(k="fifty")
    with pytest.raises(InputError, match="^method 'bliss' option 'knot_spacing_px': expected one "
                                         "or two positive spacings in pixels$"):
        parse_method_options(Bliss, {"knot_spacing_px": float("inf")})


def test_a_method_takes_its_options_instance_as_it_is():
    opts = parse_method_options(Bliss, {"knot_spacing_px": 0.03})
    model = Bliss(_data(), opts)
    assert model.options is opts
    assert model.with_flux(model.data.flux).options is opts
    assert Bliss(_data(), opts, min_points_per_knot=2).options == dataclasses.replace(
        opts, min_points_per_knot=2)
    with pytest.raises(InputError, match="expected BlissOptions, got KrDataOptions"):
        Bliss(_data(), KrDataOptions())


def test_the_options_resolve_once_table_then_team_then_given():
    section = dataclasses.replace(ReduceSection(),
                                  options={"gp": {"bin_seconds": 60.0, "max_points": 900}})
    configured = configured_method_options(section)
    assert resolve_method_options("gp", section, configured=configured) is configured["gp"]
    paper = resolve_method_options("gp", section, {"max_points": 700}, profile="paper",
                                   configured=configured)
    assert (paper.bin_seconds, paper.max_points) == (30.0, 700)   # the team's 30 s over the table
    assert resolve_method_options("gp", section, {"bin_seconds": 10.0},
                                  profile="paper").bin_seconds == 10.0
    typed = GpOptions(max_points=50)
    assert resolve_method_options("gp", section, typed, profile="paper") is typed
    with pytest.raises(ConfigError, match="'reduce.options.gp.bin_second'"):
        resolve_method_options("gp", dataclasses.replace(section,
                                                         options={"gp": {"bin_second": 1.0}}))
    with pytest.raises(InputError, match="^method 'gp' option 'bin_second': unknown option"):
        resolve_method_options("gp", section, {"bin_second": 1.0})
