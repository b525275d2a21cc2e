"""An epoch without an eclipse of the planet is named in a warning (issue 16 follow-up)."""

from __future__ import annotations

import logging

from eclipsebench.config import load_config
from eclipsebench.simulation.stage import challenge_plans


def test_another_planet_with_the_challenge_start_times_is_named(caplog):
    cfg = load_config(None, ['system.name="HD 189733b"', "challenge.epochs=1"])
    with caplog.at_level(logging.WARNING):
        plans = challenge_plans(cfg)
    assert len(plans) == 1
    assert "no eclipse of HD 189733b" in caplog.text
    assert "observation.start_times_jd" in caplog.text


def test_the_default_challenge_plans_every_epoch_silently(caplog):
    with caplog.at_level(logging.WARNING):
        plans = challenge_plans(load_config(None))
    assert [p.epoch for p in plans] == list(range(1, 11)) and "no eclipse" not in caplog.text
