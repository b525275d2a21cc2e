"""A plugin is named by its entry point and runs in both profiles (issue 27).

``plugin_demo/`` holds a distribution whose class subclasses BLISS without
setting ``name``; its entry point registers it as ``demo``.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import eclipsebench as eb
from eclipsebench.decorrelate import base
from eclipsebench.engine.layout import Layout

from ..conftest import TINY_RUN_SETS

PLUGIN_DIR = Path(__file__).parent / "plugin_demo"
SRC = Path(__file__).resolve().parents[2] / "src"
# The tiny challenge of tests/conftest.py (two epochs of 233 two-frame cubes), its methods named
# on the command line.
TINY = [s for s in TINY_RUN_SETS if not s.startswith("run.methods=")]


@pytest.fixture
def demo():
    """Install the demo distribution on sys.path and load its entry point; undo afterwards."""
    sys.path.insert(0, str(PLUGIN_DIR))
    base.load_plugins(refresh=True)
    yield eb.method_class("demo")
    sys.path.remove(str(PLUGIN_DIR))
    base._REGISTRY.pop("demo", None)
    sys.modules.pop("ebdemo", None)


def test_a_subclass_without_a_name_takes_its_entry_point_s(demo):
    assert "demo" in eb.methods()
    assert demo.name == "demo" and demo.__name__ == "Demo"
    bliss = eb.method_class("bliss")
    assert bliss.name == "bliss" and issubclass(demo, bliss)
    # its own record: BLISS's fitter policy (the code it runs), no team's profile
    assert demo.record is not bliss.record
    assert demo.record.policy == bliss.record.policy
    assert demo.record.paper is None and not demo.record.in_paper


def test_a_class_naming_itself_otherwise_is_refused(tmp_path):
    pkg = tmp_path / "ebwrong"
    pkg.mkdir()
    (pkg / "__init__.py").write_text(
        "from typing import ClassVar\nfrom eclipsebench.decorrelate.bliss import Bliss\n\n"
        "class Wrong(Bliss):\n    name: ClassVar[str] = 'other'\n")
    info = tmp_path / "ebwrong-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: ebwrong\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[eclipsebench.methods]\nwrong = ebwrong:Wrong\n")
    sys.path.insert(0, str(tmp_path))
    try:
        with pytest.warns(RuntimeWarning, match="named 'other', not 'wrong'"):
            base.load_plugins(refresh=True)
        assert "wrong" not in eb.methods()
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop("ebwrong", None)


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_the_plugin_runs_beside_bliss_in_both_profiles(tmp_path, tiny_run_once):
    out = tmp_path / "run"
    # the tiny challenge's epochs, photometry and BLISS results (tests/conftest.py): the same
    # settings, so the run reuses them and reduces only the plugin's method
    done, _, _ = tiny_run_once
    for folder in ("simulation", "photometry", "results", "results_paper"):
        shutil.copytree(done / folder, out / folder)
    sets = [a for s in TINY for a in ("--set", s)]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(PLUGIN_DIR), str(SRC)])}
    run = subprocess.run([sys.executable, "-m", "eclipsebench", "run", "--epochs", "2",
                          "--methods", "bliss,demo", "--workers", "1", "--out", str(out),
                          "--quiet", "--json", *sets],
                         capture_output=True, text=True, env=env, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    lay = Layout(out)
    summary = json.loads(lay.summary.read_text())
    assert set(summary["methods"]) == {"bliss", "demo"}
    assert set(summary["profiles"]["paper"]["methods"]) == {"bliss", "demo"}
    for e in (1, 2):
        for profile in ("controlled", "paper"):
            res = json.loads(lay.result("demo", e, profile=profile).read_text())
            assert res["method"] == "demo" and res["profile"] == profile
            assert res["depth_ppm"] is not None
        paper = json.loads(lay.result("demo", e, profile="paper").read_text())
        # no team's pipeline: the controlled settings (BLISS's own team entry is not inherited)
        assert paper["profile_detail"] == {"team": None, "settings": "controlled"}
        assert paper["phase"] == "quadratic" and "bic" not in paper["profile_detail"]
