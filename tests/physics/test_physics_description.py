"""The physical description of a robot (omnikin.physics.description) and its MJCF text: pure
data, checked against independent geometry (generic ellipsoid support functions, the kinematic
rolling rows of omnikin.kinematics.wheels, static force balance). No MuJoCo needed."""

from __future__ import annotations

import math
import subprocess
import sys
import xml.etree.ElementTree as ET
from dataclasses import replace

import numpy as np
import pytest

from omnikin import Encoder, Robot, Wheel, load_robot
from omnikin.kinematics.physical import PhysicalBody, PhysicalWheel
from omnikin.physics.description import describe, wheel_loads
from omnikin.physics.mjcf import mjcf
from omnikin.presets import PRESET_NAMES
from support.paths import omnikin_env

SWEDISH_PRESETS = ["tomasi-omni3", "garcia-sillas-omni3", "omni4", "mecanum4"]


def rot_y(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def axle_heights(wheel_body, angles):
    """Height of the axle above the floor [m] at each wheel angle: the lowest point of all
    rollers, each the ellipsoid x^T A^-1 x <= 1 with A = R diag(b^2, b^2, a^2) R^T, whose support
    in direction d is sqrt(d^T A d) (a generic fact, not the description's formula)."""
    rs = wheel_body.rollers
    down = np.array([0.0, 0.0, -1.0])
    out = []
    for theta in angles:
        turn = rot_y(theta)
        lowest = -np.inf
        for roller in rs.rollers:
            e = turn @ np.array(roller.axis)
            centre = turn @ np.array(roller.position)
            a_mat = rs.radius**2 * np.eye(3) + (rs.half_length**2 - rs.radius**2) * np.outer(e, e)
            lowest = max(lowest, -centre[2] + math.sqrt(down @ a_mat @ down))
        out.append(lowest)
    return np.array(out)


@pytest.mark.parametrize("name", SWEDISH_PRESETS)
def test_rollers_roll_the_wheel_radius_on_average_with_a_small_ripple(name):
    for wheel in describe(load_robot(name)).wheels:
        rs = wheel.rollers
        pitch = 2 * math.pi / (rs.per_row * rs.rows)
        # one hand-over interval holds every phase of the envelope; the mean over it is the rolling radius
        angles = np.linspace(-pitch / 2, pitch / 2, 2001)
        h = axle_heights(wheel, angles)
        mean = float(np.sum(h[1:] + h[:-1]) / 2 * (angles[1] - angles[0]) / pitch)
        assert mean == pytest.approx(wheel.radius, rel=1e-6)
        assert np.ptp(h) < 0.01 * wheel.radius  # the height ripple: below 1 % of the radius
        assert np.ptp(h) == pytest.approx(rs.ripple, rel=1e-3)
        assert h.max() == pytest.approx(rs.crest, rel=1e-9)


@pytest.mark.parametrize("name", SWEDISH_PRESETS)
def test_the_bottom_roller_lies_along_the_direction_in_which_the_contact_cannot_slip(name):
    robot = load_robot(name)
    for wheel, body in zip(robot.wheels, describe(robot).wheels, strict=True):
        bottom = [r for r in body.rollers.rollers if r.row == 0 and r.index == 0][0]
        axis_wheel = np.array(bottom.axis)
        assert axis_wheel[2] == pytest.approx(0.0, abs=1e-12)
        # wheel frame (x along u, y along the axle) -> body frame
        u = np.array([math.cos(wheel.drive), math.sin(wheel.drive)])
        a = np.array([-math.sin(wheel.drive), math.cos(wheel.drive)])
        axis_body = axis_wheel[0] * u + axis_wheel[1] * a
        row = wheel.rolling_row()[:2]  # the kinematic row: no slip along (cos(delta+gamma), sin(delta+gamma))
        assert axis_body == pytest.approx(row / np.linalg.norm(row), abs=1e-12)
        assert np.array(bottom.position) == pytest.approx([0.0, 0.0, -body.rollers.centre_radius], abs=1e-15)


def test_rollers_follow_any_roller_angle_and_count():
    for gamma_deg in (0.0, 30.0, -45.0, 60.0, 80.0):
        for rows, per_row in ((1, 9), (2, 5), (3, 4)):
            physical = PhysicalWheel(rows=rows, rollers=per_row)
            wheel = Wheel("w", "swedish", 0.2, 0.0, math.pi / 2, 0.05, roller=math.radians(gamma_deg))
            body = describe(Robot("r", (replace(wheel, physical=physical), *_others()))).wheels[0]
            assert len(body.rollers.rollers) == rows * per_row
            angles = np.linspace(0, 2 * math.pi / (rows * per_row), 401)
            h = axle_heights(body, angles)
            assert float(np.mean(h[:-1])) == pytest.approx(0.05, rel=2e-4)
            # every roller axis makes the roller angle with the wheel plane (its y component is sin gamma)
            for r in body.rollers.rollers:
                assert r.axis[1] == pytest.approx(math.sin(math.radians(gamma_deg)), abs=1e-12)
                assert np.linalg.norm(r.axis) == pytest.approx(1.0, abs=1e-12)


def _others():
    """Two omni wheels completing a three-wheel circle around a wheel at angle 0."""
    return tuple(
        Wheel(f"o{i}", "omni", 0.2 * math.cos(b), 0.2 * math.sin(b), b + math.pi / 2, 0.05)
        for i, b in ((1, 2 * math.pi / 3), (2, 4 * math.pi / 3))
    )


@pytest.mark.parametrize(
    "name, shape",
    [
        ("tomasi-omni3", "cylinder"),
        ("omni4", "cylinder"),
        ("synchro", "cylinder"),
        ("xr4000", "cylinder"),
        ("diff-drive", "box"),
        ("ackermann", "box"),
        ("mecanum4", "box"),
    ],
)
def test_the_chassis_is_a_cylinder_for_wheels_evenly_on_a_circle_else_a_box(name, shape):
    robot = load_robot(name)
    chassis = describe(robot).chassis
    assert chassis.shape == shape
    x = [w.x for w in robot.wheels]
    y = [w.y for w in robot.wheels]
    if shape == "cylinder":
        assert chassis.size[0] == pytest.approx(math.hypot(x[0] - np.mean(x), y[0] - np.mean(y)))
    else:
        assert 2 * chassis.size[0] == pytest.approx(max(np.ptp(x), 2 * np.mean([w.radius for w in robot.rolling])))


def test_the_file_s_physical_fields_override_the_defaults():
    robot = load_robot("tomasi-omni3")
    wheels = list(robot.wheels)
    wheels[0] = replace(
        wheels[0], physical=PhysicalWheel(width=0.03, mass=0.25, rollers=5, rows=2, friction=0.6, max_torque=0.4)
    )
    built = replace(robot, wheels=tuple(wheels), physical=PhysicalBody(mass=3.0, com=(0.01, -0.02, 0.05), height=0.03))
    d = describe(built)
    assert d.chassis.mass == 3.0
    assert d.chassis.com == (0.01, -0.02, 0.05)
    assert d.chassis.size[1] == pytest.approx(0.015)
    w = d.wheels[0]
    assert (w.width, w.mass, w.friction, w.motor.max_torque) == (0.03, 0.25, 0.6, 0.4)
    assert (w.rollers.rows, w.rollers.per_row) == (2, 5)
    assert w.rollers.offsets == pytest.approx((-0.0075, 0.0075))  # rows spread evenly over the given width
    assert w.hub_mass + w.rollers.mass * 10 == pytest.approx(0.25)
    assert d.mass == pytest.approx(3.0 + 0.25 + 2 * d.wheels[1].mass)
    # the other wheels keep their defaults: rows in the mid-plane
    assert d.wheels[1].rollers.offsets == (0.0, 0.0)


def test_static_wheel_loads_balance_force_and_moment():
    contacts = np.array([[0.3, 0.0], [-0.1, 0.2], [-0.1, -0.25]])
    com = np.array([0.02, -0.01])
    loads = wheel_loads(contacts, com, 100.0)
    assert loads.sum() == pytest.approx(100.0)
    assert loads @ contacts == pytest.approx(100.0 * com)
    # symmetric layout: the even share
    square = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], dtype=float)
    assert wheel_loads(square, np.zeros(2), 40.0) == pytest.approx([10.0] * 4)


def test_default_torque_slips_the_wheel_under_its_share_of_the_weight():
    d = describe(load_robot("tomasi-omni3"))
    for w in d.wheels:  # symmetric layout: mu m g / 3 at the radius
        assert w.motor.max_torque == pytest.approx(1.0 * d.mass * 9.81 / 3 * w.radius)


def test_a_robot_on_one_axle_has_no_support_area():
    wheels = (
        Wheel("left", "standard", 0.0, 0.2, 0.0, 0.1, encoder=Encoder(100)),
        Wheel("right", "standard", 0.0, -0.2, 0.0, 0.1, encoder=Encoder(100)),
    )
    assert describe(Robot("segway", wheels)).support_margin == 0.0
    assert describe(load_robot("diff-drive")).support_margin > 0.05


def test_driven_wheels_are_the_encoded_ones_and_castors_are_passive():
    d = describe(load_robot("ackermann"))
    assert [w.name for w in d.driven] == ["rear_left", "rear_right"]
    assert [w.name for w in d.steered] == ["front_left", "front_right"]
    castor = describe(load_robot("diff-drive")).wheel("castor")
    assert castor.motor is None and not castor.steering.actuated and castor.steering.trail == 0.03


@pytest.mark.parametrize("name", ["diff-drive", "ackermann", "xr4000"])
def test_the_description_does_not_depend_on_the_order_of_the_wheels_in_the_file(name):
    """The file lists wheels in any order: the same robot with its wheels reversed (a castor or
    a steered wheel before a fixed one) has the same bodies, each fork a quarter of its wheel's
    mass (docs/physics.md, "Defaults"), and a total mass that is the sum of its parts."""
    robot = load_robot(name)
    reordered = replace(robot, wheels=tuple(reversed(robot.wheels)))
    ours, theirs = describe(robot), describe(reordered)
    assert theirs.mass == pytest.approx(ours.mass, rel=1e-12)
    forks = [w.steering.fork_mass for w in theirs.wheels if w.steering is not None]
    assert theirs.mass == pytest.approx(theirs.chassis.mass + sum(w.mass for w in theirs.wheels) + sum(forks))
    for body in theirs.wheels:
        mine = ours.wheel(body.name)
        assert body.mass == pytest.approx(mine.mass, rel=1e-12)
        if body.steering is not None:
            assert body.steering.fork_mass == pytest.approx(0.25 * body.mass, rel=1e-12)
            assert body.steering.inertia == pytest.approx(mine.steering.inertia, rel=1e-9)
            assert body.steering.damping == pytest.approx(mine.steering.damping, rel=1e-9)
    assert "<mujoco" in mjcf(reordered)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_mjcf_names_every_joint_and_actuator_after_the_wheels(name):
    robot = load_robot(name)
    root = ET.fromstring(mjcf(robot))
    joints = {j.get("name") for j in root.iter("joint")}
    assert set(robot.wheel_names) <= joints
    assert {f"{n}_steer" for n in robot.steer_names} <= joints
    actuators = {a.get("name"): a for a in root.find("actuator")}
    driven = [w.name for w in describe(robot).driven]
    assert sorted(actuators) == sorted(driven + [f"{n}_steer" for n in robot.steer_names])
    for n in driven:
        motor = describe(robot).wheel(n).motor
        assert [float(v) for v in actuators[n].get("forcerange").split()] == pytest.approx(
            [-motor.max_torque, motor.max_torque]
        )
    assert root.find("option").get("integrator") == "implicitfast"
    assert root.find("option").get("timestep") == "0.002"


def test_mjcf_escapes_the_robot_name():
    hostile = 'a"<b>&c\'</mujoco><x y="'
    robot = replace(load_robot("tomasi-omni3"), name=hostile)
    root = ET.fromstring(mjcf(robot))
    assert root.get("model") == hostile
    assert root.tag == "mujoco" and root.find("x") is None


def test_the_description_and_the_mjcf_work_without_mujoco():
    code = (
        "import sys\n"
        "sys.modules['mujoco'] = None  # importing it now fails\n"
        "from omnikin import load_robot\n"
        "from omnikin.physics.mjcf import mjcf\n"
        "print(len(mjcf(load_robot('mecanum4'))))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=omnikin_env(), timeout=60)
    assert out.returncode == 0, out.stderr
    assert int(out.stdout) > 1000


def test_a_time_step_out_of_range_is_refused():
    from omnikin.errors import InputError

    # 3 and 4 ms: more than half the contacts' 4 ms time constant, which MuJoCo would lengthen
    for step in (0.0, -0.001, 0.01, 0.004, 0.003, float("nan"), "0.002", True):
        with pytest.raises(InputError, match="time step"):
            mjcf(load_robot("diff-drive"), step)
    assert "<option" in mjcf(load_robot("diff-drive"), 0.002)


def test_a_robot_file_s_physical_fields_reach_the_model(tmp_path):
    path = tmp_path / "built.yaml"
    path.write_text(
        "omnikin: 1\n"
        "name: built\n"
        "physical: {mass: 2.5, com: [0.0, 0.01, 0.06], height: 0.02}\n"
        "wheels:\n"
        "  - {name: a, type: omni, distance: 0.15, angle_deg: 0, radius: 0.04,\n"
        "     physical: {width: 0.03, mass: 0.12, rollers: 7, rows: 2, friction: 0.8, max_torque: 0.4}}\n"
        "  - {name: b, type: omni, distance: 0.15, angle_deg: 120, radius: 0.04}\n"
        "  - {name: c, type: omni, distance: 0.15, angle_deg: 240, radius: 0.04}\n"
    )
    d = describe(load_robot(path))
    assert (d.chassis.mass, d.chassis.com, 2 * d.chassis.size[1]) == (2.5, (0.0, 0.01, 0.06), pytest.approx(0.02))
    a = d.wheel("a")
    assert (a.width, a.mass, a.friction, a.motor.max_torque) == (0.03, 0.12, 0.8, 0.4)
    assert (a.rollers.rows, a.rollers.per_row) == (2, 7)
    root = ET.fromstring(mjcf(d))
    assert len([b for b in root.iter("body") if b.get("name", "").startswith("a:roller:")]) == 14
    geom = next(g for g in root.iter("geom") if g.get("name") == "a:roller:1:6")
    assert geom.get("friction").split()[0] == "0.8"
