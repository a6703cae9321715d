"""A run's sensors in its bag: /imu, /scan, /tf and a latched /tf_static, in time order, with what
the readings and the robot file say."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="bags need rosbags (extra 'bags')")

from rosbags.rosbag2 import Reader  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

from support.cli import run_cli  # noqa: E402
from support.paths import ROOT  # noqa: E402

STORE = get_typestore(Stores.ROS2_HUMBLE)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sensor-bag")
    bag, scans = folder / "run.bag", folder / "scans.npz"
    from omnikin.cli.main import main

    rc = main(
        [
            "simulate", "tomasi-omni3-lidar", "--world", str(ROOT / "examples" / "worlds" / "room.yaml"),
            "--path", "line 1", "--errors", "none", "--noise", "none", "--bag", str(bag), "--scan-log", str(scans),
        ]
    )  # fmt: skip
    assert rc == 0
    messages: dict[str, list] = {}
    stamps = []
    with Reader(bag) as reader:
        qos = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
        for connection, stamp, raw in reader.messages():
            stamps.append(stamp)
            messages.setdefault(connection.topic, []).append(STORE.deserialize_cdr(raw, connection.msgtype))
    return messages, stamps, qos, scans


def test_the_bag_holds_every_sensor_topic_in_time_order(recorded):
    messages, stamps, qos, _ = recorded
    assert set(messages) == {
        "/ground_truth",
        "/odom",
        "/joint_states",
        "/cmd_vel",
        "/tf",
        "/tf_static",
        "/imu",
        "/scan",
    }
    assert stamps == sorted(stamps)
    duration = messages["/odom"][-1].header.stamp.sec + messages["/odom"][-1].header.stamp.nanosec * 1e-9
    assert len(messages["/imu"]) == math.floor(duration * 200 + 1e-9)
    assert len(messages["/scan"]) == math.floor(duration * 10 + 1e-9) + 1
    assert len(messages["/tf_static"]) == 1
    assert qos["/tf_static"] and qos["/tf_static"][0].durability.name == "TRANSIENT_LOCAL"


def test_the_scans_are_the_scan_log_as_laserscan_declares_its_beams(recorded):
    messages, _, _, scans = recorded
    first = messages["/scan"][0]
    assert first.header.frame_id == "laser"
    assert first.angle_min == pytest.approx(-math.pi)
    assert first.angle_max == pytest.approx(math.pi - math.radians(1.0), rel=1e-6)
    assert first.angle_increment == pytest.approx(math.radians(1.0), rel=1e-6)
    assert (first.range_min, first.range_max) == (pytest.approx(0.15), pytest.approx(12.0))
    assert first.scan_time == pytest.approx(0.1) and first.time_increment == pytest.approx(0.1 / 360)
    with np.load(scans, allow_pickle=False) as data:
        np.testing.assert_array_equal(np.array([m.ranges for m in messages["/scan"]]), data["laser.ranges"])
    assert first.ranges[270] == pytest.approx(1.95, abs=1e-5)  # the north wall, by hand from room.yaml


def test_tf_carries_the_odometry_and_tf_static_every_sensor_mount(recorded):
    messages, _, _, _ = recorded
    for tf, odom in zip(messages["/tf"], messages["/odom"], strict=True):
        (transform,) = tf.transforms
        assert (transform.header.frame_id, transform.child_frame_id) == ("odom", "base_link")
        assert transform.header.stamp == odom.header.stamp
        assert transform.transform.translation.x == odom.pose.pose.position.x
        assert transform.transform.rotation.z == pytest.approx(odom.pose.pose.orientation.z, abs=1e-15)
    mounts = {t.child_frame_id: t for t in messages["/tf_static"][0].transforms}
    assert set(mounts) == {"imu", "laser"}
    assert mounts["laser"].header.frame_id == "base_link"
    assert mounts["laser"].transform.translation.z == pytest.approx(0.12)
    assert mounts["imu"].transform.translation.z == pytest.approx(0.06)


def test_the_imu_messages_state_their_noise_and_an_unknown_orientation(recorded):
    messages, _, _, _ = recorded
    imu = messages["/imu"][0]
    assert imu.header.frame_id == "imu"
    assert imu.orientation_covariance[0] == -1.0  # REP 145: no orientation estimate
    assert imu.angular_velocity_covariance[0] == pytest.approx(8.7e-5**2 * 200)
    assert imu.linear_acceleration_covariance[8] == pytest.approx(3.9e-3**2 * 200)
    assert imu.linear_acceleration.z == pytest.approx(9.81)  # --noise none: exact


def test_a_robot_without_sensors_writes_the_bag_it_always_did(capsys, tmp_path):
    rc, out, err = run_cli(capsys, "simulate", "tomasi-omni3", "--path", "line 1", "--bag", tmp_path / "plain.bag")
    assert rc == 0, err
    with Reader(tmp_path / "plain.bag") as reader:
        assert {c.topic for c in reader.connections} == {"/ground_truth", "/odom", "/joint_states", "/cmd_vel"}
