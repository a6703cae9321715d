"""``omnikin sweep`` on real Dask clusters: a scheduler and two worker processes on loopback, a
worker killed mid-study, a study interrupted with Ctrl-C and resumed. The reference everywhere
is the same study run by the embedded cluster: a study's table must not depend on where, in
what order or in how many pieces its trials ran."""

from __future__ import annotations

import os
import signal
import time

from support.cluster_study import HANG_S, assert_same_table, no_traceback, start_sweep, sweep, table, write_study
from support.dask_cluster import dask_cluster

SQUARE = {"side": 2, "runs": 2}
"""The UMBmark square of this file's study: 2 m, 2 runs per direction."""


def test_a_study_on_an_external_cluster_gives_the_embedded_clusters_table(tmp_path):
    spec = write_study(tmp_path, 6, **SQUARE)
    local = sweep(spec, "-o", tmp_path / "local", "--workers", "1", "--task-trials", "4")
    assert local.returncode == 0, local.stderr
    with dask_cluster(tmp_path) as cluster:
        remote = sweep(spec, "-o", tmp_path / "remote", "--scheduler", cluster.address, "--task-trials", "1")
        assert remote.returncode == 0, remote.stderr
        assert f"the cluster at {cluster.address} (2 workers)" in remote.stderr
        with cluster.client() as client:  # the trials ran on the cluster's workers, one task per trial
            logs = client.run(lambda dask_worker: len(dask_worker.state.log))
        assert all(count > 0 for count in logs.values()), logs
    reference, result = table(tmp_path / "local"), table(tmp_path / "remote")
    assert len(result["trial"]) == 2 * 6
    assert_same_table(result, reference)
    assert all(e is None for e in result["error"])


def _task_running(client) -> str | None:
    """The address of a worker that has a sweep task assigned, if any."""
    for address, keys in client.processing().items():
        if any("omnikin-sweep" in str(key) for key in keys):
            return address
    return None


def test_a_worker_killed_mid_study_costs_a_retry_not_a_result(tmp_path):
    spec = write_study(tmp_path, 16, calibrate=True, **SQUARE)  # tasks of 8 trials: about a second each
    reference = sweep(spec, "-o", tmp_path / "reference", "--workers", "2", "--task-trials", "5")
    assert reference.returncode == 0, reference.stderr
    with dask_cluster(tmp_path) as cluster:
        study = start_sweep(
            spec, "-o", tmp_path / "out", "--scheduler", cluster.address, "--task-trials", "8", new_session=False
        )
        with cluster.client() as client:
            deadline = time.monotonic() + HANG_S  # a loaded machine starts slowly: a hang guard, not a pace
            victim = None
            while victim is None and time.monotonic() < deadline and study.poll() is None:
                victim = _task_running(client)
                time.sleep(0.05)
            assert victim is not None, "no task reached a worker"
            time.sleep(0.3)  # inside the task
            os.kill(cluster.workers[victim], signal.SIGKILL)
            out, err = study.communicate(timeout=HANG_S)
            assert len(client.scheduler_info()["workers"]) == 1  # the killed worker is gone
    no_traceback(err)
    assert study.returncode == 0, err
    assert "failed" not in err
    result = table(tmp_path / "out")
    assert all(e is None for e in result["error"])  # no trial lost
    assert_same_table(result, table(tmp_path / "reference"))


def test_an_interrupted_study_resumes_and_computes_only_what_is_missing(tmp_path):
    spec = write_study(tmp_path, 12, **SQUARE)
    reference = sweep(spec, "-o", tmp_path / "reference", "--workers", "2")
    assert reference.returncode == 0, reference.stderr
    out = tmp_path / "out"
    study = start_sweep(spec, "-o", out, "--workers", "1", "--task-trials", "1")
    deadline = time.monotonic() + HANG_S  # a hang guard, not a pace
    while time.monotonic() < deadline and study.poll() is None and len(list(out.glob("parts/*/*.parquet"))) < 3:
        time.sleep(0.02)
    assert study.poll() is None, "the study ended before it could be interrupted"
    os.killpg(study.pid, signal.SIGINT)  # Ctrl-C reaches the whole process group, workers too
    _, err = study.communicate(timeout=HANG_S)
    assert study.returncode == 130, err
    no_traceback(err)
    assert err.strip().splitlines()[-1].startswith("omnikin: interrupted; the finished tasks are in")
    assert not list(out.rglob("*.tmp")), "a part half written"
    kept = len(list(out.glob("parts/*/*.parquet")))
    assert 3 <= kept < 24
    again = sweep(spec, "-o", out, "--workers", "1")
    assert again.returncode == 0, again.stderr
    assert f"{kept} of 24 trials already in the folder" in again.stderr
    assert f"({24 - kept} computed now, {kept} from the folder, 0 failed)" in again.stdout
    assert_same_table(table(out), table(tmp_path / "reference"))
