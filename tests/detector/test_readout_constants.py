"""Readout constants live in one place: detector/constants.py."""

from __future__ import annotations

import subprocess
import sys

import pytest

from eclipsebench.config import detector as D
from eclipsebench.config import load_config
from eclipsebench.detector import constants as C
from eclipsebench.simulation import from_config


def test_read_noise_per_model_and_override():
    assert C.read_noise_per_read_e("physical") == C.READ_NOISE_E == 9.4
    assert C.read_noise_per_read_e("iracsim2015") == C.READ_NOISE_IRACSIM2015_E == 16.8
    assert C.read_noise_per_read_e("iracsim2015", 12) == 12.0
    assert D.read_noise_of(load_config(None, [])) == 9.4
    cfg = load_config(None, ["simulation.noise_model=iracsim2015"])
    assert D.read_noise_of(cfg) == 16.8
    cfg = load_config(None, ["simulation.read_noise_e=11.5"])
    assert D.read_noise_of(cfg) == pytest.approx(11.5)


def test_simulation_uses_the_one_read_noise_definition():
    assert from_config.read_noise_of is D.read_noise_of


def test_calibration_does_not_import_the_challenge_simulation():
    code = ("import sys, eclipsebench.simulation.calibration; "
            "sys.exit('eclipsebench.simulation.challenge' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0
