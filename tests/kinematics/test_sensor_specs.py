"""Sensors in robot files: the preset's stated values, LaserScan's beam angles, one-line errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from omnikin.errors import InputError, RobotFileError
from omnikin.io.robot_file import load_robot, parse_robot_text, robot_from_dict, robot_to_dict
from omnikin.kinematics.sensors import Bumper, Imu, Lidar, Mount

BASE = """\
omnikin: 1
name: sensed
wheels:
  - {name: w1, type: omni, distance: 0.1, angle_deg: 0, radius: 0.03, encoder: {ticks_per_rev: 600}}
  - {name: w2, type: omni, distance: 0.1, angle_deg: 120, radius: 0.03, encoder: {ticks_per_rev: 600}}
  - {name: w3, type: omni, distance: 0.1, angle_deg: 240, radius: 0.03, encoder: {ticks_per_rev: 600}}
sensors:
"""


def _robot(sensors: str):
    return parse_robot_text(BASE + sensors, "r.yaml")


def test_the_lidar_preset_carries_the_stated_imu_lidar_and_bumper():
    robot = load_robot("tomasi-omni3-lidar")
    imu, laser, bumper = robot.sensors
    assert isinstance(imu, Imu) and imu.rate == 200.0 and imu.mount == Mount(0.0, 0.0, 0.06, 0.0)
    assert imu.gyro.noise_density == 8.7e-5 and imu.gyro.misalignment == pytest.approx(math.radians(0.5))
    assert imu.accel.noise_density == 3.9e-3 and imu.accel.bias_walk == 6e-4
    assert isinstance(laser, Lidar) and (laser.beams, laser.rate, laser.range_min, laser.range_max) == (
        360,
        10.0,
        0.15,
        12.0,
    )
    assert (laser.range_noise, laser.dropout) == (0.01, 0.01)
    assert isinstance(bumper, Bumper)
    assert robot.wheels == load_robot("tomasi-omni3").wheels


def test_sensors_written_out_read_back_the_same():
    robot = load_robot("tomasi-omni3-lidar")
    again = robot_from_dict(yaml.safe_load(yaml.safe_dump(robot_to_dict(robot))))
    assert again.sensors == robot.sensors


def test_a_full_turn_of_beams_never_repeats_its_first_beam():
    lidar = Lidar("l", beams=360)
    angles = lidar.angles()
    assert lidar.angle_min == -math.pi
    assert lidar.angle_increment == pytest.approx(2 * math.pi / 360)
    np.testing.assert_allclose(angles, -math.pi + np.arange(360) * math.radians(1.0), atol=1e-15)
    assert angles[-1] == pytest.approx(math.pi - math.radians(1.0))


def test_a_partial_field_of_view_puts_its_first_and_last_beam_on_its_edges():
    lidar = Lidar("l", beams=541, fov=math.radians(270))
    angles = lidar.angles()
    assert angles[0] == pytest.approx(-math.radians(135), abs=1e-15)
    assert angles[-1] == pytest.approx(math.radians(135), abs=1e-12)
    assert lidar.angle_increment == pytest.approx(math.radians(0.5))


@pytest.mark.parametrize(
    ("entry", "expected"),
    [
        (
            "  - {name: l, type: lidar, beams: 1000000}",
            "sensor 'l' (#1): field 'beams': must be a whole number from 1 to 10000",
        ),
        ("  - {name: l, type: lidar, range_min: 5, range_max: 2}", "range_min 5 m must be below range_max 2 m"),
        ("  - {name: l, type: lidar, range_noise: .nan}", "field 'range_noise': must be finite"),
        ("  - {name: l, type: lidar, dropout: 1}", "field 'dropout': must lie in [0, 0.99]"),
        ("  - {name: l, type: laser}", "unknown sensor type 'laser'; one of ['imu', 'lidar', 'bumper']"),
        ("  - {name: l, type: lidar, beam: 10}", "did you mean 'beams'?"),
        ("  - {name: i, type: imu, gyro: {noise: 1}}", "sensor 'i' (#1): field 'gyro': unknown key(s) ['noise']"),
        ("  - {name: i, type: imu, rate: 0}", "field 'rate': must lie in [1, 2000] Hz"),
        ("  - {name: i, type: imu, accel: {scale: -0.1}}", "accel: field 'scale': must lie in [0, 0.5]"),
        ("  - {name: w1, type: bumper}", "sensor 'w1': its name is also a wheel's or another sensor's"),
        ("  - {name: 'a b', type: bumper}", "a letter, then letters, digits and underscores"),
        ("  - {name: b, type: bumper, arc_deg: [90, -90]}", "need low < high within one turn"),
        ("  - {name: l, type: lidar, mount: {z: -1}}", "field 'mount.z': must lie in [0, 10] m"),
    ],
)
def test_a_bad_sensor_is_one_line_naming_it_and_its_field(entry, expected):
    with pytest.raises(RobotFileError) as caught:
        _robot(entry + "\n")
    message = str(caught.value)
    assert "\n" not in message and message.startswith("r.yaml: ")
    assert expected in message


def test_too_many_sensors_are_refused():
    many = "".join(f"  - {{name: b{i}, type: bumper}}\n" for i in range(40))
    with pytest.raises(RobotFileError, match=r"field 'sensors': must be a list of at most 32 sensors"):
        _robot(many)


@pytest.mark.parametrize(
    ("arc", "bearing", "pressed"),
    [((-0.5, 0.5), 0.0, True), ((-0.5, 0.5), 0.6, False), ((2.5, 3.5), -3.0, True), ((2.5, 3.5), 2.0, False)],
)
def test_a_bumper_is_pressed_by_contacts_within_its_arc_whatever_the_turn(arc, bearing, pressed):
    # -3.0 rad is 3.283 rad a turn later: within (2.5, 3.5)
    assert Bumper("b", arc).presses(bearing) is pressed


def test_sensors_built_in_python_are_checked():
    with pytest.raises(InputError, match=r"sensor 'l': field 'fov': must lie in"):
        Lidar("l", fov=7.0)
    with pytest.raises(InputError, match=r"sensor 'i': field 'mount': must be a Mount"):
        Imu("i", mount=(0, 0, 0))


@pytest.mark.parametrize("frame", ["base_link", "odom", "map"])
def test_a_sensor_may_not_take_a_frame_of_the_base_or_of_rep_105(frame):
    with pytest.raises(RobotFileError, match=rf"'{frame}' is a frame of the robot's base or of REP 105"):
        _robot(f"  - {{name: {frame}, type: imu}}\n")
