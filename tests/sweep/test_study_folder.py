"""The study folder (``omnikin.sweep.store``) without Dask: what it takes over, refuses, keeps and
throws away. Parts are written by hand from rows of ``run_trials`` (a real trial, 1 m square)."""

from __future__ import annotations

import os
from dataclasses import replace

import numpy as np
import pytest

from omnikin.errors import OutputExistsError
from omnikin.io.robot_file import load_robot
from omnikin.sweep.points import Point, point_key, robot_hash
from omnikin.sweep.study import Study
from omnikin.sweep.trials import run_trials

pytest.importorskip("pyarrow", reason="omnikin[sweep] (pyarrow) is not installed")
from omnikin.sweep.store import MANIFEST, StudyFolder, part_name  # noqa: E402

ROBOT = load_robot("tomasi-omni3")
POINT = Point("tomasi-omni3", robot_hash(ROBOT), side=1.0, runs=1, calibrate=False)
KEY = point_key(POINT)


def study(trials: int = 4, seed: int = 5, points=(POINT,)) -> Study:
    return Study("s.yaml", "s", seed, trials, "grid", tuple(points), {"tomasi-omni3": ROBOT})


def write(folder: StudyFolder, first: int, stop: int, seed: int = 5) -> None:
    folder.write_part(KEY, first, stop, run_trials(ROBOT, POINT, seed, first, stop))


def test_a_folder_of_the_same_seed_is_resumed_with_more_trials_than_before(tmp_path):
    with StudyFolder.open(tmp_path / "out", study(trials=2)) as folder:
        folder.coverage()
        write(folder, 0, 2)
    with StudyFolder.open(tmp_path / "out", study(trials=4)) as folder:
        coverage = folder.coverage()
        assert coverage.done[KEY].tolist() == [True, True, False, False]
        write(folder, 2, 4)
        table = folder.trial_table()
    assert table.column("trial").to_pylist() == [0, 1, 2, 3]
    fresh = run_trials(ROBOT, POINT, 5, 0, 4)  # trials 0..3 in one go: the same numbers
    np.testing.assert_array_equal(table.column("e_max_syst_before").to_numpy(), fresh["e_max_syst_before"])


def test_fewer_trials_than_on_disk_keep_only_the_first_ones(tmp_path):
    with StudyFolder.open(tmp_path / "out", study(trials=4)) as folder:
        folder.coverage()
        write(folder, 0, 4)
    with StudyFolder.open(tmp_path / "out", study(trials=3)) as folder:
        assert folder.coverage().done[KEY].all()
        assert folder.trial_table().column("trial").to_pylist() == [0, 1, 2]


def test_a_damaged_or_lying_part_is_removed_and_computed_again(tmp_path):
    with StudyFolder.open(tmp_path / "out", study()) as folder:
        folder.coverage()
        write(folder, 0, 2)
        write(folder, 2, 4)
    parts = tmp_path / "out" / "parts" / KEY
    (parts / part_name(2, 4)).write_bytes(b"PAR1 not really")  # truncated or overwritten
    os.rename(parts / part_name(0, 2), parts / part_name(0, 3))  # its name claims a trial it lacks
    with StudyFolder.open(tmp_path / "out", study()) as folder:
        coverage = folder.coverage()
    assert not coverage.done[KEY].any()
    assert len(coverage.removed) == 2
    assert not list(parts.iterdir())


def test_a_part_left_half_written_by_an_interrupted_run_is_removed(tmp_path):
    with StudyFolder.open(tmp_path / "out", study()) as folder:
        folder.coverage()
    parts = tmp_path / "out" / "parts" / KEY
    parts.mkdir(parents=True)
    (parts / f".{part_name(0, 2)}.abc.tmp").write_bytes(b"half")
    with StudyFolder.open(tmp_path / "out", study()) as folder:
        assert not folder.coverage().done[KEY].any()
    assert not list(parts.iterdir())


def test_a_folder_omnikin_did_not_write_is_refused_and_left_as_it_was(tmp_path):
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "thesis.tex").write_text("keep me")
    with pytest.raises(OutputExistsError, match="non-empty folder omnikin did not write"):
        StudyFolder.open(tmp_path / "mine", study())
    assert sorted(p.name for p in (tmp_path / "mine").iterdir()) == ["thesis.tex"]
    (tmp_path / "file").write_text("x")
    with pytest.raises(OutputExistsError, match="not a folder"):
        StudyFolder.open(tmp_path / "file", study())


def test_another_seed_is_refused_and_force_removes_only_the_studys_files(tmp_path):
    with StudyFolder.open(tmp_path / "out", study(seed=5)) as folder:
        folder.coverage()
        write(folder, 0, 2)
    (tmp_path / "out" / "notes.txt").write_text("the user's")
    with pytest.raises(OutputExistsError, match="seed 5, this study has seed 6"):
        StudyFolder.open(tmp_path / "out", study(seed=6))
    assert (tmp_path / "out" / "parts" / KEY / part_name(0, 2)).exists()
    (tmp_path / "out" / "parts" / KEY / "README").write_text("the user's too")
    with StudyFolder.open(tmp_path / "out", study(seed=6), force=True) as folder:
        assert not folder.coverage().done[KEY].any()
        assert (tmp_path / "out" / "parts" / KEY / part_name(0, 2)).exists()  # nothing removed before the run
        folder.start_over()
    assert not (tmp_path / "out" / "parts" / KEY / part_name(0, 2)).exists()
    assert (tmp_path / "out" / "notes.txt").read_text() == "the user's"
    assert (tmp_path / "out" / "parts" / KEY / "README").read_text() == "the user's too"
    assert '"seed": 6' in (tmp_path / "out" / MANIFEST).read_text()


def test_a_manifest_omnikin_did_not_write_is_refused_even_with_force(tmp_path):
    (tmp_path / "app").mkdir()
    (tmp_path / "app" / MANIFEST).write_text('{"name": "my web app"}')
    (tmp_path / "app" / "report.md").write_text("mine")
    for force in (False, True):
        with pytest.raises(OutputExistsError, match="not an omnikin study's"):
            StudyFolder.open(tmp_path / "app", study(), force=force)
    assert (tmp_path / "app" / "report.md").read_text() == "mine"
    assert (tmp_path / "app" / MANIFEST).read_text() == '{"name": "my web app"}'


def test_results_of_another_omnikin_or_numpy_version_are_not_mixed_in(tmp_path):
    with StudyFolder.open(tmp_path / "out", study()) as folder:
        folder.coverage()
        write(folder, 0, 2)
    manifest = tmp_path / "out" / MANIFEST
    manifest.write_text(manifest.read_text().replace(f'"numpy": "{np.__version__}"', '"numpy": "1.0"'))
    with pytest.raises(OutputExistsError, match="NumPy '1.0'"):
        StudyFolder.open(tmp_path / "out", study())


def test_two_sweeps_never_write_one_folder_at_once(tmp_path):
    with StudyFolder.open(tmp_path / "out", study()):
        with pytest.raises(OutputExistsError, match="another omnikin sweep is writing"):
            StudyFolder.open(tmp_path / "out", study())
    with StudyFolder.open(tmp_path / "out", study()):  # released at the end
        pass


def test_a_point_no_longer_in_the_study_is_kept_on_disk_but_left_out_of_the_table(tmp_path):
    other = replace(POINT, scale=0.5)
    with StudyFolder.open(tmp_path / "out", study(trials=1, points=(POINT, other))) as folder:
        folder.coverage()
        write(folder, 0, 1)
        folder.write_part(point_key(other), 0, 1, run_trials(ROBOT, other, 5, 0, 1))
    with StudyFolder.open(tmp_path / "out", study(trials=1)) as folder:
        folder.coverage()
        assert folder.trial_table().column("point").to_pylist() == [KEY]
    assert (tmp_path / "out" / "parts" / point_key(other) / part_name(0, 1)).exists()


def _resume(out, s: Study) -> tuple[list[str], dict]:
    """What a rerun of the sweep does without Dask: read the folder, compute the trials it lacks
    (the tasks ``plan_tasks`` cuts, each by ``run_trials`` as a worker would), build the table."""
    from omnikin.sweep.execution import arrow_columns, plan_tasks

    with StudyFolder.open(out, s) as folder:
        coverage = folder.coverage()
        for task in plan_tasks(s, coverage, workers=1):
            point = s.points[task.index]
            rows = run_trials(ROBOT, point, s.seed, task.first, task.stop)
            folder.write_part(point_key(point), task.first, task.stop, rows)
        columns = arrow_columns(folder.trial_table().drop_columns(["seconds"]))
    return coverage.removed, columns


@pytest.mark.parametrize(
    "extra, removed",
    [
        ({"trials-0000000-0000002.parquet": (0, 2)}, 1),  # a copy of part 0-2 under another spelling
        ({part_name(1, 3): (1, 3)}, 1),  # a part covering trials of both parts
        ({part_name(0, 4): (0, 4)}, 1),  # a part covering all of them
        ({part_name(1, 3): (1, 3), part_name(3, 4): (3, 4)}, 2),  # overlapping chains
    ],
)
def test_overlapping_parts_are_read_once_and_give_the_clean_runs_table(tmp_path, extra, removed):
    from omnikin.sweep.summary import summarize

    other = replace(POINT, scale=0.5)
    s = study(trials=4, points=(POINT, other))
    _, clean = _resume(tmp_path / "clean", s)
    out = tmp_path / "out"
    _resume(out, s)  # parts 0-4 of both points
    for name, (first, stop) in extra.items():  # rows that are right, in parts that overlap
        for point in (POINT, other):
            rows = run_trials(ROBOT, point, 5, first, stop)
            with StudyFolder.open(tmp_path / "scratch", s) as scratch:
                scratch.write_part(point_key(point), first, stop, rows)
            source = tmp_path / "scratch" / "parts" / point_key(point) / part_name(first, stop)
            os.replace(source, out / "parts" / point_key(point) / name)
    gone, table = _resume(out, s)
    assert len(gone) == 2 * removed and all("overlaps another part" in line for line in gone), gone
    pairs = list(zip(table["point"].tolist(), table["trial"].tolist(), strict=True))
    assert sorted(pairs) == sorted((point_key(p), k) for p in (POINT, other) for k in range(4))  # each once
    for name in clean:
        np.testing.assert_array_equal(table[name], clean[name], err_msg=name)
    expected, got = summarize(clean, s), summarize(table, s)
    for name in expected:
        np.testing.assert_array_equal(got[name], expected[name], err_msg=name)
