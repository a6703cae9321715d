"""The physics engine in a world: walls stop the robot through contacts, boxes are pushed,
patches and the floor hand the wheels their friction."""

from __future__ import annotations

import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco", reason="the physics engine needs MuJoCo (extra 'physics')")

from omnikin.io.robot_file import load_robot  # noqa: E402
from omnikin.motion.plans import line  # noqa: E402
from omnikin.physics.description import describe  # noqa: E402
from omnikin.physics.engines import engine_named  # noqa: E402
from omnikin.physics.mjcf import PATCH_RAISE, WORLD_GROUP  # noqa: E402
from omnikin.physics.simulator import PhysicsSim  # noqa: E402
from omnikin.world import Box, Floor, Patch, Wall, make_world  # noqa: E402

FACE = 1.5 - 0.025


@pytest.fixture(scope="module")
def tomasi():
    return load_robot("tomasi-omni3")


def _front(robot) -> float:
    wheel = next(w for w in describe(robot).wheels if w.hub[0] > 0.1)
    return wheel.hub[0] + wheel.width / 2.0


def test_a_wall_stops_the_robot_through_its_contacts_where_the_kinematic_engine_stops_it(tomasi):
    world = make_world("wall", walls=[Wall(((1.5, -3.0), (1.5, 3.0)), 0.05)])
    run = engine_named("physics", world=world).drive(line(2.0), tomasi, tomasi, rate=100.0)
    # the wheel's side meets the face; MuJoCo's soft contact lets it in by well under a millimetre
    assert run.truth[0, -1, 0] == pytest.approx(FACE - _front(tomasi), abs=1e-3)
    assert abs(run.truth[0, -1, 1]) < 2e-3
    assert [c.body for c in run.contacts[0]] == ["wall 1"]
    contact = run.contacts[0][0]
    assert contact.point[0] == pytest.approx(FACE, abs=1e-3)
    assert contact.time == pytest.approx(run.t[np.argmax(run.truth[0, :, 0] > FACE - _front(tomasi) - 2e-3)], abs=0.05)
    kinematic = engine_named("kinematic", world=world)
    same = kinematic.drive(line(2.0), tomasi, tomasi, noise=kinematic.noise_model("none"), rng=1)
    assert run.truth[0, -1, 0] == pytest.approx(same.truth[0, -1, 0], abs=1e-3)
    assert contact.time == pytest.approx(same.contacts[0][0].time, abs=0.05)


def test_a_movable_box_in_the_way_is_pushed(tomasi):
    box = Box((0.6, 0.0), (0.3, 0.3, 0.2), fixed=False, mass=0.3)
    world = make_world("push", obstacles=[box])
    sim = PhysicsSim(tomasi, world=world)
    body = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_BODY, "world:obstacle:0")
    before = sim.data.xpos[body].copy()
    sim.command(tomasi.ik([0.3, 0.0, 0.0]).wheel_speeds)
    sim.advance(4.0)
    after = sim.data.xpos[body].copy()
    # the robot's front reaches the box's near face (0.45 m) after ~0.45 - front m; the rest of
    # the 1.2 m it drives pushes the box along
    pushed = 1.2 - (0.45 - _front(tomasi))
    assert after[0] - before[0] == pytest.approx(pushed, abs=0.1)
    assert [c.body for c in sim.contacts][:1] == ["box 1"]


def test_a_robot_on_a_patch_rests_on_it_alone_and_gets_its_friction(tomasi):
    patch = Patch(((-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)), friction=0.05)
    world = make_world("patch", floor=Floor(friction=0.8, patches=(patch,)))
    sim = PhysicsSim(tomasi, world=world)
    sim.step(10)
    d, m = sim.data, sim.model
    frictions = [float(d.contact.friction[k, 0]) for k in range(d.ncon)]
    floor = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    assert d.ncon >= 3
    assert all(f == pytest.approx(0.05) for f in frictions)
    assert floor not in set(d.contact.geom1[: d.ncon]) | set(d.contact.geom2[: d.ncon])
    assert sim.height == pytest.approx(PATCH_RAISE, abs=2e-4)  # standing on the patch's top
    # off the patch the floor's friction holds, by priority over the wheels' own
    away = PhysicsSim(tomasi, world=world, start=(3.0, 0.0, 0.0))
    away.step(10)
    assert {round(float(away.data.contact.friction[k, 0]), 9) for k in range(away.data.ncon)} == {0.8}


def test_walls_and_obstacles_are_what_rays_of_the_world_group_see(tomasi):
    world = make_world(
        "rays", walls=[Wall(((1.5, -3.0), (1.5, 3.0)), 0.05)], obstacles=[Box((-1.0, 0.0), (0.2, 0.2, 0.3))]
    )
    sim = PhysicsSim(tomasi, world=world)
    groups = np.zeros(6, dtype=np.uint8)
    groups[WORLD_GROUP] = 1
    geom = np.zeros(1, dtype=np.int32)
    for heading, expected in ((0.0, FACE), (math.pi, 1.0 - 0.1)):
        point = np.array([0.0, 0.0, 0.1])
        vec = np.array([math.cos(heading), math.sin(heading), 0.0])
        dist = mujoco.mj_ray(sim.model, sim.data, point, vec, groups, 1, -1, geom)
        assert dist == pytest.approx(expected, abs=1e-9)


def test_a_start_inside_a_body_is_refused_before_the_model_is_built(tomasi):
    from omnikin.errors import WorldFileError

    world = make_world("inside", obstacles=[Box((0.05, 0.0), (0.1, 0.1, 0.1))])
    with pytest.raises(WorldFileError, match=r"the robot at its start pose .* overlaps 'box 1'"):
        PhysicsSim(tomasi, world=world)
