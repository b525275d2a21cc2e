"""System catalogue: lookups, references, user catalogues and one-line errors."""

from __future__ import annotations

import json
import math
from types import SimpleNamespace

import pytest

from eclipsebench.astro.catalogue import (
    PLANET_KEYS,
    PlanetSystem,
    as_system,
    get_system,
    list_systems,
    system_for,
    system_from_mapping,
    system_from_pairs,
)
from eclipsebench.astro.lightcurve import light_curve_function
from eclipsebench.astro.orbit import BMJD_OFFSET, eclipse_time_bmjd
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


#: The planets with public Spitzer eclipse series or phase curves (issue 16 point 2).
ISSUE16 = ["WASP-12b", "WASP-14b", "WASP-19b", "WASP-33b", "WASP-103b", "HAT-P-7b", "KELT-9b",
           "CoRoT-2b", "GJ 436b", "GJ 1214b", "55 Cnc e", "HD 149026b", "HD 80606b", "TrES-3b"]


def test_the_catalogue_holds_the_issue_16_planets():
    assert set(ISSUE16) <= set(list_systems())


@pytest.mark.parametrize("name", list_systems())
def test_every_builtin_system_is_sane_and_referenced(name):
    """Every row: each value referenced, a bound transiting orbit, a finite positive eclipse."""
    s = get_system(name)
    assert s.name == name
    values = {k: v for k, v in s.to_dict().items() if k not in ("name", "references")}
    unreferenced = [k for k, v in values.items() if v is not None and k not in s.references]
    assert not unreferenced, (name, unreferenced)
    assert 0 <= s.ecc < 1 and 0 <= s.omega_deg < 360
    assert s.a_rs * (1 - s.ecc) > 1 + s.rp_rs  # periastron outside the star
    assert 0 <= s.impact_parameter < 1 + s.rp_rs  # all of them transit
    assert 0 < s.rp_rs < 0.3 and 2500 < s.teff_star_k < 12000 and 0.1 < s.r_star_rsun < 3
    assert 2450000 < s.t_transit_bjd < 2460000  # a BJD of the transit era, not a BMJD
    # the eclipse depth of the thermal model (coarse quadrature: a sanity check, not a value)
    lc = light_curve_function(s, fix_depth_ppm=0.0, n_lat=6, n_lon=12, n_time=128)
    assert math.isfinite(lc.depth_ppm) and 0 < lc.depth_ppm < 2e4, (name, lc.depth_ppm)


def test_eccentric_rows_put_the_eclipse_where_it_was_measured():
    """GJ 436b: the eclipse at phase 0.587 +- 0.005 (Deming et al. 2007, the row's check of
    Lanotte et al. 2014's e and omega). HD 80606b: the eclipse shortly before periastron
    (HJD 2454424.8575 in the row's source), about 2-3 h (Laughlin et al. 2009)."""
    gj = get_system("GJ 436b")
    t_tr = gj.t_transit_bmjd
    phase = (eclipse_time_bmjd(gj, t_tr + 0.5 * gj.period_days) - t_tr) / gj.period_days
    assert phase == pytest.approx(0.587, abs=0.005)
    hd = get_system("HD 80606b")
    t_peri = 2454424.8575 - BMJD_OFFSET
    before_h = (t_peri - eclipse_time_bmjd(hd, t_peri)) * 24
    assert 1.5 < before_h < 4.0


def test_names_match_loosely():
    assert get_system("xo3b").name == "XO-3b"
    assert get_system("hd_189733 B").name == "HD 189733b"
    assert get_system("55cnce").name == "55 Cnc e"
    assert get_system("gj436 b").name == "GJ 436b"
    assert len(list_systems()) == 20


def _one_line(exc):
    text = str(exc.value)
    assert "\n" not in text
    return text


def test_unknown_planet_is_one_line():
    with pytest.raises(InputError) as exc:
        get_system("Kepler-999z")
    text = _one_line(exc)
    assert "unknown planet 'Kepler-999z'" in text and "searched the built-in catalogue" in text


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


PAIRS = ["name=test-b"] + [f"{k}={v}" for k, v in XO3B.items()] + ["ld_quadratic=0.07,0.15"]


def test_a_planet_by_value_is_checked_as_a_catalogue_row():
    by_pairs = system_from_pairs(PAIRS)
    by_row = system_from_mapping("test-b", dict(XO3B, ld_quadratic=[0.07, 0.15]))
    assert by_pairs == by_row and by_pairs.references == {}
    assert as_system({"name": "test-b", **XO3B, "ld_quadratic": [0.07, 0.15]}) == by_row
    assert as_system(by_row) is by_row and as_system("XO-3b") == get_system("XO-3b")
    section = SimpleNamespace(name="test-b", catalogue="", planet=dict(XO3B))
    assert system_for(section).a_rs == 7.07
    assert set(PLANET_KEYS) == {"name"} | set(XO3B) - {"v_mag"} | {
        "r_star_rsun", "ld_quadratic", "v_mag", "ra_deg", "dec_deg"}


@pytest.mark.parametrize("call,words", [
    (lambda: system_from_pairs(PAIRS[1:]), "missing name"),
    (lambda: system_from_pairs(PAIRS + ["ecc=0.1"]), "ecc is given twice"),
    (lambda: system_from_pairs(PAIRS[:3]), "missing ecc"),
    (lambda: as_system({"period_days": 3.0}), "needs its name"),
    (lambda: as_system(3.0), "expected a planet name"),
    (lambda: system_for(SimpleNamespace(name="q", catalogue="", planet={"ecc": 0.1})),
     "[system] planet: system 'q': missing period_days"),
])
def test_bad_planets_by_value_are_one_line(call, words):
    with pytest.raises(InputError) as exc:
        call()
    assert words in _one_line(exc)
