"""Issue 39, "Both doors agree": ``eb.reduce`` and ``eclipsebench reduce --json`` are one door.

The same inputs go through the Python API and the command line and give the
same result, or the same one-line refusal: the command's names its options
(``--columns``, ``--system NAME``) where the API's names its keywords
(``columns``, ``system=NAME``), and nothing else differs.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import eclipsebench as eb
from eclipsebench.cli import main
from eclipsebench.commands.table_options import TABLE_LABELS
from eclipsebench.errors import InputError
from eclipsebench.fit.data import _ARGUMENTS
from eclipsebench.io.plain import json_safe

#: The command's settings for speed (least squares, no prayer bead); the API's are the same.
FAST_CLI = ["--sampler", "leastsq", "--prayer-bead", "0"]
FAST_API = {"sampler": "leastsq", "prayer_bead_shifts": 0}
#: What the command adds to the result's own keys (where it wrote what).
WRITTEN = ("table", "tables", "lightcurve_file", "result_file")


def _as_option_names(message: str) -> str:
    """The API's refusal with each keyword named as the command line names its option."""
    api = {**_ARGUMENTS, "system": "system=NAME"}
    for key, cli_name in TABLE_LABELS.items():
        if key in api:
            message = re.sub(rf"(?<![\w-]){re.escape(api[key])}(?![\w-])", cli_name, message)
    return message


def _both(capsys, tables, api_kw: dict, argv: list[str]):
    """(the API's result or refusal, the command's JSON or refusal) for the same inputs."""
    try:
        api = eb.reduce(tables if len(tables) > 1 else tables[0], "poly2", **FAST_API, **api_kw)
        api_out = json_safe(api.to_dict())
    except InputError as exc:
        api_out = f"refused: {exc}"
    code = main(["reduce", *map(str, tables), "--method", "poly2", *FAST_CLI, *argv, "--json",
                 "--quiet"])
    out, err = capsys.readouterr()
    if code == 0:
        cli_out = {k: v for k, v in json.loads(out).items() if k not in WRITTEN}
    else:
        assert code == 2 and err.count("\n") == 1, err   # one line, exit 2
        cli_out = "refused: " + err.removeprefix("eclipsebench reduce: error: ").strip()
    return api_out, cli_out


@pytest.fixture
def epoch(xo3_epoch):
    return xo3_epoch["table"](seed=21)[::3]


def test_a_table_needing_a_column_map(tmp_path, capsys, epoch):
    theirs = epoch["time_bmjd", "flux", "flux_err", "x", "y"]
    theirs.rename_columns(theirs.colnames, ["BJD", "F", "sigma", "xc", "yc"])
    theirs["BJD"] += 2400000.5
    theirs.meta = {"SYSTEM": epoch.meta["SYSTEM"]}
    path = tmp_path / "theirs.ecsv"
    theirs.write(path)

    api, cli = _both(capsys, [path], {}, [])   # no map: refused, the map to give named
    assert api.startswith(f"refused: {path}: missing column(s) time_bmjd, flux, flux_err, x, y")
    assert "columns flux=F,flux_err=sigma,x=xc,y=yc and time_column BJD time_format bjd" in api
    assert cli == _as_option_names(api)
    assert "--columns flux=F,flux_err=sigma,x=xc,y=yc and --time-column BJD --time-format bjd" \
        in cli

    api, cli = _both(capsys, [path],
                     {"columns": {"flux": "F", "flux_err": "sigma", "x": "xc", "y": "yc"},
                      "time_column": "BJD", "time_format": "bjd"},
                     ["--columns", "flux=F,flux_err=sigma,x=xc,y=yc", "--time-column", "BJD",
                      "--time-format", "bjd"])
    assert isinstance(api, dict) and api == cli
    assert abs(api["depth_ppm"] - 1875.0) < 4 * api["depth_err_ppm"]


def test_a_joint_table_of_two_planets(tmp_path, capsys, epoch):
    first, second = tmp_path / "epoch_03.fits", tmp_path / "epoch_04.fits"
    epoch.write(first)
    other = epoch.copy()
    other.meta["SYSTEM"] = "WASP-43b"
    other.write(second)
    api, cli = _both(capsys, [first, second], {}, [])
    assert api == (f"refused: {second}: names WASP-43b, {first} names XO-3b (2015 challenge); a "
                   "joint fit is of one planet (give system=NAME)")
    assert cli == _as_option_names(api)
    assert cli.endswith("(give --system NAME)")

    api, cli = _both(capsys, [first, second], {"system": "XO-3b (2015 challenge)"},
                     ["--system", "XO-3b (2015 challenge)"])   # the planet given: one fit
    assert isinstance(api, dict) and api["joint"] and api == cli


def test_a_zero_error_result(tmp_path, capsys, xo3_epoch):
    flat = xo3_epoch["table"](noise=0, systematics=False, c1=0.0, c2=0.0, depth=0.0)[::3]
    path = tmp_path / "flat.fits"
    flat.write(path)
    assert np.ptp(flat["flux"]) == 0   # constant flux: the fit has nothing to be unsure of
    api, cli = _both(capsys, [path], {}, [])
    assert re.fullmatch(rf"refused: {re.escape(str(path))}: the poly2 fit gives depth -?0\.0 \+- "
                        r"\S+ ppm: a zero or non-finite error is not a result \(constant flux or "
                        r"a degenerate fit\); nothing written", api), api
    assert cli == api
    assert sorted(p.name for p in tmp_path.iterdir()) == ["flat.fits"]
