"""The kinematic engine in a world: the robot stops at walls, its wheels and odometry do not."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin.errors import InputError, WorldFileError
from omnikin.io.robot_file import load_robot
from omnikin.motion.plans import line, spin
from omnikin.physics.description import describe
from omnikin.physics.engines import engine_named
from omnikin.simulation.engine import KinematicEngine
from omnikin.world import Wall, make_world
from omnikin.world.collision import TOUCH

FACE = 1.5 - 0.025  # inner face of a 5 cm wall along x = 1.5


@pytest.fixture(scope="module")
def tomasi():
    return load_robot("tomasi-omni3")


def _world(start=(0.0, 0.0, 0.0)):
    return make_world("wall", start=start, walls=[Wall(((1.5, -3.0), (1.5, 3.0)), 0.05)])


def _front(robot) -> float:
    """How far the robot reaches along body +x: the wheel on +x (hub at its distance, axle
    along x) stands out of the round chassis by half its width."""
    wheel = next(w for w in describe(robot).wheels if w.hub[0] > 0.1)
    return wheel.hub[0] + wheel.width / 2.0


def test_a_robot_driven_into_a_wall_stops_at_it_while_its_odometry_runs_on(tomasi):
    engine = engine_named("kinematic", world=_world())
    run = engine.drive(line(2.0), tomasi, tomasi, rate=100.0, noise=engine.noise_model("none"), rng=1)
    stop = FACE - _front(tomasi)
    assert run.truth[0, -1, 0] == pytest.approx(stop, abs=TOUCH)
    assert run.truth[0, -1, 1:] == pytest.approx([0.0, 0.0], abs=1e-12)
    assert run.odometry[-1, 0] == pytest.approx(2.0, abs=1e-9)  # the wheels turned as commanded
    (contact,) = run.contacts[0]
    assert contact.body == "wall 1"
    assert contact.point[0] == pytest.approx(FACE, abs=1e-9)
    travelled = run.truth[0, :, 0]
    first = int(np.argmax(travelled >= stop - TOUCH))
    assert run.t[first - 1] <= contact.time <= run.t[first]


def test_the_truth_stays_in_the_frame_where_the_robot_starts(tomasi):
    start = (-1.0, 0.5, math.pi / 2)
    engine = engine_named("kinematic", world=_world(start))
    run = engine.drive(
        line(0.5) + spin(-math.pi / 2) + line(3.0), tomasi, tomasi, noise=engine.noise_model("none"), rng=1
    )
    assert run.start == pytest.approx(start)
    assert run.truth[0, 0] == pytest.approx([0.0, 0.0, 0.0])
    # after 0.5 m north and a right turn, 3 m east: it stops at the wall in world x, which is
    # -y in the frame where it started (facing north)
    world_x = start[0] - run.truth[0, -1, 1]
    assert world_x == pytest.approx(FACE - _front(tomasi), abs=TOUCH)
    assert run.contacts[0][0].body == "wall 1"


def test_every_trial_stops_at_the_wall_with_its_own_noise(tomasi):
    engine = engine_named("kinematic", world=_world())
    run = engine.drive(line(2.0), tomasi, tomasi, noise=engine.noise_model("typical"), rng=3, trials=4)
    assert len(run.contacts) == 4
    assert all(len(c) >= 1 for c in run.contacts)
    ends = run.truth[:, -1]
    assert len({round(float(y), 12) for y in ends[:, 1]}) == 4  # each trial its own slip
    assert np.all(ends[:, 0] <= FACE - _front(tomasi) + 0.02)  # a slipping robot may touch askew


def test_the_back_end_stops_at_the_wall_and_reports_the_contact(tomasi):
    engine = engine_named("kinematic", world=_world())
    backend = engine.backend(tomasi, noise=engine.noise_model("none"))
    speeds = tomasi.ik([0.5, 0.0, 0.0]).wheel_speeds
    backend.read(0.0)
    backend.write(0.0, speeds)
    for k in range(1, 501):
        backend.read(k * 0.01)
    assert backend.truth[0] == pytest.approx(FACE - _front(tomasi), abs=TOUCH)
    assert [c.body for c in backend.contacts] == ["wall 1"]
    assert backend.contacts[0].time == pytest.approx((FACE - _front(tomasi)) / 0.5, abs=0.011)


def test_a_world_needs_a_footprint_and_a_start_clear_of_walls(tomasi):
    world = _world(start=(1.45, 0.0, 0.0))
    with pytest.raises(InputError, match="footprint_of"):
        KinematicEngine(world=world)
    engine = engine_named("kinematic", world=world)
    with pytest.raises(WorldFileError, match=r"the robot at its start pose .* overlaps 'wall 1'"):
        engine.drive(line(1.0), tomasi, tomasi, noise=engine.noise_model("none"), rng=1)


def test_a_long_robot_near_two_walls_stops_at_the_thin_one_ahead():
    # ackermann reaches far ahead of its reference point; a wall just behind it is nearer to that
    # point than the thin wall ahead is to its front: the clearance must not be taken from the
    # nearer wall's side alone (it went 0.65 m through the thin wall once)
    car = load_robot("ackermann")
    world = make_world(
        "near",
        walls=[Wall(((-0.797, -2.0), (-0.797, 2.0)), 0.01), Wall(((0.8125, -2.0), (0.8125, 2.0)), 0.001)],
    )
    engine = engine_named("kinematic", world=world)
    run = engine.drive(line(2.0), car, car, noise=engine.noise_model("none"), rng=1)
    front = max(w.x + w.radius for w in car.wheels)
    assert run.truth[0, -1, 0] + front <= 0.8125 - 0.0005 + 1e-9
    assert [c.body for c in run.contacts[0]] == ["wall 2"]
