"""``omnikin sweep`` (extra ``sweep``): the cost of running trials through Dask, measured in one run.

The reference is the bare Monte Carlo: ``TRIALS`` kinematic trials of tomasi-omni3 (built within
the ``typical`` tolerances, UMBmark, calibration, UMBmark again; ``omnikin.sweep.trials.run_trials``)
in a plain loop in this process, one core. The same trials are then run as a study through the
embedded Dask cluster with 1 and with 2 worker processes (tasks of about 1.5 s: the default
planning), timed from the first task submitted to the last part written (the cluster's start and
stop are reported apart). Targets (docs/sweeps.md): within 15 % of the bare loop with 1 worker; at least
1.7x with 2 workers on the 2 cores of this machine. The tables are checked to be identical.

Per-task overhead: ``OVERHEAD_TASKS`` tasks that do nothing through the same ``run_tasks`` on one
worker, wall time per task. And one physics trial (UMBmark at the defaults, calibration, UMBmark
again in MuJoCo) for the cost model of ``docs/sweeps.md``.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from _common import save
from omnikin.io.robot_file import load_robot
from omnikin.sweep.points import Point, robot_hash
from omnikin.sweep.study import Study
from omnikin.sweep.trials import run_trials

TRIALS = 60
OVERHEAD_TASKS = 400


def _nothing(k: int) -> int:
    return k


class _Clock:
    """Progress receiver that records when the cluster was up and when the last trial arrived."""

    def __init__(self):
        self.start_at = self.last_at = None

    def start(self, **_) -> None:
        self.start_at = time.perf_counter()

    def advance(self, trials: int) -> None:
        self.last_at = time.perf_counter()


def _study(robot) -> Study:
    point = Point("tomasi-omni3", robot_hash(robot))
    return Study("bench", "bench", 1, TRIALS, "grid", (point,), {"tomasi-omni3": robot})


def _swept(study: Study, workers: int, folder: Path) -> dict:
    import pyarrow.parquet as pq

    from omnikin.sweep import execution

    shutil.rmtree(folder, ignore_errors=True)
    clock = _Clock()
    t0 = time.perf_counter()
    execution.execute_study(study, folder, workers=workers, progress=clock)
    total = time.perf_counter() - t0
    tasks = clock.last_at - clock.start_at
    table = pq.read_table(folder / "trials.parquet").drop_columns(["seconds"])
    return {"workers": workers, "tasks_s": tasks, "total_s": total, "trials_per_s": TRIALS / tasks, "table": table}


def _overhead() -> float:
    from omnikin.sweep.cluster import Task, dask_client, run_tasks

    tasks = [Task(0, k, k + 1) for k in range(OVERHEAD_TASKS)]
    with dask_client(workers=1) as cluster:
        cluster.client.run(lambda: None)
        t0 = time.perf_counter()
        keys = [f"nothing-{t.first}" for t in tasks]
        run_tasks(cluster.client, _nothing, tasks, lambda t: (t.first,), lambda t: keys[t.first], lambda *a: None)
        return (time.perf_counter() - t0) / OVERHEAD_TASKS


def _physics_trial(robot) -> float | None:
    try:
        import mujoco  # noqa: F401
    except ImportError:
        return None
    point = Point("tomasi-omni3", robot_hash(robot), engine="physics", noise=None)
    t0 = time.perf_counter()
    run_trials(robot, point, 1, 0, 1)
    return time.perf_counter() - t0


def main() -> dict:
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    robot = load_robot("tomasi-omni3")
    study = _study(robot)
    load = os.getloadavg()
    run_trials(robot, study.points[0], 1, 0, 1)  # warm
    t0 = time.perf_counter()
    bare_rows = run_trials(robot, study.points[0], study.seed, 0, TRIALS)
    bare = time.perf_counter() - t0
    bare_rate = TRIALS / bare
    with tempfile.TemporaryDirectory() as tmp:
        one = _swept(study, 1, Path(tmp) / "one")
        two = _swept(study, 2, Path(tmp) / "two")
    same = one.pop("table").equals(two.pop("table"))
    bare_after = np.array(bare_rows["e_max_syst_after"])
    overhead = _overhead()
    physics = _physics_trial(robot)
    out = {
        "trials": TRIALS,
        "load_average_before": list(load),
        "bare_trials_per_s": bare_rate,
        "one_worker": one,
        "two_workers": two,
        "one_worker_vs_bare": one["trials_per_s"] / bare_rate,
        "two_workers_vs_bare": two["trials_per_s"] / bare_rate,
        "tables_identical": bool(same),
        "bare_e_max_syst_after_median_mm": float(np.median(bare_after) * 1000),
        "overhead_per_task_ms": overhead * 1000,
        "physics_trial_s": physics,
    }
    print(f"bare loop, 1 core      {bare_rate:6.2f} trials/s ({TRIALS} trials with calibration, tomasi-omni3)")
    for name, run in (("1 worker", one), ("2 workers", two)):
        ratio = run["trials_per_s"] / bare_rate
        print(
            f"sweep, {name:9s}      {run['trials_per_s']:6.2f} trials/s = {ratio:.2f}x the bare loop "
            f"(tasks {run['tasks_s']:.1f} s, whole command {run['total_s']:.1f} s)"
        )
    print(f"tables identical (1 vs 2 workers): {same}")
    print(f"Dask overhead per task: {overhead * 1000:.2f} ms (trivial tasks, 1 worker)")
    if physics is not None:
        print(f"one physics trial (defaults, with calibration): {physics:.1f} s")
    print(f"load average before: {load[0]:.2f}")
    return out


if __name__ == "__main__":
    save("sweep", main())
