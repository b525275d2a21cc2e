"""`make test` runs the suite in parallel (pytest-xdist): it must run the tests a serial run does.

Each xdist worker collects the whole suite and the controller hands out the ids (whole files,
tests/conftest.py); a parametrisation built from an unordered set, a test collected only
beside some other module, or a plugin that renames tests (xdist's ``loadgroup`` appends
``@group`` to an id) would make the two runs differ. The parallel run here takes its options
from the Makefile's ``test`` recipe, with two workers whatever the machine's cores.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
COLLECTED_IDS_ENV = "ECLIPSEBENCH_COLLECTED_IDS"  # as tests/conftest.py
WORKERS = 2


def make_test_options() -> list[str]:
    """The pytest options of the Makefile's ``test`` recipe, with ``WORKERS`` workers."""
    recipe = re.search(r"^test:.*\n\t(.*)$", (REPO / "Makefile").read_text(), re.MULTILINE)
    assert recipe, "no test recipe in the Makefile"
    options = recipe.group(1).split("-m pytest", 1)[1].split()
    return [str(WORKERS) if o == "$(TEST_WORKERS)" else o for o in options]


def _pytest(args: list[str], env: dict[str, str]) -> subprocess.CompletedProcess:
    # a fresh run, not a worker of this one (xdist tells its workers so in the environment)
    env = {k: v for k, v in env.items() if not k.startswith(("PYTEST_XDIST", "PYTEST_CURRENT"))}
    run = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", *args],
                         cwd=REPO, capture_output=True, text=True, env=env, timeout=900)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    return run


def _serial_ids(tmp_path: Path) -> list[str]:
    run = _pytest(["--collect-only", "-q", "--basetemp", str(tmp_path / "serial")],
                  dict(os.environ))
    lines = run.stdout.splitlines()
    return lines[:lines.index("")]


@pytest.mark.slow  # collects the suite three times: ~30 s of CPU
@pytest.mark.timeout(1800)
def test_the_parallel_run_collects_the_serial_run_s_test_ids(tmp_path):
    options = make_test_options()
    assert "-n" in options and options[options.index("--dist") + 1] == "loadfile", options
    folder = tmp_path / "ids"
    folder.mkdir()
    env = {**os.environ, COLLECTED_IDS_ENV: str(folder)}
    parallel = _pytest([*options, "--basetemp", str(tmp_path / "parallel")], env)
    # it only collects: every item is skipped, the doctests of src/ and docs/ too
    assert re.search(r"^\d+ skipped in ", parallel.stdout.splitlines()[-1]), parallel.stdout[-500:]
    serial = _serial_ids(tmp_path)
    assert len(serial) > 1000 and len(set(serial)) == len(serial)
    files = sorted(folder.iterdir())
    assert [f.name for f in files] == [f"gw{k}.txt" for k in range(WORKERS)]
    for f in files:
        assert sorted(f.read_text().splitlines()) == sorted(serial), f.name
