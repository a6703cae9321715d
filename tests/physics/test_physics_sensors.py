"""What the IMU and lidar read in the physics engine: the scan against closed-form distances
from the chassis' true pose, the gyro's rates summing to the true heading change, the
accelerometer's gravity at rest and centripetal force on a circle, the errors from the seed."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics engine needs MuJoCo (extra 'physics')")

from omnikin import load_robot  # noqa: E402
from omnikin.api import simulate  # noqa: E402
from omnikin.kinematics.sensors import Imu, Lidar, Mount  # noqa: E402
from omnikin.physics.simulator import PhysicsSim  # noqa: E402
from omnikin.world import Box, Cylinder, Wall, make_world  # noqa: E402
from support.rooms import to_faces  # noqa: E402

HALF, THICK = 2.0, 0.1
FACE = HALF - THICK / 2
LIDAR = Lidar("laser", Mount(0.05, -0.02, 0.12, math.radians(30)), rate=10.0, beams=720, range_max=12.0)
IMU = Imu("imu", Mount(0.04, 0.03, 0.06, math.radians(90)), rate=200.0)  # 2.5 time steps of 2 ms apart


def _robot():
    base = load_robot("tomasi-omni3")
    return dataclasses.replace(base, name="tomasi-omni3-sensed", sensors=(IMU, LIDAR))


def _world(start):
    square = ((-HALF, -HALF), (HALF, -HALF), (HALF, HALF), (-HALF, HALF), (-HALF, -HALF))
    return make_world(
        "room",
        start=start,
        walls=[Wall(square, THICK, height=0.5)],
        obstacles=[Cylinder((1.0, 1.0), 0.2, height=0.5), Box((-1.0, 1.0), (0.3, 0.3, 0.1))],
    )


def _cylinder(ox: float, oy: float, angles: np.ndarray) -> np.ndarray:
    """Distances from ``(ox, oy)`` along ``angles`` to the cylinder of radius 0.2 m at (1, 1)
    (the near root of the ray's quadratic; ``inf`` where it misses)."""
    ca, sa = np.cos(angles), np.sin(angles)
    dx, dy = ox - 1.0, oy - 1.0
    b = dx * ca + dy * sa
    disc = b * b - (dx * dx + dy * dy - 0.2**2)
    near = -b - np.sqrt(np.maximum(disc, 0.0))
    return np.where((disc >= 0) & (near > 0), near, np.inf)


def _expected(pose) -> np.ndarray:
    """Ranges from the lidar at ``pose`` to the room's faces and the cylinder (the 0.1 m box lies
    below the 0.12 m beams), by hand."""
    x, y, th = pose
    c, s = math.cos(th), math.sin(th)
    m = LIDAR.mount
    ox, oy = x + c * m.x - s * m.y, y + s * m.x + c * m.y
    angles = th + m.yaw + LIDAR.angles()
    return np.minimum(to_faces(ox, oy, angles, FACE), _cylinder(ox, oy, angles))


def test_scans_read_the_distances_from_the_true_pose_to_the_walls_and_the_cylinder():
    robot = _robot()
    start = (0.3, -0.2, 0.4)
    sim = PhysicsSim(robot, start=start, world=_world(start), sensors=True)
    poses = [sim.pose]
    sim.command(robot.ik((0.3, 0.1, 0.8)).wheel_speeds)
    for k in range(1, 6):  # scans every 0.1 s: 50 whole time steps
        sim.advance(k * 0.1)
        poses.append(sim.pose)
    truth = sim.sensors.truths()["laser"]
    np.testing.assert_array_equal(truth.t, np.arange(6) / 10.0)
    # at rest on the start pose: to MuJoCo's ray precision
    np.testing.assert_allclose(truth.ranges[0], _expected(poses[0]), rtol=0, atol=1e-9)
    # moving: the chassis pitches and rolls a little on its soft contacts, which tilts the beams
    # (a tilt t lengthens a 2 m range by 2 (1 / cos t - 1): under 0.1 mm for t < 0.01 rad)
    for k in range(1, 6):
        np.testing.assert_allclose(truth.ranges[k], _expected(poses[k]), rtol=0, atol=2e-4)
    assert np.max(np.abs(np.array(poses)[-1, :2] - start[:2])) > 0.1  # it did move


def test_the_gyro_sums_to_the_true_heading_change_and_the_accelerometer_reads_gravity_at_rest():
    robot = _robot()
    sim = PhysicsSim(robot, sensors=True)
    sim.advance(0.5)
    rest = sim.sensors.truths()["imu"]
    assert len(rest.t) == 100 and rest.t[-1] == pytest.approx(0.5, abs=1e-12)
    np.testing.assert_allclose(rest.rates, 0.0, atol=1e-6)
    np.testing.assert_allclose(rest.forces, [[0.0, 0.0, 9.81]] * 100, atol=2e-3)
    headings = [sim.pose[2]]
    sim.command(robot.ik((0.0, 0.0, 1.5)).wheel_speeds)
    for k in range(1, 21):  # every 0.05 s: 25 whole steps, a whole number of 200 Hz samples
        sim.advance(0.5 + k * 0.05)
        headings.append(sim.pose[2])
    spin = sim.sensors.truths()["imu"]
    dt = 1.0 / 200.0
    turned = np.cumsum(spin.rates[100:, 2]) * dt  # the readings are mean rates over their intervals
    np.testing.assert_allclose(turned[9::10], np.array(headings[1:]) - headings[0], rtol=0, atol=1e-9)
    assert headings[-1] - headings[0] > 0.5


def test_on_a_circle_the_accelerometer_reads_the_centripetal_force_towards_the_centre():
    robot = _robot()
    sim = PhysicsSim(robot, sensors=True)
    v, w = 0.25, 0.8
    sim.command(robot.ik((v, 0.0, w)).wheel_speeds)
    sim.advance(2.0)  # up to speed (the motors ramp within 0.5 s)
    p0 = sim.pose
    sim.advance(4.0)
    p1 = sim.pose
    imu = sim.sensors.truths()["imu"]
    late = imu.t > 2.0
    # the true mean turn rate, from the ground truth; the speed from the chord of the arc it drove
    omega = (p1[2] - p0[2]) / 2.0
    speed = math.dist(p0[:2], p1[:2]) * omega / (2.0 * math.sin(omega))
    # the IMU sits at p = (0.04, 0.03) in the body frame, its x axis along body y (yaw 90 deg);
    # the body turns at omega and moves at speed along x: the mount point's specific force is
    # omega x (v + omega x p) = (-omega^2 p_x, omega speed - omega^2 p_y) in body axes
    px, py = 0.04, 0.03
    body = np.array([-(omega**2) * px, omega * speed - omega**2 * py])
    sensor = np.array([body[1], -body[0]])  # body axes turned by -90 deg
    mean = imu.forces[late].mean(axis=0)
    np.testing.assert_allclose(mean[:2], sensor, rtol=0, atol=0.01 * abs(omega * speed))
    assert mean[2] == pytest.approx(9.81, abs=2e-3)
    assert imu.rates[late, 2].mean() == pytest.approx(omega, rel=1e-3)


def test_physics_readings_carry_the_sensor_errors_of_the_seed_and_repeat_bit_for_bit():
    robot = load_robot("tomasi-omni3-lidar")

    def readings(seed):
        run = simulate(robot, "line 0.2", engine="physics", seed=seed).run
        return run.sensing

    a, b, c = readings(5), readings(5), readings(6)
    assert a is not None and b is not None and c is not None
    assert [r.sensor.name for r in a.imus] == ["imu"] and [r.sensor.name for r in a.scans] == ["laser"]
    np.testing.assert_array_equal(a.imus[0].gyro, b.imus[0].gyro)
    np.testing.assert_array_equal(a.scans[0].ranges, b.scans[0].ranges)
    assert not np.array_equal(a.imus[0].gyro, c.imus[0].gyro)
    # the preset's gyro bias (0.005 rad/s) and noise shows: at rest before the run starts moving
    # the readings are not the exact zero the truth gives
    assert np.std(a.imus[0].gyro[:, 2]) > 1e-4
    assert np.all(np.isposinf(a.scans[0].ranges) | np.isnan(a.scans[0].ranges))  # an empty floor


def test_readings_drained_cycle_by_cycle_are_the_run_read_at_once_and_an_undrained_backlog_stays_bounded():
    """A live robot's sensors are drained each cycle: the pieces put together are what the
    same simulation kept whole; one that nobody drains keeps only its latest ``keep`` seconds."""
    robot = _robot()
    whole, pieces, bounded = (PhysicsSim(robot, sensors=keep) for keep in (True, True, 0.5))
    drained = []
    command = robot.ik((0.2, 0.0, 0.6)).wheel_speeds
    for sim in (whole, pieces, bounded):
        sim.command(command)
    for k in range(1, 31):  # cycles of 33.3 ms: the samples fall anywhere between them
        for sim in (whole, pieces, bounded):
            sim.advance(k / 30.0)
        drained.append(pieces.sensors.drain())
    kept = whole.sensors.truths()
    for name in ("imu", "laser"):
        t = np.concatenate([d[name].t for d in drained])
        np.testing.assert_array_equal(t, kept[name].t)
    np.testing.assert_array_equal(np.concatenate([d["imu"].rates for d in drained]), kept["imu"].rates)
    np.testing.assert_array_equal(np.concatenate([d["imu"].forces for d in drained]), kept["imu"].forces)
    np.testing.assert_array_equal(np.concatenate([d["laser"].ranges for d in drained]), kept["laser"].ranges)
    last = bounded.sensors.truths()
    assert len(last["imu"].t) == 100 and len(last["laser"].t) == 5  # 0.5 s of each
    np.testing.assert_array_equal(last["imu"].t, kept["imu"].t[-100:])
    np.testing.assert_array_equal(last["imu"].rates, kept["imu"].rates[-100:])
    assert bounded.sensors.dropped == (len(kept["imu"].t) - 100) + (len(kept["laser"].t) - 5)


def test_a_lidar_mounted_on_the_floor_sees_every_wall_as_the_kinematic_engine_does():
    """The default mount is on the floor (z = 0): its beams leave from half a millimetre up, so
    they meet the room's faces, the cylinder and the low box just as the kinematic engine's 2D
    rays do (verified against closed forms in tests/sensors/test_lidar.py); along the floor's
    surface they found the walls' bottom edges for about a quarter of them."""
    from omnikin.sensors.lidar import true_ranges
    from omnikin.world.shapes import shapes_of

    low = Lidar("laser", Mount(), rate=10.0, beams=360, range_max=12.0)
    robot = dataclasses.replace(load_robot("tomasi-omni3"), name="floor-lidar", sensors=(low,))
    start = (0.3, -0.2, 0.4)
    world = _world(start)
    sim = PhysicsSim(robot, start=start, world=world, sensors=True)
    ranges = sim.sensors.truths()["laser"].ranges[0]
    kinematic = true_ranges(shapes_of(world), sim.pose, low)[0]
    assert np.all(np.isfinite(ranges))
    np.testing.assert_allclose(ranges, kinematic, rtol=0, atol=1e-6)
