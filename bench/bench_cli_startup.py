"""How fast the command line answers (issue 29): --version, --help, and a command reaching its work.

Each case is a fresh interpreter, timed wall-clock from ``subprocess`` start
to exit, run ``--repeat`` times after one warm-up (which also writes the
bytecode cache, as ``pip install`` does); the median is printed with its
ratio to ``python -c pass`` measured the same way in the same run, so a
loaded machine shows as a slow ``pass`` rather than a slow command.

The cases:

- ``--version`` and ``reduce --help``: the parser alone (target: 0.3 s);
- ``photon-limit ...``: a light command, start to finish;
- ``reduce missing.fits``: a misspelt table, start to its one-line error;
- ``reduce TABLE --method pld`` up to the fit: the command's imports (numpy,
  scipy, astropy, numba, batman, the methods), the table read and checked,
  stopped where :func:`eclipsebench.fit.reduce.reduce_epoch` is entered
  (target: 1 s; the fit itself is ``bench_reduce.py``'s);
- ``reduce TABLE --method bliss --sampler leastsq``, the whole command, and
  below it the same command run again in the interpreter that ran it once
  (imports done, numba's kernels loaded): the difference is what starting
  costs (issue 40's goal: at most 1.0 s).

Usage: ``python bench/bench_cli_startup.py [--repeat N]``. The code timed is
the ``eclipsebench`` this interpreter imports (``PYTHONPATH=src`` for a
checkout).
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import eclipsebench

SRC = str(Path(eclipsebench.__file__).resolve().parents[1])

#: Run ``main(argv)`` with the fit replaced by an exit: the time to reach the work.
_UP_TO_THE_FIT = """
import sys
import eclipsebench.fit.reduce as fit
def stop(*args, **kwargs):
    raise SystemExit(0)
fit.reduce_epoch = stop
from eclipsebench.cli import main
sys.exit(main(sys.argv[1:]))
"""


#: Run ``main(argv)`` once (imports, kernels), then time it again in the same process; exit
#: with the second run's CPU seconds in microseconds on stderr's last line.
_IN_PROCESS = """
import sys, time
from eclipsebench.cli import main
main(sys.argv[1:])
c0 = time.process_time()
main(sys.argv[1:])
print(f"{time.process_time() - c0:.4f}", file=sys.stderr)
"""


def _table(folder: Path, n: int = 2000, name: str = "lc.csv") -> Path:
    """A light curve another pipeline might give (CSV: time, flux, error, x, y), ``n`` frames
    of 2 s (15,000 span the XO-3b eclipse at 57234.519 BMJD)."""
    path = folder / name
    lines = ["time_bmjd,flux,flux_err,x,y"]
    for i in range(n):
        t = 57234.3406 + i * 2.008 / 86400
        lines.append(f"{t:.7f},{1.0 + 1e-4 * ((i * 7919) % 13 - 6):.6f},0.002,"
                     f"{15.0 + 0.01 * ((i * 31) % 7):.3f},{15.1 + 0.01 * ((i * 17) % 5):.3f}")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _cases(folder: Path) -> list[tuple[str, list[str]]]:
    py = [sys.executable]
    cli = py + ["-m", "eclipsebench"]
    table = _table(folder)
    bliss = [a.replace("{table}", str(_table(folder, 15000, "lc_eclipse.csv"))) for a in BLISS]
    return [
        ("python -c pass", py + ["-c", "pass"]),
        ("eclipsebench --version", cli + ["--version"]),
        ("eclipsebench reduce --help", cli + ["reduce", "--help"]),
        ("eclipsebench photon-limit --flux-net 70858 ... (whole command)",
         cli + ["photon-limit", "--flux-net", "70858", "--flux-aperture", "70917",
                "--flux-background", "463", "--frames", "14912", "--depth-ppm", "1520"]),
        ("eclipsebench reduce missing.fits --method pld (to its error)",
         cli + ["reduce", str(folder / "missing.fits"), "--method", "pld"]),
        ("eclipsebench reduce lc.csv --method pld (to the fit)",
         py + ["-c", _UP_TO_THE_FIT, "reduce", str(table), "--method", "pld",
               "--out", str(folder / "lc.pld.json")]),
        ("eclipsebench reduce lc_eclipse.csv --method bliss --sampler leastsq",
         cli + bliss + [str(folder / "lc.bliss.json")]),
    ]


#: The reduction whose start-up is issue 40's goal (the table's path first).
BLISS = ["reduce", "{table}", "--method", "bliss", "--sampler", "leastsq", "--system", "XO-3b",
         "--quiet", "--out"]


def _in_process_fit(folder: Path, env: dict[str, str], repeat: int) -> list[float]:
    """CPU seconds of the BLISS command run a second time in one interpreter, ``repeat`` times."""
    argv = [a.replace("{table}", str(folder / "lc_eclipse.csv")) for a in BLISS]
    out = []
    for _ in range(repeat):
        done = subprocess.run([sys.executable, "-c", _IN_PROCESS, *argv,
                               str(folder / "lc.bliss.json")], env=env, capture_output=True,
                              text=True, check=True)
        out.append(float(done.stderr.strip().splitlines()[-1]))
    return out


def _cpu() -> float:
    """CPU seconds (user + system) of the finished children so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _time(argv: list[str], env: dict[str, str], repeat: int) -> tuple[list[float], list[float]]:
    """Wall and CPU seconds of ``repeat`` runs after one warm-up."""
    warm = subprocess.run(argv, env=env, capture_output=True, check=False)  # + bytecode
    if warm.returncode not in (0, 2):  # 2: the misspelt table's one-line error
        raise SystemExit(f"{argv}: exit {warm.returncode}: {warm.stderr.decode()[-500:]}")
    wall, cpu = [], []
    for _ in range(repeat):
        c0, t0 = _cpu(), time.perf_counter()
        subprocess.run(argv, env=env, capture_output=True, check=False)
        wall.append(time.perf_counter() - t0)
        cpu.append(_cpu() - c0)
    return wall, cpu


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7, help="timed runs per case (default 7)")
    args = parser.parse_args(argv)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPATH"] = SRC + os.pathsep + env.get("PYTHONPATH", "")
    print(f"# {time.strftime('%Y-%m-%d %H:%M %Z')}, {platform.machine()}, "
          f"{platform.processor() or platform.platform()}, Python {platform.python_version()}, "
          f"cores {os.cpu_count()}, load average {os.getloadavg()[0]:.2f}, "
          f"eclipsebench {eclipsebench.__version__} from {SRC}")
    print(f"# median of {args.repeat} runs after one warm-up, wall seconds from process "
          "start to exit; cpu: the median user + system seconds (less sensitive to a loaded "
          "machine)")
    print(f"{'command':<66} {'median s':>9} {'min s':>7} {'x pass':>7} {'cpu s':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        base = None
        for label, command in _cases(Path(tmp)):
            times, cpu = _time(command, env, args.repeat)
            median = statistics.median(times)
            base = base if base is not None else median
            print(f"{label:<66} {median:9.3f} {min(times):7.3f} {median / base:7.1f} "
                  f"{statistics.median(cpu):6.3f}")
            whole_cpu = statistics.median(cpu)
        fit_cpu = statistics.median(_in_process_fit(Path(tmp), env, args.repeat))
        print(f"{'  the same BLISS fit run again in-process (cpu)':<66} {'':>9} {'':>7} {'':>7} "
              f"{fit_cpu:6.3f}")
        print(f"start-up of the BLISS command: {whole_cpu - fit_cpu:.3f} cpu s (goal 1.0)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
