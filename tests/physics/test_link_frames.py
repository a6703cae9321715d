"""The URDF's kinematics for /tf (omnikin.physics.link_frames), checked against independent sources:
urdf_parser_py's parse of the same text, SciPy's rotations, and a wheel's pose written out by
hand from the robot file (hub at ``(x, y, r)``, turned by the drive direction, then spun about
its axle)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from urdf_parser_py.urdf import URDF

from omnikin import load_robot
from omnikin.errors import InputError
from omnikin.physics.joint_motion import JointMotion
from omnikin.physics.link_frames import LinkFrames, urdf_joints
from omnikin.physics.urdf import urdf
from omnikin.presets import PRESET_NAMES


def matrix(q) -> np.ndarray:
    """Rotation matrix of the unit quaternion ``(x, y, z, w)`` (the textbook formula)."""
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_joints_read_as_urdf_parser_py_reads_them(name):
    text = urdf(load_robot(name))
    theirs = {j.name: j for j in URDF.from_xml_string(text).joints}
    ours = urdf_joints(text)
    assert [j.name for j in ours] == list(theirs)
    for j in ours:
        t = theirs[j.name]
        assert (j.type, j.parent, j.child) == (t.type, t.parent, t.child)
        assert j.xyz == pytest.approx(t.origin.xyz, abs=1e-15)
        assert j.rpy == pytest.approx(t.origin.rpy, abs=1e-15)
        if t.axis is not None:  # a fixed joint (a sensor's frame) has none
            assert j.axis == pytest.approx(np.array(t.axis) / np.linalg.norm(t.axis), abs=1e-15)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_every_link_gets_a_frame_in_one_tree_under_base_link(name):
    """/tf then holds every link rviz2's RobotModel draws: each link but the root is the child
    of exactly one transform, and every parent is base_link or such a child."""
    parsed = URDF.from_xml_string(urdf(load_robot(name)))
    frames = LinkFrames(urdf_joints(urdf(load_robot(name))))
    children = [j.child for j in frames.movable + frames.fixed]
    assert len(children) == len(set(children))
    assert set(children) | {"base_link"} == {link.name for link in parsed.links}
    assert {j.parent for j in frames.movable + frames.fixed} <= set(children) | {"base_link"}
    assert parsed.get_root() == "base_link"


@pytest.mark.parametrize("name", ["tomasi-omni3", "mecanum4", "ackermann", "diff-drive", "xr4000"])
def test_child_rotation_is_origin_rpy_then_the_turn_about_the_axis(name):
    """R = Rz(yaw) Ry(pitch) Rx(roll) Rot(axis, q) (SciPy: extrinsic 'xyz' Euler angles, rotation vector)."""
    text = urdf(load_robot(name))
    frames = LinkFrames(urdf_joints(text))
    q = np.random.default_rng(3).uniform(-7.0, 7.0, len(frames.movable))
    xyz, rot = frames.moved(q)
    for j, t, r, angle in zip(frames.movable, xyz, rot, q, strict=True):
        want = Rotation.from_euler("xyz", j.rpy) * Rotation.from_rotvec(np.array(j.axis) * angle)
        assert matrix(r) == pytest.approx(want.as_matrix(), abs=1e-12), j.name
        assert np.linalg.norm(r) == pytest.approx(1.0, abs=1e-14)
        assert t == pytest.approx(j.xyz, abs=0.0)  # a rotation about the axis keeps the origin


def test_a_wheel_link_sits_at_its_hub_turned_by_the_drive_and_its_angle():
    """tomasi-omni3's wheel w2 from the robot file: origin (x, y, r), x axis (cos d cos q,
    sin d cos q, -sin q), y axis (the axle) (-sin d, cos d, 0), d the drive direction."""
    robot = load_robot("tomasi-omni3")
    wheel = robot.wheel("w2")
    frames = LinkFrames(urdf_joints(urdf(robot)))
    i = frames.movable_names.index("w2")
    positions = np.zeros(len(frames.movable))
    positions[i] = q = 0.7
    xyz, rot = frames.moved(positions)
    assert frames.movable[i].child == "w2_wheel" and frames.movable[i].parent == "base_link"
    d = wheel.drive
    assert xyz[i] == pytest.approx([wheel.x, wheel.y, wheel.radius], abs=1e-15)
    m = matrix(rot[i])
    assert m[:, 0] == pytest.approx([math.cos(d) * math.cos(q), math.sin(d) * math.cos(q), -math.sin(q)], abs=1e-14)
    assert m[:, 1] == pytest.approx([-math.sin(d), math.cos(d), 0.0], abs=1e-14)


PRISMATIC = """<robot name="slide">
  <link name="base_link"/><link name="carriage"/><link name="sensor"/>
  <joint name="slide" type="prismatic">
    <parent link="base_link"/><child link="carriage"/>
    <origin xyz="0.1 0.2 0.3" rpy="0 0 1.5707963267948966"/><axis xyz="2 0 0"/>
  </joint>
  <joint name="mount" type="fixed">
    <parent link="carriage"/><child link="sensor"/><origin xyz="0 0 0.05" rpy="0 0.5 0"/>
  </joint>
</robot>"""


def test_prismatic_joint_travels_along_its_turned_axis_and_fixed_joints_stay():
    frames = LinkFrames(urdf_joints(PRISMATIC))
    assert frames.movable_names == ["slide"] and [j.name for j in frames.fixed] == ["mount"]
    xyz, rot = frames.moved([0.25])
    assert xyz[0] == pytest.approx([0.1, 0.2 + 0.25, 0.3], abs=1e-15)  # x turned by 90 deg is y
    assert matrix(rot[0]) == pytest.approx(Rotation.from_euler("z", math.pi / 2).as_matrix(), abs=1e-15)
    xyz, rot = frames.still()
    assert xyz[0] == pytest.approx([0.0, 0.0, 0.05]) and matrix(rot[0]) == pytest.approx(
        Rotation.from_euler("y", 0.5).as_matrix(), abs=1e-15
    )


@pytest.mark.parametrize(
    ("text", "says"),
    [
        (PRISMATIC.replace('type="prismatic"', 'type="floating"'), "type 'floating'"),
        (PRISMATIC.replace('xyz="2 0 0"', 'xyz="0 0 0"'), "finite, non-zero length"),
        (PRISMATIC.replace('xyz="2 0 0"', 'xyz="1 0"'), "three finite numbers"),
        (PRISMATIC.replace('xyz="2 0 0"', 'xyz="1 nan 0"'), "three finite numbers"),
        (PRISMATIC.replace('<parent link="base_link"/>', ""), "needs a parent and a child"),
    ],
)
def test_joints_it_cannot_move_are_refused_in_one_line(text, says):
    with pytest.raises(InputError, match=says) as info:
        urdf_joints(text)
    assert "URDF joint" in str(info.value) and "\n" not in str(info.value)


def test_a_huge_axis_is_only_a_direction():
    frames = LinkFrames(urdf_joints(PRISMATIC.replace('xyz="2 0 0"', 'xyz="1e308 1e308 0"')))
    assert frames.movable[0].axis == pytest.approx((math.sqrt(0.5), math.sqrt(0.5), 0.0), rel=1e-15)


def test_positions_must_match_the_movable_joints():
    frames = LinkFrames(urdf_joints(PRISMATIC))
    with pytest.raises(InputError, match="1 movable joints, 2 positions"):
        frames.moved([0.0, 1.0])


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_joint_states_names_place_every_link(name):
    """The node's joint_states (measured joints, then JointMotion's) hold every movable joint:
    the index picks each joint's own position (here: its position in the message plus one)."""
    robot = load_robot(name)
    frames = LinkFrames(urdf_joints(urdf(robot)))
    names = (
        robot.encoded_names + [f"{n}_steer" for n in robot.steer_names] + JointMotion(robot, robot.encoded_names).names
    )
    index = frames.index_in(names)
    positions = np.arange(len(names), dtype=float) + 1.0
    assert [names[i] for i in index] == frames.movable_names
    assert positions[index].tolist() == [names.index(n) + 1.0 for n in frames.movable_names]


def test_a_joint_missing_from_the_positions_is_named():
    frames = LinkFrames(urdf_joints(urdf(load_robot("diff-drive"))))
    with pytest.raises(InputError, match="castor_steer"):
        frames.index_in(["left", "right", "castor"])
