"""A lidar's scan: ranges against closed-form distances, REP 117's special values, noise and
dropouts with their configured statistics, the same seed the same scan."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin.kinematics.sensors import Lidar, Mount
from omnikin.sensors.lidar import measured, scan, true_ranges
from omnikin.world import Box, Cylinder, Wall, make_world
from omnikin.world.shapes import shapes_of
from support.rooms import to_faces

HALF, THICK = 2.0, 0.05
FACE = HALF - THICK / 2


def _room(*obstacles):
    square = ((-HALF, -HALF), (HALF, -HALF), (HALF, HALF), (-HALF, HALF), (-HALF, -HALF))
    return shapes_of(make_world("room", walls=[Wall(square, THICK, height=0.3)], obstacles=list(obstacles)))


def _to_faces(x: float, y: float, angles: np.ndarray) -> np.ndarray:
    return to_faces(x, y, angles, FACE)


def test_ranges_are_the_distances_from_the_mount_to_the_walls_along_each_declared_beam():
    lidar = Lidar("l", Mount(0.05, -0.02, 0.12, math.radians(30)), beams=720, range_max=12.0)
    pose = (0.3, -0.2, 0.4)
    ranges, bodies = true_ranges(_room(), pose, lidar)
    # the mount in the world: (x, y) + R(theta) (0.05, -0.02); beam k at theta + yaw + angle_k
    c, s = math.cos(0.4), math.sin(0.4)
    x, y = 0.3 + c * 0.05 + s * 0.02, -0.2 + s * 0.05 - c * 0.02
    angles = 0.4 + math.radians(30) - math.pi + np.arange(720) * (2 * math.pi / 720)
    np.testing.assert_allclose(ranges, _to_faces(x, y, angles), rtol=0, atol=1e-12)
    assert set(bodies) == {0}


def test_a_cylinder_ahead_is_met_at_the_near_root_and_a_low_box_is_beneath_the_beams():
    lidar = Lidar("l", Mount(z=0.12), beams=4, range_max=12.0)  # beams at -pi, -pi/2, 0, pi/2
    shapes = _room(Cylinder((1.0, 0.0), 0.25, height=0.5), Box((0.0, 1.0), (0.2, 0.2, 0.1)))
    ranges, bodies = true_ranges(shapes, (0.0, 0.0, 0.0), lidar)
    assert ranges[2] == pytest.approx(1.0 - 0.25, abs=1e-12) and bodies[2] == 1
    assert ranges[3] == pytest.approx(FACE, abs=1e-12) and bodies[3] == 0  # the 0.1 m box lies below 0.12 m


def test_beyond_range_max_is_plus_infinity_and_closer_than_range_min_minus_infinity():
    lidar = Lidar("l", beams=4, range_min=0.5, range_max=1.9)
    out = scan(_room(), (1.8, 0.0, 0.0), lidar)
    # from x = 1.8: +x face at 0.175 (too close), +y and -y faces at 1.975 (too far), -x at 3.775
    assert out[2] == -np.inf
    assert out[1] == np.inf and out[3] == np.inf and out[0] == np.inf


def test_noise_and_dropouts_have_the_configured_statistics_over_many_scans():
    lidar = Lidar("l", beams=360, range_noise=0.02, dropout=0.05, range_max=12.0)
    shapes = _room()
    truth, _ = true_ranges(shapes, (0.1, 0.2, 0.3), lidar)
    rng = np.random.default_rng(11)
    scans = np.array([measured(truth, lidar, rng) for _ in range(400)])
    lost = np.isnan(scans)
    n = lost.size
    # a binomial count within 4.5 standard deviations of its mean
    assert abs(lost.sum() - 0.05 * n) < 4.5 * math.sqrt(n * 0.05 * 0.95)
    errors = (scans - truth)[~lost]
    assert abs(errors.mean()) < 4.5 * 0.02 / math.sqrt(errors.size)
    assert errors.std() == pytest.approx(0.02, rel=0.02)


def test_the_same_seed_gives_the_same_scan_bit_for_bit_and_no_rng_the_exact_one():
    lidar = Lidar("l", beams=180, range_noise=0.01, dropout=0.1)
    shapes = _room()
    first = scan(shapes, (0.0, 0.5, 1.0), lidar, np.random.default_rng(3))
    again = scan(shapes, (0.0, 0.5, 1.0), lidar, np.random.default_rng(3))
    np.testing.assert_array_equal(first, again)
    exact = scan(shapes, (0.0, 0.5, 1.0), lidar)
    np.testing.assert_array_equal(exact, true_ranges(shapes, (0.0, 0.5, 1.0), lidar)[0])
