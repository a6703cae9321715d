"""omnikin view --replay: the runs an UMBmark report keeps, and the command playing a report
or a bag (real processes: omnikin umbmark, omnikin simulate --bag, omnikin view)."""

import csv
import http.client
import math
import re
import subprocess
import sys
from urllib.parse import urlsplit

import numpy as np
import pytest

from omnikin.io.robot_file import load_robot
from omnikin.io.run_poses import read_run_poses
from omnikin.physics.description import describe
from omnikin.viewer.replay import TrackReplay
from omnikin.viewer.replay_sources import load_report
from support.cli import run_entry_point
from support.paths import omnikin_env


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    folder = tmp_path_factory.mktemp("umbmark") / "report"
    done = run_entry_point("umbmark", "--runs", "1", "--side", "1", "--noise", "none", "-o", folder)
    assert done.returncode == 0, done.stderr
    return folder


def measurement_rows(path):
    with open(path, encoding="utf-8") as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


@pytest.fixture(scope="module")
def physics_report(tmp_path_factory):
    folder = tmp_path_factory.mktemp("umbmark") / "physics"
    done = run_entry_point(
        "umbmark", "--engine", "physics", "--runs", "1", "--side", "1", "--no-calibrate", "-o", folder
    )
    assert done.returncode == 0, done.stderr
    return folder


def check_ends(report, phases):
    """measurements_PHASE.csv (written from the UMBmark statistics, another path) holds per run
    the true end minus the odometry end (x_abs - x_calc, 1 um); run k of a direction in
    run_poses.csv must end there, and its replay at the end of the run must show that pose."""
    runs = read_run_poses(report / "run_poses.csv")
    assert sorted(r.name for r in runs) == sorted(f"{p} {d} run 1" for p in phases for d in ("cw", "ccw"))
    source = load_report(report)
    robot = load_robot(report / "true_robot.yaml")
    assert source.side == 1.0 and source.robot.wheels == robot.wheels and source.robot.name == robot.name
    description = describe(robot)
    for phase in phases:
        rows = measurement_rows(report / f"measurements_{phase}.csv")
        for direction in ("cw", "ccw"):
            expected = [r for r in rows if r["direction"] == direction]
            kept = [r for r in runs if r.phase == phase and r.direction == direction]
            assert len(kept) == len(expected) == 1
            for row, run in zip(expected, kept, strict=True):
                end = run.truth[-1] - run.odometry[-1]
                assert end[0] == pytest.approx(float(row["x_abs"]) - float(row["x_calc"]), abs=2e-6)
                assert end[1] == pytest.approx(float(row["y_abs"]) - float(row["y_calc"]), abs=2e-6)
                heading = math.radians(float(row["theta_abs_deg"]) - float(row["theta_calc_deg"]))
                assert math.remainder(end[2] - heading, 2 * math.pi) == pytest.approx(0.0, abs=1e-6)
                track = next(t for t in source.tracks if t.name == run.name)
                shown = TrackReplay(robot, description, track).snapshot(track.duration)
                assert shown.truth[:2] == pytest.approx(tuple(run.truth[-1, :2]), abs=1e-9)
                assert shown.odometry[:2] == pytest.approx(tuple(run.odometry[-1, :2]), abs=1e-9)
                assert np.diff(run.t).max() <= 0.05 + 1e-9  # kept at 20 Hz (every 5th sample at 100 Hz)


def test_the_report_keeps_every_run_and_each_ends_where_the_measurement_file_says(report):
    check_ends(report, ("before", "after"))


def test_a_physics_report_keeps_its_runs_too(physics_report):
    """The physics engine measures the true end pose exactly (no measurement noise)."""
    check_ends(physics_report, ("before",))


def serve(*argv, seconds=4.0):
    """Run ``omnikin view ARGV --port 0 --duration seconds``, fetch the page while it serves;
    returns (exit code, stdout, stderr, page status)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "omnikin.cli.main", "view", *map(str, argv), "--port", "0", "--duration", str(seconds)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=omnikin_env(),
    )
    try:
        first = proc.stdout.readline()
        status = None
        found = re.search(r"http://\S+/", first)
        if found:
            parts = urlsplit(found.group(0))
            conn = http.client.HTTPConnection(parts.hostname, parts.port, timeout=10)
            conn.request("GET", "/")
            status = conn.getresponse().status
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    return proc.returncode, first + out, err, status


def test_view_replays_a_report_for_a_few_seconds(report):
    code, out, err, status = serve("--replay", report)
    assert code == 0 and status == 200, err
    assert "replay of" in out and "4 runs" in out and err == ""


def test_view_replays_a_bag_of_omnikin_simulate(line_spin_bag):
    code, out, err, status = serve("tomasi-omni3", "--replay", line_spin_bag)
    assert code == 0 and status == 200, err
    assert "1 run" in out and err == ""


@pytest.mark.parametrize(
    "argv, words",
    [
        (("--replay", "{bag}"), "give ROBOT"),
        (("tomasi-omni3", "--replay", "{report}"), "give no ROBOT"),
        (("tomasi-omni3", "--replay", "{bag}", "--odom-topic", "/wheel_odom"), "no topic '/wheel_odom'"),
        (("mecanum4", "--replay", "{bag}"), "the topic's joints are ['w1', 'w2', 'w3']"),
        (("--replay", "{missing}"), "no such report folder or bag"),
        (("--replay", "{report}", "--engine", "physics"), "--engine does not apply to --replay"),
    ],
)
def test_view_replay_refuses_in_one_line(report, line_spin_bag, tmp_path, argv, words):
    names = {"bag": line_spin_bag, "report": report, "missing": tmp_path / "nothing"}
    done = run_entry_point("view", *[a.format(**names) for a in argv], "--port", "0", "--duration", "1")
    assert done.returncode != 0 and "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and words in done.stderr, done.stderr


def test_a_bag_without_pose_topics_names_what_it_has(line_spin_bag):
    done = run_entry_point(
        "view",
        "tomasi-omni3",
        "--replay",
        line_spin_bag,
        "--ground-truth-topic",
        "/a",
        "--odom-topic",
        "/b",
        "--duration",
        "1",
    )
    assert done.returncode != 0 and len(done.stderr.strip().splitlines()) == 1
    assert "/joint_states (sensor_msgs/msg/JointState)" in done.stderr and "/a" in done.stderr


def test_a_report_s_robot_as_built_is_drawn_with_the_body_of_its_design(report):
    """The report's robot as built differs from the one it was built to (the seed robot, as the
    user named it) by millimetres of hub errors: the page draws it with its design's chassis."""
    source = load_report(report)
    nominal = load_robot("tomasi-omni3")
    assert source.robot.wheels == load_robot(report / "true_robot.yaml").wheels  # as built
    design = source.robot.design
    assert design is not None and design.name == nominal.name  # as written in the report, to 1e-12
    for built, planned in zip(design.wheels, nominal.wheels, strict=True):
        assert (built.x, built.y, built.drive, built.radius) == pytest.approx(
            (planned.x, planned.y, planned.drive, planned.radius), abs=1e-12
        )
    drawn, planned = describe(source.robot).chassis, describe(nominal).chassis
    assert drawn.shape == planned.shape == "cylinder"
    assert drawn.mass == pytest.approx(planned.mass, rel=1e-9) and drawn.size == pytest.approx(planned.size, rel=1e-9)


@pytest.mark.parametrize(
    "robot, words",
    [({"omnikin": 1, "name": "x"}, "result.json: robot"), ("a robot", "result.json: robot")],
)
def test_a_report_whose_design_is_not_a_robot_is_one_line(report, tmp_path, robot, words):
    import json
    import shutil

    copy = tmp_path / "report"
    shutil.copytree(report, copy)
    doc = json.loads((copy / "result.json").read_text())
    doc["robot"] = robot
    (copy / "result.json").write_text(json.dumps(doc))
    done = run_entry_point("view", "--replay", copy, "--port", "0", "--duration", "1")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("omnikin: error: ") and words in lines[0], done.stderr


@pytest.mark.parametrize("damage", ["missing", "truncated", "nan", "huge"])
def test_a_damaged_report_is_one_line(report, tmp_path, damage):
    import shutil

    copy = tmp_path / "report"
    shutil.copytree(report, copy)
    target = copy / "run_poses.csv"
    if damage == "missing":
        target.unlink()
    elif damage == "truncated":
        text = target.read_text()
        target.write_text(text[: len(text) // 2 - 7])
    elif damage == "nan":
        lines = target.read_text().splitlines()
        fields = lines[-5].split(",")
        fields[4] = "nan"
        lines[-5] = ",".join(fields)
        target.write_text("\n".join(lines) + "\n")
    else:
        with open(target, "r+b") as f:
            f.truncate(1 << 40)
    done = run_entry_point("view", "--replay", copy, "--port", "0", "--duration", "1")
    assert done.returncode != 0 and "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and "run_poses.csv" in done.stderr, done.stderr


def test_view_replays_two_reports_together(report, tmp_path):
    import shutil

    again = tmp_path / "again"
    shutil.copytree(report, again)
    code, out, err, status = serve("--replay", report, "--replay", again)
    assert code == 0 and status == 200, err
    assert "8 runs" in out and err == ""  # before and after, cw and ccw, of each


def test_runs_of_two_robots_are_not_shown_together(report):
    from omnikin.errors import ReplayError
    from omnikin.viewer.replay_sources import ReplaySource, combine

    mine = load_report(report)
    other = ReplaySource("mecanum-runs", load_robot("mecanum4"), mine.tracks)
    with pytest.raises(ReplayError) as refused:
        combine([mine, other])
    message = str(refused.value)
    assert "\n" not in message and "runs shown together must be of one robot" in message
    assert "'mecanum4' with 4 wheels" in message and "3 wheels ['w1', 'w2', 'w3']" in message


def test_runs_of_several_sources_keep_their_names_and_robots(report):
    from dataclasses import replace

    from omnikin.viewer.replay_sources import combine

    first = load_report(report)
    as_built = replace(first.robot, name="another build")  # same wheels, another robot file
    second = replace(first, label="elsewhere/after", robot=as_built)
    both = combine([first, second, second])
    names = [t.name for t in first.tracks]
    assert [t.name for t in both.tracks] == (
        [f"report: {n}" for n in names] + [f"after: {n}" for n in names] + [f"after: {n} (2)" for n in names]
    )
    assert [t.robot for t in both.tracks] == [first.robot] * len(names) + [as_built] * (2 * len(names))
