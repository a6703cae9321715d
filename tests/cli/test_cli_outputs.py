"""Files the command line writes: never an input, an existing output only with --force (a folder
only if omnikin wrote it), whole or not at all, and '-' carries the data only.

Every case runs the real command (``main([...])`` in-process, or the entry point in a
subprocess for signals) on real files in tmp_path, and checks the files afterwards byte for
byte: the attack is "which file did the command destroy?".
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from omnikin.cli.main import main
from support.cli import run_cli as cli
from support.paths import omnikin_env

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
LOG = "t,w1,w2,w3\n0,0,0,0\n0.1,5,-3,2\n0.2,10,-6,4\n"
ROBOT = (
    "omnikin: 1\nname: tri\nwheels:\n"
    "  - {name: a, type: omni, distance: 0.2, angle_deg: 90, radius: 0.05}\n"
    "  - {name: b, type: omni, distance: 0.2, angle_deg: 210, radius: 0.05}\n"
    "  - {name: c, type: omni, distance: 0.2, angle_deg: 330, radius: 0.05}\n"
)


def refused(rc, err, *fragments):
    """Exit 2 with one line naming the problem."""
    assert rc == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("omnikin: error: "), err
    for f in fragments:
        assert f in lines[0], (f, err)


def snapshot(folder):
    """Every file under ``folder`` with its bytes (to prove nothing changed)."""
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture
def log(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text(LOG)
    return path


def entry_point(*argv, **kwargs):
    """The real entry point in a subprocess, with this checkout's omnikin whatever the folder."""
    env = omnikin_env()
    kwargs = {"stdout": subprocess.PIPE, "stderr": subprocess.PIPE, **kwargs}
    return subprocess.Popen(
        [sys.executable, "-m", "omnikin.cli.main", *[str(a) for a in argv]], env=env, text=True, **kwargs
    )


@pytest.fixture(scope="module")
def sim_bag(tmp_path_factory):
    """A small simulated bag (a quarter turn in place at 50 Hz) written by omnikin itself."""
    pytest.importorskip("rosbags")
    path = tmp_path_factory.mktemp("sim") / "sim.bag"
    assert (
        main(
            [
                "simulate",
                "tomasi-omni3",
                "--path",
                "spin 90",
                "--rate",
                "50",
                "--errors",
                "none",
                "--noise",
                "none",
                "--bag",
                str(path),
            ]
        )
        == 0
    )
    return path


def odom_count(bag, topic="/odom"):
    """Messages of ``topic``, counted by rosbags itself."""
    from rosbags.rosbag2 import Reader

    with Reader(bag) as reader:
        return sum(1 for _ in reader.messages(connections=[c for c in reader.connections if c.topic == topic]))


# --- never an input ----------------------------------------------------------------------------------
def test_odometry_never_writes_over_its_log(capsys, log):
    for extra in ([], ["--force"]):
        rc, out, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", log, *extra)
        refused(rc, err, "input")
        assert log.read_text() == LOG


def test_show_plot_never_writes_over_the_robot_file(capsys, tmp_path):
    robot = tmp_path / "tri.png"  # a robot file with a drawing's name
    robot.write_text(ROBOT)
    for extra in ([], ["--force"]):
        rc, _, err = cli(capsys, "show", robot, "--plot", robot, *extra)
        refused(rc, err, "input")
        assert robot.read_text() == ROBOT


def test_bag_export_never_writes_into_the_bag(capsys, sim_bag):
    before = snapshot(sim_bag)
    for target in (sim_bag / "metadata.yaml", sim_bag / "new.tum", sim_bag):
        rc, _, err = cli(
            capsys, "bag", "export", sim_bag, "--topic", "/odom", "--format", "tum", "-o", target, "--force"
        )
        assert rc == 2 and "omnikin: error:" in err
    assert snapshot(sim_bag) == before


def test_bag_odometry_never_writes_over_or_inside_its_input(capsys, sim_bag):
    before = snapshot(sim_bag)
    for target in (sim_bag, sim_bag / "inner.bag", sim_bag.parent):
        rc, _, err = cli(capsys, "bag", "odometry", "tomasi-omni3", sim_bag, "-o", target, "--force")
        refused(rc, err, "input")
    assert snapshot(sim_bag) == before


# --- existing outputs ------------------------------------------------------------------------------------
def test_existing_drawing_is_replaced_only_with_force(capsys, tmp_path):
    png = tmp_path / "layout.png"
    png.write_bytes(b"my own picture")
    rc, _, err = cli(capsys, "show", "omni4", "--plot", png)
    refused(rc, err, "exists", "--force")
    assert png.read_bytes() == b"my own picture"
    rc, out, err = cli(capsys, "show", "omni4", "--plot", png, "--force")
    assert rc == 0, err
    assert png.read_bytes()[:8] == PNG_MAGIC
    assert sorted(p.name for p in tmp_path.iterdir()) == ["layout.png"]  # no temporary left


def test_unknown_drawing_format_is_refused_before_anything_is_written(capsys, tmp_path):
    rc, out, err = cli(capsys, "show", "omni4", "--plot", tmp_path / "layout.xyz")
    refused(rc, err, "xyz", "png")
    assert out == "" and list(tmp_path.iterdir()) == []


def test_existing_trajectory_is_replaced_only_with_force(capsys, sim_bag, tmp_path):
    out = tmp_path / "odom.tum"
    out.write_text("keep me\n")
    argv = ["bag", "export", sim_bag, "--topic", "/odom", "--format", "tum", "-o", out]
    rc, _, err = cli(capsys, *argv)
    refused(rc, err, str(out), "--force")
    assert out.read_text() == "keep me\n"
    rc, _, err = cli(capsys, *argv, "--force")
    assert rc == 0, err
    assert len(out.read_text().splitlines()) == odom_count(sim_bag)


def test_bag_output_replaces_only_a_bag_omnikin_wrote(capsys, sim_bag, tmp_path):
    from rosbags.rosbag2 import Reader

    foreign = tmp_path / "recorded.bag"
    foreign.mkdir()
    (foreign / "metadata.yaml").write_text("a bag recorded by someone else")
    for extra in ([], ["--force"]):
        rc, _, err = cli(capsys, "bag", "odometry", "tomasi-omni3", sim_bag, "-o", foreign, *extra)
        refused(rc, err, "did not write")
    assert snapshot(foreign) == {"metadata.yaml": b"a bag recorded by someone else"}

    out = tmp_path / "odom.bag"
    assert cli(capsys, "bag", "odometry", "tomasi-omni3", sim_bag, "-o", out)[0] == 0
    (out / "stray.txt").write_text("from the first run")
    rc, _, err = cli(capsys, "bag", "odometry", "tomasi-omni3", sim_bag, "-o", out, "--odom-topic", "/second")
    refused(rc, err, "--force")
    rc, _, err = cli(
        capsys, "bag", "odometry", "tomasi-omni3", sim_bag, "-o", out, "--odom-topic", "/second", "--force"
    )
    assert rc == 0, err
    assert not (out / "stray.txt").exists()  # replaced as a whole, never mixed
    with Reader(out) as reader:
        assert [c.topic for c in reader.connections] == ["/second"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["odom.bag", "recorded.bag"]


def test_simulate_never_replaces_a_file(capsys, tmp_path):
    pytest.importorskip("rosbags")
    notes = tmp_path / "notes.bag"
    notes.write_text("not a bag")
    rc, _, err = cli(capsys, "simulate", "diff-drive", "--path", "spin 10", "--bag", notes, "--force")
    refused(rc, err, "did not write")
    assert notes.read_text() == "not a bag"


# --- '-' is the data only ----------------------------------------------------------------------------------
def test_bag_export_to_stdout_carries_the_poses_only(capsys, sim_bag):
    rc, out, err = cli(capsys, "bag", "export", sim_bag, "--topic", "/ground_truth", "--format", "tum", "-o", "-")
    assert rc == 0
    rows = np.array([[float(v) for v in line.split()] for line in out.splitlines()])
    assert rows.shape == (odom_count(sim_bag, "/ground_truth"), 8)
    assert f"{len(rows)} poses" in err  # the message went to stderr


def test_odometry_to_stdout_carries_the_trajectory_only(capsys, log):
    rc, out, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", "-")
    assert rc == 0, err
    lines = out.splitlines()
    assert lines[0] == "t,x,y,theta" and len(lines) == 4
    assert all(len([float(v) for v in line.split(",")]) == 4 for line in lines[1:])
    assert "final pose" in err


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux)")
def test_full_disk_is_one_line_and_status_1(capsys, sim_bag):
    rc, _, err = cli(capsys, "bag", "export", sim_bag, "--topic", "/odom", "--format", "tum", "-o", "/dev/full")
    assert rc == 1 and err.strip() == "omnikin: error: /dev/full: cannot write: No space left on device"
    with open("/dev/full", "w") as full:
        proc = entry_point("presets", "--json", stdout=full)
        _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1
    assert err == "omnikin: error: standard output: cannot write: No space left on device\n"


def test_dev_null_needs_no_force(capsys, log):
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", os.devnull)
    assert rc == 0, err


# --- interrupted runs leave nothing behind -------------------------------------------------------------------
def test_interrupted_simulation_leaves_no_bag_and_exits_130(tmp_path):
    """Ctrl-C while the bag is being written: one line, status 130, and no bag or staging folder."""
    pytest.importorskip("rosbags")
    bag = tmp_path / "long.bag"
    proc = entry_point(
        "simulate",
        "mecanum4",
        "--path",
        "line 40",
        "--rate",
        "2000",
        "--bag",
        bag,
        cwd=tmp_path,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    deadline = time.monotonic() + 120
    while not any(p.name.startswith(".long.bag.") for p in tmp_path.iterdir()):  # the bag is being written
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.05)
    time.sleep(0.3)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert err == "omnikin: interrupted\n" and out == ""
    assert list(tmp_path.iterdir()) == []


def test_help_documents_the_output_policy():
    out, _ = entry_point("--help").communicate(timeout=120)
    text = " ".join(out.split())
    for phrase in ("--force", "never", "standard output", "data only", "--max-memory", "exit status 2"):
        assert phrase in text, phrase


@pytest.mark.parametrize(
    "argv",
    [
        ["show", "omni4", "--plot", ""],
        ["odometry", "tomasi-omni3", "LOG", "-o", ""],
        ["simulate", "diff-drive", "--bag", ""],
    ],
)
def test_empty_output_name_is_refused(capsys, log, argv):
    """An empty name is not 'no output' and not the current folder."""
    if argv[0] == "simulate":
        pytest.importorskip("rosbags")
    rc, _, err = cli(capsys, *[log if a == "LOG" else a for a in argv])
    refused(rc, err, "empty output path")


# --- every command that writes a file: one way to fail ---------------------------------------------------------
RUNS = "ROOT/examples/calibration_runs.csv"


def _argv(argv, log, sim_bag=None):
    from support.paths import ROOT

    swap = {"LOG": log, "BAG": sim_bag, RUNS: ROOT / "examples" / "calibration_runs.csv"}
    return [swap.get(a, a) for a in argv]


FILE_WRITERS = [
    ["odometry", "tomasi-omni3", "LOG", "-o", "OUT"],
    ["calibrate", "tomasi-omni3", RUNS, "-o", "OUT"],
    ["calibrate", "tomasi-omni3", "--plan", "-o", "OUT"],
    ["simulate", "tomasi-omni3", "--path", "spin 10", "--log", "OUT"],
    ["bag", "export", "BAG", "--topic", "/odom", "--format", "tum", "-o", "OUT"],
    ["show", "tomasi-omni3", "--plot", "OUT"],
]
"""One command line per way omnikin writes a single file (OUT: the file)."""


def _needs(argv):
    if "BAG" in argv:
        pytest.importorskip("rosbags")
    if "--plot" in argv:
        pytest.importorskip("matplotlib")


@pytest.fixture
def bag_if_needed(request, tmp_path_factory):
    return request.getfixturevalue("sim_bag") if "BAG" in request.node.callspec.params.get("argv", []) else None


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux)")
@pytest.mark.parametrize("argv", FILE_WRITERS, ids=lambda a: " ".join(a[:2]))
def test_every_file_writer_reports_a_full_disk_once_with_status_1(capsys, log, bag_if_needed, tmp_path, argv):
    """odometry, calibrate and simulate --log said '/dev/full: cannot write: /dev/full: cannot
    write: No space left on device' with status 2; bag export said it right."""
    _needs(argv)
    full = "/dev/full"
    if "--plot" in argv:  # the drawing format follows the extension
        full = tmp_path / "full.png"
        full.symlink_to("/dev/full")
    argv = [(full if a == "OUT" else a) for a in _argv(argv, log, bag_if_needed)]
    rc, _, err = cli(capsys, *argv)
    assert (rc, err) == (1, f"omnikin: error: {full}: cannot write: No space left on device\n")


@pytest.mark.parametrize("argv", FILE_WRITERS, ids=lambda a: " ".join(a[:2]))
def test_a_file_output_ending_in_a_separator_is_refused(capsys, log, bag_if_needed, tmp_path, argv):
    """odometry -o newdir/ wrote a regular file 'newdir'."""
    _needs(argv)
    out = tmp_path / "fresh"
    argv = [(f"{out}/" if a == "OUT" else a) for a in _argv(argv, log, bag_if_needed)]
    rc, _, err = cli(capsys, *argv)
    refused(rc, err, f"{out}/: names a folder")
    assert not out.exists()


@pytest.mark.parametrize(
    "argv, both",
    [
        (["simulate", "tomasi-omni3", "--log", "-", "--json"], "--log - and --json"),
        (["odometry", "tomasi-omni3", "LOG", "-o", "-", "--json"], "-o - and --json"),
        (["calibrate", "tomasi-omni3", RUNS, "-o", "-", "--json"], "-o - and --json"),
        (["calibrate", "tomasi-omni3", "--plan", "-o", "-", "--json"], "-o - and --json"),
    ],
)
def test_data_and_json_never_share_standard_output(capsys, log, argv, both):
    """simulate --log - --json wrote the CSV log and the JSON document both to stdout, status 0."""
    rc, out, err = cli(capsys, *_argv(argv, log))
    refused(rc, err, f"{both} would both write to standard output")
    assert out == ""


def test_a_command_never_names_one_path_for_two_outputs(capsys, tmp_path):
    """simulate --log x1.csv --bag x1.csv wrote a 13 MB bag, then failed with a doubled message."""
    pytest.importorskip("rosbags")
    bag, log = tmp_path / "x1.csv", tmp_path / "x1.csv"
    inner, folder = tmp_path / "run.bag" / "log.csv", tmp_path / "run.bag"
    for bag_path, log_path, message in (
        (bag, log, f"--bag {bag} and --log {log} are the same path"),
        (folder, inner, f"--log {inner} lies inside --bag {folder}"),
        (tmp_path / "sub" / ".." / "x2.csv", tmp_path / "x2.csv", "are the same path"),
    ):
        rc, _, err = cli(capsys, "simulate", "tomasi-omni3", "--bag", bag_path, "--log", log_path)
        refused(rc, err, message)
        assert list(tmp_path.iterdir()) == []


def test_a_report_is_never_written_over_the_current_folder(tmp_path):
    """'cd report && omnikin umbmark -o .' failed with 'Device or resource busy' and left an empty
    '..xxxx.old' folder inside the report."""
    first = entry_point("umbmark", "diff-drive", "--runs", "1", "--no-calibrate", "-o", "rep", cwd=tmp_path)
    assert first.communicate(timeout=300) and first.returncode == 0
    rep = tmp_path / "rep"
    before = snapshot(tmp_path)
    for out in (".", "..", "./", str(rep)):
        proc = entry_point("umbmark", "diff-drive", "--runs", "1", "-o", out, cwd=rep)
        _, err = proc.communicate(timeout=300)
        assert proc.returncode == 2 and err.startswith("omnikin: error: ") and "current folder" in err, err
        assert err.count("\n") == 1
    assert snapshot(tmp_path) == before
    assert [p.name for p in tmp_path.rglob(".*")] == [".omnikin-report"]  # no staging or '.old' folder


def test_simulate_log_to_stdout_carries_the_log_only(capsys):
    """simulate --log - printed its summary into the tick log on standard output."""
    rc, out, err = cli(capsys, "simulate", "tomasi-omni3", "--path", "spin 20", "--rate", "20", "--log", "-")
    assert rc == 0, err
    lines = out.splitlines()
    assert lines[0].startswith("# encoder tick log of tomasi-omni3") and lines[1] == "t,w1,w2,w3"
    assert all(len(line.split(",")) == 4 for line in lines[1:])
    assert "tick log written to standard output" in err
