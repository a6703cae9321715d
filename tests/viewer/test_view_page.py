"""``omnikin view`` in a real browser: the page loads from this machine alone, shows the robot,
and the keyboard and the page's controls drive it as the kinematics say.

The robot is the kinematic engine's (exact), so a held key's effect has a closed form: the
command ramps up at the acceleration limit from the press and down from the release, and a
trapezoid whose two ramps have equal slopes covers ``v T`` in all, ``T`` the time the key was
held (measured on the page's clock from when its key handlers ran: a page busy drawing a frame runs
them later than the key went down or up).
"""

from __future__ import annotations

import re
import subprocess
import sys
import time

import numpy as np
import pytest

from browser import colour_mask, hold_key, page_seconds, record_keys, recorded_keys, screenshot_rgb, wait_for
from omnikin.viewer.scene import CHASSIS_COLOUR
from omnikin_paths import omnikin_env

SPEED, TURN = 0.2, 0.5  # the keys' defaults [m/s, rad/s]
ACCEL = 0.5  # MotionLimits' default linear acceleration [m/s^2]
READOUT = "#omnikin-readout"


@pytest.fixture
def view():
    """Start ``omnikin view`` on a free port; yields a function that opens it on a page and waits
    for the first readout and the key channel."""
    procs = []

    def start(page, robot="tomasi-omni3", *args):
        proc = subprocess.Popen(
            [sys.executable, "-m", "omnikin.cli.main", "view", robot, "--port", "0", "--duration", "120", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=omnikin_env(),
        )
        procs.append(proc)
        line = proc.stdout.readline()
        found = re.search(r"http://\S+/", line)
        assert found, f"no address printed: {line!r} {proc.stderr.read() if proc.poll() is not None else ''}"
        page.goto(found.group(0))
        page.wait_for_selector(f"{READOUT}[data-x]", timeout=30000)
        wait_for(page, "document.documentElement.dataset.omnikinKeys === 'connected'")
        return proc

    yield start
    for proc in procs:
        proc.terminate()
        try:
            _, err = proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            _, err = proc.communicate()
        assert "Traceback" not in err, f"the viewer printed a traceback: {err[-2000:]}"


def pose(page):
    values = page.evaluate(
        f"(() => {{ const d = document.querySelector('{READOUT}').dataset;"
        " return [d.t, d.x, d.y, d.theta, d.vx, d.vy, d.omega].map(Number); })()"
    )
    return dict(zip(("t", "x", "y", "theta", "vx", "vy", "omega"), values, strict=True))


def settle(page, seconds=None):
    """Wait until the robot has stopped (twist zero on the page) and return its pose."""
    time.sleep(seconds if seconds is not None else SPEED / ACCEL + 0.3)
    wait_for(
        page,
        f"(() => {{ const d = document.querySelector('{READOUT}').dataset;"
        " return Number(d.vx) === 0 && Number(d.vy) === 0 && Number(d.omega) === 0; })()",
    )
    return pose(page)


def held_seconds(page, key):
    """How long the page's key handlers saw ``key`` held [s] (the teleop script sends when they run)."""
    events = [e for e in recorded_keys(page) if e["key"] == key and not e["repeat"]]
    down = next(e["handled"] for e in events if e["type"] == "keydown")
    up = next(e["handled"] for e in events if e["type"] == "keyup")
    return up - down


def test_the_page_comes_from_this_machine_and_shows_the_robot(view, page, page_log):
    view(page)
    page.keyboard.press("2")  # top camera: straight down on the robot
    time.sleep(1.0)
    mask = colour_mask(screenshot_rgb(page), CHASSIS_COLOUR)
    assert mask.sum() > 2000, "the chassis is not on the page"
    rows, cols = np.nonzero(mask)
    height, width = mask.shape
    assert abs(rows.mean() - height / 2) < 0.1 * height and abs(cols.mean() - width / 2) < 0.1 * width
    assert page_log.external == [] and page_log.page_errors == []
    assert all(url.startswith("ws://127.0.0.1:") for url in page_log.websockets)


@pytest.mark.parametrize(
    "key, axis, rate",
    [("w", "x", SPEED), ("s", "x", -SPEED), ("a", "y", SPEED), ("d", "y", -SPEED), ("q", "theta", TURN)],
)
def test_a_held_key_drives_as_far_as_the_kinematics_say_and_its_release_stops(view, page, key, axis, rate):
    view(page)
    record_keys(page)
    before = pose(page)
    hold_key(page, key, 1.2)
    after = settle(page, (abs(rate) / (ACCEL if axis != "theta" else 2.0)) + 0.3)
    held = held_seconds(page, key)
    expected = rate * held
    # the messages cross a loaded machine: 0.1 s of the hold either way (the other axes stay exact)
    assert after[axis] - before[axis] == pytest.approx(expected, abs=abs(rate) * 0.1)
    for other in {"x", "y", "theta"} - {axis}:
        assert abs(after[other] - before[other]) < 1e-9


def test_teleop_keys_do_not_reach_viser_s_camera_controls(view, page):
    """viser's camera moves on W/A/S/D/Q/E through listeners on the document: the key script
    takes them at the window, before the document sees them; other keys pass."""
    view(page)
    page.evaluate("() => { window.__doc = []; document.addEventListener('keydown', (e) => window.__doc.push(e.key)); }")
    for key in ("w", "a", "q", "x"):
        page.keyboard.press(key)
    wait_for(page, "window.__doc.length > 0")
    assert page.evaluate("window.__doc") == ["x"]


def test_a_differential_drive_does_not_strafe_on_a_but_turns_on_q(view, page):
    view(page, "diff-drive")
    before = pose(page)
    hold_key(page, "a", 0.6)
    after = settle(page)
    assert (after["x"], after["y"], after["theta"]) == pytest.approx((before["x"], before["y"], before["theta"]))
    record_keys(page)
    hold_key(page, "q", 0.8)
    after = settle(page, 0.6)
    assert after["theta"] == pytest.approx(TURN * held_seconds(page, "q"), abs=TURN * 0.1)


def test_the_go_button_drives_to_the_marker_and_stop_stops_a_set_twist(view, page):
    view(page)
    page.get_by_role("button", name="Go to the marker").click()  # the marker starts 1 m ahead
    wait_for(page, f"Math.abs(Number(document.querySelector('{READOUT}').dataset.x) - 1.0) < 0.002", timeout=20)
    after = settle(page, 0.2)
    assert after["y"] == pytest.approx(0.0, abs=1e-3) and after["theta"] == pytest.approx(0.0, abs=0.01)
    page.get_by_role("button", name="Drive").click()  # sliders at zero: a zero twist
    page.get_by_role("button", name="Stop").click()
    assert settle(page, 0.2)["x"] == pytest.approx(after["x"], abs=1e-9)


def test_a_key_press_reaches_the_pose_on_the_page_within_a_few_control_steps(view, page):
    view(page)
    page.evaluate(
        f"""() => {{
          const el = document.querySelector('#omnikin-readout');
          window.__moved = null;
          const x0 = el.dataset.x;
          new MutationObserver(() => {{
            const now = document.querySelector('{READOUT}');
            if (window.__moved === null && now && now.dataset.x !== x0) window.__moved = performance.now();
          }}).observe(document.body, {{subtree: true, childList: true, attributes: true}});
        }}"""
    )
    record_keys(page)
    pressed_at = page_seconds(page)
    hold_key(page, "w", 0.3)
    moved = wait_for(page, "window.__moved") / 1000.0
    down = next(e["t"] for e in recorded_keys(page) if e["type"] == "keydown")
    assert down >= pressed_at - 1e-3
    latency = moved - down
    assert 0 < latency < 0.5, (
        f"{latency * 1000:.0f} ms from the key to the pose on the page"
    )  # (benchmark: median 33 ms)


def test_a_twist_set_on_the_page_stops_when_the_last_page_closes(browser):
    """The Drive button's twist holds until Stop: with no page left to press Stop, it stops."""
    import threading

    from omnikin.io.robot_file import load_robot
    from omnikin.viewer.app import LiveViewer
    from omnikin.viewer.live import LiveRobot

    live = LiveRobot(load_robot("tomasi-omni3"))
    viewer = LiveViewer(live, "127.0.0.1", 0)
    loop = threading.Thread(target=viewer.run, args=(60,), daemon=True)
    loop.start()
    context = browser.new_context()
    try:
        page = context.new_page()
        page.goto(viewer.url)
        page.wait_for_selector(f"{READOUT}[data-x]", timeout=30000)
        live.set_twist((0.2, 0.0, 0.0))  # as the Drive button does
        time.sleep(1.0)
        assert viewer.last.command[0] > 0.1
        page.close()
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline and viewer.last.command != (0.0, 0.0, 0.0):
            time.sleep(0.05)
        assert viewer.last.command == (0.0, 0.0, 0.0)
    finally:
        context.close()
        viewer.close()
        loop.join(5)
