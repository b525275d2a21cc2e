"""Run every benchmark in bench/ (files named bench_*.py) and print their figures.

Each benchmark is a script that prints its own results; pass names to run a
subset: ``python bench/run_all.py photometry simulate``.
"""

from __future__ import annotations

import platform
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(argv: list[str]) -> int:
    scripts = sorted(HERE.glob("bench_*.py"))
    if argv:
        scripts = [s for s in scripts if any(a in s.stem for a in argv)]
    print(f"# eclipsebench benchmarks, {time.strftime('%Y-%m-%d')}, {platform.machine()}, "
          f"{platform.python_version()}, cores: {__import__('os').cpu_count()}")
    status = 0
    for script in scripts:
        print(f"\n## {script.stem}", flush=True)
        status |= subprocess.call([sys.executable, str(script)])
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
