"""The Dask side of the engine: a local cluster closed to others, or an existing scheduler.

A local cluster (``workers >= 2``) listens on 127.0.0.1 only and speaks TLS
with temporary credentials made for it (``security=True``: a key and
certificate that exist only in this process's memory and its workers'), so
no other process, of this user or another, can submit code to it. Its HTTP
endpoints are off (no ``/info`` pages, no dashboard) unless asked for with
``dashboard=True``, which puts the dashboard on 127.0.0.1 and logs its
address.

An existing scheduler (``--scheduler ADDRESS`` or the environment variable
``ECLIPSEBENCH_SCHEDULER``, never a configuration file: the tasks are code
run wherever it says) may be ``tcp://`` or ``tls://``; a ``tls://`` address
takes the certificate options that Dask's ``Security`` takes
(:class:`ClusterOptions`, or Dask's own ``distributed.comm.tls.*``
configuration). The connection, its handshake included, is given
``connect_timeout_s`` (30 s); then the run says so in one line.

Dask's own log messages (a worker restarted after it died, its tasks
recomputed elsewhere) are about processes the engine already looks after:
they are passed to the ``eclipsebench.dask`` logger at DEBUG level, so
``--quiet`` is silent and ``--verbose`` shows them.
"""

from __future__ import annotations

import contextlib
import logging
import os
import shutil
import sys
import tempfile
import weakref
from dataclasses import dataclass
from typing import Any

from ..errors import InputError
from ..progress import get_logger

__all__ = ["ClusterOptions", "SchedulerUnreachable", "SCHEDULER_ENV", "TLS_ENV", "external_security",
           "check_tls_files", "scheduler_from_environment", "open_client", "route_dask_logging"]

#: The environment variable that names an existing scheduler (as ``--scheduler``).
SCHEDULER_ENV = "ECLIPSEBENCH_SCHEDULER"
#: Environment variables of the TLS options, by :class:`ClusterOptions` field.
TLS_ENV = {"tls_ca_file": "ECLIPSEBENCH_TLS_CA_FILE", "tls_cert": "ECLIPSEBENCH_TLS_CERT",
           "tls_key": "ECLIPSEBENCH_TLS_KEY"}
#: Seconds to reach an existing scheduler, its handshake included.
DEFAULT_CONNECT_TIMEOUT_S = 30.0

log = get_logger("challenge")
dask_log = get_logger("dask")


class SchedulerUnreachable(InputError):
    """The scheduler named could not be reached in time (nothing of the run was started)."""


@dataclass(frozen=True)
class ClusterOptions:
    """How the engine starts or reaches its Dask cluster.

    Attributes
    ----------
    dashboard : bool
        Serve the local cluster's dashboard on 127.0.0.1 (a free port,
        logged); off by default: it shows the workers' logs and stacks to
        anyone on this machine who finds the port.
    connect_timeout_s : float
        Seconds to reach an existing scheduler, its handshake included.
    tls_ca_file, tls_cert, tls_key : str, optional
        For a ``tls://`` scheduler: the certificate authority that signed the
        scheduler's certificate, and this client's certificate and key (PEM;
        the key may be appended to the certificate). Unset: the environment
        variables of :data:`TLS_ENV`, then Dask's ``distributed.comm.tls``
        configuration.
    """

    dashboard: bool = False
    connect_timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S
    tls_ca_file: str | None = None
    tls_cert: str | None = None
    tls_key: str | None = None

    def __post_init__(self) -> None:
        if not self.connect_timeout_s > 0:
            raise InputError(f"--connect-timeout {self.connect_timeout_s}: expected a positive "
                             "number of seconds")


def scheduler_from_environment() -> str | None:
    """The scheduler named by :data:`SCHEDULER_ENV`, or None."""
    value = os.environ.get(SCHEDULER_ENV, "").strip()
    return value or None


def _tls_setting(options: ClusterOptions, name: str) -> str | None:
    value = getattr(options, name) or os.environ.get(TLS_ENV[name], "").strip() or None
    if value is not None and not os.path.isfile(value):
        option = "--" + name.replace("_", "-")
        raise InputError(f"{option} {value}: no such file (expected a PEM file)")
    return value


def external_security(address: str, options: ClusterOptions):
    """The ``distributed.Security`` of an existing scheduler (None for ``tcp://``).

    Its files are loaded here (:func:`check_tls_files`): callers call this
    before they make or write any folder, so a missing or bad file is one line
    naming its option and leaves nothing behind.
    """
    if not address.startswith("tls://"):
        return None
    from distributed import Security  # heavy, optional: only with a cluster

    given = {"tls_ca_file": _tls_setting(options, "tls_ca_file"),
             "tls_client_cert": _tls_setting(options, "tls_cert"),
             "tls_client_key": _tls_setting(options, "tls_key")}
    security = Security(require_encryption=True,
                        **{k: v for k, v in given.items() if v is not None})
    # read back: Dask's configuration may have given what the options did not
    ca_file = getattr(security, "tls_ca_file", None)
    cert = getattr(security, "tls_client_cert", None)
    if not ca_file or not cert:
        raise InputError(f"--scheduler {address}: a tls:// scheduler needs --tls-ca-file and "
                         "--tls-cert (and --tls-key unless the key is in the certificate file), "
                         f"or {TLS_ENV['tls_ca_file']} and {TLS_ENV['tls_cert']}")
    check_tls_files(ca_file, cert, getattr(security, "tls_client_key", None))
    return security


def _ssl_reason(exc: Exception) -> str:
    return " ".join(str(getattr(exc, "reason", None) or exc).split()) or type(exc).__name__


def check_tls_files(ca_file: str, cert: str, key: str | None) -> None:
    """Load the TLS files as the connection will, so that a bad one is one line before any work.

    The certificate authority with :meth:`ssl.SSLContext.load_verify_locations`,
    the certificate and its key with :meth:`ssl.SSLContext.load_cert_chain`;
    each must be a regular file (not a device or a FIFO).

    Raises
    ------
    InputError
        One line naming the option (``--tls-ca-file``, ``--tls-cert``,
        ``--tls-key``) and its file: not PEM, no key, or a key that is not the
        certificate's.
    """
    import ssl

    from ..io.inputs import check_input_file
    from ..limits import MAX_TEXT_FILE_BYTES

    names = (("--tls-ca-file", ca_file), ("--tls-cert", cert), ("--tls-key", key))
    for option, path in names:
        if path is not None:
            try:
                check_input_file(path, "PEM file", MAX_TEXT_FILE_BYTES)
            except InputError as exc:
                raise InputError(f"{option} {exc}") from None
    context = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
    try:
        context.load_verify_locations(cafile=ca_file)
    except (ssl.SSLError, OSError, ValueError) as exc:
        raise InputError(f"--tls-ca-file {ca_file}: not a PEM certificate authority "
                         f"({_ssl_reason(exc)})") from None
    try:
        with open(cert, encoding="ascii", errors="replace") as fh:
            text = fh.read()
        start = text.index(ssl.PEM_HEADER)
        end = text.index(ssl.PEM_FOOTER, start) + len(ssl.PEM_FOOTER)
        ssl.PEM_cert_to_DER_cert(text[start:end])   # the first certificate decodes
    except ValueError:
        raise InputError(f"--tls-cert {cert}: not a PEM certificate (no '-----BEGIN "
                         "CERTIFICATE-----' block)") from None
    try:
        context.load_cert_chain(cert, key)
    except (ssl.SSLError, OSError, ValueError) as exc:
        where = (f"--tls-key {key}: not the PEM private key of --tls-cert {cert}" if key
                 else f"--tls-cert {cert}: holds no private key of its certificate (give "
                      "--tls-key)")
        raise InputError(f"{where} ({_ssl_reason(exc)})") from None


async def _handshake(address: str, connection_args: dict[str, Any], timeout_s: float) -> None:
    """Connect to ``address`` and ask for its identity; raise on no answer in ``timeout_s``."""
    import asyncio  # only to reach a scheduler: every command's parser imports this module

    from distributed.comm import connect

    async def ask() -> None:
        comm = await connect(address, timeout=timeout_s, **connection_args)
        try:
            await comm.write({"op": "identity"})
            await comm.read()
        finally:
            comm.abort()

    await asyncio.wait_for(ask(), timeout_s)


def _connect_external(address: str, options: ClusterOptions):
    import asyncio  # only to reach a scheduler: every command's parser imports this module

    from distributed import Client

    security = external_security(address, options)
    args = security.get_connection_args("client") if security is not None else {}
    timeout_s = options.connect_timeout_s
    try:
        # Dask's own timeout does not cover a peer that accepts and never answers
        asyncio.run(_handshake(address, args, timeout_s))
        return Client(address, timeout=f"{timeout_s}s", security=security)
    except (OSError, TimeoutError) as exc:
        reason = " ".join(str(exc).split()) or "no answer"
        raise SchedulerUnreachable(f"--scheduler {address}: cannot connect within "
                                   f"{timeout_s:g} s ({reason}); nothing was run") from None
    except (TypeError, ValueError) as exc:  # e.g. an address of an unknown protocol
        raise SchedulerUnreachable(f"--scheduler {address}: cannot connect "
                                   f"({' '.join(str(exc).split())}); nothing was run") from None


class _ToOurLogger(logging.Handler):
    """Passes Dask's records to ``eclipsebench.dask`` at DEBUG (one line each)."""

    def emit(self, record: logging.LogRecord) -> None:
        first = record.getMessage().strip().splitlines()[:1]
        dask_log.debug("%s: %s", record.name, first[0] if first else "")


def route_dask_logging() -> None:
    """Send this process's ``distributed`` log records through :data:`dask_log` (DEBUG)."""
    import distributed  # noqa: F401 - its import installs its own handler: replace it after

    logger = logging.getLogger("distributed")
    if not any(isinstance(h, _ToOurLogger) for h in logger.handlers):
        for handler in list(logger.handlers):
            logger.removeHandler(handler)
        logger.addHandler(_ToOurLogger())
    logger.propagate = False
    logger.setLevel(logging.WARNING)  # INFO would be formatted for nobody


def _quiet_resource_tracker() -> None:
    """Start multiprocessing's resource tracker with its "leaked semaphore" warning off.

    A worker killed by the system leaves its semaphores for the tracker, a
    process of its own that warns on stderr at the end; nothing is lost (the
    task is retried). The filter is passed on its command line, as
    multiprocessing passes this process's ``-W`` options.
    """
    from multiprocessing import resource_tracker

    flag = "ignore:resource_tracker:UserWarning"
    added = flag not in sys.warnoptions
    if added:
        sys.warnoptions.append(flag)
    try:
        resource_tracker.ensure_running()
    finally:
        if added:
            sys.warnoptions.remove(flag)


def _worker_env() -> dict[str, str]:
    # One thread per worker process: the parallelism is across tasks.
    return {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
            "NUMBA_NUM_THREADS": "1"}


def _local_config(dashboard: bool) -> dict[str, Any]:
    """Dask settings of the local cluster (see docs/runner.md for the first two)."""
    config: dict[str, Any] = {
        "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
        "distributed.worker.profile.enabled": False,
        # the workers' own log lines (their stderr is ours): the engine reports failures
        "distributed.nanny.pre-spawn-environ.DASK_LOGGING__DISTRIBUTED": "critical",
        # no HTTP endpoints but the health check: /info shows logs and call stacks
        "distributed.worker.http.routes": ["distributed.http.health"],
    }
    if not dashboard:
        config["distributed.scheduler.http.routes"] = ["distributed.http.health"]
    return config


def _start_local(workers: int, options: ClusterOptions):
    from dask import config as dask_config
    from distributed import Client, LocalCluster

    _quiet_resource_tracker()
    # The single-thread environment goes to the worker processes only: changing
    # NUMBA_NUM_THREADS in this process after numba started its threads makes
    # every later compilation here fail.
    # Dask's nannies set MALLOC_TRIM_THRESHOLD_=65536 in their workers by default;
    # fixing any glibc malloc threshold turns off its dynamic mmap threshold, so every
    # array above 128 KiB becomes a fresh mmap whose pages fault in zeroed: our tasks,
    # which allocate large temporary arrays, then ran 1.8x slower (BENCHMARKS.md).
    # The statistical profiler takes the GIL from the task every 10 ms; nobody reads it.
    # The workers' scratch space (spilled data, their lock files) in a folder of this
    # run's own, mode 0700 (mkdtemp's), removed with the cluster: Dask's default,
    # /tmp/dask-scratch-space, is shared by every user of the machine.
    scratch = tempfile.mkdtemp(prefix="eclipsebench-dask-")
    try:
        with dask_config.set(_local_config(options.dashboard)):
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   host="127.0.0.1", security=True, local_directory=scratch,
                                   # a free port even with no dashboard: the health check's
                                   # server took 8787 otherwise, and a second run at once
                                   # failed
                                   dashboard_address="127.0.0.1:0",
                                   scheduler_kwargs={"dashboard": options.dashboard},
                                   silence_logs=logging.CRITICAL + 1, env=_worker_env())
            client = Client(cluster)
    except BaseException:
        shutil.rmtree(scratch, ignore_errors=True)
        raise
    weakref.finalize(cluster, shutil.rmtree, scratch, ignore_errors=True)
    if options.dashboard:
        log.warning("Dask dashboard (this machine only): %s", cluster.dashboard_link)
    return client, cluster


def open_client(workers: int, scheduler: str | None, options: ClusterOptions | None = None):
    """A Dask client: ``(client, cluster or None, label)``.

    Parameters
    ----------
    workers : int
        Processes of the local cluster (when no scheduler is named).
    scheduler : str, optional
        Address of an existing scheduler (``tcp://`` or ``tls://``).
    options : ClusterOptions, optional
        Dashboard, connection timeout, TLS files.

    Raises
    ------
    SchedulerUnreachable
        The scheduler did not answer within ``options.connect_timeout_s``.
    InputError
        A ``tls://`` scheduler without certificate options.
    """
    options = options or ClusterOptions()
    route_dask_logging()
    if scheduler:
        return _connect_external(scheduler, options), None, f"dask scheduler {scheduler}"
    client, cluster = _start_local(workers, options)
    return client, cluster, f"dask LocalCluster ({workers} processes)"


def close(client, cluster) -> None:
    """Close the client, then the local cluster if this run started it."""
    with contextlib.suppress(Exception):
        client.close()
    if cluster is not None:
        with contextlib.suppress(Exception):
            cluster.close()
