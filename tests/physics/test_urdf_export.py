"""The URDF export (omnikin.physics.urdf, ``omnikin urdf``) read by two independent parsers,
urdf_parser_py (ROS's Python parser) and MuJoCo's URDF import, for every preset: the tree,
joint names and types, hub positions and axle directions are checked against the robot file's
geometry (hub = mounting point minus the steering offset along the drive direction, at the
height of the radius; axle = z x drive direction), not only that it parses."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from urdf_parser_py.urdf import URDF

from omnikin import Robot, Wheel, load_robot
from omnikin.physics.description import describe
from omnikin.physics.urdf import urdf
from omnikin.presets import PRESET_NAMES
from support.cli import run_cli


def rpy_matrix(rpy) -> np.ndarray:
    """URDF's fixed-axis roll-pitch-yaw: ``Rz(yaw) Ry(pitch) Rx(roll)`` (the URDF specification)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def link_frames(model) -> dict:
    """World pose ``(R, p)`` of every link at zero joint angles, composed from the parsed joints."""
    frames = {model.get_root(): (np.eye(3), np.zeros(3))}
    by_child = {j.child: j for j in model.joints}
    pending = [j.child for j in model.joints]
    while pending:
        child = pending.pop(0)
        joint = by_child[child]
        if joint.parent not in frames:
            pending.append(child)
            continue
        rot, pos = frames[joint.parent]
        origin = joint.origin
        frames[child] = (rot @ rpy_matrix(origin.rpy), pos + rot @ np.array(origin.xyz))
    return frames


def expected_hub(w: Wheel) -> np.ndarray:
    trail = w.offset if (w.is_steerable or w.is_castor) else 0.0
    return np.array([w.x - trail * math.cos(w.drive), w.y - trail * math.sin(w.drive), w.radius])


def expected_axle(w: Wheel) -> np.ndarray:
    return np.array([-math.sin(w.drive), math.cos(w.drive), 0.0])


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_urdf_parser_reads_the_tree_hubs_axles_and_rollers_of_every_preset(name):
    robot = load_robot(name)
    model = URDF.from_xml_string(urdf(robot))
    joints = {j.name: j for j in model.joints}
    assert model.get_root() == "base_link"
    frames = link_frames(model)
    assert set(frames) == {link.name for link in model.links}  # one tree, every link reached
    # what the ROS node publishes in joint_states: encoded wheels and NAME_steer of steerable ones
    published = set(robot.encoded_names) | {f"{n}_steer" for n in robot.steer_names}
    assert published <= set(joints)
    massive = [link for link in model.links if link.inertial is not None]  # a sensor's link has no mass
    assert sum(link.inertial.mass for link in massive) == pytest.approx(describe(robot).mass, rel=1e-12)
    for w in robot.wheels:
        joint = joints[w.name]
        assert joint.type == "continuous"
        rot, pos = frames[joint.child]
        np.testing.assert_allclose(pos, expected_hub(w), atol=1e-12)
        np.testing.assert_allclose(rot @ np.array(joint.axis), expected_axle(w), atol=1e-12)
        if w.is_steerable or w.is_castor:
            steer = joints[f"{w.name}_steer"]
            assert (steer.parent, joint.parent) == ("base_link", steer.child)
            np.testing.assert_allclose(frames[steer.child][0] @ np.array(steer.axis), (0.0, 0.0, 1.0), atol=1e-12)
            np.testing.assert_allclose(frames[steer.child][1], (w.x, w.y, w.radius), atol=1e-12)
            limited = w.steer is not None and (w.steer.lower > -math.pi + 1e-9 or w.steer.upper < math.pi - 1e-9)
            if limited:
                assert steer.type == "revolute"
                assert (steer.limit.lower, steer.limit.upper) == pytest.approx((w.steer.lower, w.steer.upper))
            else:
                assert steer.type == "continuous"
        else:
            assert joint.parent == "base_link"
        rollers = [j for j in model.joints if j.parent == joint.child]
        if not w.is_swedish:
            assert rollers == []
            continue
        body = describe(robot).wheel(w.name).rollers
        assert len(rollers) == body.rows * body.per_row >= 6
        assert all(j.type == "continuous" for j in rollers)
        # the roller at the bottom (row 0, index 0) lies along delta + gamma on the floor, its
        # collision sphere touching the floor within the height ripple
        bottom = joints[f"{w.name}_roller_0_0"]
        r_bottom, p_bottom = frames[bottom.child]
        direction = rot @ np.array(bottom.axis)
        np.testing.assert_allclose(
            direction, (math.cos(w.drive + w.roller), math.sin(w.drive + w.roller), 0.0), atol=1e-12
        )
        sphere = next(c for c in model.link_map[bottom.child].collisions if hasattr(c.geometry, "radius"))
        assert abs(p_bottom[2] - sphere.geometry.radius) <= 0.01 * w.radius


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_mujoco_imports_the_urdf_with_hubs_and_axles_where_the_file_puts_them(name):
    robot = load_robot(name)
    model = mujoco.MjModel.from_xml_string(urdf(robot))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    for w in robot.wheels:
        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"{w.name}_wheel")
        joint = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, w.name)
        assert body >= 0 and joint >= 0 and model.jnt_bodyid[joint] == body
        assert model.jnt_type[joint] == mujoco.mjtJoint.mjJNT_HINGE
        np.testing.assert_allclose(data.xpos[body], expected_hub(w), atol=1e-9)
        np.testing.assert_allclose(data.xaxis[joint], expected_axle(w), atol=1e-9)
        parent = model.body(model.body_parentid[body]).name
        assert parent == (f"{w.name}_fork" if (w.is_steerable or w.is_castor) else "world")  # base_link fused
    swedish = describe(robot)
    rollers = sum(len(b.rollers.rollers) for b in swedish.wheels if b.rollers is not None)
    steer = sum(1 for w in robot.wheels if w.is_steerable or w.is_castor)
    assert model.njnt == len(robot.wheels) + steer + rollers
    # base_link, fixed to the world, is fused into it: the moving parts carry the rest of the mass
    assert float(np.sum(model.body_mass)) == pytest.approx(swedish.mass - swedish.chassis.mass, rel=1e-9)


def test_urdf_refuses_a_wheel_name_that_meets_a_generated_link_name():
    a = Wheel("w", "omni", 0.2, 0.0, math.pi / 2, 0.05)
    b = Wheel("w_roller_0_1", "omni", -0.1, 0.17, math.pi / 2 + 2.09, 0.05)
    c = Wheel("c", "omni", -0.1, -0.17, math.pi / 2 - 2.09, 0.05)
    with pytest.raises(ValueError, match="two joints named 'w_roller_0_1'"):
        urdf(Robot("clash", (a, b, c)))


def test_urdf_command_writes_the_file_through_the_output_policy(tmp_path, capsys):
    out = tmp_path / "robot.urdf"
    rc, _, err = run_cli(capsys, "urdf", "ackermann", "-o", out)
    assert rc == 0, err
    assert URDF.from_xml_string(out.read_text()).name == "ackermann"
    rc, _, err = run_cli(capsys, "urdf", "ackermann", "-o", out)
    assert rc == 2 and "--force" in err and err.count("\n") == 1
    rc, text, err = run_cli(capsys, "urdf", "diff-drive", "-o", "-")
    assert rc == 0 and text.startswith("<?xml") and URDF.from_xml_string(text).name == "diff-drive"


def test_mjcf_command_writes_a_model_mujoco_loads_with_the_given_step(tmp_path, capsys):
    out = tmp_path / "robot.xml"
    rc, _, err = run_cli(capsys, "mjcf", "tomasi-omni3", "-o", out, "--step", "0.001")
    assert rc == 0, err
    model = mujoco.MjModel.from_xml_path(str(out))
    assert model.opt.timestep == 0.001
    assert {model.actuator(i).name for i in range(model.nu)} == set(load_robot("tomasi-omni3").encoded_names)
    rc, _, err = run_cli(capsys, "mjcf", "tomasi-omni3", "-o", tmp_path / "fast.xml", "--step", "0.01")
    assert rc == 2 and "time step" in err and err.count("\n") == 1
    assert not (tmp_path / "fast.xml").exists()


def test_each_imu_and_lidar_is_a_fixed_link_of_base_link_at_its_mount():
    robot = load_robot("tomasi-omni3-lidar")
    model = URDF.from_xml_string(urdf(robot))
    frames = link_frames(model)
    mounts = {s.name: s.mount for s in robot.sensors if s.type in ("imu", "lidar")}
    assert set(mounts) == {"imu", "laser"}  # the bumper has no frame
    joints = {j.name: j for j in model.joints}
    for name, m in mounts.items():
        joint = joints[f"{name}_joint"]
        assert joint.type == "fixed" and joint.parent == "base_link" and joint.child == name
        rot, pos = frames[name]
        np.testing.assert_allclose(pos, [m.x, m.y, m.z], atol=1e-12)
        np.testing.assert_allclose(rot[:2, 0], [math.cos(m.yaw), math.sin(m.yaw)], atol=1e-12)
    assert "imu" not in urdf(describe(robot))  # a description alone carries no sensors
