"""Issue 37: every input bounded and malformed inputs refused before any work.

Before: a configuration, catalogue or ``--pmap`` naming ``/dev/zero`` read
without end, a FIFO blocked for ever (the timeout guards each test).
"""

from __future__ import annotations

import os

import pytest


@pytest.fixture
def fifo(tmp_path):
    """A FIFO no one writes to: opening it to read would block for ever."""
    path = tmp_path / "fifo.toml"
    os.mkfifo(path)
    return path


@pytest.mark.timeout(60)
@pytest.mark.parametrize("special", ["/dev/zero", "fifo"])
@pytest.mark.parametrize("kind", ["config", "catalogue", "set-catalogue"])
def test_a_device_or_fifo_as_configuration_or_catalogue_is_one_line(kind, special, fifo,
                                                                   tmp_path, cli, bad):
    path = str(fifo) if special == "fifo" else special
    out = tmp_path / "sim"
    argv = {"config": ["simulate", path, "--out", out],
            "catalogue": ["lightcurve", "XO-3b", "--catalogue", path, "--out", out / "lc.ecsv"],
            "set-catalogue": ["simulate", "--set", f"system.catalogue={path}", "--out", out],
            }[kind]
    code, _, err = cli(*argv, "--quiet")
    bad.assert_one_line(code, err, path, "not a regular file")
    assert not out.exists()


@pytest.mark.timeout(60)
@pytest.mark.parametrize("special", ["/dev/zero", "fifo"])
def test_a_device_or_fifo_as_pmap_is_one_line(special, fifo, tmp_path, cli, bad):
    path = str(fifo) if special == "fifo" else special
    table = bad.xo3_table(tmp_path / "t.fits")
    out = tmp_path / "out"
    code, _, err = cli("reduce", table, "--method", "kr-pmap", "--pmap", path,
                       "--out", out / "r.json", "--quiet")
    bad.assert_one_line(code, err, path, "not a regular file")
    code, _, err = cli("trust", table, "--pmap", path, "--out", out, "--quiet")
    bad.assert_one_line(code, err, path, "not a regular file")
    assert not out.exists()


def test_a_configuration_above_its_size_limit_is_one_line(tmp_path, cli, bad, monkeypatch):
    import eclipsebench.config.base as base

    path = tmp_path / "big.toml"
    path.write_text("[challenge]\nseed = 1\n" + "# padding\n" * 200)
    monkeypatch.setattr(base, "MAX_TEXT_FILE_BYTES", 1000)   # the real limit is 16 MiB
    code, _, err = cli("config", path)
    bad.assert_one_line(code, err, str(path), "above the limit of 1000")
