"""Options and positional arguments mix freely in every command: an option between (or before)
the positionals changes nothing.

``omnikin calibrate tomasi-omni3 --side 3 examples/calibration_runs.csv -o x.yaml`` said
'unexpected argument': argparse had given the optional RUNS up before it reached the file.
Each case runs a command in the usual order and in a mixed one and compares what they print.
"""

from __future__ import annotations

import pytest

from omnikin.cli.main import main
from support.cli import run_cli as cli
from support.paths import ROOT

EXAMPLES = ROOT / "examples"


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    pytest.importorskip("rosbags")
    path = tmp_path_factory.mktemp("bag") / "sim.bag"
    argv = ["simulate", "tomasi-omni3", "--path", "spin 30", "--rate", "20", "--noise", "none", "--bag", str(path)]
    assert main(argv) == 0
    return path


def trajectories(tmp_path):
    ref, est = tmp_path / "ref.csv", tmp_path / "est.csv"
    ref.write_text("t,x,y,theta\n0,0,0,0\n1,1,0,0\n2,2,0,0\n")
    est.write_text("t,x,y,theta\n0,0,0,0\n1,1.1,0,0\n2,2.1,0,0.1\n")
    return ref, est


LOG = EXAMPLES / "tick_log.csv"
RUNS = EXAMPLES / "calibration_runs.csv"
MEASUREMENTS = EXAMPLES / "umbmark_measurements.csv"

CASES = {
    "show": (["show", "tomasi-omni3", "--json"], ["show", "--json", "tomasi-omni3"]),
    "ik": (
        ["ik", "tomasi-omni3", "0.2", "-1e-1", "0.5", "--heading", "-0.3", "--json"],
        ["ik", "--json", "tomasi-omni3", "0.2", "--heading", "-0.3", "-1e-1", "0.5"],
    ),
    "fk": (["fk", "omni4", "10", "-5", "-10", "5", "--json"], ["fk", "omni4", "10", "--json", "-5", "-10", "5"]),
    "odometry": (
        ["odometry", "tomasi-omni3", LOG, "-o", "-", "--format", "tum"],
        ["odometry", "--format", "tum", "tomasi-omni3", "-o", "-", LOG],
    ),
    "calibrate": (
        ["calibrate", "tomasi-omni3", RUNS, "--json"],
        ["calibrate", "tomasi-omni3", "--json", RUNS],
    ),
    "calibrate --plan": (
        ["calibrate", "tomasi-omni3", "--plan", "--side", "3"],
        ["calibrate", "--side", "3", "tomasi-omni3", "--plan"],
    ),
    "umbmark analyze": (
        ["umbmark", "analyze", MEASUREMENTS, "--robot", "diff-drive", "--side", "4", "--json"],
        ["umbmark", "analyze", "--robot", "diff-drive", MEASUREMENTS, "--json", "--side", "4"],
    ),
    "simulate": (
        ["simulate", "tomasi-omni3", "--path", "spin 20", "--rate", "20", "--log", "-"],
        ["simulate", "--rate", "20", "tomasi-omni3", "--log", "-", "--path", "spin 20"],
    ),
    "bag export": (
        ["bag", "export", "BAG", "--topic", "/odom", "--format", "csv"],
        ["bag", "export", "--topic", "/odom", "BAG", "--format", "csv"],
    ),
    "metrics": (["metrics", "REF", "EST", "--align", "--json"], ["metrics", "--align", "REF", "--json", "EST"]),
}


@pytest.mark.parametrize("name", list(CASES))
def test_options_may_come_between_the_positionals(capsys, tmp_path, request, name):
    usual, mixed = CASES[name]
    files = {}
    if "BAG" in usual:
        files["BAG"] = request.getfixturevalue("bag")
    if "REF" in usual:
        files["REF"], files["EST"] = trajectories(tmp_path)
    capsys.readouterr()
    results = []
    for argv in (usual, mixed):
        rc, out, err = cli(capsys, *[files.get(a, a) for a in argv])
        assert rc == 0, (argv, err)
        results.append(out)
    assert results[0] == results[1] and results[0]


def test_calibrate_runs_after_an_option_writes_the_robot(capsys, tmp_path):
    """The reported case, and the file it writes equals the usual order's."""
    a, b = tmp_path / "a.yaml", tmp_path / "b.yaml"
    assert cli(capsys, "calibrate", "tomasi-omni3", RUNS, "-o", a)[0] == 0
    rc, _, err = cli(capsys, "calibrate", "tomasi-omni3", "--side", "3", RUNS, "-o", b)
    assert rc == 0, err
    assert a.read_text() == b.read_text()


def test_the_optional_robot_of_umbmark_follows_options(capsys):
    """umbmark [ROBOT]: a robot after options is still the robot (here one that does not exist,
    so that nothing runs)."""
    rc, _, err = cli(capsys, "umbmark", "--runs", "1", "no-such-robot", "--trials", "1")
    assert rc == 2 and "no-such-robot" in err, err


def test_bag_odometry_positionals_after_options(capsys, tmp_path, bag):
    capsys.readouterr()
    outs = []
    for argv in (
        ["bag", "odometry", "tomasi-omni3", bag, "-o", tmp_path / "a.bag", "--method", "euler", "--json"],
        ["bag", "odometry", "--method", "euler", "tomasi-omni3", "--json", bag, "-o", tmp_path / "b.bag"],
    ):
        rc, out, err = cli(capsys, *argv)
        assert rc == 0, err
        outs.append(out.replace(str(tmp_path / "a.bag"), "OUT").replace(str(tmp_path / "b.bag"), "OUT"))
    assert outs[0] == outs[1]


def test_too_many_positionals_are_still_named(capsys):
    rc, _, err = cli(capsys, "calibrate", "tomasi-omni3", "--side", "3", RUNS, "extra.csv")
    assert rc == 2 and "unexpected argument 'extra.csv'" in err, err
