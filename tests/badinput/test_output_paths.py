"""Output paths that cannot be written: one line naming the path, exit 2, before any work."""

from __future__ import annotations

import importlib
import os

import pytest

KINDS = ("existing_folder", "parent_is_file", "proc", "read_only")


def _no_work(monkeypatch):
    """Make every command's real work fail loudly: the check must come first."""
    def boom(*args, **kwargs):
        raise AssertionError("work started before the output path was checked")

    # where the commands find them when they run (each imports its work inside ``run``)
    for module, name in (("eclipsebench.photometry.pipeline", "photometry_tables"),
                         ("eclipsebench.simulation.challenge", "simulate_challenge"),
                         ("eclipsebench.api", "reduce_epoch"),   # reduce runs eb.reduce
                         ("eclipsebench.astro.lightcurve", "light_curve_function")):
        monkeypatch.setattr(importlib.import_module(module), name, boom)


def _bad_out(kind: str, tmp_path, monkeypatch, name: str, folder: bool) -> str:
    """An output path of the given kind; ``folder``: the command writes a folder there."""
    if kind == "existing_folder":
        target = tmp_path / name
        if folder:
            target.write_text("a file where a folder is expected")
        else:
            target.mkdir()
        return str(target)
    if kind == "parent_is_file":
        blocker = tmp_path / "plain.txt"
        blocker.write_text("x")
        return str(blocker / name)
    if kind == "proc":
        return f"/proc/eclipsebench-test/{name}"
    ro = tmp_path / "read-only"
    ro.mkdir()
    ro.chmod(0o555)
    real_access = os.access

    def access(path, mode, *args, **kwargs):  # we run as root: chmod alone does not stop us
        if os.path.abspath(path) == str(ro) and mode & os.W_OK:
            return False
        return real_access(path, mode, *args, **kwargs)

    monkeypatch.setattr(os, "access", access)
    return str(ro / name)


COMMANDS = {
    # command: (argv before --out, name of the output, the command writes a folder)
    "photometry-file": (lambda d: ["photometry", d["bcd"]], "o.fits", False),
    "photometry-folder": (lambda d: ["photometry", d["bcd"]], "phot", True),
    "simulate": (lambda d: ["simulate"], "sim", True),
    "lightcurve": (lambda d: ["lightcurve"], "lc.ecsv", False),
    "reduce": (lambda d: ["reduce", d["table"], "--method", "pld"], "r.json", False),
}


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_unwritable_out_is_one_line_before_any_work(command, kind, tmp_path, monkeypatch, cli,
                                                    bad, star_folder):
    table = tmp_path / "epoch_01.fits"
    table.write_bytes(b"not read: the output is checked first")
    argv, name, folder = COMMANDS[command]
    if command == "photometry-folder" and kind == "existing_folder":
        name = "phot"  # a regular file where the output folder should be
    out = _bad_out(kind, tmp_path, monkeypatch, name, folder)
    _no_work(monkeypatch)
    before = bad.snapshot(tmp_path)
    code, _, err = cli(*argv({"bcd": star_folder, "table": table}), "--out", out, "--quiet")
    bad.assert_one_line(code, err, "--out", out)
    expected = "a folder" if folder else "a file"
    assert expected in err[0] or "permission denied" in err[0] or "cannot write" in err[0]
    assert bad.snapshot(tmp_path) == before


def test_reduce_out_naming_a_folder_leaves_no_orphan_light_curve(tmp_path, cli, bad, monkeypatch):
    table = tmp_path / "epoch_01.fits"
    table.write_bytes(b"x")
    (tmp_path / "DIR.json").mkdir()
    _no_work(monkeypatch)
    code, _, err = cli("reduce", table, "--method", "pld", "--out",
                           tmp_path / "DIR.json")
    bad.assert_one_line(code, err, "DIR.json", "existing folder")
    assert not (tmp_path / "DIR.lc.ecsv").exists()


def test_reduce_light_curve_path_is_checked_too(tmp_path, cli, bad, monkeypatch):
    table = tmp_path / "epoch_01.fits"
    table.write_bytes(b"x")
    (tmp_path / "r.lc.ecsv").mkdir()
    _no_work(monkeypatch)
    code, _, err = cli("reduce", table, "--method", "pld", "--out", tmp_path / "r.json")
    bad.assert_one_line(code, err, "r.lc.ecsv")
    assert not (tmp_path / "r.json").exists()


@pytest.mark.parametrize("option,value", [("--plot", "lc.xyz"), ("--out", "")])
def test_lightcurve_plot_format_and_empty_out(option, value, tmp_path, cli, bad, monkeypatch):
    _no_work(monkeypatch)
    target = str(tmp_path / value) if value else value
    code, _, err = cli("lightcurve", option, target)
    if value:
        bad.assert_one_line(code, err, option, "lc.xyz", ".png")
    else:
        assert code == 0 or len(err) == 1  # an empty --out means "no file"
    assert bad.snapshot(tmp_path) == set()


def test_a_failed_simulate_leaves_no_empty_output_folder(tmp_path, cli, bad):
    config = tmp_path / "unknown.toml"
    config.write_text('[system]\nname = "XO-99z"\n')
    out = tmp_path / "new" / "sim"
    code, _, err = cli("simulate", config, "--out", out, "--quiet")
    bad.assert_one_line(code, err, "XO-99z")
    assert bad.snapshot(tmp_path) == {"unknown.toml"}
