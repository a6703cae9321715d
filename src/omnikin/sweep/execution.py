"""A whole study (``omnikin sweep``): plan the missing trials, run them on Dask, write the results.

:func:`execute_study`:

1. opens the study folder (:class:`~omnikin.sweep.store.StudyFolder`) and reads which trials are
   already on disk (an interrupted or extended study computes only the others);
2. cuts the missing trials of each point into tasks of about :data:`TASK_SECONDS` of work
   (:func:`plan_tasks`: long enough that Dask's few milliseconds per task do not count, short
   enough that a lost worker costs little and the last tasks end together);
3. runs them (:mod:`omnikin.sweep.cluster`: the embedded cluster or ``scheduler``) and writes each
   task's trials as a part of the folder the moment it arrives;
4. writes the trial table, the summary per point (:mod:`omnikin.sweep.summary`), the figure and
   ``report.md`` (:mod:`omnikin.sweep.report`) that answers the study's question.

A task that failed on its workers (:func:`~omnikin.sweep.cluster.run_tasks`), or whose result was
refused because its worker runs other omnikin or NumPy versions, enters the tables as rows with
its reason, but is not written as a part: the study resumed computes it again.

Called from Python, the embedded cluster starts worker *processes* (``spawn``): a script that
calls :func:`execute_study` (or :func:`omnikin.run_sweep`) must do so under
``if __name__ == "__main__":``, as every program that starts processes with ``multiprocessing``
must.
"""

from __future__ import annotations

import importlib.util
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Protocol

from ..common.messages import one_line, shorten
from ..errors import InputError, WorkerMismatch
from ..evaluation.calibration import RECOMMENDED_REPEATS, recommended_runs
from ..kinematics.robot import Robot
from ..motion.plans import umbmark_square
from ..motion.timing import estimated_samples
from ..physics.engines import engine_class
from .points import Point, point_key
from .store import Coverage, StudyFolder, arrow_schema
from .study import Study
from .trials import error_rows, run_trials

TASK_SECONDS = 1.5
"""Work per task aimed at [s] (module docstring; Dask costs about 3 ms per task, docs/sweeps.md)."""

TRIAL_SAMPLES_PER_SECOND = 2e6
"""Robot-samples per second of a kinematic trial on one core (measured: UMBmark before and after,
calibration runs and fit, about 0.15 s for tomasi-omni3 at the defaults; docs/sweeps.md)."""

MAX_TRIALS_PER_TASK = 1000
TASKS_PER_WORKER = 4
"""At least this many tasks per worker when the study is small enough to need splitting (load balance)."""


def require_sweep() -> None:
    """Raise an error naming the extra when Dask or pyarrow is missing."""
    missing = [name for name in ("distributed", "pyarrow", "cryptography") if importlib.util.find_spec(name) is None]
    if missing:
        raise InputError(f"omnikin sweep needs {' and '.join(missing)}: pip install 'omnikin[sweep]'")


@lru_cache(maxsize=256)
def _trial_samples(robot: Robot, side: float, mode: str, runs: int, rate: float, calibrate: bool) -> float:
    square = estimated_samples(umbmark_square("cw", side, mode), robot, rate)
    samples = 2.0 * (runs + 1) * square * (2 if calibrate else 1)  # the procedures and their systematic parts
    if calibrate:
        samples += RECOMMENDED_REPEATS * sum(
            estimated_samples(plan, robot, rate) for _, plan in recommended_runs(robot, side)
        )
    return samples


def trial_seconds(point: Point, robot: Robot) -> float:
    """Estimated computing time of one trial of ``point`` on one core [s] (kinematic engine:
    its samples at :data:`TRIAL_SAMPLES_PER_SECOND`; the physics engine: one trial is a task)."""
    if engine_class(point.engine).measured_cost:  # a trial is a task of its own
        return math.inf
    try:
        samples = _trial_samples(
            point.robot_for(robot), point.side, point.mode, point.runs, point.rate, point.calibrate
        )
    except InputError:  # a point whose runs cannot be planned: its trials fail fast
        return 0.0
    return samples / TRIAL_SAMPLES_PER_SECOND


def plan_tasks(study: Study, coverage: Coverage, workers: int, task_trials: int | None = None) -> list:
    """The tasks of the trials not on disk (module docstring): runs of missing trials of each
    point cut into tasks of ``task_trials`` trials (default: about :data:`TASK_SECONDS` of work,
    fewer when the study has under :data:`TASKS_PER_WORKER` tasks per worker)."""
    from .cluster import Task

    missing: list[tuple[int, int, int]] = []
    for index, point in enumerate(study.points):
        have = coverage.done[point_key(point)]
        k = 0
        while k < study.trials:
            if have[k]:
                k += 1
                continue
            stop = k
            while stop < study.trials and not have[stop]:
                stop += 1
            missing.append((index, k, stop))
            k = stop
    sizes = {}
    for index, _, _ in missing:
        if index not in sizes:
            point = study.points[index]
            seconds = trial_seconds(point, study.robots[point.robot])
            sizes[index] = task_trials or int(
                min(MAX_TRIALS_PER_TASK, max(1, round(TASK_SECONDS / max(seconds, 1e-9))))
            )
    if task_trials is None:
        total = sum(stop - first for _, first, stop in missing)
        tasks = sum(math.ceil((stop - first) / sizes[i]) for i, first, stop in missing)
        wanted = TASKS_PER_WORKER * workers
        if 0 < tasks < wanted:
            share = max(1, math.ceil(total / wanted))
            sizes = {i: min(size, share) for i, size in sizes.items()}
    return [
        Task(index, first, min(first + sizes[index], stop))
        for index, start, stop in missing
        for first in range(start, stop, sizes[index])
    ]


class Progress(Protocol):
    """What :func:`execute_study` tells its caller while it runs."""

    def start(self, *, total: int, done: int, where: str, dashboard: str) -> None: ...

    def advance(self, trials: int) -> None: ...


@dataclass
class SweepResult:
    """What a sweep did: the study, its folder, trials computed now and found on disk, failed
    trials (rows with an error), damaged parts removed, and the files written."""

    study: Study
    folder: Path
    computed: int = 0
    reused: int = 0
    failed: int = 0
    failed_tasks: int = 0
    refused: list[str] = field(default_factory=list)
    """One line per worker whose results were refused (other omnikin or NumPy versions)."""
    removed: list[str] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)
    answers: list = field(default_factory=list)


def execute_study(
    study: Study,
    out,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    task_trials: int | None = None,
    force: bool = False,
    progress: Progress | None = None,
    tls=None,
) -> SweepResult:
    """Run ``study`` into the folder ``out`` (module docstring) and return what was done;
    ``tls``: the credentials of a ``tls://`` ``scheduler``
    (:class:`~omnikin.sweep.cluster.TLSFiles`; default: Dask's configuration)."""
    require_sweep()
    check_run_options(workers, task_trials)
    with StudyFolder.open(out, study, force=force) as folder:
        coverage = folder.coverage()
        result = SweepResult(study, folder.path, reused=coverage.trials, removed=coverage.removed)
        failed_rows: list[dict] = []
        count = workers or os.cpu_count() or 1
        tasks = plan_tasks(study, coverage, count, task_trials)
        if tasks:
            _compute(study, folder, tasks, scheduler, workers, progress, result, failed_rows, tls)
        elif folder.stale:
            folder.start_over()
        _finish(study, folder, failed_rows, result)
    return result


MAX_WORKERS = 1024
"""Most worker processes of the embedded cluster (one machine)."""


def check_run_options(workers, task_trials) -> None:
    """Refuse a worker count or task size that is not a whole number in range (one line)."""
    for name, value, high in (("workers", workers, MAX_WORKERS), ("task_trials", task_trials, MAX_TRIALS_PER_TASK)):
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= high:
            option = "--" + name.replace("_", "-")
            raise InputError(f"{name} ({option}) must be a whole number from 1 to {high}, got {shorten(value)}")


def _compute(study, folder, tasks, scheduler, workers, progress, result, failed_rows, tls) -> None:
    from .cluster import dask_client, run_tasks

    keys = [point_key(p) for p in study.points]

    def done(task, columns, error) -> None:
        point = study.points[task.index]
        if error is not None:
            reason = (
                f"task of trials {task.first} to {task.stop - 1} failed: {type(error).__name__}: {one_line(error, 200)}"
            )
            failed_rows.append(error_rows(point, range(task.first, task.stop), reason))
            result.failed_tasks += 1
            if isinstance(error, WorkerMismatch) and one_line(error) not in result.refused:
                result.refused.append(one_line(error))
        else:
            folder.write_part(keys[task.index], task.first, task.stop, columns)
            result.computed += task.trials
        if progress is not None:
            progress.advance(task.trials)

    with dask_client(scheduler, workers, tls) as cluster:
        if folder.stale:  # the cluster answers: now the study will run, the old one may go
            folder.start_over()
        if progress is not None:
            total = study.trials * len(study.points)
            progress.start(total=total, done=result.reused, where=cluster.where, dashboard=cluster.dashboard)
        run_tasks(
            cluster.client,
            run_trials,
            tasks,
            lambda t: (study.robots[study.points[t.index].robot], study.points[t.index], study.seed, t.first, t.stop),
            lambda t: f"omnikin-sweep-{keys[t.index]}-{t.first}-{t.stop}",
            done,
        )


def arrow_columns(table) -> dict:
    """An Arrow table as NumPy columns: numbers as arrays, text and nullable columns as object
    arrays (None for null)."""
    import numpy as np
    import pyarrow as pa

    out = {}
    for name in table.column_names:
        column = table.column(name)
        if pa.types.is_string(column.type) or column.null_count:
            out[name] = np.array(column.to_pylist(), dtype=object)
        else:
            out[name] = column.to_numpy()
    return out


def _finish(study: Study, folder: StudyFolder, failed_rows: Sequence[dict], result: SweepResult) -> None:
    """Write the trial table, the summary, the figure and the report (module docstring)."""
    import numpy as np
    import pyarrow as pa

    from .report import study_markdown
    from .summary import SUMMARY_COLUMNS, answers, summarize

    table = folder.trial_table(failed_rows)
    columns = arrow_columns(table)
    result.failed = int(sum(e is not None for e in columns["error"])) if table.num_rows else 0
    result.files.append(folder.write_table("trials.parquet", table))
    summary = summarize(columns, study)
    schema = arrow_schema(SUMMARY_COLUMNS)
    summary_table = pa.Table.from_pydict(
        {
            name: [None if isinstance(v, float) and np.isnan(v) and kind != "float64" else v for v in summary[name]]
            for name, kind in SUMMARY_COLUMNS
        },
        schema=schema,
    )
    result.files.append(folder.write_table("summary.parquet", summary_table))
    result.files.append(folder.write_table("summary.csv", summary_table))
    result.answers = answers(summary, study)
    figures = _figures(study, summary, folder.path)
    result.files += [folder.path / f for f in figures]
    failures = [e for e in dict.fromkeys(columns["error"]) if e is not None] if table.num_rows else []
    report = study_markdown(study, summary, result.answers, figures=figures, failures=failures)
    from ..io.output import write_text

    write_text(folder.path / "report.md", report)
    result.files.append(folder.path / "report.md")


def _figures(study: Study, summary, path: Path) -> list[str]:
    """The figure of the study (``figures/tolerance.png``), or none without matplotlib."""
    if importlib.util.find_spec("matplotlib") is None:
        return []
    from ..io.output import atomic_write
    from ..viz import save_figure
    from ..viz.sweep import tolerance_figure

    (path / "figures").mkdir(exist_ok=True)
    name = "figures/tolerance.png"
    figure = tolerance_figure(summary, study)
    with atomic_write(path / name, "wb") as handle:
        save_figure(figure, handle, format="png")
    return [name]
