"""The joints no sensor reads (omnikin.physics.joint_motion): their names are the URDF's, and they
move as closed forms of rigid-body kinematics say, with every geometric quantity read from the
URDF (urdf_parser_py) or the robot file, never from the code under test."""

from __future__ import annotations

import math

import numpy as np
import pytest
from urdf_parser_py.urdf import URDF

from omnikin import load_robot
from omnikin.physics.joint_motion import JointMotion
from omnikin.physics.urdf import urdf
from omnikin.presets import PRESET_NAMES

DT = 0.02  # [s] the control interval of the runs below


def run(robot, twist, seconds: float, steer=None) -> tuple[JointMotion, np.ndarray, np.ndarray]:
    motion = JointMotion(robot, robot.encoded_names)
    positions = velocities = np.zeros(len(motion.names))
    for k in range(round(seconds / DT) + 1):
        positions, velocities = motion.update(k * DT, twist, steer)
    return motion, dict(zip(motion.names, positions, strict=True)), dict(zip(motion.names, velocities, strict=True))


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_measured_and_implied_joints_are_every_movable_urdf_joint(name):
    robot = load_robot(name)
    movable = [j.name for j in URDF.from_xml_string(urdf(robot)).joints if j.type != "fixed"]
    published = (
        robot.encoded_names + [f"{n}_steer" for n in robot.steer_names] + JointMotion(robot, robot.encoded_names).names
    )
    assert sorted(published) == sorted(movable)  # each once


def _roller_geometry(robot, wheel: str):
    """From the URDF: the wheel's drive direction (its joint's yaw), the spin axis of the roller
    at the bottom (roller 0 of row 0, in the wheel frame at zero wheel angle) and the roller's
    radius (its collision sphere)."""
    parsed = URDF.from_xml_string(urdf(robot))
    joints = {j.name: j for j in parsed.joints}
    delta = joints[wheel].origin.rpy[2]
    axis = np.array(joints[f"{wheel}_roller_0_0"].axis)
    assert joints[f"{wheel}_roller_0_0"].origin.xyz[0] == pytest.approx(0.0, abs=1e-15)  # at the bottom
    link = parsed.link_map[f"{wheel}_roller_0_0"]
    return delta, axis, link.collisions[0].geometry.radius


@pytest.mark.parametrize(
    ("name", "twist"),
    [
        ("tomasi-omni3", (0.0, 0.15, 0.0)),
        ("mecanum4", (0.0, 0.2, 0.0)),
        ("omni4", (0.1, -0.05, 0.0)),
        ("mecanum4", (0.1, 0.0, 0.0)),
    ],
)
def test_rollers_turn_as_the_rim_velocity_across_their_axis_over_their_radius(name, twist):
    """A translation ``v`` for ``T`` s: the rim point at the contact moves at ``v - r w u`` (``w``
    the wheel speed that leaves no slip along the roller axis ``e``: ``w = (v . e) / (r u . e)``);
    the roller of radius ``b`` cancels it by spinning at ``-(v_rim . (z x e)) / b``; every roller
    of the wheel turns by that times ``T``. (omni3 sideways: ``-v cos(delta) T / b``; mecanum
    sideways: ``-v T / (b cos gamma)``; mecanum forward: 0.)"""
    robot = load_robot(name)
    seconds = 1.5
    _, positions, velocities = run(robot, twist, seconds)
    v = np.array([twist[0], twist[1], 0.0])
    for wheel in robot.swedish_names:
        delta, e_wheel, b = _roller_geometry(robot, wheel)
        c, s = math.cos(delta), math.sin(delta)
        e = np.array([c * e_wheel[0] - s * e_wheel[1], s * e_wheel[0] + c * e_wheel[1], e_wheel[2]])
        u = np.array([c, s, 0.0])
        r = robot.wheel(wheel).radius
        w = (v @ e) / (r * (u @ e))
        rim = v - r * w * u
        rate = -(rim @ np.cross([0.0, 0.0, 1.0], e)) / b
        rollers = [n for n in positions if n.startswith(f"{wheel}_roller_")]
        assert len(rollers) >= 6
        for n in rollers:
            assert positions[n] == pytest.approx(rate * seconds, rel=1e-12, abs=1e-12), n
            assert velocities[n] == pytest.approx(rate, rel=1e-12, abs=1e-12), n


def test_unencoded_steered_wheels_roll_the_distance_over_their_radius():
    """Ackermann's front wheels have no encoder: steered straight, x for T s turns each by x / r."""
    robot = load_robot("ackermann")
    _, positions, _ = run(robot, (0.3, 0.0, 0.0), 2.0, steer=np.zeros(2))
    for n in ("front_left", "front_right"):
        assert positions[n] == pytest.approx(0.3 * 2.0 / robot.wheel(n).radius, rel=1e-12)


def test_a_castor_trails_a_straight_drive_and_rolls_the_distance():
    robot = load_robot("diff-drive")
    _, positions, _ = run(robot, (0.2, 0.0, 0.0), 2.0)
    assert positions["castor_steer"] == 0.0
    assert positions["castor"] == pytest.approx(0.2 * 2.0 / robot.wheel("castor").radius, rel=1e-12)


def test_a_castor_swivels_to_the_steady_angle_of_a_turn_in_place():
    """diff-drive's castor at (x, 0) = (-0.2, 0), trail d = 0.03, the robot turning at w: the swivel
    axis moves at (0, w x); the contact stops sliding sideways where n . v_p = d w, i.e.
    cos(beta) = d / x = -0.15, on the branch beta < 0 that the swivel reaches from 0 (its rate there,
    w (x / d - 1), is negative for w > 0); there it rolls at x sin(beta) w / r."""
    robot = load_robot("diff-drive")
    wheel = robot.wheel("castor")
    omega = 0.5
    _, positions, velocities = run(robot, (0.0, 0.0, omega), 12.0)
    beta = -math.acos(wheel.offset / wheel.x)
    assert positions["castor_steer"] == pytest.approx(beta, abs=1e-9)
    assert velocities["castor_steer"] == pytest.approx(0.0, abs=1e-9)
    assert velocities["castor"] == pytest.approx(wheel.x * math.sin(beta) * omega / wheel.radius, rel=1e-8)


def test_a_castor_stays_bounded_when_it_settles_within_one_interval():
    """1 m/s with 3 cm of trail settles the swivel in a few milliseconds: a long interval takes the
    steady angle (reversing: it turns round) instead of an Euler step that would overshoot."""
    robot = load_robot("diff-drive")
    motion = JointMotion(robot, robot.encoded_names)
    i = motion.names.index("castor_steer")
    motion.update(0.0, (-1.0, 0.0, 0.0))
    positions, _ = motion.update(0.5, (-1.0, 0.0, 0.0))
    assert abs(positions[i]) == pytest.approx(math.pi, abs=1e-12)
