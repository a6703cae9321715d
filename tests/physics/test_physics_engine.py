"""The robot stepped in MuJoCo (omnikin.physics.simulator.PhysicsSim): rest, the motions of
Garcia-Sillas et al., commanded against simulated twists, encoders. Expected values come from
the kinematics (Robot.fk of the commanded wheel speeds) and closed forms, never from the engine.

Tolerances: the twist is compared as ``(vx, vy, l omega)``, ``l`` the largest wheel distance
from the body origin, so that linear and angular errors weigh alike; averaged over 2 s after
0.5 s of ramp."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco", reason="the physics engine needs MuJoCo (extra 'physics')")

from omnikin import Encoder, Robot, Wheel, load_robot  # noqa: E402
from omnikin.errors import InputError  # noqa: E402
from omnikin.kinematics.se2 import wrap_angle  # noqa: E402
from omnikin.physics.description import describe, steered_support_margin  # noqa: E402
from omnikin.physics.simulator import TIPPED, PhysicsSim  # noqa: E402
from omnikin.presets import PRESET_NAMES  # noqa: E402

RAMP = 0.5
WINDOW = 2.0


def lever(robot) -> float:
    return max(math.hypot(w.x, w.y) for w in robot.wheels)


def scaled(robot, twist):
    t = np.asarray(twist, dtype=float)
    return np.array([t[0], t[1], lever(robot) * t[2]])


def drive(sim: PhysicsSim, speeds, steer=None, every: int = 5, settle: float = RAMP):
    """Command, wait ``settle`` [s] or until the ramp has reached the command if later, then
    sample the twist and pose over the window."""
    sim.command(speeds, steer)
    sim.advance(sim.time + settle)
    while sim.ramping:
        sim.step(every)
    start = sim.time
    twists, poses = [], [sim.pose]
    while sim.time < start + WINDOW - 1e-9:
        sim.step(every)
        twists.append(sim.twist)
        poses.append(sim.pose)
    return np.mean(twists, axis=0), np.array(poses)


def relative_error(robot, measured, expected) -> float:
    return float(
        np.linalg.norm(scaled(robot, measured) - scaled(robot, expected)) / np.linalg.norm(scaled(robot, expected))
    )


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_every_preset_loads_and_rests_without_bouncing_or_drifting(name):
    robot = load_robot(name)
    sim = PhysicsSim(robot)
    assert mujoco.MjModel.from_xml_string(sim.xml).nbody == sim.model.nbody
    assert sim.time == 0.0 and sim.pose == pytest.approx([0, 0, 0], abs=1e-12)
    heights = []
    for _ in range(100):  # 2 s
        sim.step(10)
        heights.append(sim.height)
    r = min(w.radius for w in robot.wheels)
    assert np.ptp(heights) < 1e-5 * r  # no bounce
    assert abs(np.mean(heights)) < 1e-3 * r  # at its design height, within 0.1 % of the radius
    assert np.hypot(*sim.pose[:2]) < 1e-5 and abs(sim.pose[2]) < 2e-5  # no drift
    assert np.abs(sim.wheel_angles).max() < 1e-4


def test_wheel_one_at_rest_and_the_others_opposite_drive_a_straight_line():
    """Garcia-Sillas et al., the first motion: wheels 2 and 3 equal and opposite, wheel 1 at rest."""
    robot = load_robot("tomasi-omni3")
    speeds = np.array([0.0, 6.0, -6.0])
    expected = robot.fk(speeds).twist
    assert abs(expected[2]) < 1e-12 and abs(expected[1]) < 1e-12  # the kinematics: along -x
    assert expected[0] < 0
    sim = PhysicsSim(robot)
    twist, poses = drive(sim, speeds)
    assert relative_error(robot, twist, expected) < 0.005
    path = poses[:, :2] - poses[0, :2]
    heading = path[-1] / np.linalg.norm(path[-1])
    assert heading == pytest.approx([-1.0, 0.0], abs=0.005)
    side = path[:, 0] * heading[1] - path[:, 1] * heading[0]
    assert np.abs(side).max() < 0.005 * np.linalg.norm(path[-1])  # a straight line
    assert abs(poses[-1, 2] - poses[0, 2]) < 0.005


def test_three_equal_wheel_speeds_turn_the_robot_on_the_spot():
    """Garcia-Sillas et al., the second motion: all three wheels at the same speed."""
    robot = load_robot("tomasi-omni3")
    speeds = np.array([5.0, 5.0, 5.0])
    expected = robot.fk(speeds).twist
    assert expected[:2] == pytest.approx([0, 0], abs=1e-12)
    sim = PhysicsSim(robot)
    twist, poses = drive(sim, speeds)
    assert relative_error(robot, twist, expected) < 0.005
    turned = poses[-1, 2] - poses[0, 2]
    assert turned == pytest.approx(expected[2] * WINDOW, rel=0.005)
    assert np.hypot(*(poses[:, :2] - poses[0, :2]).T).max() < 1e-3  # the centre stays put


def effective_mecanum(robot, per_row: int):
    """The robot whose rollers have the angle a mecanum wheel shows on average: the roller axis
    tilts out of the floor by the wheel angle phi, so the contact cannot slip along a direction
    with tan(gamma') = tan(gamma) / cos(phi); averaged over the hand-over interval
    |phi| <= pi / n: k = mean(sec phi) = ln(sec(pi/n) + tan(pi/n)) / (pi/n)."""
    half = math.pi / per_row
    k = math.log(1 / math.cos(half) + math.tan(half)) / half
    return Robot("effective", tuple(replace(w, roller=math.atan(k * math.tan(w.roller))) for w in robot.wheels)), k


@pytest.mark.parametrize("twist", [(0.0, 0.3, 0.0), (0.3, 0.0, 0.0), (0.0, 0.0, 1.0)])
def test_mecanum4_strafes_as_its_inclined_rollers_say(twist):
    robot = load_robot("mecanum4")
    rows = describe(robot).wheels[0].rollers
    assert rows.rows == 1
    effective, k = effective_mecanum(robot, rows.per_row)
    speeds = robot.ik(twist).wheel_speeds
    measured, _ = drive(PhysicsSim(robot), speeds)
    assert relative_error(robot, measured, effective.fk(speeds).twist) < 0.002
    if twist[1]:  # strafing: 1/k of the kinematic speed (1.2 % slower with 12 rollers)
        assert measured[1] == pytest.approx(twist[1] / k, rel=0.002)
        assert abs(measured[1] - twist[1]) > 0.005 * twist[1]


def test_a_differential_drive_does_not_strafe():
    robot = load_robot("diff-drive")
    commanded = (0.3, 0.0, 0.6)
    speeds = robot.ik(commanded).wheel_speeds
    measured, poses = drive(PhysicsSim(robot), speeds)
    assert relative_error(robot, measured, commanded) < 0.005
    assert abs(measured[1]) < 0.005 * commanded[0]  # no sideways motion on the arc
    # on the spot: turns about the axle's middle
    sim = PhysicsSim(robot)
    measured, poses = drive(sim, robot.ik((0.0, 0.0, 1.0)).wheel_speeds)
    assert measured == pytest.approx([0.0, 0.0, 1.0], abs=0.005)
    assert np.hypot(*(poses[:, :2] - poses[0, :2]).T).max() < 2e-3


SPEED = 0.3
"""Speed [m/s] of the validation motions; turn rates are given as rim speeds ``l omega``."""
CANDIDATES = {
    "forward": (1.0, 0.0, 0.0),
    "sideways": (0.0, 1.0, 0.0),
    "arc": (0.6, 0.0, 0.25),
    "combined": (0.6, 0.3, 0.25),
    "turning": (0.0, 0.0, 1.0),
}
"""Validation motions in units of ``SPEED`` on the scaled twist ``(vx, vy, l omega)``."""
STEERED = 0.01
"""Steering error [rad] below which the steering counts as set."""


def validation_motions(robot):
    """The candidate motions ``(label, twist, ik)`` the robot can make, and those its fixed wheels
    forbid (side slip of a fixed wheel, every steering within its limits): commanded with the
    inverse kinematics' wheel speeds, those show that the robot does not slide sideways."""
    out = []
    for label, (a, b, c) in CANDIDATES.items():
        twist = SPEED * np.array([a, b, c / lever(robot)])
        ik = robot.ik(twist, on_infeasible="return")
        if not np.any(ik.steer_limited):
            out.append((label, twist, ik))
    return out


TOLERANCE = 0.005
"""Validation tolerance: scaled twists within 0.5 % of the kinematics."""


def kinematic_reference(robot):
    """The kinematics the physics is held to: the robot itself, or for inclined rollers
    (mecanum) the robot of their effective roller angle (the closed form of
    :func:`effective_mecanum`)."""
    if not any(w.is_swedish and w.roller != 0.0 for w in robot.wheels):
        return robot
    rows = describe(robot).wheels[0].rollers
    assert rows is not None and rows.rows == 1
    return effective_mecanum(robot, rows.per_row)[0]


def steer_first(sim: PhysicsSim, steer) -> None:
    """Wheels standing, steering to ``steer`` [rad], until it is set and the robot at rest (5 s)."""
    stop = np.zeros(len(sim.robot.rolling))
    sim.command(stop, steer)
    end = sim.time + 5.0
    while sim.time < end:
        sim.advance(sim.time + 0.1)
        error = np.abs(wrap_angle(sim.steer_angles - np.asarray(steer)))
        if error.max() < STEERED and np.abs(sim.twist).max() < 1e-4 and not sim.ramping:
            return
    raise AssertionError(f"steering not set within 5 s: error {error.max():.3g} rad")


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_every_preset_drives_its_motions_as_its_kinematics_say(name):
    """Every preset, every motion its mobility allows (forward, sideways, an arc, combined with a
    turn, turning on the spot: whichever the inverse kinematics can steer), commanded from rest
    with the steering set first, against the forward kinematics of the commanded wheel speeds and
    steering, within 0.5 % (mecanum: of its inclined rollers' closed form). Motions a
    fixed wheel forbids are commanded too: the robot makes the part its wheels allow and does not
    slide sideways (a differential drive does not strafe). A steering whose contacts do not
    surround the centre of mass (villasenor-omni3's legs swung sideways) must tip the robot over."""
    robot = load_robot(name)
    reference = kinematic_reference(robot)
    motions = validation_motions(robot)
    assert {label for label, _, ik in motions if np.all(ik.feasible)} >= {"forward"}
    if not robot.fixed:  # holonomic or steered into any direction
        assert {label for label, *_ in motions} >= {"forward", "sideways"}
    for label, _, ik in motions:
        sim = PhysicsSim(robot)  # from rest (a shared model would keep its free rollers' spin)
        steer = ik.steer_angles if robot.steerable else None
        if steer is not None and steered_support_margin(robot, describe(robot).com, steer) <= 0.0:
            sim.command(np.zeros(len(robot.rolling)), steer)  # its contacts there cannot carry it
            tilt = 0.0
            for _ in range(40):
                sim.advance(sim.time + 0.05)
                tilt = max(tilt, sim.tilt)
            assert tilt > TIPPED, f"{name} {label}: stands where its contacts do not surround its weight"
            continue
        if steer is not None:
            steer_first(sim, steer)
        expected = reference.fk(ik.wheel_speeds, steer).twist
        if np.linalg.norm(scaled(robot, expected)) < 1e-9:  # all wheels stand: so does the robot
            sim.command(ik.wheel_speeds, steer)
            sim.advance(sim.time + RAMP + WINDOW)
            assert np.hypot(*sim.twist[:2]) < 1e-3 and abs(sim.twist[2]) * lever(robot) < 1e-3, label
            continue
        measured, _ = drive(sim, ik.wheel_speeds, steer)
        error = relative_error(robot, measured, expected)
        assert error < TOLERANCE, f"{name} {label}: {100 * error:.3g} % from the kinematics"
        if not np.all(ik.feasible):  # the fixed wheels' part of the motion, no sideways slip
            assert abs(measured[1] - expected[1]) < TOLERANCE * SPEED, f"{name} {label}: slides sideways"


@pytest.mark.parametrize("turn", [math.pi / 2, -math.pi / 3])
def test_off_centred_wheels_steered_at_rest_carry_the_chassis_along(turn):
    """xr4000's wheels trail their steering axes by ``d``; steered at rest with the wheels held,
    a contact cannot slide sideways, so the axis swings about it: with every wheel turned alike
    the body moves ``d (cos(beta) - 1, sin(beta))`` (no-slip condition of an off-centred wheel,
    ``n . v_p = d (omega + beta')``, Campion, Bastin and d'Andrea-Novel, with ``omega = 0``).
    The encoders see none of it: steering before driving moves the robot off its odometry."""
    robot = load_robot("xr4000")
    d = robot.wheels[0].offset
    sim = PhysicsSim(robot)
    steer_first(sim, np.full(4, turn))
    assert sim.pose[:2] == pytest.approx(d * np.array([math.cos(turn) - 1.0, math.sin(turn)]), abs=0.03 * d)
    assert abs(sim.pose[2]) < 1e-3
    assert np.abs(sim.wheel_angles).max() < 0.01  # held: the wheels did not roll


def test_encoder_ticks_are_the_joint_angles_in_whole_ticks():
    robot = load_robot("tomasi-omni3")
    sim = PhysicsSim(robot)
    assert sim.encoder_ticks().tolist() == [0, 0, 0]
    speeds = np.array([4.0, -3.0, 2.0])
    sim.command(speeds)
    sim.advance(1.0)
    rpt = 2 * math.pi / 600
    ticks = sim.encoder_ticks()
    assert ticks.dtype == np.int64
    assert np.abs(ticks * rpt - sim.wheel_angles).max() <= rpt / 2
    # about the commanded turns: the wheels ramp together over t_r = max |w| / alpha, so each
    # turns w (1 s - t_r / 2)
    ramp_time = np.abs(speeds).max() / describe(robot).wheels[0].motor.max_accel
    assert ticks * rpt == pytest.approx(speeds * (1.0 - ramp_time / 2.0), rel=0.02)


def test_encoder_counters_wrap_and_invert_like_the_hardware():
    robot = load_robot("tomasi-omni3")
    wheels = [replace(w, encoder=Encoder(600, counter_bits=8, invert=(i == 1))) for i, w in enumerate(robot.wheels)]
    sim = PhysicsSim(replace(robot, wheels=tuple(wheels)))
    sim.command([6.0, 6.0, -6.0])
    sim.advance(1.0)
    counts = np.rint(sim.wheel_angles / (2 * math.pi / 600) * np.array([1, -1, 1])).astype(np.int64)
    assert np.abs(counts).min() > 256  # the counters did wrap
    assert sim.encoder_ticks().tolist() == (counts % 256).tolist()


def test_a_step_command_is_ramped_at_the_motors_acceleration_limit():
    robot = load_robot("tomasi-omni3")
    sim = PhysicsSim(robot)
    accel = describe(robot).wheels[0].motor.max_accel
    sim.command([20.0, 20.0, 20.0])
    sim.step(10)
    assert np.abs(sim.wheel_speeds).max() <= accel * sim.time * 1.05
    sim.advance(20.0 / accel + 0.3)
    assert sim.wheel_speeds == pytest.approx([20.0] * 3, rel=1e-3)


def test_the_simulation_starts_settled_at_the_start_pose():
    robot = load_robot("diff-drive")
    sim = PhysicsSim(robot, start=(1.0, -2.0, 2.5))
    assert sim.pose == pytest.approx([1.0, -2.0, 2.5], abs=1e-12)
    sim.command(robot.ik((0.2, 0.0, 0.0)).wheel_speeds)
    sim.advance(1.0)
    moved = sim.pose[:2] - np.array([1.0, -2.0])
    assert moved / np.linalg.norm(moved) == pytest.approx([math.cos(2.5), math.sin(2.5)], abs=2e-3)


def test_wrong_commands_and_robots_that_cannot_stand_are_refused():
    robot = load_robot("ackermann")
    sim = PhysicsSim(robot)
    with pytest.raises(InputError, match="expected 4 finite wheel speeds"):
        sim.command([1.0, 1.0])
    with pytest.raises(InputError, match="expected 2 finite steering angles"):
        sim.command([1.0] * 4, [0.1, float("nan")])
    segway = Robot(
        "segway",
        (
            Wheel("left", "standard", 0.0, 0.2, 0.0, 0.1, encoder=Encoder(100)),
            Wheel("right", "standard", 0.0, -0.2, 0.0, 0.1, encoder=Encoder(100)),
        ),
    )
    with pytest.raises(InputError, match="cannot stand"):
        PhysicsSim(segway)
    for n in (-1, 1.5, True, "2"):
        with pytest.raises(InputError, match="whole number"):
            sim.step(n)
    with pytest.raises(InputError, match="finite"):
        sim.advance(float("nan"))
    with pytest.raises(InputError, match="physical description has wheels"):
        PhysicsSim(robot, description=describe(load_robot("diff-drive")))


def test_commands_beyond_the_motor_limits_are_held_there_and_counted():
    """A wheel speed beyond the motor's speed limit is held at the limit (as a motor would) and
    the command is counted in ``saturated`` (and the back-end's stats), never silently."""
    from omnikin.physics.backend import PhysicsBackend
    from omnikin.physics.simulator import PhysicsSim

    robot = load_robot("tomasi-omni3")
    sim = PhysicsSim(robot)
    limit = 3.0 / robot.wheels[0].radius  # the default motor speed: a rim speed of 3 m/s
    sim.command([0.5 * limit, 0.0, 0.0])
    assert sim.saturated == 0
    sim.command([2.0 * limit, 0.0, 0.0])
    assert sim.saturated == 1
    backend = PhysicsBackend(robot)
    backend.write(0.0, [0.0, 2.0 * limit, 0.0])
    assert backend.stats()["saturated"] == 1
