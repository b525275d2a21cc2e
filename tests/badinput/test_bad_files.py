"""Bad input files: header values, duplicated cubes, unreadable folders, configurations, full disks."""

from __future__ import annotations

import errno
import os
import shutil

import pytest
from astropy.io import fits

from eclipsebench.errors import EXIT_ENVIRONMENT, DataError
from eclipsebench.io.bcd_read import read_bcd_header


def _set_raw_card(path, key: str, text: str) -> None:
    """Overwrite the value of header card ``key`` with raw ``text`` (astropy will not write NaN)."""
    data = bytearray(path.read_bytes())
    start = data.find(key.ljust(8).encode() + b"=")
    assert start >= 0
    data[start:start + 80] = (key.ljust(8) + "= " + text.rjust(20)).ljust(80).encode()
    path.write_bytes(bytes(data))


@pytest.mark.shared_data
@pytest.mark.parametrize("key,value,expected", [
    ("EXPID", "'xyz'", "expected an integer"),
    ("BMJD_OBS", "NaN", "expected a finite number"),
    ("BMJD_OBS", "'soon'", "expected a finite number"),
    ("GAIN", "'three'", "expected a finite number"),
    ("AFOWLNUM", "8.5", "expected an integer"),
    ("RONOISE", "'x'", "expected a finite number"),
])
def test_bad_header_value_names_the_file_and_key(key, value, expected, real_cubes, tmp_path,
                                                 cli, bad):
    path = real_cubes((2,))[0]
    _set_raw_card(path, key, value)
    out = tmp_path / "o.fits"
    code, _, err = cli("photometry", path.parent, "--out", out, "--quiet")
    bad.assert_one_line(code, err, path.name, key, expected)
    assert not out.exists()


@pytest.mark.shared_data
def test_a_cube_copied_under_another_expid_is_refused(real_cubes, tmp_path, cli, bad):
    first, *_ = real_cubes((0, 1, 2))
    copy = first.with_name(first.name.replace("_0000_0000_", "_0005_0000_"))
    shutil.copy(first, copy)
    before = bad.snapshot(tmp_path)
    code, _, err = cli("photometry", first.parent, "--out", tmp_path / "o.fits", "--quiet")
    bad.assert_one_line(code, err, copy.name, "EXPID")
    assert bad.snapshot(tmp_path) == before


@pytest.mark.shared_data
def test_a_duplicate_cube_with_consistent_headers_is_refused(real_cubes, tmp_path, cli, bad):
    first, *_ = real_cubes((0, 1, 2))
    copy = first.with_name(first.name.replace("_0000_0000_", "_0005_0000_"))
    shutil.copy(first, copy)
    with fits.open(copy, mode="update") as hdul:
        hdul[0].header["EXPID"] = 5
    code, _, err = cli("photometry", first.parent, "--out", tmp_path / "o.fits", "--quiet")
    bad.assert_one_line(code, err, "duplicate", first.name, copy.name)
    assert not (tmp_path / "o.fits").exists()


def test_two_cubes_with_the_same_bmjd_obs_are_refused(tmp_path, cli, bad):
    folder = tmp_path / "bcd"
    for k in range(3):
        bad.write_cube(folder, bad.star_cube(8, seed=k), expid=k, bmjd=57000.0 if k < 2 else None)
    code, _, err = cli("photometry", folder, "--out", tmp_path / "o.fits", "--quiet")
    bad.assert_one_line(code, err, "duplicate", "BMJD_OBS", "SPITZER_I2_123456_0001_0000_1_bcd.fits")
    assert not (tmp_path / "o.fits").exists()


def test_identical_aorkey_expid_dce_in_two_folders_is_refused(tmp_path, cli, bad):
    for sub in ("a", "b"):
        bad.write_cube(tmp_path / "bcd" / sub, bad.star_cube(8, seed=1), expid=0)
    code, _, err = cli("photometry", tmp_path / "bcd", "--out", tmp_path / "o.fits", "--quiet")
    bad.assert_one_line(code, err, "duplicate", "EXPID 0")


@pytest.mark.parametrize("where", ["root", "subfolder"])
def test_unreadable_folder_is_permission_denied(where, tmp_path, cli, bad, monkeypatch):
    folder = tmp_path / "bcd"
    bad.write_cube(folder, bad.star_cube(8), expid=0)
    locked = folder if where == "root" else folder / "locked"
    locked.mkdir(exist_ok=True)
    locked.chmod(0o000)
    real_access, real_scandir = os.access, os.scandir

    def access(path, mode, *args, **kwargs):  # root ignores mode 000: pretend we are not root
        if os.path.abspath(path) == str(locked):
            return False
        return real_access(path, mode, *args, **kwargs)

    def scandir(path="."):
        if os.path.abspath(path) == str(locked):
            raise PermissionError(errno.EACCES, "Permission denied", str(locked))
        return real_scandir(path)

    monkeypatch.setattr(os, "access", access)
    monkeypatch.setattr(os, "scandir", scandir)
    try:
        code, _, err = cli("photometry", folder, "--out", tmp_path / "o.fits", "--quiet")
    finally:
        locked.chmod(0o755)
    bad.assert_one_line(code, err, str(locked), "permission denied")
    assert "no IRAC" not in err[0]


@pytest.mark.parametrize("content,expected", [
    (b"\xff\xfe[\x00c\x00]\x00", "UTF-16"),
    (b"\xef\xbb\xbf[challenge]\nseed = 1\n", "byte-order mark"),
    (b'[system]\nname = "\xe9"\n', "not UTF-8"),
])
def test_config_not_utf8_names_the_file(content, expected, tmp_path, cli, bad):
    path = tmp_path / "conf ü.toml"
    path.write_bytes(content)
    for argv in (["config", path], ["simulate", path, "--out", tmp_path / "sim"],
                 ["photometry", tmp_path, "--config", path, "--out", tmp_path / "o.fits"]):
        code, _, err = cli(*argv, "--quiet")
        bad.assert_one_line(code, err, str(path), expected)
    assert bad.snapshot(tmp_path) == {path.name}


def test_config_with_an_unknown_planet_names_the_key_and_file(tmp_path, cli, bad):
    path = tmp_path / "c.toml"
    path.write_text('[system]\nname = "XO-99z"\n')
    code, _, err = cli("config", path)
    bad.assert_one_line(code, err, str(path), "system.name", "XO-99z")
    code, _, err = cli("config", "--set", "system.name=Nope-1b")
    bad.assert_one_line(code, err, "system.name", "Nope-1b")
    out = tmp_path / "sim"
    for command in ("simulate", "run"):
        code, _, err = cli(command, path, "--out", out)
        bad.assert_one_line(code, err, str(path), "system.name", "XO-99z")
        assert not out.exists()


@pytest.mark.parametrize("command", ["photometry", "lightcurve", "reduce-json"])
def test_a_full_disk_names_the_file_and_leaves_nothing(command, tmp_path, cli, bad, monkeypatch,
                                                       star_folder):
    """ENOSPC from the writer: one line naming the file and its folder, no temporary or
    partial file, and the exit code of an environment failure (issue 28: not bad input)."""
    import eclipsebench.io.atomic as atomic

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    if command == "photometry":
        out = tmp_path / "out" / "o.fits"
        monkeypatch.setattr(fits.HDUList, "writeto", full)
        argv = ["photometry", star_folder, "--out", out]
    elif command == "lightcurve":
        out = tmp_path / "out" / "lc.ecsv"
        from astropy.table import Table
        monkeypatch.setattr(Table, "write", full)
        argv = ["lightcurve", "--hours", "0.1", "--out", out]
    else:
        from astropy.table import Table
        out = tmp_path / "out" / "r.json"
        Table({name: [1.0] for name in ("time_bmjd", "flux", "flux_err", "x", "y")}).write(
            tmp_path / "t.ecsv", format="ascii.ecsv")  # the columns a fit needs (checked first)
        _fake_reduce(monkeypatch)
        monkeypatch.setattr(atomic.Path, "write_bytes", full)
        argv = ["reduce", tmp_path / "t.ecsv", "--method", "pld", "--out", out,
                "--system", "XO-3b"]
    before = bad.snapshot(tmp_path)
    code, _, err = cli(*argv, "--quiet")
    bad.assert_one_line(code, err, str(out), str(out.parent), "no space left",
                        exit_code=EXIT_ENVIRONMENT)
    assert bad.snapshot(tmp_path) == before  # no partial file, no temporary, no empty folder


def _fake_reduce(monkeypatch):
    """reduce_epoch returning a tiny result (the fit itself is not what is tested), where
    ``eclipsebench reduce`` reaches it: through ``eb.reduce``."""
    import types

    import numpy as np
    from astropy.table import Table

    import eclipsebench.api as fit_reduce

    def reduce_epoch(*args, **kwargs):
        return types.SimpleNamespace(
            depth_ppm=1800.0, depth_err_ppm=kwargs.pop("_err", 50.0), chain=None,
            to_dict=lambda: {"depth_ppm": 1800.0, "depth_err_ppm": 50.0},
            lightcurve_table=lambda: Table({"time_bmjd": np.arange(3.0)}))

    monkeypatch.setattr(fit_reduce, "reduce_epoch", reduce_epoch)


def test_read_bcd_header_error_is_a_data_error(tmp_path, bad):
    path = bad.write_cube(tmp_path, bad.star_cube(2), expid=3, EXPID=4)
    with pytest.raises(DataError, match="EXPID = 4 but the name says 0003"):
        read_bcd_header(path)


def test_a_file_size_limit_is_one_line_exit_3_and_leaves_nothing(tmp_path):
    """EFBIG (``ulimit -f``) is the machine's limit, not bad input: exit 3, one line naming
    the file and what to do, no partial file (issue 38: it was exit 2 in three lines)."""
    import resource
    import subprocess
    import sys

    out = tmp_path / "out" / "lc.ecsv"
    code = ("import resource, sys\n"
            "resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))\n"
            "from eclipsebench.cli import main\n"
            "sys.exit(main(sys.argv[1:]))\n")
    assert resource.getrlimit(resource.RLIMIT_FSIZE)[0] != 0
    run = subprocess.run([sys.executable, "-c", code, "lightcurve", "--hours", "2", "--out",
                          str(out), "--quiet"], capture_output=True, text=True, timeout=300)
    lines = run.stderr.strip().splitlines()
    assert run.returncode == EXIT_ENVIRONMENT, run.stderr
    assert len(lines) == 1 and str(out) in lines[0] and "ulimit -f" in lines[0], lines
    assert not out.exists() and not list(out.parent.glob("*"))
