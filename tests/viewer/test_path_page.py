"""The page follows a path: the Path folder's Follow button plans it from the robot's pose and
tracks it, the path and its reference point drawn (a real browser on the live page of this
process; the robot kinematic and exact, so it ends on the path's last waypoint)."""

from __future__ import annotations

import numpy as np
import pytest

from omnikin.io.robot_file import load_robot
from omnikin.viewer.app import LiveViewer
from omnikin.viewer.live import LiveRobot
from omnikin.viewer.panel import PATH_COLOUR
from support.browser import wait_for, wait_for_colour, wait_for_viser, wait_until
from support.viewer_wire import served


def test_the_follow_button_drives_the_path_drawn_on_the_floor_to_its_end(page, page_log):
    corners = [(0.6, 0.0), (0.6, 0.6)]
    live = LiveRobot(load_robot("omni4"))
    with served(LiveViewer(live, "127.0.0.1", 0, waypoints=corners, path_options={"smooth": False})) as viewer:
        page.goto(viewer.url)
        wait_for_viser(page, timeout=30)
        page.get_by_role("button", name="top", exact=True).click()
        wait_for(page, "document.body.innerText.includes('2 waypoints (from --path)')", timeout=30)
        page.get_by_role("button", name="Follow the path").click()
        wait_until(lambda: live.follower.following, "the path followed", timeout=30)
        wait_for_colour(page, PATH_COLOUR, min_pixels=50, timeout=30)  # the path on the floor
        wait_until(lambda: live.follower.state == "done", "the end of the path", timeout=120)
        assert np.asarray(live.backend.truth)[:2] == pytest.approx(corners[-1], abs=1e-3)
        wait_for(page, "document.body.innerText.includes(\"done path 'plan'\")", timeout=30)
    assert page_log.external == [] and page_log.page_errors == []
