"""Method options and seeds through ``eclipsebench reduce`` (the house issue's acceptance).

* ``--option no_such_option=1`` is one stderr line naming it, exit 2, for every method;
* ``[reduce.options.<method>]`` in a configuration file reaches the fit, and an
  unknown key there is one line naming the dotted key;
* ``--seed`` reaches the stochastic method (ICA): the same seed gives the same
  bytes, another seed another result; ``run --seed`` goes in as the int it is.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from eclipsebench.cli import main
from eclipsebench.decorrelate import available_methods


@pytest.fixture
def table_file(tmp_path, xo3_epoch):
    """A synthetic XO-3b epoch whose 3x3 pixels differ (pointing-dependent, noisy)."""
    t = xo3_epoch["table"](seed=21)[::4]
    g = np.random.default_rng(5)
    dx = np.asarray(t["x"]) - np.mean(t["x"])
    dy = np.asarray(t["y"]) - np.mean(t["y"])
    weights = 1.0 / 9 + 0.02 * g.standard_normal((3, 3))
    tilt_x, tilt_y = g.standard_normal((2, 3, 3))
    stamp = np.asarray(t["flux"])[:, None, None] * (
        weights + 0.05 * (dx[:, None, None] * tilt_x + dy[:, None, None] * tilt_y))
    t["stamp3"] = stamp + 3.0 * g.standard_normal(stamp.shape)
    path = tmp_path / "epoch_03.fits"
    t.write(path)
    return path


@pytest.mark.parametrize("method", available_methods())
def test_unknown_option_is_one_line_exit_2(method, table_file, capsys):
    assert main(["reduce", str(table_file), "--method", method,
                 "--option", "no_such_option=1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no_such_option" in err and method in err
    assert not list(table_file.parent.glob("*.json"))


def test_toml_method_options_change_the_fit_and_unknown_keys_are_named(tmp_path, table_file,
                                                                        capsys):
    def reduce(config=None):
        out = tmp_path / f"r{len(list(tmp_path.glob('r*.json')))}.json"
        args = ["reduce", str(table_file), "--method", "bliss", "--prayer-bead", "0",
                "--out", str(out)]
        code = main(args + (["--config", str(config)] if config else []))
        return code, (json.loads(out.read_text()) if code == 0 else None)

    code, default = reduce()
    assert code == 0
    cfg = tmp_path / "bliss.toml"
    cfg.write_text("[reduce.options.bliss]\nknot_spacing_px = 0.03\nmin_points_per_knot = 2\n")
    code, custom = reduce(cfg)
    assert code == 0
    assert custom["options"] == {"knot_spacing_px": 0.03, "min_points_per_knot": 2}
    assert default["options"]["knot_spacing_px"] is None
    assert custom["diagnostics"]["n_knots"] != default["diagnostics"]["n_knots"]
    assert custom["depth_ppm"] != default["depth_ppm"]

    bad = tmp_path / "bad.toml"
    bad.write_text("[reduce.options.bliss]\nknot_spacing = 0.03\n")
    capsys.readouterr()
    code, _ = reduce(bad)
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "reduce.options.bliss.knot_spacing" in err


def test_ica_seed_same_bytes_other_seed_other_result(tmp_path, table_file):
    def reduce(seed, name):
        out = tmp_path / name / "result.json"
        assert main(["reduce", str(table_file), "--method", "ica", "--seed", str(seed),
                     "--prayer-bead", "0", "--option", "n_restarts=3",
                     "--out", str(out)]) == 0
        text = out.read_bytes()
        return text.replace(name.encode(), b"RUN")

    one, again, two = reduce(1, "run_one"), reduce(1, "run_again"), reduce(2, "run_two")
    assert one == again
    a, c = json.loads(one), json.loads(two)
    assert a["seed"] == 1 and c["seed"] == 2
    assert a["diagnostics"] != c["diagnostics"]


def test_run_seed_goes_in_as_the_int_given_over_a_set():
    from eclipsebench.cli import build_parser
    from eclipsebench.commands import run as run_cmd

    args = build_parser().parse_args(["run", "--seed", "123", "--set", "challenge.seed=5"])
    assert run_cmd._overrides(args) == ["challenge.seed=5"]   # --seed is not made text
    assert run_cmd._config(args).challenge.seed == 123


@pytest.mark.parametrize("toml, key", [
    ("[reduce.options.bliss]\nknot_spacing = 0.03\n", "reduce.options.bliss.knot_spacing"),
    ("[reduce.options.blis]\nknot_spacing_px = 0.03\n", "reduce.options.blis"),
    ('[reduce.options.kr-data]\nk = "fifty"\n', "reduce.options.kr-data.k"),
])
def test_run_refuses_bad_method_options_before_any_work(tmp_path, capsys, toml, key):
    cfg = tmp_path / "run.toml"
    cfg.write_text(toml)
    out = tmp_path / "run"
    assert main(["run", str(cfg), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and key in err
    assert not out.exists()


def test_one_option_grammar_for_reduce_and_trust(table_file, tmp_path, capsys):
    """Issue 39: ``--option [METHOD.]KEY=VALUE`` for every command; ``reduce`` runs one
    method, so METHOD may be left out there, and must be that method when given."""
    from eclipsebench.commands.options import method_options

    assert method_options(["kr-data.k=3"], method="kr-data") == \
        method_options(["k=3"], method="kr-data") == {"kr-data": {"k": 3}}
    out = tmp_path / "r.json"
    for option in ("kr-data.k=3", "k=3"):   # the same fit either way
        assert main(["reduce", str(table_file), "--method", "kr-data", "--sampler", "leastsq",
                     "--prayer-bead", "0", "--option", option, "--out", str(out)]) == 0
        assert json.loads(out.read_text())["options"]["k"] == 3
    capsys.readouterr()
    assert main(["reduce", str(table_file), "--method", "poly2", "--option", "kr-data.k=3",
                 "--out", str(tmp_path / "p.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "names method 'kr-data', not --method 'poly2'" in err
    assert main(["trust", str(table_file), "--out", str(tmp_path / "t"), "--option", "k=3",
                 "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--option 'k=3': expected METHOD.KEY=VALUE" in err
    assert not (tmp_path / "p.json").exists() and not (tmp_path / "t").exists()
