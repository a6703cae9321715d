"""Plane shapes of a world: signed distances and ray casts against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin.world import Box, Cylinder, Wall, make_world
from omnikin.world.plane import rect_distance, rect_rect_distance
from omnikin.world.shapes import BLOCK, Shapes, cast_rays, shapes_of

HALF = 2.0
THICK = 0.05


def _room(*obstacles):
    square = ((-HALF, -HALF), (HALF, -HALF), (HALF, HALF), (-HALF, HALF), (-HALF, -HALF))
    return make_world("room", walls=[Wall(square, THICK)], obstacles=list(obstacles))


def test_a_square_wall_is_closed_at_its_corners():
    shapes = shapes_of(_room())
    # each segment is lengthened by half the thickness: the corner square is covered
    corner = np.array([[HALF + THICK / 2 - 1e-9, HALF + THICK / 2 - 1e-9]])
    assert rect_distance(corner, shapes.rects).min() < 0.0
    # a ray along the diagonal meets the inner corner at sqrt(2) (HALF - THICK / 2)
    ranges, bodies = cast_rays(shapes, [[0.0, 0.0]], [math.pi / 4], 10.0)
    assert ranges[0] == pytest.approx(math.sqrt(2) * (HALF - THICK / 2), abs=1e-12)
    assert bodies[0] == 0


@pytest.mark.parametrize("x, y", [(0.0, 0.0), (0.7, -0.3), (-1.2, 1.1)])
def test_beams_meet_the_walls_at_the_distance_of_their_inner_faces(x, y):
    shapes = shapes_of(_room())
    face = HALF - THICK / 2
    angles = np.linspace(-math.pi, math.pi, 720, endpoint=False)
    ranges, _ = cast_rays(shapes, np.tile([x, y], (len(angles), 1)), angles, 100.0)
    c, s = np.cos(angles), np.sin(angles)
    with np.errstate(divide="ignore"):
        to_x = np.where(c > 0, (face - x) / c, np.where(c < 0, (-face - x) / c, np.inf))
        to_y = np.where(s > 0, (face - y) / s, np.where(s < 0, (-face - y) / s, np.inf))
    np.testing.assert_allclose(ranges, np.minimum(to_x, to_y), rtol=0, atol=1e-12)


def test_a_beam_meets_a_cylinder_at_the_near_root_of_its_circle():
    shapes = shapes_of(_room(Cylinder((1.0, 0.5), 0.2)))
    # from the origin along angle a the beam meets the circle |p - c| = r at
    # t = c.d - sqrt((c.d)^2 - |c|^2 + r^2)
    for a in np.linspace(0.3, 0.6, 7):
        d = np.array([math.cos(a), math.sin(a)])
        cd = 1.0 * d[0] + 0.5 * d[1]
        disc = cd * cd - 1.25 + 0.04
        ranges, bodies = cast_rays(shapes, [[0.0, 0.0]], [a], 10.0)
        if disc >= 0:
            assert ranges[0] == pytest.approx(cd - math.sqrt(disc), abs=1e-12)
            assert bodies[0] == 1
        else:
            assert bodies[0] == 0  # it passes the cylinder and meets the wall


def test_a_turned_box_is_met_on_its_turned_face():
    # a 0.4 m square turned 45 deg at (1, 0): along +x from the origin the beam meets its corner
    shapes = shapes_of(_room(Box((1.0, 0.0), (0.4, 0.4, 0.3), yaw=math.pi / 4)))
    ranges, _ = cast_rays(shapes, [[0.0, 0.0]], [0.0], 10.0)
    assert ranges[0] == pytest.approx(1.0 - 0.2 * math.sqrt(2), abs=1e-12)


def test_misses_are_infinite_beyond_the_range_and_inside_a_shape_is_zero():
    shapes = shapes_of(_room())
    ranges, bodies = cast_rays(shapes, [[0.0, 0.0], [HALF, 0.0]], [0.0, 1.0], 1.0)
    assert ranges[0] == math.inf and bodies[0] == -1
    assert ranges[1] == 0.0 and bodies[1] == 0  # the origin lies in the wall
    empty = Shapes(np.empty((0, 5)), np.empty(0, dtype=np.int64), np.empty((0, 3)), np.empty(0, dtype=np.int64))
    assert cast_rays(empty, [[0.0, 0.0]], [0.0], 5.0)[0][0] == math.inf


def test_many_beams_against_many_shapes_are_computed_in_blocks_alike():
    walls = [Wall(((i * 0.1, 3.0), (i * 0.1 + 0.05, 3.0)), 0.01) for i in range(-40, 40)]
    shapes = shapes_of(make_world("comb", walls=walls))
    angles = np.linspace(0.1, math.pi - 0.1, 3 * BLOCK // shapes.count + 7)
    origins = np.zeros((len(angles), 2))
    ranges, _ = cast_rays(shapes, origins, angles, 100.0)
    one_by_one = np.array(
        [cast_rays(shapes, origins[i : i + 1], angles[i : i + 1], 100.0)[0][0] for i in range(0, len(angles), 97)]
    )
    np.testing.assert_array_equal(ranges[::97], one_by_one)


def test_rectangles_apart_are_as_far_as_their_nearest_corner_and_overlapping_ones_negative():
    a = np.array([[0.0, 0.0, 0.5, 0.5, 0.0]])
    # a unit square turned 45 deg with its corner pointing at a's face x = 0.5 from x = 1.5
    b = np.array([[1.5 + math.sqrt(0.5), 0.0, 0.5, 0.5, math.pi / 4]])
    assert rect_rect_distance(a, b)[0, 0] == pytest.approx(1.0, abs=1e-12)
    # overlapping by 0.1 along x: penetration depth 0.1
    c = np.array([[0.9, 0.2, 0.5, 0.5, 0.0]])
    assert rect_rect_distance(a, c)[0, 0] == pytest.approx(-0.1, abs=1e-12)
    # crossed bars with no corner inside the other: still overlapping (separating axes); one
    # must move 1 + 0.1 along either bar to leave the other
    bar_x = np.array([[0.0, 0.0, 1.0, 0.1, 0.0]])
    bar_y = np.array([[0.0, 0.0, 1.0, 0.1, math.pi / 2]])
    assert rect_rect_distance(bar_x, bar_y)[0, 0] == pytest.approx(-1.1, abs=1e-12)
