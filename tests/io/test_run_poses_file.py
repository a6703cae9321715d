"""run_poses.csv (the UMBmark report's runs over time): what it writes reads back, and every
hostile file is refused in one line naming the file and the line."""

import math

import numpy as np
import pytest

from omnikin.errors import InputError, ResourceLimitError, RunPosesFileError
from omnikin.evaluation.run_poses import MAX_ROWS, RunPoses, decimated, stride
from omnikin.io.run_poses import COLUMNS, MAX_READ_BYTES, read_run_poses, run_poses_text

HEADER = ",".join(COLUMNS)


def write(tmp_path, text: str):
    path = tmp_path / "run_poses.csv"
    path.write_text(text, encoding="utf-8")
    return path


def good_rows(phase="before", direction="cw", run=1, times=(0.0, 0.05, 0.1)):
    return [f"{phase},{direction},{run},{t},{t},0,0,{t},0,0" for t in times]


def test_what_is_written_reads_back_to_the_micrometre(tmp_path):
    rng = np.random.default_rng(3)
    runs = []
    for k, (phase, direction) in enumerate((("before", "cw"), ("before", "ccw"), ("after", "cw"))):
        t = np.cumsum(rng.uniform(0.01, 0.1, 7))
        runs.append(RunPoses(phase, direction, k + 1, t, rng.normal(size=(7, 3)), rng.normal(size=(7, 3))))
    text = run_poses_text(runs, "made by a test")
    back = read_run_poses(write(tmp_path, text))
    assert [(r.phase, r.direction, r.run) for r in back] == [(r.phase, r.direction, r.run) for r in runs]
    for a, b in zip(back, runs, strict=True):
        assert np.abs(a.t - b.t).max() <= 5e-7
        assert np.abs(a.truth[:, :2] - b.truth[:, :2]).max() <= 5e-7
        assert np.abs(a.odometry[:, 2] - b.odometry[:, 2]).max() <= 5e-8
    assert "# made by a test" in text and text.splitlines()[0].startswith("# omnikin-run-poses/1")


def test_decimation_keeps_at_most_20_hz_and_always_the_end():
    """100 Hz for 10.005 s (1002 samples): every 5th sample (20 Hz) and the last one."""
    t = np.arange(1002) * 0.01
    k = stride(len(t), 100.0, 5)
    assert k == 5
    tt, truth, _ = decimated(t, np.column_stack([t, t, t]), np.zeros((1002, 3)), k)
    assert np.diff(tt)[:-1] == pytest.approx(0.05) and tt[-1] == t[-1] and truth[-1, 0] == t[-1]
    # many long runs: the rows per phase and direction stay under MAX_ROWS
    k = stride(100_000, 100.0, 50)
    assert 50 * (math.ceil(100_000 / k) + 1) <= MAX_ROWS


@pytest.mark.parametrize(
    "body, where",
    [
        ("", "empty file"),
        ("phase,direction,run,t,x,y,theta,odom_x,odom_y\n", "missing column"),
        (HEADER + "\n", "no data rows"),
        (HEADER + "\n" + "\n".join(good_rows()) + "\nbefore,cw,1,0.15,0.1", "line 5: 5 fields"),  # truncated
        (HEADER + "\nbefore,cw,1,0,nan,0,0,0,0,0\nbefore,cw,1,1,0,0,0,0,0,0\n", "line 2, column 'x'"),
        (HEADER + "\nbefore,cw,1,0,0,0,0,0,0,0\nbefore,cw,1,1,0,inf,0,0,0,0\n", "line 3, column 'y'"),
        (HEADER + "\n" + "\n".join(good_rows(times=(0.0, 0.1, 0.1))), "line 4, column 't'"),
        (HEADER + "\n" + "\n".join(good_rows(times=(0.0, 0.2, 0.1))), "line 4, column 't'"),
        (HEADER + "\n" + "\n".join(good_rows(phase="during")), "line 2, column 'phase'"),
        (HEADER + "\n" + "\n".join(good_rows(direction="up")), "line 2, column 'direction'"),
        (HEADER + "\n" + "\n".join(good_rows(run="0")), "line 2, column 'run'"),
        (HEADER + "\n" + "\n".join(good_rows(run="1.5")), "line 2, column 'run'"),
        (HEADER + "\n" + "\n".join(good_rows(times=(0.0,))), "line 2: before cw run 1 has one sample"),
        (
            HEADER + "\n" + "\n".join(good_rows() + good_rows(run=2) + good_rows(times=(1.0, 2.0))),
            "line 8: before cw run 1 again",
        ),
        (HEADER + "\nbefore,cw,1,0,0,0,0,0,,0\n", "line 2, column 'odom_y'"),
        ("\x00\x01binary", "line 1"),
    ],
)
def test_a_hostile_file_is_refused_in_one_line_naming_file_and_line(tmp_path, body, where):
    path = write(tmp_path, body)
    with pytest.raises(RunPosesFileError) as e:
        read_run_poses(path)
    message = str(e.value)
    assert "\n" not in message and str(path) in message and where in message


def test_a_missing_file_or_a_folder_is_one_line(tmp_path):
    for path in (tmp_path / "nothing.csv", tmp_path):
        with pytest.raises(InputError) as e:
            read_run_poses(path)
        assert "\n" not in str(e.value) and str(path) in str(e.value)


def test_a_huge_file_is_refused_before_it_is_read(tmp_path):
    """A sparse file of 1 TB: refused from its size at once (reading it would take hours)."""
    path = tmp_path / "run_poses.csv"
    with open(path, "wb") as f:
        f.write((HEADER + "\n").encode())
        f.truncate(1 << 40)
    with pytest.raises(ResourceLimitError) as e:
        read_run_poses(path)
    assert "\n" not in str(e.value) and str(path) in str(e.value) and str(MAX_READ_BYTES) in str(e.value)


def test_more_rows_than_allowed_are_refused_while_reading(tmp_path):
    """A file longer than the row bound (a pipe has no size to check first) is refused while read."""
    path = write(tmp_path, HEADER + "\n" + "\n".join(good_rows(times=np.arange(50) * 0.1)) + "\n")
    with pytest.raises(ResourceLimitError) as e:
        read_run_poses(path, max_rows=20)
    assert "\n" not in str(e.value) and "more than 20 rows" in str(e.value)


def test_a_file_cut_short_is_refused_even_at_a_line_end(tmp_path):
    """The format line counts the rows: a file cut after a whole row (every row left valid) is
    still refused, and so is one cut inside a number (the row still has its ten fields)."""
    t = np.arange(6) * 0.05
    run = RunPoses("before", "cw", 1, t, np.column_stack([t, t, t]), np.zeros((6, 3)))
    text = run_poses_text([run])
    lines = text.splitlines(keepends=True)
    for cut in ("".join(lines[:-1]), text[:-3]):
        with pytest.raises(RunPosesFileError) as e:
            read_run_poses(write(tmp_path, cut))
        assert "\n" not in str(e.value) and ("line 1 announces 6" in str(e.value) or "cut short" in str(e.value))
