"""``omnikin sweep``: a tolerance or design study on Dask (:func:`omnikin.run_sweep`; extra ``sweep``)."""

from __future__ import annotations

import argparse
import os
import sys
import time

from ..errors import InputError, LinkError, OutputExistsError
from .common import console, whole

EPILOG = """the study file (YAML; examples/tolerance.yaml is a commented example):
  robots      presets or robot files;  seed;  trials per point
  factors     scale, radius, hub, drive_deg (the build tolerances: scale x each sigma),
              noise, ticks_per_rev, rate, calibrate, engine: a value, a list, or a range
              {from: A, to: B, count: N, spacing: log}
  design      grid (every combination) or random (points: N drawn from the ranges)
  question    target_mm (10), quantile (0.95): "which tolerances keep E_max,syst < 10 mm
              for 95 % of the robots built, before and after calibration?"

the folder OUT_DIR:
  parts/       trials written as each task finishes (an interrupted study loses only the
               tasks that were running: rerun the same command to resume)
  trials.parquet    one row per trial;  summary.parquet, summary.csv: one row per point
  figures/tolerance.png, report.md: the answer

where it runs:
  by default a local Dask cluster of one worker process per core (--workers N) that only this
  run can reach (TLS with temporary credentials); with --scheduler tls://HOST:8786 and
  --tls-ca-file/--tls-cert/--tls-key, an existing cluster secured with TLS (started with
  'dask scheduler --protocol tls' and 'dask worker tls://HOST:8786' with their own --tls-*
  options, where omnikin[sweep] of the same version is installed; docs/sweeps.md). Results of
  a worker of another omnikin or NumPy version are refused, whenever it joins. The same study
  gives the same table whatever the workers, the cluster and the order in which tasks finish.

examples:
  omnikin sweep examples/tolerance.yaml -o study/
  omnikin sweep examples/tolerance.yaml -o study/ --workers 1
  omnikin sweep examples/layouts.yaml -o layouts/ --scheduler tls://HOST:8786 \
      --tls-ca-file ca.pem --tls-cert me.pem --tls-key me.key"""


def add_parser(sub, robot_help: str) -> None:
    """Add ``sweep`` to ``sub``."""
    sp = sub.add_parser(
        "sweep",
        help="tolerance and design studies: thousands of robots as built through UMBmark and calibration, on Dask",
        description="Run the study of a study file: for every point of its grid (robots, build tolerances, "
        "noise, encoder resolution, rate, calibration, engine), many robots as built within the "
        "tolerances, each through UMBmark, calibration and UMBmark again; write the trials, a summary "
        "per point, a figure of the error against the tolerance and a report that answers which "
        "tolerances keep E_max,syst below the target (extra sweep: Dask and pyarrow).",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sp.add_argument("spec", metavar="SPEC.yaml", help="the study file")
    sp.add_argument(
        "-o",
        "--out",
        metavar="OUT_DIR",
        required=True,
        help="the study folder: created, or resumed when it holds this study (same seed); "
        "not - (a folder cannot go to standard output)",
    )
    sp.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on the Dask cluster whose scheduler listens at ADDRESS (tls://HOST:8786 with --tls-*, or an "
        "unauthenticated tcp://HOST:8786); default: a local cluster only this run can reach "
        "(temporary TLS credentials)",
    )
    sp.add_argument(
        "--tls-ca-file",
        metavar="PEM",
        help="with --scheduler tls://...: the certificate authority that signed the cluster's certificates",
    )
    sp.add_argument(
        "--tls-cert", metavar="PEM", help="with --scheduler tls://...: this client's certificate (signed by that CA)"
    )
    sp.add_argument(
        "--tls-key",
        metavar="PEM",
        help="with --scheduler tls://...: this client's private key (default: in --tls-cert)",
    )
    sp.add_argument(
        "--workers",
        type=whole,
        metavar="N",
        help="worker processes of the local cluster (default: one per core; not with --scheduler)",
    )
    sp.add_argument(
        "--task-trials",
        type=whole,
        metavar="N",
        help="trials per task (default: about 1.5 s of work per task, 1 for the physics engine)",
    )
    sp.add_argument(
        "--force",
        action="store_true",
        help="OUT_DIR holds a study of another seed: remove its results and start over",
    )
    sp.set_defaults(func=run)


class _Progress:
    """The study's progress on standard error: where it runs, the dashboard, and a bar with the
    time left (a line every 10 % when standard error is not a terminal)."""

    def __init__(self):
        self.con = console(120, stderr=True)
        self.bar = None
        self.total = self.done = 0
        self.started = time.monotonic()
        self.told = 0

    def start(self, *, total: int, done: int, where: str, dashboard: str) -> None:
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn, TimeRemainingColumn

        self.total, self.done, self.first = total, done, done
        print(f"running on {where}; Dask dashboard: {dashboard}", file=sys.stderr)
        if done:
            print(f"{done} of {total} trials already in the folder: computing the others", file=sys.stderr)
        if self.con.is_terminal:
            self.bar = Progress(
                "trials",
                BarColumn(),
                MofNCompleteColumn(),
                TimeElapsedColumn(),
                "left",
                TimeRemainingColumn(),
                console=self.con,
                transient=False,
            )
            self.task = self.bar.add_task("trials", total=total, completed=done)
            self.bar.start()

    def advance(self, trials: int) -> None:
        self.done += trials
        if self.bar is not None:
            self.bar.advance(self.task, trials)
            return
        tenth = (self.done * 10) // max(self.total, 1)
        if tenth > self.told:
            self.told = tenth
            rate = (self.done - self.first) / max(time.monotonic() - self.started, 1e-9)
            left = (self.total - self.done) / rate if rate > 0 else float("nan")
            print(f"{self.done} of {self.total} trials, about {left:.0f} s left", file=sys.stderr)

    def stop(self) -> None:
        if self.bar is not None:
            self.bar.stop()
            self.bar = None


def _check_paths(args) -> None:
    """``-o -`` is refused (a study is a folder, standard output cannot hold it); the study file
    must not lie inside the study folder (``--force`` removes what is in it)."""
    if args.out == "-":
        raise InputError(
            "-o '-': a sweep writes a folder; '-' (standard output) cannot hold it: name a folder, e.g. -o study/"
        )
    spec = os.path.realpath(args.spec)
    out = os.path.realpath(args.out)
    if spec == out or spec.startswith(out.rstrip(os.sep) + os.sep):
        raise OutputExistsError(f"{args.out}: contains the study file {args.spec}; write the study elsewhere")
    if args.workers is not None and args.scheduler is not None:
        raise InputError("--workers sets the local cluster's size: not with --scheduler (the cluster has its own)")


def run(args) -> int:
    """Run the study into its folder, print the answers; status 0."""
    from ..api import run_sweep
    from ..sweep.execution import require_sweep
    from ..sweep.spec import load_study

    _check_paths(args)
    require_sweep()
    from ..sweep.cluster import TLSFiles

    tls = TLSFiles(args.tls_ca_file, args.tls_cert, args.tls_key)
    tls.check(args.scheduler)
    if args.scheduler is not None and args.scheduler.startswith("tcp://"):
        print(
            f"omnikin: warning: {args.scheduler} is an unauthenticated (tcp://) cluster: whoever reaches it can run "
            "code on its workers and send this study results; use tls:// (docs/sweeps.md)",
            file=sys.stderr,
        )
    study = load_study(args.spec)
    progress = _Progress()
    try:
        result = run_sweep(
            study,
            args.out,
            scheduler=args.scheduler,
            workers=args.workers,
            task_trials=args.task_trials,
            force=args.force,
            progress=progress,
            tls=tls,
        )
    except KeyboardInterrupt:
        progress.stop()
        raise KeyboardInterrupt(f"the finished tasks are in {args.out}: rerun the same command to resume") from None
    except LinkError as exc:  # the cluster failed: what finished is kept
        progress.stop()
        raise LinkError(f"{exc}; the finished tasks are in {args.out}: rerun the same command to resume") from None
    finally:
        progress.stop()
    for line in result.refused:
        print(f"omnikin: warning: {line}; its tasks are computed again on the next run", file=sys.stderr)
    for line in result.removed:
        print(f"omnikin: warning: {line}: removed, computed again", file=sys.stderr)
    total = study.trials * len(study.points)
    print(
        f"{study.name}: {len(study.points)} points x {study.trials} trials = {total} trials "
        f"({result.computed} computed now, {result.reused} from the folder, {result.failed} failed)"
    )
    if result.failed:
        print(
            f"omnikin: warning: {result.failed} of {total} trials failed: their reasons are in the table's error "
            f"column and in {os.path.join(args.out, 'report.md')}",
            file=sys.stderr,
        )
    if result.failed_tasks:
        print(
            f"omnikin: warning: {result.failed_tasks} tasks failed on their workers; their trials are marked "
            "in the table and computed again on the next run",
            file=sys.stderr,
        )
    for answer in result.answers:
        print(f"  {answer.text}")
    print(f"report: {os.path.join(args.out, 'report.md')}")
    return 0
