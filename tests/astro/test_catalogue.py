"""System catalogue: lookups, references, user catalogues and one-line errors."""

from __future__ import annotations

import json

import pytest

from eclipsebench.astro.catalogue import PlanetSystem, get_system, list_systems
from eclipsebench.cli import main
from eclipsebench.config.system import CHALLENGE_SYSTEM, SystemSection
from eclipsebench.errors import InputError

XO3B = {"period_days": 3.1915239, "t_transit_bjd": 2454449.86816, "ecc": 0.2769,
        "omega_deg": 347.2, "inc_deg": 84.20, "a_rs": 7.07, "rp_rs": 0.0906,
        "teff_star_k": 6429.0, "v_mag": 9.80}


def test_xo3b_has_the_issue_values():
    s = get_system("XO-3b")
    for key, value in XO3B.items():
        assert getattr(s, key) == value, key
    assert set(XO3B) - {"v_mag"} <= set(s.references)


def test_challenge_row_is_xo3b_with_the_2015_elements():
    """Issue 15: the 2015 challenge's XO-3b differs from XO-3b only in e and omega."""
    s = get_system(CHALLENGE_SYSTEM)
    assert s.name == "XO-3b (2015 challenge)" and (s.ecc, s.omega_deg) == (0.2884, 346.0)
    assert "Winn et al. 2008" in s.references["ecc"]
    assert "Winn et al. 2008" in s.references["omega_deg"]
    wong = get_system("XO-3b")
    assert (wong.ecc, wong.omega_deg) == (0.2769, 347.2)
    assert {k: v for k, v in s.to_dict().items() if k not in ("name", "references")} == \
        {k: v for k, v in dict(wong.to_dict(), ecc=0.2884, omega_deg=346.0).items()
         if k not in ("name", "references")}
    # the built-in challenge uses it; XO-3b by name keeps Wong et al. 2014
    assert SystemSection().name == CHALLENGE_SYSTEM


@pytest.mark.parametrize("name", ["xo3b-challenge2015", "XO3B_CHALLENGE_2015",
                                  "xo-3b (2015 challenge)", "XO-3b (2015 Challenge)"])
def test_challenge_row_aliases(name):
    assert get_system(name).name == CHALLENGE_SYSTEM


@pytest.mark.parametrize("name", ["XO-3b", "XO-3b (2015 challenge)", "HD 189733b", "HD 209458b",
                                  "WASP-43b", "WASP-18b"])
def test_every_builtin_system_is_valid_and_referenced(name):
    s = get_system(name)
    assert s.name == name
    for key in ("period_days", "t_transit_bjd", "inc_deg", "a_rs", "rp_rs", "teff_star_k"):
        assert key in s.references, (name, key)
    assert 0 < s.impact_parameter < 1 + s.rp_rs  # all of them transit


def test_names_match_loosely():
    assert get_system("xo3b").name == "XO-3b"
    assert get_system("hd_189733 B").name == "HD 189733b"
    assert len(list_systems()) == 6


def _one_line(exc):
    text = str(exc.value)
    assert "\n" not in text
    return text


def test_unknown_planet_is_one_line():
    with pytest.raises(InputError) as exc:
        get_system("Kepler-999z")
    assert "unknown planet 'Kepler-999z'" in _one_line(exc)


@pytest.mark.parametrize("key,value,words", [
    ("ecc", 1.0, "0 <= e < 1"),
    ("ecc", 1.3, "0 <= e < 1"),
    ("a_rs", 0.8, "a/R* >= 1"),
    ("rp_rs", 0.0, "Rp/R* > 0"),
    ("rp_rs", -0.1, "Rp/R* > 0"),
])
def test_impossible_systems_are_rejected(tmp_path, key, value, words):
    table = dict(XO3B, **{key: value})
    body = "\n".join(f"{k} = {v!r}" for k, v in table.items())
    path = tmp_path / "mine.toml"
    path.write_text(f'["Bad-1b"]\n{body}\n')
    with pytest.raises(InputError) as exc:
        get_system("Bad-1b", path)
    text = _one_line(exc)
    assert words in text and "Bad-1b" in text and str(path) in text


def test_direct_construction_validates():
    with pytest.raises(InputError):
        PlanetSystem(name="x", **dict(XO3B, ecc=0.99))  # periastron inside the star


def test_user_catalogue_adds_systems(tmp_path):
    body = "\n".join(f"{k} = {v!r}" for k, v in XO3B.items())
    path = tmp_path / "mine.toml"
    path.write_text(f'["My-1b"]\n{body}\nr_star_rsun = 1.2\n\n["My-1b".references]\n'
                    'period_days = "me"\n')
    s = get_system("My-1b", path)
    assert s.r_star_rsun == 1.2 and s.references == {"period_days": "me"}
    assert get_system("XO-3b", path).name == "XO-3b"  # built-in ones still found
    assert list_systems(path) == ["My-1b"]


def test_user_catalogue_aliases(tmp_path):
    body = "\n".join(f"{k} = {v!r}" for k, v in XO3B.items())
    path = tmp_path / "mine.toml"
    path.write_text(f'["My-1b"]\naliases = ["mine", "first-planet"]\n{body}\n')
    assert get_system("First Planet", path).name == "My-1b"
    # a user's name wins over a built-in alias
    path.write_text(f'["xo3b-challenge2015"]\n{body}\n')
    assert get_system("xo3b-challenge2015", path).ecc == 0.2769
    path.write_text(f'["My-1b"]\naliases = "mine"\n{body}\n')
    with pytest.raises(InputError) as exc:
        get_system("mine", path)
    assert "aliases must be a list of names" in _one_line(exc) and str(path) in str(exc.value)


def test_bad_catalogue_files(tmp_path):
    with pytest.raises(InputError, match="no such catalogue file"):
        get_system("x", tmp_path / "none.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[x\n")
    with pytest.raises(InputError, match="not valid TOML"):
        get_system("x", bad)
    unknown = tmp_path / "unknown.toml"
    unknown.write_text('["Q-1b"]\nperiod = 3.0\n')
    with pytest.raises(InputError, match="unknown key 'period'"):
        get_system("Q-1b", unknown)


def test_cli_prints_one_line_and_exits_2(tmp_path, capsys):
    body = "\n".join(f"{k} = {v!r}" for k, v in dict(XO3B, ecc=1.2).items())
    path = tmp_path / "mine.toml"
    path.write_text(f'["Bad-1b"]\n{body}\n')
    assert main(["lightcurve", "Bad-1b", "--catalogue", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "0 <= e < 1" in err
    assert main(["lightcurve", "Nope-1b", "--json"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert "unknown planet" in captured.err
    with pytest.raises(json.JSONDecodeError):
        json.loads(captured.out)
