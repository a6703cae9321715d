"""The small study that the tests running ``omnikin sweep`` on real Dask clusters share
(``tests/sweep/test_sweep_cluster.py``, ``tests/sweep/test_sweep_security.py``): its file, the
sweep started as a user starts it, and its trial table compared bit for bit.

Importing this module skips the importing test module when ``omnikin[sweep]`` (pyarrow, Dask
distributed) is not installed. It is a module beside ``dask_cluster.py``, as every helper the
tests import, not a second ``conftest`` module."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from support.cli import run_entry_point
from support.paths import omnikin_env

pa = pytest.importorskip("pyarrow", reason="omnikin[sweep] (pyarrow) is not installed")
pq = pytest.importorskip("pyarrow.parquet", reason="omnikin[sweep] (pyarrow) is not installed")
pytest.importorskip("distributed", reason="omnikin[sweep] (Dask distributed) is not installed")

HANG_S = 900.0
"""How long a sweep, or a state it must reach, may take before a test calls it hung [s]: a guard,
never a pace. The 32 calibrated trials of the worker-kill test's reference took more than 300 s
on 2 cores with a load average of 25."""

STUDY = """\
omnikin_sweep: 1
name: {name}
robots: [tomasi-omni3]
seed: 7
trials: {trials}
umbmark: {{side: {side:g}, runs: {runs}}}
factors:
  scale: [0.1, 1]
  calibrate: {calibrate}
"""


def write_study(
    tmp_path: Path, trials: int, calibrate: bool = False, *, side: float, runs: int, name: str = "cluster test"
) -> Path:
    """``tmp_path/study.yaml``: tomasi-omni3, seed 7, two points (scale 0.1 and 1), ``trials``
    trials each, UMBmark on a ``side`` [m] square with ``runs`` runs per direction."""
    spec = tmp_path / "study.yaml"
    spec.write_text(
        STUDY.format(name=name, trials=trials, side=side, runs=runs, calibrate="true" if calibrate else "false")
    )
    return spec


def table(folder: Path) -> dict[str, np.ndarray]:
    """The trial table of the study in ``folder`` without its one run-dependent column (computing
    time), as NumPy columns (text columns as object arrays holding str or None)."""
    read = pq.read_table(folder / "trials.parquet").drop_columns(["seconds"])
    return {
        name: np.array(read.column(name).to_pylist(), dtype=object if read.column(name).type == pa.string() else None)
        for name in read.column_names
    }


def assert_same_table(result: dict, reference: dict) -> None:
    """Equal column by column, bit for bit and of the same dtype (NaN where the other has NaN:
    the after columns of a trial without calibration)."""
    assert list(result) == list(reference)
    for name in reference:
        np.testing.assert_array_equal(result[name], reference[name], err_msg=name, strict=True)


def no_traceback(stderr: str) -> None:
    """Nothing of Python's or Dask's own reached the user's terminal."""
    assert "Traceback" not in stderr and "distributed." not in stderr, stderr


def sweep(*argv, timeout: float = HANG_S) -> subprocess.CompletedProcess:
    """``omnikin sweep ARGV`` run to its end (``timeout`` [s]: a hang guard), checked for tracebacks."""
    done = run_entry_point("sweep", *argv, timeout=timeout)
    no_traceback(done.stderr)
    return done


def start_sweep(*argv, new_session: bool = True) -> subprocess.Popen:
    """``omnikin sweep ARGV`` started and left running, its output captured as text; in a session
    of its own (``new_session``) so that ``os.killpg`` reaches it and its workers as Ctrl-C does."""
    return subprocess.Popen(
        [sys.executable, "-m", "omnikin.cli.main", "sweep", *map(str, argv)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=omnikin_env(),
        start_new_session=new_session,
    )
