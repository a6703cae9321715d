"""What ``omnikin sweep`` computes, against closed forms: a robot built exactly has no error, the
systematic error grows in proportion to the tolerances (first order, common random numbers),
a point whose robots cannot be built fails alone, the physics engine runs, and the example study
of the README runs end to end and answers its question."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from support.cli import run_entry_point
from support.paths import ROOT

pq = pytest.importorskip("pyarrow.parquet", reason="omnikin[sweep] (pyarrow) is not installed")
pytest.importorskip("distributed", reason="omnikin[sweep] (Dask distributed) is not installed")


def run_study(tmp_path: Path, text: str, *extra: str, timeout: float = 300):
    spec = tmp_path / "study.yaml"
    spec.write_text("omnikin_sweep: 1\nrobots: [tomasi-omni3]\nseed: 3\n" + text)
    done = run_entry_point("sweep", spec, "-o", tmp_path / "out", "--workers", "2", *extra, timeout=timeout)
    assert "Traceback" not in done.stderr, done.stderr
    columns = {}
    if (tmp_path / "out" / "trials.parquet").exists():
        table = pq.read_table(tmp_path / "out" / "trials.parquet")
        columns = {name: np.array(table.column(name).to_pylist()) for name in table.column_names}
    return done, columns


def test_a_robot_built_exactly_and_driven_without_noise_has_no_error(tmp_path):
    done, trials = run_study(
        tmp_path,
        "trials: 3\numbmark: {side: 1, runs: 1}\nfactors: {radius: 0, hub: 0, drive_deg: 0, noise: none}\n",
    )
    assert done.returncode == 0, done.stderr
    for name in ("e_max_syst_before", "e_max_syst_after", "systematic_before", "systematic_after"):
        assert np.all(np.abs(trials[name].astype(float)) < 1e-9), (name, trials[name])


def test_the_systematic_error_grows_in_proportion_to_the_tolerances(tmp_path):
    # first order in the build errors: E(2 s) = 2 E(s) for the same build (trial k of both points
    # draws the same normals: common random numbers); at these small tolerances the second-order
    # part is below a percent
    done, trials = run_study(
        tmp_path, "trials: 4\numbmark: {side: 2, runs: 1}\nfactors: {scale: [0.01, 0.02], calibrate: false}\n"
    )
    assert done.returncode == 0, done.stderr
    small = trials["systematic_before"][trials["scale"] == 0.01].astype(float)
    large = trials["systematic_before"][trials["scale"] == 0.02].astype(float)
    assert small.shape == large.shape == (4,)
    np.testing.assert_allclose(large / small, 2.0, rtol=0.02)


def test_a_point_whose_robots_cannot_be_built_fails_alone_and_the_study_goes_on(tmp_path):
    # radius sigma 0.5 x scale 1000: every wheel radius drawn is far outside the valid range
    done, trials = run_study(
        tmp_path,
        "trials: 3\numbmark: {side: 1, runs: 1}\nfactors: {scale: [0.1, 1000], radius: 0.5, calibrate: false}\n",
    )
    assert done.returncode == 0, done.stderr
    failed = trials["scale"] == 1000
    assert all(e is not None and "not a valid robot" in e for e in trials["error"][failed])
    assert all(e is None for e in trials["error"][~failed])
    assert np.all(np.isnan(trials["e_max_syst_before"][failed].astype(float)))
    assert "3 failed" in done.stdout
    report = (tmp_path / "out" / "report.md").read_text()
    assert "not a valid robot" in report
    summary = pq.read_table(tmp_path / "out" / "summary.parquet").to_pydict()
    assert summary["failed"] == [0, 3]


def test_a_point_in_the_physics_engine_runs_with_its_roller_contact(tmp_path):
    pytest.importorskip("mujoco", reason="omnikin[physics] (MuJoCo) is not installed")
    done, trials = run_study(
        tmp_path,
        "trials: 2\numbmark: {side: 1, runs: 1}\nfactors: {scale: 0.1, calibrate: false, engine: physics}\n",
    )
    assert done.returncode == 0, done.stderr
    assert list(trials["engine"]) == ["physics", "physics"]
    assert all(n is None for n in trials["noise"])
    before = trials["e_max_syst_before"].astype(float)
    assert np.all(np.isfinite(before) & (before > 0))
    assert np.all(np.isnan(trials["systematic_before"].astype(float)))  # no noise model to leave out


@pytest.mark.slow
def test_the_example_study_runs_and_answers_its_question(tmp_path):
    done = run_entry_point("sweep", ROOT / "examples" / "tolerance.yaml", "-o", tmp_path / "study", timeout=1200)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    out = tmp_path / "study"
    trials = pq.read_table(out / "trials.parquet")
    summary = pq.read_table(out / "summary.parquet")
    assert trials.num_rows == 4 * 80 and summary.num_rows == 4
    assert trials.column("error").null_count == trials.num_rows
    assert (out / "figures" / "tolerance.png").stat().st_size > 10_000
    report = (out / "report.md").read_text()
    assert "figures/tolerance.png" in report
    # the answer: a tolerance in each phase, said in a sentence; never "none"
    before, after = [line for line in report.splitlines() if line.startswith("- tomasi-omni3, ")]
    assert "before calibration: E_max,syst stays below 10 mm for 95 % of the robots up to scale " in before
    assert "after calibration: E_max,syst stays below 10 mm for 95 % of the robots" in after
    assert "none" not in done.stdout and " at none " not in report


@pytest.mark.parametrize("option", [["--workers", "0"], ["--workers", "-1"], ["--task-trials", "-3"]])
def test_a_worker_count_or_task_size_out_of_range_is_refused(tmp_path, option):
    done, _ = run_study(tmp_path, "trials: 2\n", *option)
    assert done.returncode == 2
    assert done.stderr.startswith("omnikin: error: ") and "must be a whole number from 1" in done.stderr
    assert len(done.stderr.splitlines()) == 1


def test_force_with_a_scheduler_that_cannot_be_used_removes_nothing(tmp_path):
    done, _ = run_study(tmp_path, "trials: 1\numbmark: {side: 1, runs: 1}\nfactors: {calibrate: false}\n")
    assert done.returncode == 0, done.stderr
    parts = sorted((tmp_path / "out" / "parts").rglob("*.parquet"))
    spec = tmp_path / "study.yaml"
    spec.write_text(spec.read_text().replace("seed: 3", "seed: 4"))
    again = run_entry_point("sweep", spec, "-o", tmp_path / "out", "--force", "--scheduler", "foo")
    assert again.returncode == 2 and "scheduler" in again.stderr, again.stderr
    assert sorted((tmp_path / "out" / "parts").rglob("*.parquet")) == parts


def test_standard_output_cannot_hold_a_study_folder(tmp_path):
    spec = tmp_path / "study.yaml"
    spec.write_text("omnikin_sweep: 1\nrobots: [tomasi-omni3]\nseed: 3\ntrials: 1\n")
    done = run_entry_point("sweep", spec, "-o", "-", cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert done.stderr == (
        "omnikin: error: -o '-': a sweep writes a folder; '-' (standard output) cannot hold it: "
        "name a folder, e.g. -o study/\n"
    )
    assert done.stdout == "" and not (tmp_path / "-").exists()
