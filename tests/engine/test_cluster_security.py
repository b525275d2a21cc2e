"""Issue 28: the local Dask cluster is closed to other processes; schedulers are named safely.

Before: the scheduler's HTTP endpoint listened on 0.0.0.0 (``/info`` pages of
the workers' logs and call stacks without a login), any local process that
found the scheduler's port could run code on our workers, a configuration
file could send the tasks anywhere, a peer that accepts and never answers
hung ``run`` for good (holding ``run.lock``), and ``tls://`` was an internal
TypeError.
"""

from __future__ import annotations

import json
import logging
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import cloudpickle
import psutil
import pytest

from eclipsebench.cli import main
from eclipsebench.engine.cluster import ClusterOptions, SchedulerUnreachable
from eclipsebench.engine.tasks import Task, run_tasks
from eclipsebench.errors import InputError

cloudpickle.register_pickle_by_value(sys.modules[__name__])

LOOPBACK = {"127.0.0.1", "::1"}

# as tests/challenge/test_runner.py
TINY = ["challenge.epochs=2", "observation.pre_cubes=1", "observation.frames_per_cube=2",
        "simulation.subsamples=1", "simulation.calibration_frames=2000",
        'run.methods=["pld", "bliss"]', "run.bootstrap=50", "run.report=false",
        "run.empirical_photon_limit=false"]

INTRUDER = """
import os, sys
from distributed import Client
client = Client(sys.argv[1], timeout="5s")
print(client.submit(os.getpid, pure=False).result(timeout=10))
"""


def listening_addresses(root_pid: int) -> set[str]:
    """Local addresses on which ``root_pid`` or any of its descendants listens (TCP)."""
    root = psutil.Process(root_pid)
    found = set()
    for proc in [root, *root.children(recursive=True)]:
        try:
            connections = proc.net_connections(kind="inet")
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
        found |= {c.laddr.ip for c in connections if c.status == psutil.CONN_LISTEN}
    return found


def probe_cluster(out: str, run_pid: int) -> None:
    """A task: record the run's listening sockets and what an intruder without credentials got."""
    from distributed import get_worker

    address = get_worker().scheduler.address
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2] / "src")}
    attempts = {}
    for label, target in (("as given", address),
                          ("as tcp", address.replace("tls://", "tcp://"))):
        run = subprocess.run([sys.executable, "-c", INTRUDER, target], capture_output=True,
                             text=True, timeout=120, env=env)
        attempts[label] = {"code": run.returncode, "stdout": run.stdout.strip()}
    Path(out).write_text(json.dumps({"address": address, "attempts": attempts,
                                     "listening": sorted(listening_addresses(run_pid))}))


def write_text(out: str, text: str) -> None:
    Path(out).write_text(text)


@pytest.mark.slow  # a 2-worker cluster and two intruder processes: ~20 s
@pytest.mark.timeout(300)
def test_a_two_worker_cluster_listens_on_loopback_and_refuses_other_clients(tmp_path):
    out = tmp_path / "probe.json"
    run_tasks([Task("probe", "probe", probe_cluster, (str(out), os.getpid()), (out,)),
               Task("other", "other", write_text, (str(tmp_path / "o.txt"), "x"),
                    (tmp_path / "o.txt",))], workers=2)
    probe = json.loads(out.read_text())
    assert probe["address"].startswith("tls://127.0.0.1:")
    assert probe["listening"] and set(probe["listening"]) <= LOOPBACK, probe["listening"]
    for label, attempt in probe["attempts"].items():
        assert attempt["code"] != 0 and not attempt["stdout"], (label, attempt)


def _silent_server() -> tuple[socket.socket, int]:
    """A TCP server that accepts connections and never says a word."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    held = []

    def accept() -> None:
        while True:
            try:
                held.append(server.accept())
            except OSError:
                return

    threading.Thread(target=accept, daemon=True).start()
    return server, server.getsockname()[1]


@pytest.mark.timeout(120)  # before: hung for good
def test_a_scheduler_that_never_answers_times_out_in_one_line(tmp_path, capsys):
    server, port = _silent_server()
    out = tmp_path / "new" / "run"
    args = ["run", "--out", str(out), "--quiet", "--scheduler", f"tcp://127.0.0.1:{port}",
            "--connect-timeout", "2"]
    for item in TINY:
        args += ["--set", item]
    start = time.monotonic()
    try:
        code = main(args)
    finally:
        server.close()
    err = capsys.readouterr().err.splitlines()
    assert code == 2 and len(err) == 1, err
    assert f"tcp://127.0.0.1:{port}" in err[0] and "within 2 s" in err[0]
    assert time.monotonic() - start < 60
    assert not (tmp_path / "new").exists()  # no run_config.toml, no lock, no empty folder


def test_an_unreachable_scheduler_is_refused_before_any_task(tmp_path):
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    out = tmp_path / "o.txt"
    with pytest.raises(SchedulerUnreachable, match="cannot connect within 1 s"):
        run_tasks([Task("a", "a", write_text, (str(out), "x"), (out,))],
                  scheduler=f"tcp://127.0.0.1:{port}",
                  cluster=ClusterOptions(connect_timeout_s=1))
    assert not out.exists()


def test_a_configuration_file_cannot_name_a_scheduler(tmp_path, capsys):
    config = tmp_path / "handed-to-me.toml"
    config.write_text('[run]\nscheduler = "tcp://203.0.113.5:8786"\n')
    code = main(["run", str(config), "--out", str(tmp_path / "r"), "--quiet"])
    err = capsys.readouterr().err.splitlines()
    assert code == 2 and len(err) == 1, err
    assert "run.scheduler" in err[0] and "--scheduler" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["handed-to-me.toml"]


def test_a_tls_scheduler_without_certificates_is_one_line(tmp_path, capsys):
    args = ["run", "--out", str(tmp_path / "r"), "--quiet", "--scheduler",
            "tls://127.0.0.1:1"]
    for item in TINY:
        args += ["--set", item]
    code = main(args)
    err = capsys.readouterr().err.splitlines()
    assert code == 2 and len(err) == 1, err
    assert "--tls-ca-file" in err[0] and "internal error" not in err[0]
    assert list(tmp_path.iterdir()) == []


def _pem_files(folder: Path) -> dict[str, str]:
    """A temporary CA/certificate/key (Dask's own) written to PEM files."""
    from distributed import Security

    sec = Security.temporary()
    files = {}
    for name, text in (("ca", sec.tls_ca_file), ("cert", sec.tls_client_cert),
                       ("key", sec.tls_client_key)):
        files[name] = str(folder / f"{name}.pem")
        Path(files[name]).write_text(text)
    return files


@pytest.mark.timeout(120)
def test_a_tls_scheduler_runs_the_tasks_with_the_certificate_options(tmp_path):
    from distributed import LocalCluster, Security

    pem = _pem_files(tmp_path)
    security = Security(tls_ca_file=pem["ca"], tls_scheduler_cert=pem["cert"],
                        tls_scheduler_key=pem["key"], tls_worker_cert=pem["cert"],
                        tls_worker_key=pem["key"], tls_client_cert=pem["cert"],
                        tls_client_key=pem["key"], require_encryption=True)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, host="127.0.0.1",
                      protocol="tls://", security=security, dashboard_address="127.0.0.1:0",
                      scheduler_kwargs={"dashboard": False}) as cluster:
        assert cluster.scheduler_address.startswith("tls://")
        out = tmp_path / "o.txt"
        report = run_tasks([Task("a", "a", write_text, (str(out), "x"), (out,))],
                           scheduler=cluster.scheduler_address,
                           cluster=ClusterOptions(tls_ca_file=pem["ca"], tls_cert=pem["cert"],
                                                  tls_key=pem["key"]))
    assert report.ran == ["a"] and out.read_text() == "x"
    assert report.executor == f"dask scheduler {cluster.scheduler_address}"


def test_a_missing_certificate_file_is_named(tmp_path):
    with pytest.raises(InputError, match="--tls-cert .*no such file"):
        run_tasks([Task("a", "a", write_text, (str(tmp_path / "o"), "x"), (tmp_path / "o",))],
                  scheduler="tls://127.0.0.1:1",
                  cluster=ClusterOptions(tls_ca_file=__file__, tls_cert=str(tmp_path / "no")))


def record_listening(out: str, run_pid: int) -> None:
    """A task: the run's listening addresses."""
    Path(out).write_text(json.dumps(sorted(listening_addresses(run_pid))))


@pytest.mark.slow  # a 2-worker cluster: ~15 s
@pytest.mark.timeout(300)
def test_the_dashboard_is_served_on_loopback_only_when_asked_and_its_address_said(tmp_path):
    out = tmp_path / "listening.json"
    said: list[str] = []
    handler = logging.Handler(logging.WARNING)
    handler.emit = lambda record: said.append(record.getMessage())
    logger = logging.getLogger("eclipsebench")
    logger.addHandler(handler)
    try:
        run_tasks([Task("l", "l", record_listening, (str(out), os.getpid()), (out,))],
                  workers=2, cluster=ClusterOptions(dashboard=True))
    finally:
        logger.removeHandler(handler)
    said = [m for m in said if "dashboard" in m]
    assert len(said) == 1 and "http://127.0.0.1:" in said[0], said
    assert set(json.loads(out.read_text())) <= LOOPBACK


@pytest.mark.slow  # a 2-worker cluster: ~10 s
@pytest.mark.timeout(300)
def test_a_run_starts_while_another_holds_dask_s_default_port(tmp_path):
    # before, the scheduler's health-check server took 127.0.0.1:8787, so a second run at the
    # same time met "Port 8787 is already in use" (an error here, where warnings are errors)
    out = tmp_path / "listening.json"
    with socket.socket() as other:
        try:
            other.bind(("127.0.0.1", 8787))
            other.listen()
        except OSError:   # somebody holds it already: the same situation
            pass
        run_tasks([Task("l", "l", record_listening, (str(out), os.getpid()), (out,))], workers=2)
    assert set(json.loads(out.read_text())) <= LOOPBACK


def test_the_scheduler_can_come_from_the_environment(tmp_path, capsys, monkeypatch):
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{s.getsockname()[1]}"
    monkeypatch.setenv("ECLIPSEBENCH_SCHEDULER", address)
    args = ["run", "--out", str(tmp_path / "r"), "--quiet", "--connect-timeout", "1"]
    for item in TINY:
        args += ["--set", item]
    code = main(args)
    err = capsys.readouterr().err.splitlines()
    assert code == 2 and len(err) == 1 and address in err[0] and "cannot connect" in err[0], err
    assert list(tmp_path.iterdir()) == []
