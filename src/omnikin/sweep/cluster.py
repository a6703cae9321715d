"""Running a study's tasks on Dask: an embedded local cluster, or a cluster the user runs.

:func:`dask_client` gives a :class:`distributed.Client`:

* **embedded** (the default): a ``LocalCluster`` of ``workers`` processes (all cores), one
  thread each (the trials hold the GIL: threads in one process would take turns), every
  listener on loopback (``127.0.0.1``) and every Dask connection (client, scheduler, nannies,
  workers) over TLS with temporary credentials made for this run (``Security.temporary()``: a
  key and self-signed certificate held in memory, never written, that each end must present):
  another process or user of the machine cannot connect and run code in the study's processes
  (a Dask scheduler runs what its clients send); no HTTP served (:data:`NO_HTTP`,
  :func:`_close_http`): Dask's scheduler and each worker always open an HTTP listener of their
  own (the dashboard, worker logs and call stacks, a task event stream WebSocket that takes any
  web site's origin, JSON, health, metrics) that checks neither Host nor Origin, so every other
  user of the machine, and any web page in the user's browser through DNS rebinding, could read
  it; here it has no route, no dashboard, and is closed as soon as the cluster is up (the
  scheduler's) or the worker joins (:class:`CloseHttp`); the Dask logs silenced
  (what goes wrong reaches the user as omnikin's own one-line messages), and two Dask defaults
  switched off that cost a CPU-bound NumPy workload 20 to 30 % (measured, ``docs/sweeps.md``):
  the workers' statistical profiler and the ``MALLOC_TRIM_THRESHOLD_`` the nanny sets;
* **a scheduler address** (``tls://host:8786``, or an unauthenticated ``tcp://``): the client
  connects to it with the user's credentials (:class:`TLSFiles`, or Dask's own configuration
  ``distributed.comm.tls.*`` when none are given), waits for a worker, and checks that the
  workers run the same omnikin and NumPy as the client (otherwise a worker's result could
  differ, or it could not even import the task); workers that join later are checked by their
  results (:func:`run_tasks`).

This module imports Dask: import it after :func:`omnikin.sweep.execution.require_sweep`.

Workers ignore Ctrl-C (:class:`IgnoreInterrupts`): the embedded cluster's workers share the
terminal's process group, and a Ctrl-C meant for ``omnikin sweep`` must end the study with one
line, not a traceback from every worker.

:func:`run_tasks` submits the tasks and hands each result to the caller as soon as it
arrives (as completed, in any order), then releases it: a result held on a worker would be lost
with the worker. Every task returns, beside its result, the omnikin and NumPy versions of the
worker that computed it (:func:`versioned_call`); a result whose versions differ from the
client's, or that does not say (a worker of another omnikin), is refused: the task is handed to
the caller as failed (not written, so the next run computes it again) and the worker is named in
one line (:class:`WorkerMismatch`), whenever it joined the cluster. So a worker that joins after
the start is held to the check the ones present at the start passed.

A task that raises is retried once (Dask's ``retries``); a task whose workers die is
rescheduled by Dask itself (``distributed.scheduler.allowed-failures``, 3 by default) and then
fails with ``KilledWorker``; either way its failure is handed to the caller, the study goes on.
"""

from __future__ import annotations

import contextlib
import importlib.util
import logging
import os
import signal
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import CancelledError
from dataclasses import dataclass
from typing import Any

from distributed import WorkerPlugin

from ..common.messages import one_line, shorten
from ..errors import InputError, LinkError, WorkerMismatch
from .points import result_versions

RETRIES = 1
"""Reruns of a task that raised (Dask's ``retries``); worker deaths are counted apart."""

CONNECT_TIMEOUT = 10.0
"""How long the client tries to reach a scheduler [s]."""

WORKER_WAIT = 60.0
"""How long a study waits for the first worker of a cluster [s]."""

NO_HTTP: dict[str, list[str]] = {"distributed.scheduler.http.routes": [], "distributed.worker.http.routes": []}
"""No route on the HTTP listeners Dask opens whatever it is told (module docstring): from their
start until :func:`_close_http` closes them, every request is answered 404 (but Dask's own
``/sitemap.json``, which lists no route)."""

EMBEDDED_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.nanny.pre-spawn-environ": {"OMP_NUM_THREADS": 1, "MKL_NUM_THREADS": 1, "OPENBLAS_NUM_THREADS": 1},
    "distributed.logging.distributed": "critical",
    **NO_HTTP,
}
"""Dask configuration of the embedded cluster (module docstring), set only while it runs: the
client of a cluster given with ``--scheduler``, or one of the caller's own, keeps its own."""

DASHBOARD_OFF = (
    "off in the local cluster (its pages would be open to every user of this machine); for one, "
    "run a dask scheduler over TLS and give --scheduler"
)
"""What a study on the embedded cluster says of Dask's dashboard."""


def _close_http(server) -> None:
    """Close the HTTP listener of a Dask scheduler or worker ``server`` (run on its event loop):
    no connection reaches it any more. Dask stops it again when it closes (a no-op)."""
    http = getattr(server, "http_server", None)
    if http is not None:
        http.stop()


def _close_scheduler_http(dask_scheduler) -> None:
    """:func:`_close_http` of the scheduler, through ``Client.run_on_scheduler`` (which hands the
    scheduler to a parameter of this name)."""
    _close_http(dask_scheduler)


class CloseHttp(WorkerPlugin):
    """A Dask worker plugin: the worker's HTTP listener is closed when it joins (module docstring)."""

    name = "omnikin-close-http"

    def setup(self, worker) -> None:
        _close_http(worker)


class IgnoreInterrupts(WorkerPlugin):
    """A Dask worker plugin: the worker process ignores SIGINT (module docstring)."""

    name = "omnikin-ignore-interrupts"

    def setup(self, worker) -> None:
        with contextlib.suppress(ValueError):  # not the main thread of the worker: nothing to do
            signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def _interrupts_ignored() -> Iterator[None]:
    """Ignore SIGINT while the embedded cluster's processes start (an ignored signal stays ignored
    in the processes started meanwhile); a Ctrl-C then is lost: the cluster starts in about a
    second. Outside the main thread (where handlers cannot be set) it does nothing."""
    try:
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


QUIET_LOGGERS = ("distributed", "tornado", "asyncio")
"""Loggers silenced in the sweep's process while it runs a cluster: Dask's, and those of the
libraries under it that log a peer's failed connection (a foreign client refused by TLS) with a
traceback."""


@contextlib.contextmanager
def _quiet_client_logs() -> Iterator[None]:
    """Dask's own log lines off in this process (a lost scheduler reaches the user as one line,
    a client refused for lacking the credentials as nothing)."""
    loggers = [logging.getLogger(name) for name in QUIET_LOGGERS]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels, strict=True):
            logger.setLevel(level)


@dataclass(frozen=True)
class Cluster:
    """A connected client; ``where`` says in words where the tasks run, ``dashboard`` the
    dashboard's address (or how to get one)."""

    client: Any
    where: str
    dashboard: str
    workers: int


def _dashboard(client) -> str:
    """The dashboard of a cluster the user runs (``--scheduler``): its address, as its scheduler says."""
    if importlib.util.find_spec("bokeh") is None:
        return "none (pip install bokeh to get Dask's dashboard)"
    return str(client.dashboard_link)


@dataclass(frozen=True)
class TLSFiles:
    """The credentials of a client of a TLS Dask cluster (``--tls-ca-file``, ``--tls-cert``,
    ``--tls-key``; Dask's ``dask scheduler`` and ``dask worker`` take the same three options):
    PEM files of the certificate authority that signed the cluster's certificates, the client's
    certificate (signed by it) and its private key (None: in ``cert``). All None: Dask's
    configuration (``distributed.comm.tls.ca-file``, ``.client.cert``, ``.client.key``, e.g.
    ``DASK_DISTRIBUTED__COMM__TLS__CA_FILE``)."""

    ca_file: str | None = None
    cert: str | None = None
    key: str | None = None

    @property
    def given(self) -> bool:
        return any(v is not None for v in (self.ca_file, self.cert, self.key))

    def check(self, scheduler: str | None) -> None:
        """Refuse in one line credentials without a ``tls://`` scheduler, a key without a
        certificate, a certificate without its authority, or a file that cannot be read."""
        if not self.given:
            if scheduler is not None and scheduler.startswith("tls://") and self.security().tls_client_cert is None:
                raise InputError(
                    f"scheduler {shorten(scheduler)}: a tls:// cluster needs this client's credentials: "
                    "--tls-ca-file, --tls-cert and --tls-key (or Dask's DASK_DISTRIBUTED__COMM__TLS__* settings)"
                )
            return
        if scheduler is None:
            raise InputError(
                "--tls-ca-file/--tls-cert/--tls-key are the credentials of a cluster given with --scheduler "
                "tls://...; the local cluster makes its own"
            )
        if not scheduler.startswith("tls://"):
            raise InputError(f"--tls-ca-file/--tls-cert/--tls-key need a tls:// scheduler, got {shorten(scheduler)}")
        if self.cert is None or self.ca_file is None:
            raise InputError("a TLS client needs --tls-ca-file and --tls-cert (and --tls-key unless the key is in it)")
        for option, path in (("--tls-ca-file", self.ca_file), ("--tls-cert", self.cert), ("--tls-key", self.key)):
            if path is None:
                continue
            if not os.path.isfile(path):
                raise InputError(f"{option} {shorten(path)}: no such file")
            if not os.access(path, os.R_OK):
                raise InputError(f"{option} {shorten(path)}: cannot read it")

    def security(self):
        """A :class:`distributed.security.Security` of these files (every connection encrypted),
        or Dask's configured one when none are given."""
        from distributed.security import Security

        if not self.given:
            return Security()
        return Security(
            tls_ca_file=self.ca_file,
            tls_client_cert=self.cert,
            tls_client_key=self.key,
            require_encryption=True,
        )


@contextlib.contextmanager
def dask_client(
    scheduler: str | None = None, workers: int | None = None, tls: TLSFiles | None = None
) -> Iterator[Cluster]:
    """A :class:`Cluster`: embedded with ``workers`` processes (default: every core), or the
    cluster whose scheduler listens at ``scheduler``, reached with the credentials ``tls``
    (module docstring)."""
    import dask
    from distributed import Client, LocalCluster
    from distributed.security import Security

    tls = tls or TLSFiles()
    tls.check(scheduler)
    if scheduler is None:
        count = workers or os.cpu_count() or 1
        security = Security.temporary()  # this run's own credentials (module docstring)
        with dask.config.set(EMBEDDED_CONFIG), _quiet_client_logs():
            with _interrupts_ignored():  # the processes started now inherit it: a Ctrl-C while they start
                cluster = LocalCluster(  # up (importing, before the plugin) would print their tracebacks
                    n_workers=count,
                    threads_per_worker=1,
                    processes=True,
                    host="127.0.0.1",
                    protocol="tls",
                    security=security,
                    dashboard_address="127.0.0.1:0",  # a free port on loopback, closed at once (module docstring)
                    scheduler_kwargs={"dashboard": False},  # no Bokeh dashboard even where bokeh is installed
                    silence_logs=logging.CRITICAL,
                )
            try:
                client = Client(cluster, security=security)
                try:
                    client.run_on_scheduler(_close_scheduler_http)
                    client.register_plugin(CloseHttp())
                    client.register_plugin(IgnoreInterrupts())
                    try:
                        client.wait_for_workers(count, timeout=WORKER_WAIT)
                    except TimeoutError:
                        raise LinkError(
                            f"the local cluster: its {count} workers did not start within {WORKER_WAIT:g} s"
                        ) from None
                    yield Cluster(client, f"a local cluster of {count} worker processes", DASHBOARD_OFF, count)
                finally:
                    client.close()
            finally:
                cluster.close()
        return
    with dask.config.set({"distributed.logging.distributed": "critical"}), _quiet_client_logs():
        try:
            client = _connect(Client, scheduler, tls.security())
        except (OSError, TimeoutError) as exc:
            raise LinkError(f"scheduler {shorten(scheduler)}: cannot connect: {one_line(exc, 200)}") from None
        except Exception as exc:  # noqa: BLE001 - not an address Dask can use (ValueError, a protocol not installed)
            raise InputError(
                f"scheduler (--scheduler) {shorten(scheduler)}: not a scheduler address ({one_line(exc, 200)}); "
                "give one like tls://HOST:8786 (or tcp://HOST:8786)"
            ) from None
        try:
            count = _check_workers(client, scheduler)
            yield Cluster(client, f"the cluster at {scheduler} ({count} workers)", _dashboard(client), count)
        finally:
            client.close()


HANDSHAKE_TIMEOUT = 10.0
"""How long a server that accepted the connection may take to answer as a Dask scheduler [s]."""


def _connect(client_class, scheduler: str, security=None):
    """A client of ``scheduler``, or TimeoutError: Dask's own timeout covers the connection, not the
    handshake, so a server that accepts and never answers (an HTTP server on that port) would hold
    the study forever; the client is made in a daemon thread that is abandoned past the deadline."""
    box: dict[str, Any] = {}

    def connect() -> None:
        try:
            box["client"] = client_class(scheduler, timeout=f"{CONNECT_TIMEOUT}s", security=security)
        except BaseException as exc:  # noqa: BLE001 - handed to the caller's thread
            box["error"] = exc

    thread = threading.Thread(target=connect, name="omnikin-sweep-connect", daemon=True)
    thread.start()
    thread.join(CONNECT_TIMEOUT + HANDSHAKE_TIMEOUT)
    if thread.is_alive():
        raise TimeoutError(f"no Dask scheduler answered within {CONNECT_TIMEOUT + HANDSHAKE_TIMEOUT:g} s")
    if "error" in box:
        raise box["error"]
    return box["client"]


def _check_workers(client, scheduler: str) -> int:
    """Wait for a worker; refuse workers whose omnikin or NumPy differ from the client's."""
    try:
        client.wait_for_workers(1, timeout=WORKER_WAIT)
    except TimeoutError:
        raise LinkError(f"scheduler {scheduler}: no worker joined within {WORKER_WAIT:g} s; start workers") from None
    try:
        found = client.run(result_versions)
    except Exception as exc:  # noqa: BLE001 - a worker without omnikin fails to unpickle the function
        raise LinkError(
            f"scheduler {scheduler}: its workers cannot run omnikin ({one_line(exc, 200)}); "
            "install omnikin[sweep] where the workers run"
        ) from None
    mine = result_versions()
    for address, theirs in found.items():
        if theirs != mine:
            raise LinkError(
                f"scheduler {scheduler}: worker {address} runs omnikin {theirs.get('omnikin')} with NumPy "
                f"{theirs.get('numpy')}, this client omnikin {mine['omnikin']} with NumPy {mine['numpy']}; "
                "results must come from the same code: "
                "install the same versions on the workers"
            )
    return len(found)


def versioned_call(function: Callable[..., Any], *arguments: Any) -> dict[str, Any]:
    """What a worker runs for a task: ``function(*arguments)`` with the versions the result
    depends on (:func:`~omnikin.sweep.points.result_versions`) and the worker's address."""
    from distributed import get_worker

    try:
        where = str(get_worker().address)
    except ValueError:  # not on a worker (called directly)
        where = "this process"
    return {"versions": result_versions(), "worker": where, "result": function(*arguments)}


def check_versions(answer: Any, mine: dict[str, str]) -> Any:
    """The result inside a :func:`versioned_call` ``answer``, or :class:`WorkerMismatch` naming
    the worker and its versions when they are not ``mine``."""
    if not isinstance(answer, dict) or not isinstance(answer.get("versions"), dict) or "result" not in answer:
        raise WorkerMismatch("a worker returned a result without its versions (another omnikin): refused")
    theirs = answer["versions"]
    if theirs != mine:
        raise WorkerMismatch(
            f"worker {shorten(answer.get('worker'))} runs omnikin {shorten(theirs.get('omnikin'))} with NumPy "
            f"{shorten(theirs.get('numpy'))}, this client omnikin {mine['omnikin']} with NumPy {mine['numpy']}: "
            "its results are refused"
        )
    return answer["result"]


@dataclass(frozen=True)
class Task:
    """One task: trials ``first..stop-1`` of the point at ``index`` of the study."""

    index: int
    first: int
    stop: int

    @property
    def trials(self) -> int:
        return self.stop - self.first


def run_tasks(
    client,
    function: Callable[..., Any],
    tasks: Sequence[Task],
    arguments: Callable[[Task], tuple],
    names: Callable[[Task], str],
    done: Callable[[Task, Any, BaseException | None], None],
) -> None:
    """Run ``function(*arguments(task))`` for every task on ``client``; call ``done(task, result,
    None)`` for each result, ``done(task, None, error)`` for each task that failed or whose worker
    runs other versions (:class:`WorkerMismatch`; module docstring), as they arrive.
    ``names(task)`` is the task's key in Dask (shown on the dashboard)."""
    from distributed import as_completed

    mine = result_versions()
    futures = {}
    for task in tasks:
        future = client.submit(versioned_call, function, *arguments(task), key=names(task), retries=RETRIES, pure=False)
        futures[future.key] = (future, task)
    for future in as_completed([f for f, _ in futures.values()]):
        _, task = futures.pop(future.key)
        try:
            result = check_versions(future.result(), mine)
        except CancelledError:  # the scheduler went away (or cancelled the task): not a result of the task
            raise LinkError(
                f"lost the Dask scheduler ({client.scheduler.address}) in the middle of the study"
            ) from None
        except Exception as exc:  # noqa: BLE001 - a task's failure (any kind) is reported, the study goes on
            done(task, None, exc)
        else:
            done(task, result, None)
        future.release()
