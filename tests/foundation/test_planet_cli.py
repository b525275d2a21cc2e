"""A planet in no catalogue, given on the command line (issue 16 point 2).

The acceptance: a made-up planet "test-b" given only with ``--planet`` is
simulated (a tiny one-epoch challenge), measured and reduced with
``reduce --planet``; the fitted depth is the simulated one within 4 sigma.
Plus the one-line errors of ``--planet`` and ``--catalogue``.
"""

from __future__ import annotations

import json
import math

import pytest

import eclipsebench as eb
from eclipsebench.astro.catalogue import system_from_pairs
from eclipsebench.astro.orbit import eclipse_time_bmjd
from eclipsebench.cli import build_parser, main
from eclipsebench.commands import run as run_cmd
from eclipsebench.commands.options import planet_overrides
from eclipsebench.config import load_config
from eclipsebench.simulation.plan import JD_OFFSET_BMJD

# An XO-3b-like planet in no catalogue: its own period, ephemeris and orbit.
TEST_B = {"name": "test-b", "period_days": 2.7431, "t_transit_bjd": 2456001.2345, "ecc": 0.12,
          "omega_deg": 75.0, "inc_deg": 85.5, "a_rs": 6.2, "rp_rs": 0.1, "teff_star_k": 6200.0,
          "r_star_rsun": 1.2}
PAIRS = [f"{k}={v}" for k, v in TEST_B.items()] + ["ld_quadratic=0.07,0.15"]
PLANET_ARGS = [a for pair in PAIRS for a in ("--planet", pair)]

# As TINY in tests/challenge/test_runner.py, with a shorter main AOR (120 cubes every 200 s:
# a 6.7 h window, 968 frames) to keep the simulation a few seconds.
TINY = ["observation.pre_cubes=1", "observation.frames_per_cube=8", "observation.main_cubes=120",
        "observation.cube_interval_s=200.0", "simulation.subsamples=1"]


def _sets(items: list[str]) -> list[str]:
    return [a for item in items for a in ("--set", item)]


def _start_jd(eclipse_bmjd: float, before_d: float = 0.14) -> float:
    """The window start (JD - 2455000, as observation.start_times_jd) ``before_d`` before an eclipse."""
    return eclipse_bmjd - before_d - JD_OFFSET_BMJD


@pytest.fixture(scope="module")
def reduced(tmp_path_factory):
    """simulate --planet, photometry, reduce --planet: the folder, the truth row and the result."""
    root = tmp_path_factory.mktemp("planet")
    t_ecl = eclipse_time_bmjd(system_from_pairs(PAIRS), 57234.5)
    start = f"observation.start_times_jd=[{_start_jd(t_ecl):.6f}]"
    assert main(["simulate", "--out", str(root / "sim"), "--epochs", "1", "--no-calibration",
                 "--quiet", "--workers", "1", *_sets(TINY + [start]), *PLANET_ARGS]) == 0
    assert main(["photometry", str(root / "sim"), "--out", str(root / "phot"), "--quiet"]) == 0
    table = root / "phot" / "epoch_01.fits"
    out = root / "test-b.pld.json"
    assert main(["reduce", str(table), "--method", "pld", "--out", str(out), "--quiet",
                 *PLANET_ARGS]) == 0
    from astropy.table import Table
    truth = Table.read(root / "sim" / "truth.ecsv", format="ascii.ecsv")[0]
    return root, t_ecl, truth, json.loads(out.read_text())


def test_a_planet_given_only_on_the_command_line_simulates_and_reduces(reduced):
    root, t_ecl, truth, result = reduced
    # the simulation is of test-b: its eclipse, its values in the folder's configuration
    assert truth["t_ecl_bmjd"] == pytest.approx(t_ecl, abs=1e-6)
    cfg = load_config(root / "sim" / "config.toml")
    assert cfg.system.name == "test-b" and cfg.system.planet["a_rs"] == 6.2
    assert list(cfg.system.planet["ld_quadratic"]) == [0.07, 0.15]
    # the reduction predicted test-b's eclipse and recovered the simulated depth
    assert result["t_ecl_predicted_bmjd"] == pytest.approx(t_ecl, abs=1e-6)
    depth, err = result["depth_ppm"], result["depth_err_ppm"]
    assert math.isfinite(depth) and 0 < err < 2000
    assert abs(depth - truth["depth_ppm"]) < 4 * err, (depth, err, truth["depth_ppm"])


def test_the_api_takes_the_planet_as_a_mapping(reduced):
    root, _, _, result = reduced
    planet = dict(TEST_B, ld_quadratic=[0.07, 0.15])
    fit = eb.reduce(root / "phot" / "epoch_01.fits", "pld", system=planet)
    assert fit.depth_ppm == pytest.approx(result["depth_ppm"], rel=1e-9)
    cfg = eb.load_config(system={"name": "test-b",
                                 "planet": {k: v for k, v in planet.items() if k != "name"}})
    assert cfg.system.planet["period_days"] == 2.7431


def test_the_wrong_planet_is_refused_by_reduce(reduced, capsys):
    root = reduced[0]
    assert main(["reduce", str(root / "phot" / "epoch_01.fits"), "--method", "pld",
                 "--system", "XO-3b", "--out", str(root / "xo3b.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "outside the time span" in err


def _one_line_error(capsys, argv: list[str], *words: str) -> str:
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1, captured.err
    for word in words:
        assert word in captured.err, (word, captured.err)
    return captured.err


def test_missing_values_are_one_line_naming_them(capsys):
    _one_line_error(capsys, ["lightcurve", "--planet", "name=x", "--planet", "period_days=3"],
                    "--planet", "'x'", "missing t_transit_bjd, ecc, omega_deg, inc_deg, a_rs, "
                    "rp_rs, teff_star_k")
    _one_line_error(capsys, ["config", "--planet", "period_days=3"], "--planet", "missing name")


@pytest.mark.parametrize("pair,words", [
    ("period_days=abc", ("--planet 'period_days=abc'", "expected a number")),
    ("period=3.1", ("unknown key 'period'", "period_days")),
    ("ld_quadratic=0.1", ("ld_quadratic=U1,U2",)),
    ("period_days", ("expected KEY=VALUE",)),
    ("ecc=1.2", ("0 <= e < 1", "test-b")),
    ("a_rs=1.05", ("periastron", "test-b")),
])
def test_bad_values_are_one_line(capsys, pair, words):
    key = pair.split("=")[0]
    pairs = [p for p in PAIRS if not p.startswith(key + "=")] + [pair]
    _one_line_error(capsys, ["config", *[a for p in pairs for a in ("--planet", p)]], *words)


def test_a_repeated_key_or_a_name_with_planet_is_one_line(capsys):
    _one_line_error(capsys, ["config", *PLANET_ARGS, "--planet", "ecc=0.1"], "ecc is given twice")
    _one_line_error(capsys, ["lightcurve", "XO-3b", *PLANET_ARGS], "SYSTEM 'XO-3b' and --planet")
    args = build_parser().parse_args(["reduce", "t.fits", "--method", "pld", *PLANET_ARGS])
    with pytest.raises(eb.InputError, match="--system 'XO-3b' and --planet"):
        planet_overrides(args, "XO-3b")


def test_unknown_planet_names_system_name_and_the_catalogues(tmp_path, capsys):
    mine = tmp_path / "mine.toml"
    mine.write_text('["My-1b"]\n' + "\n".join(
        f"{k} = {v!r}" for k, v in TEST_B.items() if k != "name") + "\n")
    for argv in (["lightcurve", "Nope-1b", "--catalogue", str(mine)],
                 ["config", "--set", "system.name=Nope-1b", "--catalogue", str(mine)],
                 ["simulate", "--out", str(tmp_path / "s"), "--set", "system.name=Nope-1b",
                  "--catalogue", str(mine)]):
        _one_line_error(capsys, argv, "system.name", "unknown planet 'Nope-1b'",
                        f"searched the built-in catalogue and {mine}", "My-1b")
    assert not (tmp_path / "s").exists()
    # the user catalogue's planet is found by every command
    assert main(["lightcurve", "my-1b", "--catalogue", str(mine), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["system"] == "My-1b"


def test_config_prints_the_planet_and_reads_it_back(tmp_path, capsys):
    assert main(["config", *PLANET_ARGS]) == 0
    text = capsys.readouterr().out
    assert "[system.planet]" in text and 'name = "test-b"' in text
    path = tmp_path / "test-b.toml"
    path.write_text(text)
    cfg = load_config(path)
    assert cfg.system.name == "test-b" and cfg.system.planet["ecc"] == 0.12
    # a bad [system.planet] table in a file names the key
    path.write_text(text.replace("ecc = 0.12", "ecc = 1.5"))
    with pytest.raises(eb.InputError, match=r"system\.planet.*0 <= e < 1"):
        load_config(path)


def test_lightcurve_of_a_planet_on_the_command_line(capsys):
    assert main(["lightcurve", *PLANET_ARGS, "--fix-depth", "0", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["system"] == "test-b"
    assert math.isfinite(result["eclipse_depth_ppm"]) and result["eclipse_depth_ppm"] > 0


def test_run_and_simulate_take_the_options():
    parser = build_parser()
    args = parser.parse_args(["run", "--epochs", "3", "--catalogue", "mine.toml", *PLANET_ARGS])
    overrides = run_cmd._overrides(args)
    assert 'system.catalogue="mine.toml"' in overrides and 'system.name="test-b"' in overrides
    cfg = load_config(None, overrides)
    assert cfg.system.planet["rp_rs"] == 0.1 and cfg.challenge.epochs == 3
    extra = {"simulate": ["--out", "x"], "reduce": ["t.fits", "--method", "pld"]}
    for command in ("simulate", "reduce", "lightcurve", "config"):
        args = parser.parse_args([command, *extra.get(command, []), *PLANET_ARGS])
        assert args.planet == PAIRS and args.catalogue is None
