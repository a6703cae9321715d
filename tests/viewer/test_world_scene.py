"""The live page in a world: walls, obstacles, patches and marks drawn where the world file puts
them, seen from where the robot started (the odometry's frame), and a pushed obstacle moved.

On the viser scene state the server sends every page; expected poses come from the world file
by hand, not from the viewer's code."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin.io.robot_file import load_robot
from omnikin.physics.engines import engine_named
from omnikin.viewer.app import LiveViewer
from omnikin.viewer.live import LiveRobot
from omnikin.world import Box, Cylinder, Floor, Mark, Patch, Wall, make_world
from support.viewer_wire import world_transform

START = (1.0, 0.5, math.pi / 2)


def _world():
    return make_world(
        "page",
        start=START,
        floor=Floor(patches=(Patch(((-1.0, -1.0), (0.0, -1.0), (0.0, 0.0)), 0.1),)),
        walls=[Wall(((3.0, -2.0), (3.0, 2.0)), thickness=0.1, height=0.5)],
        obstacles=[Box((-1.0, 2.0), (0.4, 0.2, 0.3), yaw=0.3), Cylinder((2.0, -1.0), 0.15, height=0.6)],
        marks=[Mark(((0.0, 0.0), (1.0, 0.0)))],
    )


def _seen_from_start(x: float, y: float) -> tuple[float, float]:
    """A world point in the frame where the robot started (START), by hand."""
    dx, dy = x - START[0], y - START[1]
    c, s = math.cos(START[2]), math.sin(START[2])
    return c * dx + s * dy, -s * dx + c * dy


@pytest.mark.parametrize("engine", ["kinematic", "physics"])
def test_the_world_is_drawn_where_the_file_puts_it_seen_from_where_the_robot_started(engine):
    if engine == "physics":
        pytest.importorskip("mujoco", reason="the physics engine needs MuJoCo (extra 'physics')")
    viewer = LiveViewer(LiveRobot(load_robot("tomasi-omni3"), engine_named(engine, world=_world())), "127.0.0.1", 0)
    try:
        handles = viewer.server.scene._handle_from_node_name
        wall = world_transform(viewer.server.scene, "/world/wall0/0")
        # the wall's one segment: centre (3, 0), 0.5 m high; facing +y from (1, 0.5) it lies to the right
        assert wall.translation()[:2] == pytest.approx(_seen_from_start(3.0, 0.0), abs=1e-9)
        assert wall.translation()[2] == pytest.approx(0.25)
        assert np.asarray(handles["/world/wall0/0"].dimensions) == pytest.approx([4.1, 0.1, 0.5])
        box = world_transform(viewer.server.scene, "/world/obstacle0")
        assert box.translation()[:2] == pytest.approx(_seen_from_start(-1.0, 2.0), abs=1e-9)
        assert box.rotation().as_rpy_radians().yaw == pytest.approx(0.3 - math.pi / 2)
        assert world_transform(viewer.server.scene, "/world/obstacle1").translation()[:2] == pytest.approx(
            _seen_from_start(2.0, -1.0)
        )
        assert "/world/patch0" in handles and "/world/mark0" in handles
        # the robot itself starts at the origin of the page's frame
        assert viewer.live.shown_pose == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)
    finally:
        viewer.close()


def test_an_empty_floor_draws_no_world():
    viewer = LiveViewer(LiveRobot(load_robot("tomasi-omni3")), "127.0.0.1", 0)
    try:
        assert not [n for n in viewer.server.scene._handle_from_node_name if n.startswith("/world")]
        assert viewer.world is None
    finally:
        viewer.close()
