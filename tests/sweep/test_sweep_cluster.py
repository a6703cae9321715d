"""``omnikin sweep`` on real Dask clusters: a scheduler and two worker processes on loopback, a
worker killed mid-study, a study interrupted with Ctrl-C and resumed. The reference everywhere
is the same study run by the embedded cluster: a study's table must not depend on where, in
what order or in how many pieces its trials ran."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from conftest import omnikin_env, run_entry_point
from dask_cluster import dask_cluster

pa = pytest.importorskip("pyarrow", reason="omnikin[sweep] (pyarrow) is not installed")
pq = pytest.importorskip("pyarrow.parquet", reason="omnikin[sweep] (pyarrow) is not installed")
pytest.importorskip("distributed", reason="omnikin[sweep] (Dask distributed) is not installed")

STUDY = """\
omnikin_sweep: 1
name: cluster test
robots: [tomasi-omni3]
seed: 7
trials: {trials}
umbmark: {{side: 2, runs: 2}}
factors:
  scale: [0.1, 1]
  calibrate: {calibrate}
"""


def write_study(tmp_path: Path, trials: int = 6, calibrate: str = "false") -> Path:
    spec = tmp_path / "study.yaml"
    spec.write_text(STUDY.format(trials=trials, calibrate=calibrate))
    return spec


def table(folder: Path) -> dict:
    """The trial table without its one run-dependent column (computing time), as NumPy columns."""
    read = pq.read_table(folder / "trials.parquet").drop_columns(["seconds"])
    return {name: np.array(read.column(name).to_pylist(), dtype=object if read.column(name).type == pa.string()
                           else None) for name in read.column_names}  # fmt: skip


def assert_same_table(result: dict, reference: dict) -> None:
    """Equal column by column, bit for bit (NaN where the other has NaN: a trial without calibration)."""
    assert list(result) == list(reference)
    for name in reference:
        np.testing.assert_array_equal(result[name], reference[name], err_msg=name, strict=True)


def no_traceback(stderr: str) -> None:
    assert "Traceback" not in stderr and "distributed." not in stderr, stderr


def sweep(*argv, timeout: float = 300) -> subprocess.CompletedProcess:
    done = run_entry_point("sweep", *argv, timeout=timeout)
    no_traceback(done.stderr)
    return done


def test_a_study_on_an_external_cluster_gives_the_embedded_clusters_table(tmp_path):
    spec = write_study(tmp_path)
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
    spec = write_study(tmp_path, trials=16, calibrate="true")  # tasks of 8 trials: about a second each
    reference = sweep(spec, "-o", tmp_path / "reference", "--workers", "2", "--task-trials", "5")
    assert reference.returncode == 0, reference.stderr
    with dask_cluster(tmp_path) as cluster:
        study = subprocess.Popen(
            [sys.executable, "-m", "omnikin.cli.main", "sweep", str(spec), "-o", str(tmp_path / "out"),
             "--scheduler", cluster.address, "--task-trials", "8"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=omnikin_env(),
        )  # fmt: skip
        with cluster.client() as client:
            deadline = time.monotonic() + 300  # a loaded machine starts slowly: a hang guard, not a pace
            victim = None
            while victim is None and time.monotonic() < deadline and study.poll() is None:
                victim = _task_running(client)
                time.sleep(0.05)
            assert victim is not None, "no task reached a worker"
            time.sleep(0.3)  # inside the task
            os.kill(cluster.workers[victim], signal.SIGKILL)
            out, err = study.communicate(timeout=300)
            assert len(client.scheduler_info()["workers"]) == 1  # the killed worker is gone
    no_traceback(err)
    assert study.returncode == 0, err
    assert "failed" not in err
    result = table(tmp_path / "out")
    assert all(e is None for e in result["error"])  # no trial lost
    assert_same_table(result, table(tmp_path / "reference"))


def test_an_interrupted_study_resumes_and_computes_only_what_is_missing(tmp_path):
    spec = write_study(tmp_path, trials=12)
    reference = sweep(spec, "-o", tmp_path / "reference", "--workers", "2")
    assert reference.returncode == 0, reference.stderr
    out = tmp_path / "out"
    study = subprocess.Popen(
        [sys.executable, "-m", "omnikin.cli.main", "sweep", str(spec), "-o", str(out), "--workers", "1",
         "--task-trials", "1"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=omnikin_env(), start_new_session=True,
    )  # fmt: skip
    deadline = time.monotonic() + 300  # a hang guard, not a pace
    while time.monotonic() < deadline and study.poll() is None and len(list(out.glob("parts/*/*.parquet"))) < 3:
        time.sleep(0.02)
    assert study.poll() is None, "the study ended before it could be interrupted"
    os.killpg(study.pid, signal.SIGINT)  # Ctrl-C reaches the whole process group, workers too
    _, err = study.communicate(timeout=60)
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
