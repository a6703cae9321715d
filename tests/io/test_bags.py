"""ROS 2 bags (omnikin.io.bags, omnikin bag / simulate): real bag files in tmp_path.

Joint states are written by hand for a robot driving a known constant twist (wheel angles
``angle_i(t) = row_i . twist * t`` with the rows of docs/conventions.md typed in), so the
odometry read back from the output bag must be the closed-form circle. The bags are read
back with rosbags directly, not through omnikin, so a sign or field mix-up on one side
cannot cancel one on the other.
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np
import pytest

pytest.importorskip("rosbags")

from rosbags.rosbag2 import Reader, Writer
from rosbags.typesys import Stores, get_typestore

from omnikin import load_robot
from omnikin.errors import BagError, InputError, OmnikinError, OutputExistsError
from omnikin.io import bags
from omnikin.io.trajectories import read_trajectory

TS = get_typestore(Stores.ROS2_HUMBLE)
T = TS.types
T0 = 1_700_000_000 * 10**9 + 123_456_789  # first stamp [ns]
DT = 10_000_000  # 100 Hz [ns]

TOMASI_L, TOMASI_R = 0.113, 0.04125
TOMASI_J = np.array([[-math.sin(b), math.cos(b), TOMASI_L] for b in np.radians([0.0, 120.0, 240.0])]) / TOMASI_R


def wrap(a):
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi


def circle(twist, t):
    """Closed-form pose after constant body twist for times t from the origin."""
    vx, vy, w = twist
    th = w * t
    x = (vx * np.sin(th) - vy * (1 - np.cos(th))) / w
    y = (vx * (1 - np.cos(th)) + vy * np.sin(th)) / w
    return np.stack([x, y, wrap(th)], axis=-1)


# --- helpers that use rosbags directly ------------------------------------------------------------------
def write_joint_states(path, names, positions, stamps, topic="/joint_states", extra=None, header_zero=False):
    with Writer(path, version=8) as w:
        c = w.add_connection(topic, "sensor_msgs/msg/JointState", typestore=TS)
        if extra:
            ce = w.add_connection(extra, "std_msgs/msg/String", typestore=TS)
            w.write(ce, int(stamps[0]), TS.serialize_cdr(T["std_msgs/msg/String"](data="hello"), "std_msgs/msg/String"))
        for s, p in zip(stamps, positions, strict=True):
            st = (
                T["builtin_interfaces/msg/Time"](sec=0, nanosec=0)
                if header_zero
                else T["builtin_interfaces/msg/Time"](sec=int(s) // 10**9, nanosec=int(s) % 10**9)
            )
            msg = T["sensor_msgs/msg/JointState"](
                header=T["std_msgs/msg/Header"](stamp=st, frame_id=""),
                name=list(names),
                position=np.asarray(p, dtype=float),
                velocity=np.zeros(0),
                effort=np.zeros(0),
            )
            w.write(c, int(s), TS.serialize_cdr(msg, "sensor_msgs/msg/JointState"))


def read_topic(path, topic):
    out = []
    with Reader(path) as r:
        conns = [c for c in r.connections if c.topic == topic]
        assert conns, f"no {topic} in {path}"
        for c, t_ns, raw in r.messages(connections=conns):
            out.append((t_ns, c.msgtype, TS.deserialize_cdr(raw, c.msgtype)))
    return out


def odom_arrays(path, topic="/odom"):
    msgs = read_topic(path, topic)
    stamps = np.array([m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, _, m in msgs])
    poses = np.array(
        [
            (
                m.pose.pose.position.x,
                m.pose.pose.position.y,
                2 * math.atan2(m.pose.pose.orientation.z, m.pose.pose.orientation.w),
            )
            for _, _, m in msgs
        ]
    )
    twists = np.array([(m.twist.twist.linear.x, m.twist.twist.linear.y, m.twist.twist.angular.z) for _, _, m in msgs])
    poses[:, 2] = wrap(poses[:, 2])  # x and y as they are (metres, not angles)
    return stamps, poses, twists, msgs


def run_cli(argv):
    """A bag command as ``omnikin.cli.main`` runs it (outputs checked first), errors raised."""
    from omnikin.cli import bag, metrics, simulate
    from omnikin.cli.common import running

    p = argparse.ArgumentParser(prog="omnikin")
    sub = p.add_subparsers()
    for command in (bag, simulate, metrics):
        command.add_parser(sub, "preset or robot file")
    args = p.parse_args([str(a) for a in argv])
    with running(args):
        return args.func(args)


@pytest.fixture
def circle_bag(tmp_path):
    """tomasi-omni3 driving twist (0.2, 0.1, 0.5) for 4 s, joint states at 100 Hz, names shuffled
    among an unrelated joint, plus an unrelated topic."""
    twist = np.array([0.2, 0.1, 0.5])
    n = 401
    stamps = T0 + DT * np.arange(n)
    t = (stamps - T0) * 1e-9
    angles = np.outer(t, TOMASI_J @ twist)  # (n, 3): w1, w2, w3
    names = ["w3", "lift", "w1", "w2"]
    pos = np.column_stack([angles[:, 2], np.full(n, 7.0), angles[:, 0], angles[:, 1]])
    path = tmp_path / "in.bag"
    write_joint_states(path, names, pos, stamps, extra="/chatter")
    return path, twist, stamps, t


# --- bag odometry ---------------------------------------------------------------------------------------
def test_bag_odometry_is_the_closed_form_circle(circle_bag, tmp_path, capsys):
    path, twist, stamps, t = circle_bag
    out = tmp_path / "odom.bag"
    assert run_cli(["bag", "odometry", "tomasi-omni3", path, "-o", out, "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["samples"] == 401 and summary["stamp_source"] == "header" and summary["skipped_messages"] == 0
    got_stamps, poses, twists, msgs = odom_arrays(out)
    np.testing.assert_array_equal(got_stamps, stamps)
    np.testing.assert_array_equal([b for b, _, _ in msgs], stamps)  # bag time = input record time
    np.testing.assert_allclose(poses, circle(twist, t), atol=1e-9)
    np.testing.assert_allclose(twists[1:], np.tile(twist, (400, 1)), atol=1e-9)
    np.testing.assert_array_equal(twists[0], 0.0)
    m = msgs[-1][2]
    assert m.header.frame_id == "odom" and m.child_frame_id == "base_link"
    assert m.pose.covariance.shape == (36,) and m.twist.covariance.shape == (36,)
    assert not m.pose.covariance.any() and not m.twist.covariance.any()
    q = m.pose.pose.orientation
    assert q.x == q.y == 0 and q.z**2 + q.w**2 == pytest.approx(1, abs=1e-15)
    assert m.pose.pose.position.z == 0 and m.twist.twist.linear.z == 0


def test_bag_odometry_options_and_mcap(circle_bag, tmp_path):
    path, twist, _, t = circle_bag
    out = tmp_path / "odom_mcap"
    assert (
        run_cli(
            [
                "bag",
                "odometry",
                "tomasi-omni3",
                path,
                "-o",
                out,
                "--odom-topic",
                "/wheel_odom",
                "--frame-id",
                "world",
                "--child-frame-id",
                "base",
                "--storage",
                "mcap",
                "--method",
                "euler",
                "--pose-cov-diag",
                1,
                2,
                3,
                4,
                5,
                6,
                "--twist-cov-diag",
                0.1,
                0,
                0,
                0,
                0,
                0.2,
            ]
        )
        == 0
    )
    mcap_files = list(out.glob("*.mcap"))
    assert len(mcap_files) == 1
    track = bags.read_poses(mcap_files[0], "/wheel_odom")  # a bare .mcap file reads too
    assert track.frame_id == "world" and track.child_frame_id == "base" and len(track.poses) == 401
    _, poses, _, msgs = odom_arrays(out, "/wheel_odom")
    m = msgs[0][2]
    assert m.header.frame_id == "world" and m.child_frame_id == "base"
    np.testing.assert_array_equal(m.pose.covariance.reshape(6, 6), np.diag([1, 2, 3, 4, 5, 6]))
    assert m.twist.covariance[0] == 0.1 and m.twist.covariance[35] == 0.2
    # Euler integration is off by O(dt): close to, but not on, the circle
    err = np.abs(poses[:, :2] - circle(twist, t)[:, :2]).max()
    assert 1e-6 < err < 1e-2


TOMASI_RPT = 2 * math.pi / 600  # rad per tick of tomasi-omni3's encoders


def joint_state_bag(path, angles):
    """tomasi-omni3's wheel angles ``(n, 3)`` [rad] as joint states w1 w2 w3 at 100 Hz."""
    n = len(angles)
    write_joint_states(path, ["w1", "w2", "w3"], angles, T0 + DT * np.arange(n))
    return path, (DT * np.arange(n)) * 1e-9


def test_bag_odometry_has_the_wheel_speed_bound_of_odometry(circle_bag, tmp_path):
    """'omnikin bag odometry' gets --max-wheel-speed like 'omnikin odometry'. A 12-bit counter
    read as a wheel angle jumps by 4096 - 4 ticks = 4092 * 2 pi / 600 = 42.85 rad in 10 ms when
    it wraps: refused by default (50 m/s at the 41.25 mm rim: 1212 rad/s, 12.1 rad per sample);
    with the bound raised beyond the jump (1.5 * 3000 rad/s * 10 ms = 45 rad) the user says it
    is real, and it passes. A robot really that fast (60 m/s forward: w2 and w3 turn at
    60 sin(60 deg) / 0.04125 = 1260 rad/s) is refused by default and, with --max-wheel-speed
    1300, gives the closed-form circle; a bound below the circle bag's wheel speeds refuses it."""
    ticks = np.rint(np.outer(np.arange(101) * 0.01, TOMASI_J @ [0.2, 0.1, 0.5]) / TOMASI_RPT)
    wrapped, _ = joint_state_bag(tmp_path / "wrapped.bag", (ticks % 4096) * TOMASI_RPT)
    assert np.diff(ticks % 4096, axis=0)[0, 1] == 4092  # w2's first step, -4 ticks, wraps to +4092 (42.85 rad)
    with pytest.raises(OmnikinError, match=r"impossible jump of -?42\.\d+ rad in 0\.01 s, wheel 'w\d'"):
        run_cli(["bag", "odometry", "tomasi-omni3", wrapped, "-o", tmp_path / "a.bag"])
    assert (
        run_cli(["bag", "odometry", "tomasi-omni3", wrapped, "-o", tmp_path / "b.bag", "--max-wheel-speed", 3000]) == 0
    )
    assert len(read_topic(tmp_path / "b.bag", "/odom")) == 101

    fast = np.array([60.0, 0.0, 0.5])
    t = np.arange(201) * 0.01
    path, t = joint_state_bag(tmp_path / "fast.bag", np.outer(t, TOMASI_J @ fast))
    with pytest.raises(OmnikinError, match=r"faster than 1212\.12 rad/s \(50 m/s at the rim\)"):
        run_cli(["bag", "odometry", "tomasi-omni3", path, "-o", tmp_path / "c.bag"])
    assert run_cli(["bag", "odometry", "tomasi-omni3", path, "-o", tmp_path / "d.bag", "--max-wheel-speed", 1300]) == 0
    np.testing.assert_allclose(odom_arrays(tmp_path / "d.bag")[1], circle(fast, t), atol=1e-9)

    slow = circle_bag[0]  # wheel speeds up to |J (0.2, 0.1, 0.5)| = 5.8 rad/s
    with pytest.raises(OmnikinError, match=r"faster than 1\.5 rad/s \(1\.5 x max_wheel_speed 1 rad/s\)"):
        run_cli(["bag", "odometry", "tomasi-omni3", slow, "-o", tmp_path / "e.bag", "--max-wheel-speed", 1])


def test_bag_odometry_has_the_change_of_speed_bound_of_odometry(tmp_path):
    """--max-wheel-accel reaches the bag's odometry. tomasi-omni3 at rest for 0.1 s, then at
    twist (1, 0.5, 2): w1's angle grows by (0.5 + 0.113 * 2) / 0.04125 * 0.01 = 0.176 rad per
    sample from one sample to the next. Joint states have no change-of-speed rule by default
    (the closed form: at rest, then the circle from t = 0.1 s); with --max-wheel-accel 1 the
    bound is 1.5 * 1 * 0.01^2 + 4 * 2 pi / 600 = 0.042 rad: refused."""
    twist = np.array([1.0, 0.5, 2.0])
    t = np.arange(201) * 0.01
    moving = np.maximum(t - 0.1, 0.0)
    path, t = joint_state_bag(tmp_path / "step.bag", np.outer(moving, TOMASI_J @ twist))
    assert run_cli(["bag", "odometry", "tomasi-omni3", path, "-o", tmp_path / "a.bag"]) == 0
    np.testing.assert_allclose(odom_arrays(tmp_path / "a.bag")[1], circle(twist, moving), atol=1e-9)
    with pytest.raises(
        OmnikinError, match=r"impossible change of speed, wheel 'w1'.*1\.5 x max_wheel_accel 1 rad/s\^2"
    ):
        run_cli(["bag", "odometry", "tomasi-omni3", path, "-o", tmp_path / "b.bag", "--max-wheel-accel", 1])
    assert not (tmp_path / "b.bag").exists()


@pytest.mark.parametrize("option", ["--max-wheel-speed", "--max-wheel-accel"])
@pytest.mark.parametrize("value", ["0", "-3", "nan", "fast"])
def test_bad_wheel_bounds_are_usage_errors_naming_the_option(capsys, tmp_path, option, value):
    """Both odometry commands refuse a bound that is no bound before reading anything, in one
    line naming the option and quoting the value as typed."""
    from support.cli import run_cli as main_cli

    for command in (
        ["bag", "odometry", "tomasi-omni3", tmp_path / "none.bag", "-o", tmp_path / "o.bag"],
        ["odometry", "tomasi-omni3", tmp_path / "none.csv", "-o", tmp_path / "o.csv"],
    ):
        rc, out, err = main_cli(capsys, *command, option, value)
        assert rc == 2 and out == "" and err.count("\n") == 1, err
        assert f"argument {option}: '{value}'" in err, err
    assert list(tmp_path.iterdir()) == []


def test_bag_odometry_falls_back_to_bag_time(tmp_path):
    twist = np.array([0.1, 0.0, 0.3])
    stamps = T0 + DT * np.arange(101)
    t = (stamps - T0) * 1e-9
    path = tmp_path / "zero_stamps"
    write_joint_states(path, ["w1", "w2", "w3"], np.outer(t, TOMASI_J @ twist), stamps, header_zero=True)
    res = bags.bag_odometry(load_robot("tomasi-omni3"), path, tmp_path / "o")
    assert res.joint_states.stamp_source == "bag"
    np.testing.assert_allclose(odom_arrays(tmp_path / "o")[1], circle(twist, t), atol=1e-9)
    with pytest.raises(BagError, match="header stamps must increase strictly.*all header stamps are zero"):
        bags.bag_odometry(load_robot("tomasi-omni3"), path, tmp_path / "o2", stamp="header")
    assert not (tmp_path / "o2").exists()


def test_duplicates_dropped_and_foreign_messages_skipped(tmp_path):
    twist = np.array([0.1, 0.0, 0.3])
    stamps = T0 + DT * np.arange(51)
    t = (stamps - T0) * 1e-9
    ang = np.outer(t, TOMASI_J @ twist)
    path = tmp_path / "dup"
    with Writer(path, version=8) as w:
        c = w.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=TS)
        for k, (s, a) in enumerate(zip(stamps, ang, strict=True)):
            extra = ([["arm"], [1.0]],) if k % 10 == 0 else ()
            for names, pos in ([["w1", "w2", "w3"], a], *extra):
                st = T["builtin_interfaces/msg/Time"](sec=int(s) // 10**9, nanosec=int(s) % 10**9)
                msg = T["sensor_msgs/msg/JointState"](
                    header=T["std_msgs/msg/Header"](stamp=st, frame_id=""),
                    name=names,
                    position=np.asarray(pos, float),
                    velocity=np.zeros(0),
                    effort=np.zeros(0),
                )
                for _ in range(2 if k == 21 else 1):  # sample 21 written twice
                    w.write(c, int(s), TS.serialize_cdr(msg, "sensor_msgs/msg/JointState"))
    js = bags.read_joint_states(path, load_robot("tomasi-omni3"))
    assert js.skipped == 6 and js.duplicates == 1 and len(js.stamps) == 51


def test_steerable_robot_reads_steer_joints(tmp_path):
    """Synchro drive: simulate --bag records W_steer joints; bag odometry of that bag reproduces /odom."""
    sim = tmp_path / "synchro.bag"
    assert (
        run_cli(
            [
                "simulate",
                "synchro",
                "--path",
                "line 1 30",
                "--rate",
                "50",
                "--errors",
                "none",
                "--noise",
                "none",
                "--bag",
                sim,
            ]
        )
        == 0
    )
    msgs = read_topic(sim, "/joint_states")
    assert list(msgs[0][2].name) == ["w1", "w2", "w3", "w1_steer", "w2_steer", "w3_steer"]
    np.testing.assert_allclose(msgs[len(msgs) // 2][2].position[3:], math.radians(30), atol=1e-12)
    out = tmp_path / "synchro_odom.bag"
    bags.bag_odometry(load_robot("synchro"), sim, out)
    _, odom, _, _ = odom_arrays(out)
    np.testing.assert_allclose(odom, odom_arrays(sim)[1], atol=1e-9)
    np.testing.assert_allclose(odom[-1], [math.cos(math.radians(30)), 0.5, 0], atol=1e-9)
    with pytest.raises(BagError, match=r"no joint\(s\) \['w1_swivel', 'w2_swivel', 'w3_swivel'\]"):
        bags.read_joint_states(sim, load_robot("synchro"), steer_suffix="_swivel")


# --- simulate --bag -------------------------------------------------------------------------------------
def test_simulate_records_four_topics(tmp_path, capsys):
    """An arc without errors or noise: ground truth and odometry are the plan's closed form
    exp(s_k xi); joint states are the IK of it; cmd_vel the commanded twists."""
    from omnikin.motion.plans import arc
    from omnikin.motion.timing import sample_plan

    out = tmp_path / "sim.bag"
    assert (
        run_cli(
            [
                "simulate",
                "tomasi-omni3",
                "--path",
                "arc 1 90",
                "--rate",
                "50",
                "--errors",
                "none",
                "--noise",
                "none",
                "--start",
                100,
                "--bag",
                out,
                "--json",
            ]
        )
        == 0
    )
    summary = json.loads(capsys.readouterr().out)
    with Reader(out) as r:
        types = {c.topic: c.msgtype for c in r.connections}
    assert types == {
        "/ground_truth": "nav_msgs/msg/Odometry",
        "/odom": "nav_msgs/msg/Odometry",
        "/joint_states": "sensor_msgs/msg/JointState",
        "/cmd_vel": "geometry_msgs/msg/Twist",
    }
    robot = load_robot("tomasi-omni3")
    sp = sample_plan(arc(1.0, math.pi / 2), robot, 50.0)
    s = np.concatenate([[0.0], np.cumsum(sp.progress)])  # arc length driven [m]
    closed = np.column_stack([np.sin(s), 1 - np.cos(s), wrap(s)])  # unit circle, centre left
    n = len(s)
    assert summary["samples"] == n and all(v == n for v in summary["topics"].values())
    st_truth, truth, tw_truth, _ = odom_arrays(out, "/ground_truth")
    st_odom, odom, tw_odom, _ = odom_arrays(out, "/odom")
    np.testing.assert_array_equal(st_truth, 100 * 10**9 + np.round(sp.t * 1e9).astype(np.int64))
    np.testing.assert_array_equal(st_odom, st_truth)
    np.testing.assert_allclose(truth, closed, atol=1e-9)
    np.testing.assert_allclose(odom, closed, atol=1e-9)
    np.testing.assert_allclose(truth[-1], [1, 1, math.pi / 2], atol=1e-9)
    # the body twist on an arc of radius 1 forward: (v, 0, v)
    v = tw_truth[1:, 0]
    np.testing.assert_allclose(tw_truth[1:], np.column_stack([v, 0 * v, v]), atol=1e-9)
    np.testing.assert_allclose(tw_odom, tw_truth, atol=1e-9)
    js = read_topic(out, "/joint_states")
    assert [list(m.name) for _, _, m in js[:1]] == [["w1", "w2", "w3"]]
    pos = np.array([m.position for _, _, m in js])
    np.testing.assert_allclose(pos, np.outer(s, TOMASI_J @ [1.0, 0.0, 1.0]), atol=1e-9)
    cmd = read_topic(out, "/cmd_vel")
    c = np.array([(m.linear.x, m.linear.y, m.angular.z) for _, _, m in cmd])
    np.testing.assert_allclose(c[:-1], np.column_stack([sp.progress, 0 * sp.progress, sp.progress]) * 50, atol=1e-9)
    np.testing.assert_array_equal(c[-1], 0)
    assert [b for b, _, _ in cmd] == list(st_truth)


def test_simulated_bag_through_odometry_and_export(tmp_path, capsys):
    """simulate --bag with errors and noise; bag odometry on its joint states reproduces its /odom;
    the exports read back as the poses; metrics of odometry against truth is non-zero."""
    sim = tmp_path / "sim.bag"
    assert (
        run_cli(
            [
                "simulate",
                "tomasi-omni3",
                "--path",
                "line 1; spin 90; line 0.5",
                "--rate",
                "50",
                "--seed",
                "3",
                "--bag",
                sim,
            ]
        )
        == 0
    )
    capsys.readouterr()
    out = tmp_path / "odom.bag"
    assert run_cli(["bag", "odometry", "tomasi-omni3", sim, "-o", out]) == 0
    st_sim, odom_sim, _, _ = odom_arrays(sim, "/odom")
    st, odom, _, _ = odom_arrays(out)
    np.testing.assert_array_equal(st, st_sim)
    np.testing.assert_allclose(odom, odom_sim, atol=1e-9)
    _, truth, _, _ = odom_arrays(sim, "/ground_truth")
    for fmt in ("tum", "kitti", "csv"):
        f = tmp_path / f"truth.{fmt}"
        assert run_cli(["bag", "export", sim, "--topic", "/ground_truth", "--format", fmt, "-o", f]) == 0
        t, poses = read_trajectory(f)
        np.testing.assert_allclose(poses, truth, atol=2e-9)
        if fmt != "kitti":
            np.testing.assert_allclose(t, st_sim * 1e-9, atol=1e-6)
    assert "written to" in capsys.readouterr().out
    assert run_cli(["bag", "export", out, "--topic", "/odom", "--format", "tum"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == len(st) and lines[0].split()[0] == f"{st[0] // 10**9}.{st[0] % 10**9:09d}"
    (tmp_path / "odom.tum").write_text("\n".join(lines) + "\n")
    assert run_cli(["metrics", tmp_path / "truth.tum", tmp_path / "odom.tum", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["ate"]["pairs"] == len(st) and doc["ate"]["translation"]["max"] > 1e-4


def test_export_pose_stamped(tmp_path):
    path = tmp_path / "ps"
    with Writer(path, version=8) as w:
        c = w.add_connection("/pose", "geometry_msgs/msg/PoseStamped", typestore=TS)
        for k in range(3):
            yaw = 1.0 + k
            msg = T["geometry_msgs/msg/PoseStamped"](
                header=T["std_msgs/msg/Header"](
                    stamp=T["builtin_interfaces/msg/Time"](sec=5 + k, nanosec=7), frame_id="map"
                ),
                pose=T["geometry_msgs/msg/Pose"](
                    position=T["geometry_msgs/msg/Point"](x=k, y=-k, z=3.0),
                    orientation=T["geometry_msgs/msg/Quaternion"](x=0, y=0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
                ),
            )
            w.write(c, k, TS.serialize_cdr(msg, "geometry_msgs/msg/PoseStamped"))
    track = bags.export_poses(path, "/pose", "csv", tmp_path / "p.csv")
    assert track.frame_id == "map" and track.msgtype == "geometry_msgs/msg/PoseStamped"
    t, poses = read_trajectory(tmp_path / "p.csv")
    np.testing.assert_allclose(t, [5.000000007, 6.000000007, 7.000000007], atol=1e-9)
    np.testing.assert_allclose(poses, [[0, 0, 1], [1, -1, 2], [2, -2, wrap(3.0)]], atol=1e-9)


# --- bad inputs -----------------------------------------------------------------------------------------
def test_missing_bag_and_broken_bags(tmp_path):
    robot = load_robot("tomasi-omni3")
    with pytest.raises(BagError, match="nope.bag: no such bag"):
        bags.read_joint_states(tmp_path / "nope.bag", robot)
    broken = tmp_path / "broken.bag"
    broken.mkdir()
    (broken / "metadata.yaml").write_text("rosbag2_bagfile_information: {version: 5}\n")
    with pytest.raises(BagError, match="broken.bag: cannot read the bag"):
        bags.read_joint_states(broken, robot)
    junk = tmp_path / "junk.db3"
    junk.write_bytes(b"this is not sqlite" * 10)
    with pytest.raises(BagError, match="junk.db3: cannot read the bag"):
        bags.read_poses(junk, "/odom")
    empty_dir = tmp_path / "empty"
    empty_dir.mkdir()
    with pytest.raises(BagError, match="empty: cannot read the bag"):
        bags.read_poses(empty_dir, "/odom")


def test_missing_topic_lists_the_topics(circle_bag, tmp_path):
    path = circle_bag[0]
    with pytest.raises(
        OmnikinError,
        match=r"in.bag: no topic '/js' in the bag; it has: /chatter \(std_msgs/msg/String"
        r"\), /joint_states \(sensor_msgs/msg/JointState\)",
    ):
        run_cli(["bag", "odometry", "tomasi-omni3", path, "-o", tmp_path / "o", "--joint-states-topic", "/js"])
    assert not (tmp_path / "o").exists()


def test_wrong_message_type(circle_bag, tmp_path):
    path = circle_bag[0]
    with pytest.raises(
        BagError,
        match=r"in.bag: topic '/joint_states' carries sensor_msgs/msg/JointState; "
        r"expected nav_msgs/msg/Odometry or geometry_msgs/msg/PoseStamped",
    ):
        run_cli(["bag", "export", path, "--topic", "/joint_states", "--format", "tum"])
    with pytest.raises(
        BagError, match="topic '/chatter' carries std_msgs/msg/String; expected sensor_msgs/msg/JointState"
    ):
        run_cli(["bag", "odometry", "tomasi-omni3", path, "-o", tmp_path / "o", "--joint-states-topic", "/chatter"])


def test_wrong_joint_names(circle_bag, tmp_path):
    path = circle_bag[0]
    with pytest.raises(
        BagError,
        match=r"in.bag: topic '/joint_states': no JointState message names the wheel "
        r"joints \['left', 'right'\] of robot 'diff-drive'.*\['lift', 'w1', 'w2', "
        r"'w3'\]",
    ):
        run_cli(["bag", "odometry", "diff-drive", path, "-o", tmp_path / "o"])
    partial = tmp_path / "partial"
    write_joint_states(partial, ["w1", "w2"], [[0, 0], [1, 1]], [T0, T0 + DT])
    with pytest.raises(BagError, match=r"partial: topic '/joint_states', message 0: no joint\(s\) \['w3'\]"):
        bags.read_joint_states(partial, load_robot("tomasi-omni3"))


def test_nan_positions_and_too_few_samples(tmp_path):
    robot = load_robot("tomasi-omni3")
    nan = tmp_path / "nan"
    write_joint_states(nan, ["w1", "w2", "w3"], [[0, 0, 0], [0, math.nan, 0]], [T0, T0 + DT])
    with pytest.raises(BagError, match=r"message 1: non-finite position of joint\(s\) \['w2'\]"):
        bags.read_joint_states(nan, robot)
    one = tmp_path / "one"
    write_joint_states(one, ["w1", "w2", "w3"], [[0, 0, 0]], [T0])
    with pytest.raises(BagError, match="at least two distinct wheel samples, got 1"):
        bags.read_joint_states(one, robot)


def test_output_bag_is_never_overwritten(circle_bag, tmp_path):
    path = circle_bag[0]
    out = tmp_path / "exists"
    out.mkdir()
    with pytest.raises(OutputExistsError, match="exists already"):
        run_cli(["bag", "odometry", "tomasi-omni3", path, "-o", out])
    with pytest.raises(InputError, match="does not exist"):
        run_cli(["simulate", "tomasi-omni3", "--path", "spin 10", "--bag", tmp_path / "no" / "dir" / "x.bag"])


@pytest.mark.parametrize(
    "argv, match",
    [
        (["simulate", "tomasi-omni3", "--path", "hop 3"], "--path: path 'hop 3'"),
        (["simulate", "tomasi-omni3", "--path", "line 1;;spin 9"], "empty part"),
        (["simulate", "tomasi-omni3", "--errors", "awful"], "unknown error profile 'awful'"),
        (["simulate", "tomasi-omni3", "--noise", "loud"], "unknown noise profile 'loud'"),
        (["simulate", "tomasi-omni3", "--rate", "0"], "--rate"),
        (["simulate", "tomasi-omni3", "--seed", "-1"], "--seed"),
        (["simulate", "diff-drive", "--path", "line 1 90"], "diff-drive"),
        (["bag"], "give a sub-command"),
    ],
)
def test_cli_bad_input_raises_omnikin_error(tmp_path, argv, match):
    if argv[0] == "simulate":
        argv = argv + ["--bag", tmp_path / "x.bag"]
    with pytest.raises(OmnikinError, match=match):
        run_cli(argv)
    assert not (tmp_path / "x.bag").exists()


def test_without_rosbags_the_error_names_the_extra(monkeypatch, tmp_path):
    import builtins

    real_import = builtins.__import__

    def no_rosbags(name, *args, **kwargs):
        if name.startswith("rosbags"):
            raise ImportError("No module named 'rosbags'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(bags._Rosbags, "_instance", None)
    monkeypatch.setattr(builtins, "__import__", no_rosbags)
    with pytest.raises(ImportError, match=r'pip install "omnikin\[bags\]"'):
        bags.read_poses(tmp_path / "x", "/odom")
    with pytest.raises(ImportError, match=r"omnikin\[bags\]"):
        run_cli(["simulate", "tomasi-omni3", "--bag", tmp_path / "x.bag"])


# --- errors that name the bag's message and fail before the long work ---------------------------------
def test_stamp_going_back_names_the_bags_message(tmp_path):
    """Wheel messages interleaved with foreign ones (skipped), two header stamps swapped: the
    error names the message index in the topic (not the index among kept samples) and the way out."""
    twist = np.array([0.1, 0.0, 0.3])
    stamps = T0 + DT * np.arange(20)
    header = stamps.copy()
    header[[8, 9]] = header[[9, 8]]
    ang = np.outer((stamps - T0) * 1e-9, TOMASI_J @ twist)
    path = tmp_path / "swapped"
    with Writer(path, version=8) as w:
        c = w.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=TS)
        for s, h, a in zip(stamps, header, ang, strict=True):
            for names, pos in ([["arm"], [1.0]], [["w1", "w2", "w3"], a]):  # topic messages 2k and 2k+1
                st = T["builtin_interfaces/msg/Time"](sec=int(h) // 10**9, nanosec=int(h) % 10**9)
                msg = T["sensor_msgs/msg/JointState"](
                    header=T["std_msgs/msg/Header"](stamp=st, frame_id=""),
                    name=names,
                    position=np.asarray(pos, float),
                    velocity=np.zeros(0),
                    effort=np.zeros(0),
                )
                w.write(c, int(s), TS.serialize_cdr(msg, "sensor_msgs/msg/JointState"))
    robot = load_robot("tomasi-omni3")
    # wheel sample 9 is topic message 2 * 9 + 1 = 19; it follows message 17
    with pytest.raises(
        BagError,
        match=r"message 19: header stamps must increase strictly.*of message 17; "
        r"--stamp bag",
    ) as info:
        bags.read_joint_states(path, robot)
    assert str(int(header[9])) in str(info.value)
    js = bags.read_joint_states(path, robot, stamp="bag")  # the record times are in order
    assert len(js.stamps) == 20


def test_taken_output_fails_before_reading_or_simulating(tmp_path):
    """The output check comes first: with an output that exists, even a missing input bag or an
    impossible path is not reached."""
    out = tmp_path / "taken"
    out.mkdir()
    with pytest.raises(OutputExistsError, match="exists already"):
        bags.bag_odometry(load_robot("tomasi-omni3"), tmp_path / "no-such-bag", out)
    with pytest.raises(OutputExistsError, match="exists already"):
        run_cli(["simulate", "tomasi-omni3", "--path", "not a path", "--bag", out])


@pytest.mark.parametrize(
    "frames, match",
    [
        (["--frame-id", ""], r"--frame-id: '' is not a valid frame id"),
        (["--child-frame-id", ""], r"--child-frame-id: '' is not a valid frame id"),
        (["--frame-id", "a b"], r"--frame-id: 'a b' is not a valid frame id"),
        (["--frame-id", "/odom"], r"--frame-id: '/odom' is not a valid frame id"),
        (["--child-frame-id", "base\nlink"], r"--child-frame-id: 'base\\nlink' is not a valid frame id"),
        (["--child-frame-id", "1base"], r"--child-frame-id: '1base' is not a valid frame id"),
        (["--child-frame-id", "odom"], r"--child-frame-id 'odom' is the same frame as --frame-id"),
        (["--frame-id", "base_link"], r"--child-frame-id 'base_link' is the same frame as --frame-id"),
    ],
)
def test_frame_ids_follow_ros_naming_rules(circle_bag, tmp_path, frames, match):
    """Frame ids '' and 'a b', and a child frame equal to its parent, are refused before the bag's
    Odometry headers are written."""
    out = tmp_path / "odom.bag"
    with pytest.raises(BagError, match=match):
        run_cli(["bag", "odometry", "tomasi-omni3", circle_bag[0], "-o", out, *frames])
    assert not out.exists()


def test_library_writers_check_frame_ids_too(tmp_path):
    stamps, poses = np.array([0, 10**8]), np.zeros((2, 3))
    for frame, child in (("odom", "odom"), ("", "base_link"), ("odom", "base link")):
        with pytest.raises(BagError, match="frame"):
            bags.write_odometry(tmp_path / "o.bag", stamps, poses, poses, frame_id=frame, child_frame_id=child)
    bags.write_odometry(tmp_path / "o.bag", stamps, poses, poses, frame_id="robot1/odom", child_frame_id="robot1/base")
    assert bags.read_poses(tmp_path / "o.bag", "/odom").child_frame_id == "robot1/base"


def test_a_huge_missing_topic_name_is_quoted_short_and_the_reason_kept(circle_bag, tmp_path):
    path = circle_bag[0]
    topic = "/" + "j" * 100_000
    with pytest.raises(OmnikinError) as info:
        run_cli(["bag", "odometry", "tomasi-omni3", path, "-o", tmp_path / "o", "--joint-states-topic", topic])
    message = str(info.value)
    assert len(message) < 1000 and "no topic" in message and "it has: /chatter" in message
