"""Issue 28: names that become paths are one safe component; outputs stay in the run folder.

Before: ``challenge.name = "../../x"`` climbed out of ``runs/``, a plugin's
entry point named ``../../../escaped`` registered and ``Layout.result`` pointed
outside the run folder, ``reduce --method a/b`` was "internal error:
ValueError", a plugin calling ``sys.exit`` while imported ended the command
with its exit code, and a run folder holding ``results -> elsewhere`` had its
results written through the link.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import pytest

from eclipsebench.challenge.runner import run_challenge
from eclipsebench.config import load_config
from eclipsebench.decorrelate import available_methods, base
from eclipsebench.engine.layout import Layout
from eclipsebench.errors import InputError
from eclipsebench.io.paths import check_inside

# as tests/challenge/test_runner.py
TINY = ["challenge.epochs=2", "observation.pre_cubes=1", "observation.frames_per_cube=2",
        "simulation.subsamples=1", "simulation.calibration_frames=2000",
        'run.methods=["pld", "bliss"]', "run.bootstrap=50", "run.report=false",
        "run.empirical_photon_limit=false"]


@pytest.mark.parametrize("name", ["/tmp/x", "../../x", "a b", ".hidden", "x/y", ""])
def test_a_challenge_name_that_is_not_one_path_component_is_refused(name, tmp_path, cli, bad,
                                                                     monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = cli("run", "--set", f'challenge.name="{name}"', "--quiet")
    bad.assert_one_line(code, err, "challenge.name")
    assert bad.snapshot(tmp_path) == set()


def test_reduce_with_a_method_name_holding_a_slash_is_an_unknown_method(tmp_path, cli, bad):
    table = bad.xo3_table(tmp_path / "epoch_01.fits")
    before = bad.snapshot(tmp_path)
    code, _, err = cli("reduce", table, "--method", "a/b")
    bad.assert_one_line(code, err, "a/b", "unknown method")
    assert bad.snapshot(tmp_path) == before


def test_layout_refuses_a_method_name_that_leaves_the_folder(tmp_path):
    with pytest.raises(InputError, match="method '../../../escaped'"):
        Layout(tmp_path).result("../../../escaped", 1)
    assert Layout(tmp_path).result("kr-pmap", 1) == tmp_path / "results" / "kr-pmap" / \
        "epoch_01.json"


def _plugin_dist(folder: Path, entries: dict[str, str], modules: dict[str, str]) -> Path:
    dist = folder / "ebbadplugins-0.1.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: ebbadplugins\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text(
        "[eclipsebench.methods]\n" + "".join(f"{k} = {v}\n" for k, v in entries.items()))
    for name, text in modules.items():
        (folder / f"{name}.py").write_text(text)
    return folder


def test_a_plugin_with_an_unsafe_name_or_calling_sys_exit_is_left_out(tmp_path):
    imported = tmp_path / "imported.txt"
    folder = _plugin_dist(
        tmp_path / "dist",
        {"../../../escaped": "ebbad_escaped:Escaped", "exits": "ebbad_exits:Exits"},
        {"ebbad_escaped": f"open({str(imported)!r}, 'w').write('imported')\n",
         "ebbad_exits": "import sys\nsys.exit(3)\n"})
    sys.path.insert(0, str(folder))
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            base.load_plugins(refresh=True)  # before: SystemExit(3) out of here
    finally:
        sys.path.remove(str(folder))
        for name in ("ebbad_escaped", "ebbad_exits"):
            sys.modules.pop(name, None)
            base._REGISTRY.pop(name, None)
    messages = [str(w.message) for w in caught]
    assert any("'../../../escaped'" in m and "not a safe file name" in m for m in messages)
    assert any("'exits'" in m and "sys.exit(3)" in m for m in messages), messages
    assert all("\n" not in m for m in messages)
    assert "../../../escaped" not in available_methods() and "exits" not in available_methods()
    assert not imported.exists()  # the unsafe name is refused before its code runs


def test_a_link_in_the_run_folder_that_leads_out_of_it_is_refused(tmp_path):
    root, elsewhere = tmp_path / "run", tmp_path / "elsewhere"
    root.mkdir()
    elsewhere.mkdir()
    (root / "results").symlink_to(elsewhere)
    with pytest.raises(InputError, match="outside the run folder"):
        run_challenge(load_config(None, TINY), root, workers=1)
    assert sorted(p.name for p in root.iterdir()) == ["results"]
    assert list(elsewhere.iterdir()) == []
    (root / "results").unlink()
    (root / "simulation").mkdir()
    (root / "simulation" / "r20150001").symlink_to(elsewhere)  # an AOR's cube folder
    with pytest.raises(InputError, match="r20150001"):
        run_challenge(load_config(None, TINY), root, workers=1)
    assert list(elsewhere.iterdir()) == []


def test_simulate_refuses_a_link_out_of_its_folder(tmp_path, cli, bad):
    out, elsewhere = tmp_path / "sim", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / "lightcurves").symlink_to(elsewhere)
    argv = ["simulate", "--out", out, "--quiet"]
    for item in TINY:
        argv += ["--set", item]
    code, _, err = cli(*argv)
    bad.assert_one_line(code, err, "lightcurves", "outside the run folder")
    assert list(elsewhere.iterdir()) == [] and sorted(p.name for p in out.iterdir()) == [
        "lightcurves"]


def test_check_inside_follows_links(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "up").symlink_to(tmp_path)
    assert check_inside(tmp_path / "a" / "up" / "a" / "x", tmp_path / "a") is not None
    with pytest.raises(InputError):
        check_inside(tmp_path / "a" / "up" / "x", tmp_path / "a")


@pytest.mark.filterwarnings("default::RuntimeWarning")
def test_a_plugin_calling_sys_exit_does_not_end_the_command(tmp_path, cli, bad, monkeypatch,
                                                            caplog):
    """Before: any command ended with the plugin's exit code (3) and no message."""
    folder = _plugin_dist(tmp_path / "dist", {"exits": "ebbad_exits2:Exits"},
                          {"ebbad_exits2": "import sys\nsys.exit(3)\n"})
    table = bad.xo3_table(tmp_path / "epoch_01.fits")
    monkeypatch.syspath_prepend(str(folder))
    monkeypatch.setattr(base, "_PLUGINS_LOADED", False)
    try:
        code, _, err = cli("reduce", table, "--method", "no-such-method")
        warned = [r.getMessage() for r in caplog.records if r.name == "eclipsebench.warnings"]
    finally:
        sys.modules.pop("ebbad_exits2", None)
        base._REGISTRY.pop("exits", None)
        monkeypatch.undo()
        base.load_plugins(refresh=True)
    bad.assert_one_line(code, err, "unknown method")  # not the plugin's exit code 3
    assert len(warned) == 1 and "\n" not in warned[0], warned  # one log line (stderr in a shell)
    assert "method plugin 'exits'" in warned[0] and "sys.exit(3)" in warned[0]
