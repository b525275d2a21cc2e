"""The house rule of docs/architecture.md: imports point down the layer table, and nothing cycles."""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
TOOL = REPO / "tools" / "import_graph.py"
PACKAGE = REPO / "src" / "eclipsebench"
DOC = REPO / "docs" / "architecture.md"


def _tool():
    spec = importlib.util.spec_from_file_location("import_graph", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_package_imports_point_down_the_layers():
    run = subprocess.run([sys.executable, str(TOOL)], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    graph = dict(line.split(" -> ") for line in run.stdout.splitlines())
    lowest = {k.strip(): set(v.split(", ")) for k, v in graph.items()}
    assert lowest["detector"] == {"errors"}
    assert {k for k, v in lowest.items() if "challenge" in v} <= {"api", "commands"}


def test_the_layers_come_from_the_table_in_the_docs():
    layers = _tool().layers(DOC)
    assert layers["errors"][0] == 0 and layers["detector"][0] == 1
    assert layers["decorrelate"][0] == 3 and layers["fit"][0] == 4
    assert layers["cli"][0] == 8
    # every package of the source tree has a row
    packages = {p.name for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    packages |= {p.stem for p in PACKAGE.glob("*.py") if p.stem != "__init__"}
    assert packages <= set(layers)


@pytest.fixture(scope="module")
def clean_copy(tmp_path_factory):
    """A copy of the source package, checked once to pass the rule."""
    root = tmp_path_factory.mktemp("clean") / "eclipsebench"
    shutil.copytree(PACKAGE, root, ignore=shutil.ignore_patterns("__pycache__", "data"))
    assert _tool().check(root, DOC)[1] == []
    return root


@pytest.fixture
def package_copy(clean_copy, tmp_path):
    """A copy of the source package (of ``clean_copy``, which passes the rule), to add a
    module that breaks the rule."""
    root = tmp_path / "eclipsebench"
    shutil.copytree(clean_copy, root)
    return root


@pytest.mark.parametrize("source", [
    # at module level
    "from ..fit.reduce import reduce_epoch\n",
    # inside a function
    "def f():\n    from eclipsebench.fit import reduce\n    return reduce\n",
    # for annotations only
    "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from ..fit.result import EpochResult\n",
    # a package of the same layer
    "import eclipsebench.astro.orbit\n",
])
def test_an_import_up_the_layers_fails_the_check(package_copy, source):
    (package_copy / "detector" / "leak.py").write_text(source)
    _, problems = _tool().check(package_copy, DOC)
    broken = [p for p in problems if not p.startswith("cycle:")]
    assert len(broken) == 1 and "detector/leak.py" in broken[0], problems
    run = subprocess.run([sys.executable, str(TOOL), "--root", str(package_copy)],
                         capture_output=True, text=True)
    assert run.returncode == 1 and "broken: eclipsebench/detector/leak.py" in run.stdout


def test_an_import_down_the_layers_passes(package_copy):
    (package_copy / "fit" / "fine.py").write_text("from ..detector.constants import SUB_2S\n")
    assert _tool().check(package_copy, DOC)[1] == []


def test_a_package_missing_from_the_table_fails(package_copy):
    (package_copy / "newpkg").mkdir()
    (package_copy / "newpkg" / "__init__.py").write_text("from ..errors import InputError\n")
    _, problems = _tool().check(package_copy, DOC)
    assert any("'newpkg' is not in the layer table" in p for p in problems), problems


def test_the_package_has_no_cycle_between_modules():
    assert _tool().module_cycles(PACKAGE) == []


@pytest.mark.parametrize("source", [
    # the loop issue 39 found: a function-local import of a module that imports this one
    "def joint():\n    from ..reduce import reduce_epoch\n    return reduce_epoch\n",
    # at module level, through a package's name
    "from ...fit import reduce\n",
])
def test_a_cycle_between_modules_of_one_package_fails_the_check(package_copy, source):
    """fit/reduce.py imports fit/result/; result/joint.py importing reduce back closes a
    loop inside one package, which the package graph cannot see."""
    result = package_copy / "fit" / "result" / "joint.py"
    result.write_text(result.read_text() + "\n\n" + source)
    _, problems = _tool().check(package_copy, DOC)
    loops = [p for p in problems if p.startswith("module cycle:")]
    assert len(loops) == 1 and "eclipsebench.fit.reduce" in loops[0] \
        and "eclipsebench.fit.result" in loops[0], problems
    run = subprocess.run([sys.executable, str(TOOL), "--root", str(package_copy)],
                         capture_output=True, text=True)
    assert run.returncode == 1 and "broken: module cycle:" in run.stdout


def test_an_import_for_annotations_only_is_no_module_cycle(package_copy):
    result = package_copy / "fit" / "result" / "joint.py"
    result.write_text(result.read_text() + "\n\nfrom typing import TYPE_CHECKING\n"
                      "if TYPE_CHECKING:\n    from ..reduce import reduce_epoch\n")
    assert _tool().module_cycles(package_copy) == []
