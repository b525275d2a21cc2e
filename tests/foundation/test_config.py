"""TOML -> frozen dataclasses, with validation and --set overrides."""

import dataclasses

import pytest

from eclipsebench.config import Config, default_config, dump_toml, load_config, to_mapping
from eclipsebench.config.base import parse_override
from eclipsebench.errors import ConfigError, InputError


def test_defaults_are_frozen():
    cfg = default_config()
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.challenge.seed = 3


def test_file_and_overrides(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('[challenge]\nseed = 11\nepochs = 3\n[photometry]\nradii_px = [2.0, 2.5]\n')
    cfg = load_config(path, ["challenge.epochs=5", 'system.name="WASP-43b"'])
    assert cfg.challenge.seed == 11
    assert cfg.challenge.epochs == 5
    assert cfg.photometry.radii_px == (2.0, 2.5)
    assert cfg.system.name == "WASP-43b"


def test_override_of_unknown_key_names_it():
    with pytest.raises(ConfigError) as exc:
        load_config(None, ["reduce.phasee=flat"])
    assert exc.value.key == "reduce.phasee"


def test_int_accepted_for_float_but_not_bool_for_int():
    cfg = load_config(None, ["observation.x0_px=15"])
    assert cfg.observation.x0_px == 15.0 and isinstance(cfg.observation.x0_px, float)
    with pytest.raises(ConfigError, match="challenge.seed"):
        load_config(None, ["challenge.seed=true"])


def test_range_check_names_dotted_key():
    with pytest.raises(ConfigError) as exc:
        load_config(None, ["observation.fowler=0"])
    assert exc.value.key == "observation.fowler"


@pytest.mark.parametrize("text,expected", [("a.b=1", (["a", "b"], 1)),
                                           ("a.b=2.5", (["a", "b"], 2.5)),
                                           ("a.b=true", (["a", "b"], True)),
                                           ("a.b=[1, 2]", (["a", "b"], [1, 2])),
                                           ("a.b=plain words", (["a", "b"], "plain words")),
                                           ("a.b=__import__('os')", (["a", "b"], "__import__('os')"))])
def test_parse_override_reads_toml_literals_never_code(text, expected):
    assert parse_override(text) == expected


def test_parse_override_rejects_missing_key():
    with pytest.raises(InputError):
        parse_override("=3")


def test_dump_roundtrip(tmp_path):
    cfg = load_config(None, ["challenge.seed=99", "run.methods=['bliss', 'pld']"])
    path = tmp_path / "round.toml"
    path.write_text(dump_toml(to_mapping(cfg)))
    assert load_config(path) == cfg
    assert isinstance(load_config(path), Config)


def test_sections_take_python_and_numpy_values_and_name_a_wrong_key():
    import numpy as np

    import eclipsebench as eb

    cfg = eb.load_config(challenge={"epochs": np.int64(3), "seed": 7},
                         simulation={"aperture_radius_px": np.float64(2.5)},
                         overrides=["challenge.seed=9"])          # text overrides come last
    assert (cfg.challenge.epochs, cfg.challenge.seed) == (3, 9)
    r = cfg.simulation.aperture_radius_px
    assert r == 2.5 and type(r) is float
    with pytest.raises(ConfigError, match=r"challenge\.epoch.*unknown key"):
        eb.load_config(challenge={"epoch": 3})
    with pytest.raises(ConfigError, match="challenge.*expected a table"):
        eb.load_config(challenge=3)
    with pytest.raises(ConfigError, match="challenge.epochs.*integer"):
        eb.load_config(challenge={"epochs": 2.5})
