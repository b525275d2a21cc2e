"""The house rule of docs/architecture.md: the package-level import graph has no cycle."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

TOOL = Path(__file__).resolve().parents[2] / "tools" / "import_graph.py"


def test_package_imports_point_down_the_layers():
    run = subprocess.run([sys.executable, str(TOOL)], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    graph = dict(line.split(" -> ") for line in run.stdout.splitlines())
    lowest = {k.strip(): set(v.split(", ")) for k, v in graph.items()}
    assert lowest["detector"] == {"errors"}
    assert "challenge" not in set().union(*(v for k, v in lowest.items()
                                             if k not in ("commands", "challenge")))
