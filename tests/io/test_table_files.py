"""Every table omnikin reads (tick logs, measurement and runs files, CSV/TUM/KITTI trajectories):
an empty field is an error naming file, line and column, never dropped with the columns shifted;
devices and directories are refused, pipes read; header checks are linear in the columns."""

from __future__ import annotations

import os
import re
import signal
import threading

import numpy as np
import pytest

from omnikin import OdometryInputError, Robot, load_robot
from omnikin.cli.main import main
from omnikin.errors import RunsFileError, TrajectoryFileError
from omnikin.io.csvfile import column_problems, iter_fields, number, read_rows
from omnikin.io.logs import read_tick_log
from omnikin.io.runs import read_calibration_runs, read_umbmark_measurements
from omnikin.io.trajectories import read_trajectory
from support.counting import CountedName
from support.kinematics import circle_wheels


def cli(capsys, *argv):
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


# --- trajectories: the case that shifted columns ------------------------------------------------------------
GOOD_CSV = "t,x,y,theta\n0,0,0,0\n1,0.5,0.25,0.1\n2,1.0,0.5,0.2\n"


def test_metrics_with_an_empty_csv_field_names_line_and_column(tmp_path, capsys):
    """'1,0.5,,0.25,0.1' keeps its empty field (it is not t=1, x=0.5, y=0.25, theta=0.1): refused
    naming the line and the column."""
    ref = tmp_path / "ref.csv"
    ref.write_text(GOOD_CSV)
    est = tmp_path / "est.csv"
    est.write_text("t,x,y,theta\n0,0,0,0\n1,0.5,,0.25,0.1\n2,1.0,0.5,0.2\n")
    rc, out, err = cli(capsys, "metrics", ref, est)
    assert rc == 2 and out == ""
    assert err.strip() == (
        f"omnikin: error: {est}: line 3, column 'y' (field 3): empty field (every field needs a value)"
    )


@pytest.mark.parametrize(
    "fmt, line, field",
    [
        ("tum", "1,0.5,,0,0,0,0,0,1", 3),  # comma separated TUM with a hole: 8 values remain
        ("tum", "1 0.5 0.25 0 0 0 0 1,", 9),  # a trailing comma
        ("kitti", "1,0,0,0.5,,0,1,0,0.25,0,0,1,0", 5),
        ("csv", "1,0.5,0.25,0.1,", 5),
        ("csv", ",,,", 1),  # a line of separators is no blank line
    ],
)
def test_empty_field_in_any_trajectory_format(tmp_path, fmt, line, field):
    first = {"tum": "0 0 0 0 0 0 0 1", "kitti": "1 0 0 0 0 1 0 0 0 0 1 0", "csv": "t,x,y,theta\n0,0,0,0"}[fmt]
    path = tmp_path / f"traj.{fmt}"
    path.write_text(f"{first}\n{line}\n")
    with pytest.raises(TrajectoryFileError) as info:
        read_trajectory(path, fmt)
    msg = str(info.value)
    line_no = len(first.splitlines()) + 1
    assert re.fullmatch(
        rf"{re.escape(str(path))}: line {line_no}, (column '\w+' \(field {field}\)|field {field}): "
        r"empty field \(every field needs a value\)",
        msg,
    ), msg


def test_blank_separated_formats_still_read(tmp_path):
    """Runs of blanks and tabs separate fields; so does one comma with blanks around it."""
    path = tmp_path / "t.tum"
    path.write_text("# comment\n\n0 1  2\t0 0 0 0 1\n1, 2 ,3, 0, 0, 0, 0, 1\n")
    t, poses = read_trajectory(path)
    np.testing.assert_allclose(t, [0, 1])
    np.testing.assert_allclose(poses, [[1, 2, 0], [2, 3, 0]])


def test_detection_reads_only_the_first_line(tmp_path):
    path = tmp_path / "t.txt"
    path.write_text(GOOD_CSV)
    t, poses = read_trajectory(path)
    np.testing.assert_allclose(poses[-1], [1.0, 0.5, 0.2])


# --- measurement and runs files -------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "text, where",
    [
        ("direction,x_abs,y_abs,x_calc,y_calc\ncw,0.1,,0,0\nccw,0,0,0,0\n", "line 2, column 'y_abs' (field 3)"),
        ("direction,x_abs,y_abs,x_calc,y_calc\ncw,0.1,0.2,0,0,\nccw,0,0,0,0\n", "line 2, field 6"),
        ("direction,x_abs,,x_calc,y_calc\ncw,0.1,0.2,0,0\n", "line 1, field 3: empty column name"),
        (
            "direction,x_abs,y_abs,x_calc,y_calc,theta_abs_deg,theta_calc_deg\ncw,1,2,0,0,,3\nccw,0,0,0,0,1,1\n",
            "line 2, column 'theta_abs_deg' (field 6)",
        ),
    ],
)
def test_empty_field_in_umbmark_measurements(tmp_path, text, where):
    path = tmp_path / "m.csv"
    path.write_text(text)
    with pytest.raises(RunsFileError) as info:
        read_umbmark_measurements(path)
    assert str(info.value).startswith(f"{path}: {where}")


def test_empty_field_in_calibration_runs(tmp_path):
    path = tmp_path / "runs.csv"
    path.write_text("path,x_abs,y_abs,theta_abs_deg\nline 2,2.0,0.01,0.5\nline 2,2.0,,0.4\n")
    with pytest.raises(RunsFileError, match=r"line 3, column 'y_abs' \(field 3\): empty field"):
        read_calibration_runs(path)


# --- tick logs ------------------------------------------------------------------------------------------------
def test_empty_field_in_a_tick_log(tmp_path, capsys):
    log = tmp_path / "log.csv"
    log.write_text("t,w1,w2,w3\n0,0,0,0\n0.1,10,,10\n0.2,20,20,20\n")
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "out.csv")
    assert rc == 2 and f"{log}: line 3, column 'w2' (field 3): empty field" in err
    assert len(err.strip().splitlines()) == 1


def test_tick_log_of_many_wheels_is_read_in_linear_time(tmp_path, monkeypatch):
    """The column look-up once searched the header for every wheel: quadratic in the wheel count.
    Counted in name comparisons, not timed: 20 000 wheels allow a few per column."""
    import omnikin.io.logs as logs

    def counted_header(path, error):
        rows = read_rows(path, error)
        line, header = rows[0]
        return [(line, [CountedName(h) for h in header]), *rows[1:]]

    monkeypatch.setattr(logs, "read_rows", counted_header)
    n = 20_000
    r = Robot("many", circle_wheels(n))
    path = tmp_path / "log.csv"
    path.write_text(f"t,{','.join(r.encoded_names)}\n" + "".join(f"{k},{','.join([str(k)] * n)}\n" for k in range(3)))
    CountedName.counts, CountedName.budget = [], 10 * n
    log = read_tick_log(path, r)
    assert log.ticks.shape == (3, n)
    assert len(CountedName.counts) < 10 * n, len(CountedName.counts)


def test_column_problems_is_linear_and_bounded():
    """header.count per column was quadratic: 20 000 columns took seconds. Counted in name
    comparisons, not timed."""
    n = 20_000
    header = [CountedName(h) for h in ["t"] + [f"w{i}" for i in range(n)] + ["w0"]]
    CountedName.counts, CountedName.budget = [], 10 * n
    problems = column_problems(header, ["t"] + [f"w{i}" for i in range(n)] + ["w_missing"])
    assert problems == ["missing column(s) ['w_missing']", "duplicate column(s) ['w0']"]
    assert len(CountedName.counts) < 10 * n, len(CountedName.counts)
    many = column_problems([f"x{i}" for i in range(20_000)], ["t"])
    assert len(many[1]) < 400 and "(20000 in all)" in many[1]


# --- what a table file may be ---------------------------------------------------------------------------------
@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
@pytest.mark.parametrize(
    "reader",
    [lambda p: read_rows(p, RunsFileError), lambda p: list(iter_fields(p, TrajectoryFileError))],
    ids=["csv", "blank"],
)
def test_devices_and_directories_are_refused(tmp_path, reader):
    with pytest.raises((RunsFileError, TrajectoryFileError), match="character device"):
        reader("/dev/zero")
    with pytest.raises((RunsFileError, TrajectoryFileError), match="is a directory"):
        reader(tmp_path)


def test_a_pipe_is_read_as_a_stream(tmp_path):
    """`omnikin metrics <(zcat ref.tum.gz) ...` hands over a pipe: it is read, not refused."""
    fifo = tmp_path / "ref.tum"
    os.mkfifo(fifo)

    def writer():
        with open(fifo, "w") as handle:
            handle.write("0 0 0 0 0 0 0 1\n1 1 2 0 0 0 0 1\n")

    thread = threading.Thread(target=writer, daemon=True)
    thread.start()
    t, poses = read_trajectory(fifo, "tum")
    thread.join(timeout=10)
    np.testing.assert_allclose(poses[-1], [1, 2, 0])


def test_a_pipe_nobody_writes_to_is_an_error_instead_of_a_hang(tmp_path, monkeypatch):
    from omnikin.io import textfile

    monkeypatch.setattr(textfile, "PIPE_WAIT_S", 0.5)  # the default is 30 s
    fifo = tmp_path / "log.csv"
    os.mkfifo(fifo)

    def hung(signum, frame):
        raise AssertionError("no answer within 60 s: the reader waits for the pipe forever")

    signal.signal(signal.SIGALRM, hung)  # a safety timeout against a hang (a blocking open), not a pace
    signal.alarm(60)
    try:
        with pytest.raises(OdometryInputError, match=f"{fifo}: a pipe nobody wrote to within 0.5 s"):
            read_tick_log(fifo, load_robot("tomasi-omni3"))
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, signal.SIG_DFL)


def test_a_pipe_closed_without_data_is_an_empty_file(tmp_path):
    fifo = tmp_path / "log.csv"
    os.mkfifo(fifo)
    thread = threading.Thread(target=lambda: open(fifo, "w").close(), daemon=True)
    thread.start()
    with pytest.raises(OdometryInputError, match="empty log"):
        read_tick_log(fifo, load_robot("tomasi-omni3"))
    thread.join(timeout=10)


def test_a_line_without_end_is_bounded(tmp_path):
    from omnikin.io.textfile import MAX_LINE_BYTES

    path = tmp_path / "t.tum"
    path.write_bytes(b"0 " * (MAX_LINE_BYTES // 2 + 1))
    with pytest.raises(TrajectoryFileError, match=f"line 1: longer than {MAX_LINE_BYTES} bytes"):
        read_trajectory(path, "tum")


@pytest.mark.parametrize("data, line", [(b"t,w1\n0,1\n1,caf\xe9\n", 3), (b"\xff\xfe,t\n", 1)])
def test_non_utf8_names_the_line(tmp_path, data, line):
    path = tmp_path / "m.csv"
    path.write_bytes(data)
    with pytest.raises(RunsFileError, match=f"line {line}: not UTF-8 text"):
        read_rows(path, RunsFileError)


# --- numbers: plain ASCII decimals only ---------------------------------------------------------------------
HOSTILE_NUMBERS = ["0_1", "1_000", "\u0661", "\u0660.\u0665", "\uff11", "\u00b2", "0x10", "1e", "--1", "+-1", "1.2.3"]
"""Spellings float() reads (or half reads) that no table may accept: Python's digit groups,
Arabic-Indic and full-width digits, a superscript, hexadecimal, and broken forms."""


@pytest.mark.parametrize("text", HOSTILE_NUMBERS + ["nan", "inf", "-Infinity", "1e999"])
def test_number_fields_accept_only_plain_ascii_decimals(text):
    with pytest.raises(ValueError) as info:
        number(text, "t.csv", 3, "x", RunsFileError)
    assert str(info.value).startswith("t.csv: line 3, column 'x': ")


@pytest.mark.parametrize(
    "text, value", [("1", 1.0), ("-2.5", -2.5), ("+.5", 0.5), ("3.", 3.0), ("1e-3", 1e-3), ("-2.5E+2", -250.0)]
)
def test_plain_decimals_are_read(text, value):
    assert number(text, "t.csv", 1, "x", RunsFileError) == value


@pytest.mark.parametrize("text", HOSTILE_NUMBERS)
def test_every_table_refuses_a_hostile_number(tmp_path, text):
    """0_1 (1.0 to float()) and Arabic-Indic digits are not numbers in runs, measurements and
    trajectories."""
    files = {
        "measurements": (
            f"direction,x_abs,y_abs,x_calc,y_calc\ncw,{text},0,0,0\nccw,0,0,0,0\n",
            read_umbmark_measurements,
            "line 2, column 'x_abs'",
        ),
        "runs": (f"path,x_abs,y_abs\nline 2,2.0,{text}\n", read_calibration_runs, "line 2, column 'y_abs'"),
        "csv": (f"t,x,y,theta\n0,0,0,0\n1,{text},0,0\n", read_trajectory, "line 3, column 'x'"),
        "tum": (f"0 0 0 0 0 0 0 1\n1 0 {text} 0 0 0 0 1\n", read_trajectory, "line 2, field 3"),
        "kitti": (f"1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 {text} 0 1 0 0 0 0 1 0\n", read_trajectory, "line 2, field 4"),
    }
    for name, (content, reader, where) in files.items():
        path = tmp_path / f"{name}.txt"
        path.write_text(content, encoding="utf-8")
        with pytest.raises(ValueError) as info:
            reader(path)
        assert str(info.value).startswith(f"{path}: {where}"), (name, str(info.value))


@pytest.mark.parametrize("text", HOSTILE_NUMBERS)
def test_a_tick_log_time_is_a_plain_number(tmp_path, capsys, text):
    log = tmp_path / "log.csv"
    log.write_text(f"t,w1,w2,w3\n0,0,0,0\n{text},10,10,10\n", encoding="utf-8")
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "out.csv")
    assert rc == 2 and f"{log}: line 3, column 't'" in err, err
    assert not (tmp_path / "out.csv").exists()


@pytest.mark.parametrize("path", ["line 0_1", "spin \u0669\u0660", "arc 1 nan", "line inf", "square cw rotate 0x4"])
def test_numbers_in_a_path_are_plain_too(tmp_path, path):
    runs = tmp_path / "runs.csv"
    runs.write_text(f"path,x_abs,y_abs\n{path},2.0,0.0\n", encoding="utf-8")
    with pytest.raises(RunsFileError, match=r"line 2, column 'path': path '.*': (not a number: |non-finite value )"):
        read_calibration_runs(runs)


def test_a_run_is_one_path(tmp_path):
    """'line 1; spin 90' in a runs file got 'numbers expected after line'."""
    runs = tmp_path / "runs.csv"
    runs.write_text("path,x_abs,y_abs\nline 1; spin 90,1.0,0.0\n")
    with pytest.raises(RunsFileError, match=r"line 2, column 'path': .*one run is one path; ';'"):
        read_calibration_runs(runs)
