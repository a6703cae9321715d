"""What a new user sees first: which way the robot faces, where the odometry thinks it is, a
first view that frames the robot, runs shown together, readouts without data.

On the viser scene state (the server's handles: what it sends every page) and in headless
Chromium (what a page draws: colours counted in screenshots). Expected values come from the
robot file (wheel positions and radii) and from closed forms of the recorded motion, not from
the viewer's code.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest
import viser
import viser.transforms as vtf

from omnikin.io.robot_file import load_robot
from omnikin.physics.description import describe
from omnikin.viewer.app import LiveViewer
from omnikin.viewer.live import LiveRobot, Snapshot
from omnikin.viewer.replay import PoseSeries, Track
from omnikin.viewer.replay_page import ReplayViewer
from omnikin.viewer.replay_sources import ReplaySource
from omnikin.viewer.scene import ODOMETRY_COLOUR, TRUTH_COLOUR, RobotView
from support.browser import colour_mask, screenshot_rgb, wait_for, wait_for_colour, wait_for_viser, wait_until
from support.viewer_wire import served, world_transform


def reach(robot) -> float:
    """The robot's size from its file: the farthest point of a wheel from the reference point [m]."""
    return max(math.hypot(w.x, w.y) + w.radius for w in robot.wheels)


def snapshot(truth, odometry, wheels: int) -> Snapshot:
    zeros = np.zeros(wheels)
    still = (0.0,) * 3
    steer, none = np.full(wheels, np.nan), (None,) * wheels
    return Snapshot(0.0, truth, odometry, still, still, still, zeros, zeros, steer, (), none, none)


@pytest.fixture
def scene() -> Iterator[viser.ViserServer]:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        yield server
    finally:
        server.stop()


@pytest.mark.parametrize("name", ["tomasi-omni3", "mecanum4", "ackermann"])
def test_the_heading_arrows_point_along_the_true_and_odometry_headings(scene, name):
    robot = load_robot(name)
    view = RobotView(scene.scene, describe(robot))
    for truth, odometry in [
        ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
        ((1.5, -0.25, 2.5), (1.4, -0.2, 2.3)),
        ((-3.0, 2.0, -1.9), (-2.9, 2.2, 3.1)),
    ]:
        view.show(snapshot(truth, odometry, len(describe(robot).wheels)))
        for node, (x, y, theta) in (("/robot/heading", truth), ("/odometry/heading", odometry)):
            pose = world_transform(scene.scene, node)
            forward = pose.rotation().apply(np.array([1.0, 0.0, 0.0]))
            assert forward[2] == pytest.approx(0.0, abs=1e-12)  # flat on the floor
            assert math.remainder(math.atan2(forward[1], forward[0]) - theta, 2 * math.pi) == pytest.approx(0, abs=1e-9)
            assert pose.translation()[:2] == pytest.approx([x, y], abs=1e-9)  # from the reference point
    # the arrow's mesh points along its local +x, from the reference point to beyond the wheels
    for node in ("/robot/heading", "/odometry/heading"):
        vertices = np.asarray(scene.scene._handle_from_node_name[node].vertices)
        tip = vertices[np.argmax(vertices[:, 0])]
        assert vertices[:, 0].min() == pytest.approx(0.0, abs=1e-6)
        assert tip[1] == pytest.approx(0.0, abs=1e-6)
        assert tip[0] > max(w.x + w.radius for w in robot.wheels)
        assert vertices[:, 1].max() == pytest.approx(-vertices[:, 1].min(), abs=1e-6)  # symmetric about its axis


def check_first_view(server: viser.ViserServer, camera, look_at, robot) -> None:
    """``camera`` (position, look_at, fov) looks at ``look_at`` from above the floor, from a
    distance at which the robot's size fills between a tenth and a half of the view's height:
    ``R / (d tan(fov / 2))`` in [0.1, 0.5], ``R`` from the robot file."""
    position, target = np.asarray(camera.position), np.asarray(camera.look_at)
    assert target == pytest.approx(look_at, abs=1e-9)
    distance = float(np.linalg.norm(position - target))
    fills = reach(robot) / (distance * math.tan(camera.fov / 2))
    assert 0.1 <= fills <= 0.5, (distance, fills)
    assert position[2] > 0.2 * distance  # from above, not along the floor


@pytest.mark.parametrize("name", ["tomasi-omni3", "ackermann"])
def test_the_first_live_view_looks_at_the_robot_from_a_distance_that_fits_it(name):
    robot = load_robot(name)
    viewer = LiveViewer(LiveRobot(robot), "127.0.0.1", 0)
    try:
        check_first_view(viewer.server, viewer.server.initial_camera, (0.0, 0.0, 0.0), robot)  # it starts at the origin
    finally:
        viewer.close()


V, W = 0.3, 0.4  # the circle run's twist [m/s, rad/s]


def circle(t, start=(0.0, 0.0)) -> np.ndarray:
    t = np.asarray(t, dtype=float)
    return np.column_stack([start[0] + V / W * np.sin(W * t), start[1] + V / W * (1 - np.cos(W * t)), W * t])


def spin(t, rate) -> np.ndarray:
    """Turning on the spot at the origin at ``rate`` [rad/s]."""
    t = np.asarray(t, dtype=float)
    return np.column_stack([np.zeros_like(t), np.zeros_like(t), rate * t])


@pytest.fixture
def replay() -> Iterator[ReplayViewer]:
    """Two runs of tomasi-omni3 sampled at 10 Hz: "spin" turns on the spot at W while its
    odometry thinks it turns the other way; "circle" drives a circle from (2, -1)."""
    t = np.arange(0.0, 10.001, 0.1)
    tracks = [
        Track("spin", PoseSeries(t, spin(t, W)), PoseSeries(t, spin(t, -W))),
        Track("circle", PoseSeries(t, circle(t, (2.0, -1.0))), PoseSeries(t, circle(t, (2.0, -1.0)))),
    ]
    with served(
        ReplayViewer(ReplaySource("two runs", load_robot("tomasi-omni3"), tracks, side=1.0), "127.0.0.1", 0)
    ) as viewer:
        yield viewer


def arrow_direction(mask: np.ndarray) -> float:
    """The direction [rad] from the image's centre to the centroid of the ``mask`` pixels, in
    the top camera's screen frame (+x right, +y up: the world's)."""
    rows, cols = np.nonzero(mask)
    cy, cx = (mask.shape[0] - 1) / 2, (mask.shape[1] - 1) / 2
    return math.atan2(-(rows.mean() - cy), cols.mean() - cx)


def seek(page, t: float) -> None:
    field = page.get_by_role("textbox").nth(0)  # the time slider's number field comes first
    field.fill(str(t))
    field.press("Enter")
    wait_for(page, f"Math.abs(Number(document.querySelector('#omnikin-readout').dataset.t) - {t}) < 1e-9", timeout=30)


def test_the_replay_page_shows_the_headings_runs_together_and_no_zeros_for_what_was_not_recorded(
    page, page_log, replay
):
    page.goto(replay.url)
    wait_for_viser(page, timeout=30)
    wait_for(page, "document.querySelector('#omnikin-readout[data-t]') !== null", timeout=30)  # (a loaded machine)
    wait_for_colour(page, TRUTH_COLOUR, timeout=60)
    (client,) = replay.server.get_clients().values()
    # the page's own camera (reported by the browser) starts at the first run's robot
    wait_for(page, "true")
    check_first_view(replay.server, client.camera, (0.0, 0.0, 0.0), load_robot("tomasi-omni3"))

    # from above, each arrow points along its recorded heading: at t = 2.5 s the truth has
    # turned +1 rad, the odometry -1 rad (closed forms of the two spins)
    page.get_by_role("button", name="top", exact=True).click()
    seek(page, 2.5)
    for _ in range(50):  # the camera and the scene arrive in separate messages: until both show
        image = screenshot_rgb(page)
        truth, odometry = colour_mask(image, TRUTH_COLOUR), colour_mask(image, ODOMETRY_COLOUR)
        if truth.sum() > 300 and odometry.sum() > 150:
            if abs(arrow_direction(truth) - W * 2.5) < 0.05 and abs(arrow_direction(odometry) + W * 2.5) < 0.05:
                break
        page.wait_for_timeout(200)
    assert truth.sum() > 300 and odometry.sum() > 150, (truth.sum(), odometry.sum())
    assert arrow_direction(truth) == pytest.approx(W * 2.5, abs=0.05)
    assert arrow_direction(odometry) == pytest.approx(-W * 2.5, abs=0.05)

    # a replay has no command and no residual: the readout says so, with no zeros
    text = page.inner_text("#omnikin-readout")
    rows = dict(line.split("\t", 1) for line in text.splitlines() if "\t" in line)
    assert rows["command"] == "not recorded" and rows["FK residual"] == "not recorded", text

    # the circle run shown together with the spin: its robot at the same time, on its circle
    page.get_by_role("checkbox", name="circle").check()
    wait_for(page, "true")
    for _ in range(100):
        if "circle" in replay.shown:
            break
        page.wait_for_timeout(100)
    seek(page, 6.0)
    ghost = world_transform(replay.server.scene, "/runs/1/robot")
    exact = circle([6.0], (2.0, -1.0))[0]
    assert ghost.translation()[:2] == pytest.approx(exact[:2], abs=1e-9)
    yaw = vtf.SO3(ghost.rotation().wxyz).compute_yaw_radians()
    assert math.remainder(yaw - exact[2], 2 * math.pi) == pytest.approx(0.0, abs=1e-9)

    # the run camera frames both runs: straight down on the middle of their paths' box (the
    # spin at the origin, the circle of radius V / W from (2, -1): x in [2 + (V/W) sin 4, 2 + V/W])
    page.get_by_role("button", name="run", exact=True).click()
    radius = V / W
    x0, x1 = 0.0, 2.0 + radius
    y0, y1 = -1.0, -1.0 + 2 * radius
    for _ in range(100):
        look = np.asarray(client.camera.look_at)
        if look[:2] == pytest.approx([(x0 + x1) / 2, (y0 + y1) / 2], abs=1e-3):
            break
        page.wait_for_timeout(100)
    assert look[:2] == pytest.approx([(x0 + x1) / 2, (y0 + y1) / 2], abs=1e-3)
    position = np.asarray(client.camera.position)
    assert position[2] > 0 and np.hypot(*(position[:2] - look[:2])) < 1e-2 * position[2]  # straight down
    half_height = position[2] * math.tan(client.camera.fov / 2)
    assert half_height >= max(x1 - x0, y1 - y0) / 2  # the whole box is in view

    # key 2 (top) looks at the spinning robot, at the origin; key 4 frames both runs again. (The
    # page's report of where it looked before may cross the key on the wire and show the old
    # look-at for a moment: the preset is waited for, then its look-at.)
    for key, preset, centre in (("2", "top", [0.0, 0.0]), ("4", "run", [(x0 + x1) / 2, (y0 + y1) / 2])):
        page.keyboard.press(key)
        for _ in range(100):
            if replay.camera.camera == preset and np.asarray(client.camera.look_at)[:2] == pytest.approx(
                centre, abs=1e-3
            ):
                break
            page.wait_for_timeout(100)
        assert replay.camera.camera == preset, key
        assert np.asarray(client.camera.look_at)[:2] == pytest.approx(centre, abs=1e-3), key
    assert "1 2 3 4 camera free/top/follow/run" in " ".join(page.inner_text("body").split())  # the key help
    assert page_log.external == [] and page_log.page_errors == []


@pytest.fixture
def live() -> Iterator[LiveViewer]:
    """The live page of tomasi-omni3 (kinematic engine), served from this process."""
    with served(LiveViewer(LiveRobot(load_robot("tomasi-omni3")), "127.0.0.1", 0)) as viewer:
        yield viewer


def test_the_live_page_frames_the_robot_and_shows_its_heading_in_every_camera(page, page_log, live):
    page.goto(live.url)
    wait_for_viser(page, timeout=30)
    wait_for_colour(page, TRUTH_COLOUR, timeout=60)
    (client,) = live.server.get_clients().values()
    check_first_view(live.server, client.camera, (0.0, 0.0, 0.0), load_robot("tomasi-omni3"))  # the browser's camera
    for preset in ("free", "top", "follow"):  # free: the first view, as the page opened
        if preset != "free":
            page.get_by_role("button", name=preset, exact=True).click()
        for _ in range(50):  # until the camera's message has been drawn
            image = screenshot_rgb(page)
            truth, odometry = colour_mask(image, TRUTH_COLOUR), colour_mask(image, ODOMETRY_COLOUR)
            if truth.sum() > 100 and odometry.sum() > 50 and (preset != "top" or abs(arrow_direction(truth)) < 0.05):
                break
            page.wait_for_timeout(200)
        # at rest at the origin the odometry agrees with the truth: its narrower arrow lies on the
        # truth's, green showing on both sides of the magenta
        assert truth.sum() > 100 and odometry.sum() > 50, (preset, truth.sum(), odometry.sum())
        if preset == "top":  # the robot faces +x: the arrow points right from the page's middle
            assert arrow_direction(truth) == pytest.approx(0.0, abs=0.05)
            assert arrow_direction(odometry) == pytest.approx(0.0, abs=0.05)
    assert page_log.external == [] and page_log.page_errors == []


def top_aim(camera, view_size: float) -> tuple[np.ndarray, np.ndarray]:
    """Where the top camera looks from and at, for the robot at the origin: straight down from
    the height ``S / (2 tan(fov / 2))`` that frames ``S = view_size`` metres (a millimetre per
    thousand of it south, so the view's up is +y)."""
    height = view_size / (2 * math.tan(camera.fov / 2))
    return np.array([0.0, -1e-3 * height, height]), np.zeros(3)


def turn_the_page_camera(page) -> None:
    """A drag up the middle of the page's scene with the left button: viser's orbit, which tips a
    camera looking down towards the horizon."""
    size = page.viewport_size
    x, y = 0.4 * size["width"], 0.5 * size["height"]
    page.mouse.move(x, y)
    page.mouse.down()
    for k in range(1, 21):
        page.mouse.move(x, y - 10 * k)
    page.mouse.up()


@pytest.mark.parametrize("settle", [120.0, 0.0])
def test_a_page_whose_camera_leaves_a_preset_just_placed_is_put_back_only_while_it_settles(
    page, page_log, live, monkeypatch, settle
):
    # A page's camera report can cross the preset's messages on the wire; the camera control puts
    # a page that reports another camera back, for a settling time after the preset (and only
    # then: afterwards the mouse is the user's). A drag stands in for the crossing report.
    from omnikin.viewer import panel

    monkeypatch.setattr(panel, "CAMERA_SETTLE", settle)
    page.goto(live.url)
    wait_for_viser(page, timeout=30)
    wait_for_colour(page, TRUTH_COLOUR, timeout=60)
    (client,) = live.server.get_clients().values()
    position, look_at = top_aim(client.camera, live.camera.view_size.value)

    def looks_top() -> bool:
        return bool(
            np.allclose(client.camera.position, position, atol=1e-4)
            and np.allclose(client.camera.look_at, look_at, atol=1e-4)
        )

    page.get_by_role("button", name="top", exact=True).click()
    wait_until(looks_top, "page reporting the top camera")
    reported: list[np.ndarray] = []
    client.camera.on_update(lambda camera: reported.append(np.array(camera.position)))
    turn_the_page_camera(page)
    wait_until(lambda: any(np.linalg.norm(p - position) > 0.01 for p in reported), "report of the turned camera")
    if settle > 0:
        wait_until(looks_top, "page put back on the top camera")
    else:
        page.wait_for_timeout(1000)  # a page put back would have reported it by now
        assert not looks_top()
        assert np.linalg.norm(reported[-1] - position) > 0.01
    assert page_log.external == [] and page_log.page_errors == []


def test_a_run_without_ground_truth_says_so_instead_of_showing_zeros():
    from omnikin.viewer.panel import readout_html
    from omnikin.viewer.replay import TrackReplay

    robot = load_robot("tomasi-omni3")
    t = np.array([0.0, 1.0])
    odometry = PoseSeries(t, [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]])
    track = Track("odometry only", odometry, odometry, missing=("truth",))  # a bag's, without /ground_truth
    shown = readout_html(TrackReplay(robot, describe(robot), track).snapshot(0.5))
    assert "<td>pose</td><td>not recorded (drawn at the odometry)</td>" in shown
    assert "<td>command</td><td>not recorded</td>" in shown and "<td>FK residual</td><td>not recorded</td>" in shown
    assert "<td>odometry</td><td>x +0.250 m, y +0.000 m, theta +0.0 deg</td>" in shown  # recorded: shown
    assert 'data-missing="command residual truth"' in shown


def test_the_run_camera_s_key_on_a_live_page_says_it_has_no_runs(page, page_log, live):
    page.goto(live.url)
    page.wait_for_selector("#omnikin-readout[data-x]", timeout=30000)
    wait_for(page, "document.documentElement.dataset.omnikinKeys === 'connected'")
    page.keyboard.press("2")
    wait_until(lambda: live.camera.camera == "top", "the top camera on key 2")
    page.keyboard.press("4")
    wait_until(lambda: live.live.notice != "", "a notice for key 4")
    assert live.live.notice == "key 4 (camera run) frames the runs of a replay: a live page has none"
    assert live.camera.camera == "top"  # unchanged
    wait_for(page, "document.body.innerText.includes('key 4 (camera run) frames the runs of a replay')", timeout=30)
    assert page_log.external == [] and page_log.page_errors == []
