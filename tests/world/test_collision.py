"""A footprint stops at first contact: positions and angles against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin.errors import WorldFileError
from omnikin.kinematics.se2 import compose, exp
from omnikin.world import Box, Footprint, Wall, make_world
from omnikin.world.collision import TOUCH, Collider, clearance

WALL_X = 1.0
THICK = 0.05
FACE = WALL_X - THICK / 2


def _disc(radius: float) -> Footprint:
    return Footprint(np.array([[0.0, 0.0, radius]]), np.empty((0, 5)))


def _bar(half_length: float, half_width: float) -> Footprint:
    return Footprint(np.empty((0, 3)), np.array([[0.0, 0.0, half_length, half_width, 0.0]]))


def _wall_world(thickness: float = THICK, start=(0.0, 0.0, 0.0)):
    return make_world("wall", start=start, walls=[Wall(((WALL_X, -5.0), (WALL_X, 5.0)), thickness)])


def _straight(collider: Collider, dx: float, steps: int, dt: float = 0.01):
    t = np.arange(steps + 1) * dt
    poses = np.zeros((steps + 1, 3))
    poses[:, 0] = np.linspace(0.0, dx, steps + 1)
    return collider.follow(t, poses)


def test_a_disc_driven_into_a_wall_stops_its_radius_from_the_face_and_reports_one_contact():
    collider = Collider(_wall_world(), _disc(0.2))
    poses, contacts = _straight(collider, 2.0, 200)  # 1 cm per step, 1 m/s
    assert poses[-1, 0] == pytest.approx(FACE - 0.2, abs=TOUCH)
    assert poses[-1, 0] <= FACE - 0.2 + 1e-12  # never inside
    assert len(contacts) == 1
    contact = contacts[0]
    assert contact.body == "wall 1"
    assert contact.point == pytest.approx((FACE, 0.0), abs=1e-9)
    # it meets the face after travelling FACE - 0.2 m at 1 m/s
    assert contact.time == pytest.approx(FACE - 0.2, abs=TOUCH)


def test_a_thin_wall_stops_a_fast_robot_that_steps_past_it_in_one_step():
    collider = Collider(_wall_world(thickness=0.001), _disc(0.05))
    poses, contacts = _straight(collider, 3.0, 2)  # 1.5 m per step
    assert poses[-1, 0] == pytest.approx(WALL_X - 0.0005 - 0.05, abs=TOUCH)
    assert len(contacts) == 1


def test_a_robot_against_a_wall_backs_away_freely_and_touches_again_as_a_new_contact():
    collider = Collider(_wall_world(), _disc(0.2))
    t = np.arange(401) * 0.01
    x = np.concatenate([np.linspace(0, 2.0, 201), np.linspace(2.0, 0.0, 101)[1:], np.linspace(0.0, 2.0, 101)[1:]])
    poses = np.zeros((401, 3))
    poses[:, 0] = x
    out, contacts = collider.follow(t, poses)
    stop = FACE - 0.2
    # commanded 2 m back from t = 2 s: the robot goes back 2 m from where it stopped
    assert out[300, 0] == pytest.approx(stop - 2.0, abs=TOUCH)
    assert out[-1, 0] == pytest.approx(stop, abs=TOUCH)
    assert [c.body for c in contacts] == ["wall 1", "wall 1"]
    assert contacts[1].time > 3.0


def test_a_long_bar_turning_near_a_wall_stops_when_its_corner_reaches_the_face():
    half_length, half_width = 0.5, 0.1
    # the bar's centre at x = FACE - 0.4; turning clockwise from heading pi/2, its corner
    # (0.5, -0.1) reaches x = FACE at the heading h where 0.5 cos(h) + 0.1 sin(h) = 0.4, that is
    # R cos(h - phase) = 0.4 with R = |(0.5, 0.1)|, phase = atan2(0.1, 0.5)
    collider = Collider(_wall_world(start=(FACE - 0.4, 0.0, math.pi / 2)), _bar(half_length, half_width))
    steps = 100
    t = np.arange(steps + 1) * 0.01
    poses = np.zeros((steps + 1, 3))
    poses[:, 2] = np.linspace(0.0, -math.pi / 2, steps + 1)  # turning clockwise, from facing +y
    out, contacts = collider.follow(t, poses)
    reach = math.hypot(half_length, half_width)
    phase = math.atan2(half_width, half_length)
    heading = phase + math.acos(0.4 / reach)
    slope = 0.5 * math.sin(heading) - 0.1 * math.cos(heading)  # metres of x per radian there
    assert out[-1, 2] - heading == pytest.approx(TOUCH / 2 / slope, abs=TOUCH / 2 / slope)
    assert out[-1, 0] == pytest.approx(FACE - 0.4, abs=1e-12)  # turning in place: the centre stays
    assert len(contacts) == 1


def test_a_robot_starting_inside_a_wall_is_refused_in_one_line():
    with pytest.raises(
        WorldFileError, match=r"world 'wall': the robot at its start pose .* overlaps 'wall 1' by 225 mm"
    ):
        _straight(Collider(_wall_world(start=(WALL_X, 0.0, 0.0)), _disc(0.2)), 1.0, 10)


def test_far_from_everything_the_robot_goes_exactly_where_it_is_commanded():
    collider = Collider(make_world("far", obstacles=[Box((50.0, 50.0), (1.0, 1.0, 1.0))]), _disc(0.2))
    t = np.arange(101) * 0.01
    xi = np.array([0.01, 0.002, 0.02])
    poses = [np.zeros(3)]
    for _ in range(100):
        poses.append(compose(poses[-1], exp(xi)))
    out, contacts = collider.follow(t, np.array(poses))
    np.testing.assert_allclose(out, np.array(poses), rtol=0, atol=1e-12)
    assert contacts == []


def test_clearance_is_exact_near_and_a_lower_bound_far():
    world = _wall_world()
    from omnikin.world.shapes import shapes_of

    shapes = shapes_of(world)
    near = clearance(shapes, _disc(0.2), (FACE - 0.23, 0.0, 0.0), point=True)
    assert near.distance == pytest.approx(0.03, abs=1e-12)
    assert near.point == pytest.approx((FACE, 0.0))
    far = clearance(shapes, _bar(0.5, 0.1), (FACE - 3.0, 0.0, 0.0))
    assert 0.0 < far.distance <= 3.0 - 0.5  # the bar's face is 2.5 m from the wall
