"""A joint fit refuses a posterior or a team's profile in the library: both doors agree.

A joint fit (``eb.reduce([...])``, ``eclipsebench reduce A B``) is least squares with the
controlled settings; ``sampler="mcmc"`` or ``profile="paper"`` asked of one is refused in
one line, however it was given (keyword, option or configuration), before any work.
"""

from __future__ import annotations

import pytest

import eclipsebench as eb
from eclipsebench.cli import main
from eclipsebench.errors import InputError

REFUSED = ": applies to one table; a joint fit of 2 tables is least squares with the " \
          "controlled settings"


@pytest.fixture
def two_tables(tmp_path, xo3_epoch):
    epoch = xo3_epoch["table"](seed=21)[::3]
    paths = [tmp_path / "epoch_03.fits", tmp_path / "epoch_04.fits"]
    for path in paths:
        epoch.write(path)
    return paths


@pytest.mark.parametrize(("key", "value"), [("sampler", "mcmc"), ("profile", "paper")])
def test_a_joint_fit_refuses_through_both_doors(two_tables, capsys, key, value):
    tables = [str(p) for p in two_tables]
    with pytest.raises(InputError) as api:
        eb.reduce(tables, "poly2", **{key: value})
    assert str(api.value) == f'{key}="{value}"{REFUSED}'

    code = main(["reduce", *tables, "--method", "poly2", f"--{key}", value, "--quiet"])
    out, err = capsys.readouterr()
    assert (code, out) == (2, "")
    assert err == f"eclipsebench reduce: error: --{key} {value}{REFUSED}\n"
    # set in the configuration (which the command used to let through to a least-squares
    # fit that ignored it): refused the same, nothing written
    code = main(["reduce", *tables, "--method", "poly2", "--set", f'reduce.{key}="{value}"',
                 "--quiet"])
    assert code == 2 and REFUSED in capsys.readouterr().err
    assert sorted(p.name for p in two_tables[0].parent.iterdir()) == [
        "epoch_03.fits", "epoch_04.fits"]
