"""A real Dask cluster on loopback for the sweep tests: ``dask scheduler`` and ``dask worker``
processes started as a user would start them, each importing this checkout's omnikin."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from omnikin_paths import omnikin_env

READY_S = 60.0
"""How long a scheduler or its workers may take to come up [s] (about 1 s here; CI is slower)."""


@dataclass
class DaskCluster:
    """A running scheduler at ``address`` and its worker processes (``workers``: pid by worker address)."""

    address: str
    scheduler: subprocess.Popen
    processes: list[subprocess.Popen]
    workers: dict[str, int] = field(default_factory=dict)

    def client(self):
        from distributed import Client

        return Client(self.address, timeout="10s")


def _dask(*argv: str) -> list[str]:
    return [sys.executable, "-m", "distributed.cli.dask_" + argv[0], *argv[1:]]


@contextlib.contextmanager
def dask_cluster(tmp_path: Path, workers: int = 2) -> Iterator[DaskCluster]:
    """Start ``dask scheduler`` on 127.0.0.1 (a free port, found through its scheduler file) and
    ``workers`` ``dask worker`` processes without a nanny (a killed worker stays dead), one
    thread each; stop them all at the end."""
    from distributed import Client

    file = tmp_path / "scheduler.json"
    log = open(tmp_path / "dask.log", "wb")  # noqa: SIM115 - closed at the end
    env = omnikin_env(DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED="False")
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
            ),
            stdout=log,
            stderr=log,
            env=env,
        )
        started.append(scheduler)
        info = _scheduler_info(file, scheduler)
        for k in range(workers):
            started.append(
                subprocess.Popen(
                    _dask(
                        "worker",
                        "--scheduler-file",
                        str(file),
                        "--host",
                        "127.0.0.1",
                        "--nthreads",
                        "1",
                        "--no-nanny",
                        "--no-dashboard",
                        "--name",
                        f"w{k}",
                        "--death-timeout",
                        "60",
                    ),
                    stdout=log,
                    stderr=log,
                    env=env,
                )
            )
        with Client(info["address"], timeout="10s") as client:
            client.wait_for_workers(workers, timeout=READY_S)
            pids = client.run(os.getpid)
        yield DaskCluster(info["address"], scheduler, started[1:], dict(pids))
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


def _scheduler_info(file: Path, scheduler: subprocess.Popen) -> dict:
    deadline = time.monotonic() + READY_S
    while time.monotonic() < deadline:
        if scheduler.poll() is not None:
            raise RuntimeError(f"dask scheduler exited with {scheduler.returncode}; see dask.log")
        with contextlib.suppress(OSError, ValueError):
            return json.loads(file.read_text())
        time.sleep(0.05)
    raise RuntimeError(f"dask scheduler wrote no {file.name} within {READY_S:g} s")
