"""Who can reach a sweep's cluster, and whose results it takes.

* The embedded cluster: every port the ``omnikin sweep`` process and its children listen on
  (found with psutil, not from what the sweep prints) serves no page and no WebSocket (Dask's
  own HTTP servers: plain and over TLS, from another web site's origin) and refuses a Dask
  client without the run's temporary credentials, over tcp:// and over tls:// with other
  credentials; the same probe gets an answer from an open scheduler and from a TLS one with its
  credentials, and Dask's pages from a scheduler that serves them (it can fail). The Dask
  settings that do it hold only while the embedded cluster runs.
* ``--scheduler tls://``: a real scheduler and workers started with certificates made here; the
  sweep runs there with ``--tls-*`` and gives the embedded cluster's table, and without the
  credentials (or with another authority's) it is refused in one line.
* A worker that joins in the middle of a study and reports another omnikin version (a test-only
  Dask preload) has its results refused, named in one line; the next run computes them.
"""

from __future__ import annotations

import os
import signal
import subprocess
import time

import numpy as np
import pytest

from support.cli import run_entry_point
from support.cluster_study import HANG_S, assert_same_table, start_sweep, table, write_study
from support.dask_cluster import dask_answers, dask_cluster, listening_ports, make_tls, wire_answer

pytest.importorskip("cryptography", reason="omnikin[sweep] (cryptography) is not installed")
pytest.importorskip("psutil", reason="psutil finds the listening sockets")

SETTINGS = {"side": 1, "runs": 1, "name": "security test"}
"""This file's study: named so, UMBmark on a 1 m square, 1 run per direction (the quickest trials)."""

WAIT_S = HANG_S
"""Most time a study may take to come up or a condition to be reached on a loaded machine [s]."""


def wait_for(condition, what: str, process: subprocess.Popen | None = None) -> None:
    deadline = time.monotonic() + WAIT_S
    while not condition():
        assert process is None or process.poll() is None, f"the study ended before {what}"
        assert time.monotonic() < deadline, f"no {what} within {WAIT_S:g} s"
        time.sleep(0.05)


HTTP_PATHS = ("/", "/info/main/workers.html", "/json/identity.json", "/health", "/metrics", "/status", "/sitemap.json")
"""Pages a Dask scheduler or worker serves by default: its index, the workers with their logs and
call stacks, the cluster's identity, health, Prometheus metrics, the Bokeh dashboard, every route."""

WEBSOCKETS = ("/eventstream", "/status/ws")
"""Dask's task event stream (it takes any origin) and a Bokeh dashboard's document socket."""


def attacks(port: int) -> dict[str, bytes]:
    """What the server on 127.0.0.1:``port`` answers a local program or a web page asking for
    each of Dask's pages (with this port's own Host, which any Host check would pass) and opening
    its WebSocket from another web site, each in plain TCP and over TLS without a certificate."""
    host = f"127.0.0.1:{port}"
    requests = {
        f"GET {path}": f"GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n" for path in HTTP_PATHS
    }
    for path in WEBSOCKETS:
        requests[f"WebSocket {path} from http://evil.example"] = (
            f"GET {path} HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
            "Origin: http://evil.example\r\n\r\n"
        )
    return {
        f"{what} ({'TLS' if tls else 'plain'})": wire_answer(port, request.encode(), tls=tls)
        for what, request in requests.items()
        for tls in (False, True)
    }


def serves(answer: bytes) -> bool:
    """Whether ``answer`` gives anything away: an HTTP answer other than a bare refusal (403 or
    404 naming nothing of the cluster). Nothing, a reset or a TLS alert gives nothing."""
    if not answer.startswith(b"HTTP/"):
        return False
    status = answer.split(b" ", 2)[1]
    return status not in (b"403", b"404") or any(word in answer.lower() for word in (b"tls://", b"omnikin", b"worker"))


def test_no_port_of_the_embedded_cluster_serves_a_page_or_a_client_without_the_runs_credentials(tmp_path):
    from distributed import Client
    from distributed.security import Security

    spec = write_study(tmp_path, 2000, **SETTINGS)
    study = start_sweep(spec, "-o", tmp_path / "out", "--workers", "1", "--task-trials", "1")
    try:
        wait_for(lambda: list((tmp_path / "out").glob("parts/*/*.parquet")), "part written", study)
        ports = listening_ports(study.pid)  # every TCP socket of the process and its children
        assert set(ports.values()) == {"127.0.0.1"}, ports  # nothing beyond this machine
        assert len(ports) >= 3, ports  # the scheduler, the nanny and the worker at least
        foreign = Security.temporary()  # credentials of another run: signed by another authority
        for port in sorted(ports):
            served = {what: answer[:300] for what, answer in attacks(port).items() if serves(answer)}
            assert not served, f"port {port} ({len(served)} answers): {served}"
            for address, security in ((f"tcp://127.0.0.1:{port}", None), (f"tls://127.0.0.1:{port}", foreign)):
                assert not dask_answers(address, security, timeout=5), f"{address} answered"
        for port in sorted(ports)[:1]:
            with pytest.raises((OSError, TimeoutError)):
                Client(f"tcp://127.0.0.1:{port}", timeout="3s")
        assert study.poll() is None  # the study went on
    finally:
        os.killpg(study.pid, signal.SIGINT)
        out, err = study.communicate(timeout=WAIT_S)
    assert study.returncode == 130, err
    assert "Traceback" not in err, err
    assert "Dask dashboard: off" in err and "http" not in out + err, err  # no page is offered either


ROUTES = ("distributed.scheduler.http.routes", "distributed.worker.http.routes")
"""Dask's settings of the pages its schedulers and workers serve."""


def test_the_embedded_clusters_dask_settings_hold_only_while_it_runs(tmp_path):
    import dask

    from omnikin.sweep.cluster import dask_client

    default = {key: dask.config.get(key) for key in ROUTES}
    assert all(default.values()), default  # Dask's own: pages on every scheduler and worker
    with dask_client(workers=1) as embedded:
        assert {key: dask.config.get(key) for key in ROUTES} == dict.fromkeys(ROUTES, [])
        assert embedded.dashboard.startswith("off")
    assert {key: dask.config.get(key) for key in ROUTES} == default  # a client made now has Dask's pages
    with dask_cluster(tmp_path, workers=1) as cluster, dask_client(cluster.address) as given:
        assert {key: dask.config.get(key) for key in ROUTES} == default  # the user's cluster, the user's settings
        assert not given.dashboard.startswith("off")
        # the probe of the embedded cluster's test reads the pages of a scheduler that serves them
        (page,) = set(listening_ports(cluster.scheduler.pid)) - {int(cluster.address.rsplit(":", 1)[1])}
        assert serves(wire_answer(page, f"GET /json/identity.json HTTP/1.0\r\nHost: 127.0.0.1:{page}\r\n\r\n".encode()))


def test_a_tls_cluster_runs_the_study_with_the_users_credentials_and_refuses_others(tmp_path):
    spec = write_study(tmp_path, 4, **SETTINGS)
    local = run_entry_point("sweep", spec, "-o", tmp_path / "local", "--workers", "1", timeout=WAIT_S)
    assert local.returncode == 0, local.stderr
    tls = make_tls(tmp_path / "tls")
    other = make_tls(tmp_path / "other", name="another")
    with dask_cluster(tmp_path, workers=1, tls=tls) as cluster:
        assert cluster.address.startswith("tls://")
        assert not dask_answers(cluster.address.replace("tls://", "tcp://"), timeout=5)
        assert not dask_answers(cluster.address, other.security(), timeout=5)
        assert dask_answers(cluster.address, tls.security())
        remote = run_entry_point(
            "sweep", spec, "-o", tmp_path / "remote", "--scheduler", cluster.address, *tls.options, timeout=WAIT_S
        )
        assert remote.returncode == 0, remote.stderr
        assert "Traceback" not in remote.stderr and "warning" not in remote.stderr, remote.stderr
        bare = run_entry_point("sweep", spec, "-o", tmp_path / "bare", "--scheduler", cluster.address)
        assert bare.returncode == 2 and len(bare.stderr.splitlines()) == 1, bare.stderr
        assert "needs this client's credentials: --tls-ca-file, --tls-cert and --tls-key" in bare.stderr
        wrong = run_entry_point(
            "sweep", spec, "-o", tmp_path / "wrong", "--scheduler", cluster.address, *other.options, timeout=WAIT_S
        )
        assert wrong.returncode != 0 and "cannot connect" in wrong.stderr, wrong.stderr
        assert "Traceback" not in wrong.stderr and len(wrong.stderr.strip().splitlines()) == 1, wrong.stderr
    assert_same_table(table(tmp_path / "remote"), table(tmp_path / "local"))


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--tls-cert", "c.pem"], "the local cluster makes its own"),
        (["--scheduler", "tcp://127.0.0.1:1", "--tls-cert", "c.pem"], "need a tls:// scheduler"),
        (["--scheduler", "tls://127.0.0.1:1", "--tls-key", "k.pem"], "needs --tls-ca-file and --tls-cert"),
        (["--scheduler", "tls://127.0.0.1:1", "--tls-ca-file", "no.pem", "--tls-cert", "no.pem"], "no such file"),
    ],
)
def test_tls_options_that_cannot_work_are_refused_in_one_line(tmp_path, extra, words):
    spec = write_study(tmp_path, 1, **SETTINGS)
    done = run_entry_point("sweep", spec, "-o", tmp_path / "out", *extra)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("omnikin: error: ") and len(done.stderr.splitlines()) == 1, done.stderr
    assert words in done.stderr
    assert not (tmp_path / "out").exists()


def _sweep_tasks_done(client, address: str) -> int:
    """Sweep tasks whose result the worker at ``address`` holds or held (its state machine's
    log: a ``put-in-memory`` entry per finished task)."""

    def count(dask_worker) -> int:
        return sum(1 for e in dask_worker.state.log if "omnikin-sweep" in str(e[0]) and e[1] == "put-in-memory")

    return int(client.run(count, workers=[address]).get(address, 0))


def test_a_worker_of_another_version_that_joins_mid_study_has_its_results_refused(tmp_path):
    spec = write_study(tmp_path, 60, **SETTINGS)
    reference = run_entry_point("sweep", spec, "-o", tmp_path / "reference", "--workers", "1", timeout=WAIT_S)
    assert reference.returncode == 0, reference.stderr
    out = tmp_path / "out"
    with dask_cluster(tmp_path, workers=1) as cluster:
        (good_pid,) = cluster.workers.values()
        assert dask_answers(cluster.address)  # the probe of the embedded cluster's test gets answers
        study = start_sweep(spec, "-o", out, "--scheduler", cluster.address, "--task-trials", "1")
        with cluster.client() as client:
            wait_for(lambda: list(out.glob("parts/*/*.parquet")), "part written", study)
            os.kill(good_pid, signal.SIGSTOP)  # the good worker holds still: the late one takes tasks
            try:
                late = cluster.start_worker("late", version="0.0.0+other")
                wait_for(lambda: len(client.scheduler_info()["workers"]) == 2, "late worker", study)
                (address,) = [a for a in client.scheduler_info()["workers"] if a not in cluster.workers]
                wait_for(lambda: _sweep_tasks_done(client, address) >= 2, "task on the late worker", study)
            finally:
                os.kill(good_pid, signal.SIGCONT)
            out_text, err = study.communicate(timeout=WAIT_S)
        late.terminate()
    assert study.returncode == 0, err
    assert "Traceback" not in err, err
    refused = [line for line in err.splitlines() if "0.0.0+other" in line]
    assert len(refused) == 1, err  # one line for the worker, whatever the number of its tasks
    assert refused[0].startswith(f"omnikin: warning: worker '{address}' runs omnikin '0.0.0+other' with NumPy ")
    assert "its results are refused" in refused[0]
    result = table(out)
    errors = [e for e in result["error"] if e is not None]
    assert errors and all("refused" in e for e in errors)
    # every trial written came from the good worker: the same numbers as the reference
    expected = table(tmp_path / "reference")
    rows = [k for k, e in enumerate(result["error"]) if e is None]
    assert rows
    for name in expected:
        if name != "error":
            got, want = [result[name][k] for k in rows], [expected[name][k] for k in rows]
            np.testing.assert_array_equal(np.array(got), np.array(want), err_msg=name)
    # the refused trials were not written: a rerun on the embedded cluster computes them
    again = run_entry_point("sweep", spec, "-o", out, "--workers", "1", timeout=WAIT_S)
    assert again.returncode == 0, again.stderr
    assert f"({len(errors)} computed now, {len(rows)} from the folder, 0 failed)" in again.stdout
    assert_same_table(table(out), expected)
