"""A real Dask cluster on loopback for the sweep tests: ``dask scheduler`` and ``dask worker``
processes started as a user would start them, each importing this checkout's omnikin; over TLS
with certificates made here (:func:`make_tls`); a worker that joins later, optionally reporting
another omnikin version (:func:`start_worker`, ``fake_omnikin_version.py``); and the probes of
the security tests: the listening sockets of a process tree (:func:`listening_ports`), what a
server sends back to raw bytes (:func:`wire_answer`: an HTTP request, a WebSocket upgrade) and
whether a Dask server answers a connection (:func:`dask_answers`)."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from support.paths import omnikin_env

READY_S = 60.0
"""How long a scheduler or its workers may take to come up [s] (about 1 s here; CI is slower)."""


FAKE_VERSION = "OMNIKIN_TEST_FAKE_VERSION"
"""The environment variable ``fake_omnikin_version.py`` reads: the omnikin version a worker reports."""

PRELOAD = Path(__file__).with_name("fake_omnikin_version.py")


@dataclass(frozen=True)
class TLSFiles:
    """PEM files made by :func:`make_tls`: a certificate authority, and a certificate and key it
    signed (for the scheduler, the workers and the client alike); ``options`` gives them as the
    ``--tls-ca-file/--tls-cert/--tls-key`` options of ``dask`` and ``omnikin sweep``."""

    ca: Path
    cert: Path
    key: Path

    @property
    def options(self) -> list[str]:
        return ["--tls-ca-file", str(self.ca), "--tls-cert", str(self.cert), "--tls-key", str(self.key)]

    def security(self):
        from distributed.security import Security

        return Security(
            tls_ca_file=str(self.ca),
            tls_client_cert=str(self.cert),
            tls_client_key=str(self.key),
            require_encryption=True,
        )


def make_tls(folder: Path, name: str = "omnikin-test") -> TLSFiles:
    """A new certificate authority and a certificate for 127.0.0.1 signed by it, in ``folder``
    (``cryptography``: an RSA key each, valid for a day)."""
    import datetime
    import ipaddress

    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import rsa
    from cryptography.x509.oid import NameOID

    folder.mkdir(parents=True, exist_ok=True)
    now = datetime.datetime.now(datetime.timezone.utc)

    def build(subject: str, issuer: str, public, signer, ca: bool):
        builder = (
            x509.CertificateBuilder()
            .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, subject)]))
            .issuer_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, issuer)]))
            .public_key(public)
            .serial_number(x509.random_serial_number())
            .not_valid_before(now - datetime.timedelta(minutes=5))
            .not_valid_after(now + datetime.timedelta(days=1))
            .add_extension(x509.BasicConstraints(ca=ca, path_length=None), critical=True)
        )
        if not ca:
            builder = builder.add_extension(
                x509.SubjectAlternativeName(
                    [x509.DNSName("localhost"), x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]
                ),
                critical=False,
            )
        return builder.sign(signer, hashes.SHA256())

    ca_key = rsa.generate_private_key(public_exponent=65537, key_size=2048)
    ca_cert = build(f"{name} CA", f"{name} CA", ca_key.public_key(), ca_key, ca=True)
    key = rsa.generate_private_key(public_exponent=65537, key_size=2048)
    cert = build(name, f"{name} CA", key.public_key(), ca_key, ca=False)
    files = TLSFiles(folder / "ca.pem", folder / "cert.pem", folder / "key.pem")
    files.ca.write_bytes(ca_cert.public_bytes(serialization.Encoding.PEM))
    files.cert.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    files.key.write_bytes(
        key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, serialization.NoEncryption())
    )
    return files


@dataclass
class DaskCluster:
    """A running scheduler at ``address`` and its worker processes (``workers``: pid by worker
    address); ``tls``: its credentials (None: an open tcp:// cluster)."""

    address: str
    scheduler: subprocess.Popen
    processes: list[subprocess.Popen]
    workers: dict[str, int] = field(default_factory=dict)
    tls: TLSFiles | None = None
    file: Path | None = None
    log: object = None

    def client(self):
        from distributed import Client

        return Client(self.address, timeout="10s", security=self.tls.security() if self.tls else None)

    def start_worker(self, name: str, version: str | None = None) -> subprocess.Popen:
        """Start one more ``dask worker`` (``version``: the omnikin version it reports, through the
        test-only preload ``fake_omnikin_version.py``); stopped with the cluster."""
        extra = {FAKE_VERSION: version} if version is not None else {}
        argv = _worker_argv(self.file, name, self.tls)
        if version is not None:
            argv += ["--preload", str(PRELOAD)]
        process = subprocess.Popen(argv, stdout=self.log, stderr=self.log, env=_env(**extra))
        self.processes.append(process)
        return process


def _env(**extra: str) -> dict[str, str]:
    return omnikin_env(DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED="False", **extra)


def _worker_argv(file: Path | None, name: str, tls: TLSFiles | None) -> list[str]:
    return _dask(
        "worker",
        "--scheduler-file",
        str(file),
        "--host",
        "127.0.0.1",
        "--nthreads",
        "1",
        "--no-nanny",
        "--no-dashboard",
        "--dashboard-address",  # its HTTP server listens even without a dashboard: on loopback
        "127.0.0.1:0",
        "--name",
        name,
        "--death-timeout",
        "60",
        *(tls.options if tls else []),
    )


def _dask(*argv: str) -> list[str]:
    return [sys.executable, "-m", "distributed.cli.dask_" + argv[0], *argv[1:]]


@contextlib.contextmanager
def dask_cluster(tmp_path: Path, workers: int = 2, tls: TLSFiles | None = None) -> Iterator[DaskCluster]:
    """Start ``dask scheduler`` on 127.0.0.1 (a free port, found through its scheduler file; over
    TLS with ``tls``'s credentials) and ``workers`` ``dask worker`` processes without a nanny (a
    killed worker stays dead), one thread each; stop them all at the end."""
    from distributed import Client

    file = tmp_path / "scheduler.json"
    log = open(tmp_path / "dask.log", "wb")  # noqa: SIM115 - closed at the end
    started: list[subprocess.Popen] = []
    try:
        scheduler = subprocess.Popen(
            _dask(
                "scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--dashboard-address",
                "127.0.0.1:0",
                "--scheduler-file",
                str(file),
                *(["--protocol", "tls", *tls.options] if tls else []),
            ),
            stdout=log,
            stderr=log,
            env=_env(),
        )
        started.append(scheduler)
        info = _scheduler_info(file, scheduler)
        for k in range(workers):
            started.append(subprocess.Popen(_worker_argv(file, f"w{k}", tls), stdout=log, stderr=log, env=_env()))
        with Client(info["address"], timeout="10s", security=tls.security() if tls else None) as client:
            client.wait_for_workers(workers, timeout=READY_S)
            pids = client.run(os.getpid)
        cluster = DaskCluster(info["address"], scheduler, started[1:], dict(pids), tls, file, log)
        yield cluster
        started[1:] = cluster.processes
    finally:
        for process in reversed(started):
            with contextlib.suppress(OSError):
                process.send_signal(signal.SIGTERM)
        for process in started:
            try:
                process.wait(10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(10)
        log.close()


def listening_ports(pid: int) -> dict[int, str]:
    """The TCP ports on which the process ``pid`` and all its descendants listen, with the
    address each is bound to (psutil)."""
    import psutil

    root = psutil.Process(pid)
    ports: dict[int, str] = {}
    for process in [root, *root.children(recursive=True)]:
        with contextlib.suppress(psutil.NoSuchProcess):
            for conn in process.net_connections(kind="tcp"):
                if conn.status == psutil.CONN_LISTEN:
                    ports[conn.laddr.port] = conn.laddr.ip
    return ports


def wire_answer(port: int, request: bytes, *, tls: bool = False, timeout: float = 5.0) -> bytes:
    """What the server on 127.0.0.1:``port`` sends back to ``request`` (with ``tls``: over TLS,
    the server's certificate unchecked and no client certificate, as a stranger connects), read
    until it closes the connection, is silent for ``timeout`` or has sent 64 KiB; b"" when it
    refuses the connection or the TLS handshake."""
    import socket
    import ssl

    answer = b""
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=timeout) as raw:
            sock = raw
            if tls:
                context = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
                context.check_hostname = False
                context.verify_mode = ssl.CERT_NONE
                sock = context.wrap_socket(raw, server_hostname="127.0.0.1")
            sock.sendall(request)
            while len(answer) < 1 << 16:
                chunk = sock.recv(1 << 16)
                if not chunk:
                    break
                answer += chunk
    except OSError:  # refused, reset, timed out, TLS handshake refused (ssl.SSLError): what came is the answer
        pass
    return answer


def dask_answers(address: str, security=None, timeout: float = 10.0) -> bool:
    """Whether the server at ``address`` (``tcp://`` or ``tls://``) completes Dask's handshake and
    answers an ``identity`` request from a client holding ``security`` (None: no credentials)."""
    import asyncio

    from distributed.comm import connect

    args = security.get_connection_args("client") if security is not None else {}

    async def ask() -> object:
        comm = await connect(address, timeout=timeout, **args)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await asyncio.wait_for(comm.read(), timeout)
        finally:
            comm.abort()

    box: list[object] = []

    def probe() -> None:
        with contextlib.suppress(Exception):  # refused, closed, timed out, TLS failure: no answer
            box.append(asyncio.run(ask()))

    thread = threading.Thread(target=probe, daemon=True)  # abandoned if Dask's client hangs
    thread.start()
    thread.join(3 * timeout)
    return bool(box) and isinstance(box[0], dict) and "type" in box[0]


def _scheduler_info(file: Path, scheduler: subprocess.Popen) -> dict:
    deadline = time.monotonic() + READY_S
    while time.monotonic() < deadline:
        if scheduler.poll() is not None:
            raise RuntimeError(f"dask scheduler exited with {scheduler.returncode}; see dask.log")
        with contextlib.suppress(OSError, ValueError):
            return json.loads(file.read_text())
        time.sleep(0.05)
    raise RuntimeError(f"dask scheduler wrote no {file.name} within {READY_S:g} s")
