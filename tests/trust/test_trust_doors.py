"""Issue 39: ``eclipsebench trust`` is a shell over ``eb.trust``, so both doors refuse alike.

The command parses its options and calls the library's trust run
(:func:`eclipsebench.api.trust_with_report`); its refusals are the library's,
naming its options (``--out``, ``--depth``) where the API names its keywords.
"""

from __future__ import annotations

import pytest

import eclipsebench as eb
import eclipsebench.api as api_module
from eclipsebench.cli import main
from eclipsebench.errors import InputError


@pytest.fixture(scope="module")
def table(small_observation_table):
    """A short simulated epoch's photometry table (this package's; tests/conftest.py's
    small observation, shared with tests/trust)."""
    return small_observation_table


def _cli(capsys, argv: list[str]) -> str:
    code = main(["trust", *argv, "--methods", "poly2", "--twins", "10", "--workers", "1",
                 "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    return err.removeprefix("eclipsebench trust: error: ").strip()


def test_an_out_that_is_a_file_is_refused_alike(tmp_path, capsys, table):
    taken = tmp_path / "taken"
    taken.write_text("not a trust folder")
    with pytest.raises(InputError) as api:
        eb.trust(table, taken, methods=["poly2"], twins=10, workers=1)
    cli = _cli(capsys, [str(table), "--out", str(taken)])
    assert str(api.value) == f"out {taken}: exists and is not a folder; expected a folder"
    assert cli == "--" + str(api.value)
    assert taken.read_text() == "not a trust folder"


def test_a_depth_beyond_a_fit_is_refused_alike(tmp_path, capsys, table):
    with pytest.raises(InputError) as api:
        eb.trust(table, tmp_path / "t", methods=["poly2"], twins=10, workers=1,
                 depth_ppm=2e5)
    cli = _cli(capsys, [str(table), "--out", str(tmp_path / "t"), "--depth", "200000"])
    assert str(api.value).startswith("depth_ppm: 200000 ppm is beyond what a fit can return")
    assert cli == str(api.value).replace("depth_ppm:", "--depth:", 1)
    assert not (tmp_path / "t").exists()


def test_the_command_runs_the_librarys_trust(tmp_path, capsys, table, monkeypatch):
    """What the command does is the library's: a change there is a change of the command."""
    seen = {}

    def refuse(given, command):
        seen.update(given, command=command)
        raise InputError("the library's door")

    monkeypatch.setattr(api_module, "_trust", refuse)
    assert _cli(capsys, [str(table), "--out", str(tmp_path / "t"), "--sampler", "leastsq",
                         "--seed", "7"]) == "the library's door"
    assert seen["reduce_options"] == {"sampler": "leastsq"} and seen["seed"] == 7
    assert seen["labels"]["depth_ppm"] == "--depth"
    assert seen["command"].startswith("eclipsebench trust ")
