"""``omnikin track``: the summary of a figure-eight against the lemniscate's length, the TUM
outputs read back, the figure written, and one-line refusals (status 2) of bad paths, options and
outputs, before anything is driven or written."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from scipy.integrate import quad

from omnikin.io.trajectories import read_trajectory
from support.cli import run_cli, run_entry_point


def gerono_length(a: float) -> float:
    """Length of Gerono's lemniscate (a sin t, a sin 2t / 2): the integral of its speed."""
    return quad(lambda t: a * math.hypot(math.cos(t), math.cos(2 * t)), 0.0, 2 * math.pi, limit=200)[0]


def test_the_figure_eight_is_tracked_and_summarised(tmp_path, capsys):
    truth, reference, figure = tmp_path / "truth.tum", tmp_path / "ref.tum", tmp_path / "fig.svg"
    rc, out, err = run_cli(
        capsys, "track", "tomasi-omni3", "figure8 1", "--truth", truth, "--reference", reference, "--plot", figure,
        "--json",
    )  # fmt: skip
    assert rc == 0, err
    summary = json.loads(out)
    assert summary["path_length_m"] == pytest.approx(gerono_length(1.0), rel=1e-5)
    assert summary["max_wheel_speed_rad_s"] <= 12.0 * (1 + 1e-9)
    assert summary["max_error_m"] < 1e-4 and summary["rms_error_m"] <= summary["max_error_m"]
    assert summary["errors"] == "none" and summary["engine"] == "kinematic" and summary["step_s"] is None
    t, poses = read_trajectory(truth)
    assert t[0] == 0.0 and poses[0] == pytest.approx([0.0, 0.0, 0.0])
    assert np.diff(t) == pytest.approx(np.full(len(t) - 1, 1 / 50))
    assert len(t) == summary["samples"]
    t_ref, ref = read_trajectory(reference)
    assert np.array_equal(t_ref, t)
    assert ref[-1, :2] == pytest.approx([0.0, 0.0], abs=1e-9)  # the figure-eight ends where it began
    assert figure.read_text().lstrip().startswith("<?xml") and "<svg" in figure.read_text()


def test_a_path_file_with_blended_corners_is_tracked_as_a_user_runs_it(tmp_path):
    f = tmp_path / "corners.csv"
    f.write_text("x,y\n0,0\n1,0\n1,1\n")
    done = run_entry_point("track", "omni4", f, "--blend", "0.2", "--odometry", tmp_path / "odom.tum", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "omni4: corners.csv" in done.stdout and "distance to the path: RMS" in done.stdout
    assert "odometry written to" in done.stdout
    assert done.stderr == ""


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["tomasi-omni3", "figure9 1"], r"unknown path 'figure9 1'"),
        (["tomasi-omni3", "circle -1"], r"circle radius must be in \(0, 1000\] m"),
        (["tomasi-omni3", "missing.csv"], r"missing.csv"),
        (["tomasi-omni3", "figure8 1", "--heading", "sideways"], r"--heading 'sideways': one of tangent, fixed"),
        (["tomasi-omni3", "figure8 1", "--smooth"], r"smooth is for path files"),
        (["tomasi-omni3", "figure8 1", "--max-wheel-speed", "0"], r"speed\) must be a finite number > 0, got 0.0"),
        (["tomasi-omni3", "figure8 1", "--max-wheel-speed", "1e-9"], r"control ticks, more than --max-memory"),
        (["tomasi-omni3", "figure8 1", "--controller", "pid"], r"invalid choice: 'pid'"),
        (["tomasi-omni3", "figure8 1", "--engine", "physics", "--noise", "typical"], r"drop --noise"),
        (["diff-drive", "circle 1", "--heading", "fixed"], r"robot 'diff-drive' cannot drive path 'circle 1'"),
        (["ackermann", "circle 5", "--controller", "mpc"], r"robot 'ackermann' steers its wheels"),
        (["ackermann", "circle 1"], r"robot 'ackermann' cannot drive path 'circle 1'.*steering limits"),
        (["diff-drive", "circle 1", "--controller", "feedback"], r"cannot move sideways"),
        (["tomasi-omni3", "figure8 1", "--plot", "fig.xyz"], r"fig.xyz"),
    ],
)
def test_bad_input_is_one_line_and_status_2(tmp_path, monkeypatch, capsys, argv, message):
    monkeypatch.chdir(tmp_path)
    rc, out, err = run_cli(capsys, "track", *argv)
    assert rc == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("omnikin: error: "), err
    assert re.search(message, lines[0]), lines[0]
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_an_output_on_the_path_file_or_an_existing_file_is_refused_before_the_run(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    f = tmp_path / "p.csv"
    f.write_text("x,y\n0,0\n1,0\n")
    rc, _, err = run_cli(capsys, "track", "tomasi-omni3", "p.csv", "--truth", "p.csv")
    assert rc == 2 and "p.csv" in err and f.read_text() == "x,y\n0,0\n1,0\n"
    kept = tmp_path / "kept.tum"
    kept.write_text("mine\n")
    rc, _, err = run_cli(capsys, "track", "tomasi-omni3", "p.csv", "--reference", "kept.tum")
    assert rc == 2 and "--force" in err and kept.read_text() == "mine\n"


def test_the_tick_log_holds_whole_counts_whose_odometry_is_the_run_s(tmp_path, capsys):
    log, odometry = tmp_path / "ticks.csv", tmp_path / "odom.tum"
    rc, _, err = run_cli(
        capsys, "track", "tomasi-omni3", "circle 0.5", "--noise", "typical", "--log", log, "--odometry", odometry
    )
    assert rc == 0, err
    lines = log.read_text().splitlines()
    assert lines[0].startswith("# encoder tick log of tomasi-omni3 written by: omnikin track tomasi-omni3 'circle 0.5'")
    assert lines[1] == "t,w1,w2,w3"
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[2:]])
    t_odo, poses = read_trajectory(odometry)
    assert rows[:, 0] == pytest.approx(t_odo, abs=1e-9)  # a row per control tick
    assert np.array_equal(rows[:, 1:], np.rint(rows[:, 1:]))  # whole counts
    # the log read back by the batch odometry gives the pose the runtime steered by, tick by tick
    rc, _, err = run_cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "again.tum")
    assert rc == 0, err
    t_again, again = read_trajectory(tmp_path / "again.tum")
    assert np.array_equal(t_again, t_odo)
    assert again == pytest.approx(poses, abs=2e-9)  # (TUM's nine decimals)


def test_a_tick_log_of_exact_encoders_is_refused_before_the_run(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    rc, out, err = run_cli(capsys, "track", "tomasi-omni3", "circle 0.5", "--log", "ticks.csv", "--truth", "t.tum")
    assert rc == 2 and out == ""
    assert err.strip().splitlines() == [
        "omnikin: error: --log writes whole-number encoder counts, but the kinematic engine's encoders are exact "
        "under --noise none; give --noise typical, or --engine physics, or record --bag instead"
    ]
    assert list(tmp_path.iterdir()) == []


def test_the_bag_holds_the_run_s_truth_odometry_wheels_and_commands(tmp_path, capsys):
    pytest.importorskip("rosbags")
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    from omnikin import load_robot

    bag, truth, odometry = tmp_path / "run.bag", tmp_path / "truth.tum", tmp_path / "odom.tum"
    rc, out, err = run_cli(
        capsys, "track", "diff-drive", "circle 1", "--bag", bag, "--truth", truth, "--odometry", odometry, "--json"
    )
    assert rc == 0, err
    summary = json.loads(out)
    topics = ("/ground_truth", "/odom", "/joint_states", "/cmd_vel")
    assert summary["topics"] == {topic: summary["samples"] for topic in topics}
    for topic, written in (("/ground_truth", truth), ("/odom", odometry)):
        exported = tmp_path / f"exported{topic.replace('/', '_')}.tum"
        rc, _, err = run_cli(capsys, "bag", "export", bag, "--topic", topic, "--format", "tum", "-o", exported)
        assert rc == 0, err
        t_bag, poses_bag = read_trajectory(exported)
        t_tum, poses_tum = read_trajectory(written)
        assert t_bag == pytest.approx(t_tum, abs=1e-9) and poses_bag == pytest.approx(poses_tum, abs=2e-9)
    robot = load_robot("diff-drive")
    typestore = get_typestore(Stores.ROS2_HUMBLE)
    with Reader(bag) as reader:
        messages = {"/joint_states": [], "/cmd_vel": []}
        for connection, _, raw in reader.messages():
            if connection.topic in messages:
                messages[connection.topic].append(typestore.deserialize_cdr(raw, connection.msgtype))
    states, twists = messages["/joint_states"], messages["/cmd_vel"]
    assert list(states[0].name) == list(robot.encoded_names)
    # the wheels of a differential drive on a circle of radius R (1 m, turning left) roll
    # R + b and R - b for every metre of the centre (b the half track): the outer (right) wheel's
    # angle over the inner's is (R + b) / (R - b)
    angles = np.array([s.position for s in states])
    ys = [robot.wheel(n).y for n in robot.encoded_names]
    outer, inner = int(np.argmin(ys)), int(np.argmax(ys))
    b = abs(ys[0])
    assert abs(angles[-1, outer] / angles[-1, inner]) == pytest.approx((1 + b) / (1 - b), rel=1e-2)
    # /cmd_vel: the controller's twist, a differential drive's with no sideways speed
    cmd = np.array([[m.linear.x, m.linear.y, m.angular.z] for m in twists])
    assert np.all(cmd[:, 1] == 0.0) and cmd[len(cmd) // 2, 0] > 0


def test_the_bag_of_a_path_away_from_the_origin_is_in_the_frame_where_the_robot_started(tmp_path, capsys):
    pytest.importorskip("rosbags")
    path = tmp_path / "away.csv"
    path.write_text("x,y,theta\n5,3,0.785\n6,3,0.785\n6,4,0.785\n")
    bag, odometry = tmp_path / "away.bag", tmp_path / "odom.tum"
    rc, _, err = run_cli(capsys, "track", "omni4", path, "--bag", bag, "--odometry", odometry)
    assert rc == 0, err
    exported = tmp_path / "exported.tum"
    rc, _, err = run_cli(capsys, "bag", "export", bag, "--topic", "/odom", "--format", "tum", "-o", exported)
    assert rc == 0, err
    _, in_bag = read_trajectory(exported)
    _, in_path_frame = read_trajectory(odometry)
    assert in_bag[0] == pytest.approx([0.0, 0.0, 0.0], abs=1e-9)  # the odom frame starts at the robot
    assert in_path_frame[0] == pytest.approx([5.0, 3.0, 0.785], abs=1e-9)  # the TUM output: the path's frame
    # the same motion: the first leg, 1 m along the path's +x, is 1 m along cos/sin(-0.785) in the odom frame
    end = in_bag[-1]
    c, s = math.cos(0.785), math.sin(0.785)
    assert end[:2] == pytest.approx([c * 1 + s * 1, -s * 1 + c * 1], abs=2e-3)
