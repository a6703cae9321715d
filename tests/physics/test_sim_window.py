"""``omnikin sim``: the robot in MuJoCo's viewer window on a virtual X display (Xvfb), driven by
real key events (xdotool), its end state read from ``--report``, its window from a screenshot.

The tests hold on a busy machine: they assert on simulated and recorded time (each key event's
simulated time and wall arrival in the report), never on the pace of the machine. A screenshot
that must show the state after a key acted is taken after the simulator echoed (``--echo``) a
later key event and the window stopped changing (:func:`_shot_after`), not after a fixed sleep;
a sleep between two keys only sets their least distance in simulated time, and every wait has a
generous deadline that only guards against a hang."""

from __future__ import annotations

import contextlib
import json
import math
import os
import queue
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator

import numpy as np
import pytest

from support.cli import run_cli
from support.paths import omnikin_env
from support.servers import virtual_display

SPEED = 0.2  # m/s, --speed
TURN = 0.5  # rad/s, --turn
PERIOD = 0.02  # s, the simulator's control period: a key acts at the first control step after it
WAIT = 240.0  # s, longest wait for the simulator on a loaded machine (it catches up at its pace)


def _missing() -> str | None:
    for tool in ("Xvfb", "xdotool"):
        if shutil.which(tool) is None:
            return f"{tool} is not installed (apt-get install xvfb xdotool)"
    try:
        import mujoco.viewer  # noqa: F401
        from PIL import ImageGrab  # noqa: F401
    except ImportError as e:
        return f"the window test needs MuJoCo's viewer and Pillow ({e})"
    return None


@pytest.fixture(scope="module")
def display():
    """A fresh virtual display on a free number (Xvfb picks it: -displayfd)."""
    reason = _missing()
    if reason:
        pytest.skip(reason)
    with virtual_display() as name:
        yield name


def _xdotool(display: str, *args: str) -> str:
    out = subprocess.run(["xdotool", *args], env=dict(os.environ, DISPLAY=display), capture_output=True, text=True)
    return out.stdout.strip()


def _window(display: str, sim: subprocess.Popen) -> str:
    """The viewer's window id, once it is mapped (the model is built first)."""
    deadline = time.monotonic() + WAIT
    while time.monotonic() < deadline:
        assert sim.poll() is None, f"omnikin sim ended early: {sim.communicate()[1]}"
        found = _xdotool(display, "search", "--onlyvisible", "--name", "MuJoCo").split()
        if found:
            time.sleep(0.5)  # the first frames drawn
            return found[0]
        time.sleep(0.1)
    raise AssertionError(f"no MuJoCo window appeared within {WAIT:g} s")


@contextlib.contextmanager
def _running(display: str, *args: str, robot: str = "tomasi-omni3") -> Iterator[subprocess.Popen]:
    """``omnikin sim ROBOT ARGS`` on ``display``, killed on the way out if it still runs; run in a
    folder of its own (MuJoCo writes ``MUJOCO_LOG.TXT`` into the working folder when its window
    fails)."""
    with tempfile.TemporaryDirectory(prefix="omnikin-sim-") as folder:
        sim = subprocess.Popen(
            [sys.executable, "-m", "omnikin.cli.main", "sim", robot, *args],
            env=omnikin_env(DISPLAY=display),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=folder,
        )
        try:
            yield sim
        finally:
            if sim.poll() is None:
                sim.kill()
                sim.wait()


class Echo:
    """The actions ``omnikin sim --echo`` prints on stdout as they act, read in a thread."""

    def __init__(self, sim: subprocess.Popen):
        self.lines: queue.SimpleQueue[str] = queue.SimpleQueue()
        self.seen: list[str] = []
        self.stdout: list[str] = []
        threading.Thread(target=self._read, args=(sim.stdout,), daemon=True).start()

    def _read(self, stream) -> None:
        for line in stream:
            self.stdout.append(line)
            self.lines.put(line.split()[2] if len(line.split()) > 2 else "")

    def wait(self, count: int) -> list[str]:
        """The actions once ``count`` of them have acted (the simulator's pace, not the clock's)."""
        deadline = time.monotonic() + WAIT
        while len(self.seen) < count:
            try:
                self.seen.append(self.lines.get(timeout=max(0.0, deadline - time.monotonic())))
            except queue.Empty:
                raise AssertionError(f"the simulator did not act on the keys: {self.seen}") from None
        return self.seen


def _settled_shot(display: str, win: str) -> np.ndarray:
    """A screenshot of the window once its scene is at rest: two screenshots 0.4 s apart whose
    readout (top left: the simulated time) differs, so that they are two frames, and whose scene
    (between the readout and the keys' help at the bottom) is alike: at most 0.5 % of its pixels
    changed (a robot at rest still jitters by a few pixels on its contacts)."""
    deadline = time.monotonic() + WAIT
    last = _window_shot(display, win)
    while time.monotonic() < deadline:
        time.sleep(0.4)
        shot = _window_shot(display, win)
        if shot.shape == last.shape:
            height = shot.shape[0]
            readout, scene = slice(0, int(0.08 * height)), slice(int(0.4 * height), int(0.85 * height))
            changed = np.abs(shot[scene] - last[scene]).max(axis=2) > 8  # the contacts' jitter moves a few pixels
            if np.any(shot[readout] != last[readout]) and changed.mean() <= 0.005:
                return shot
        last = shot
    raise AssertionError("the window kept changing, or stopped drawing")


STOPPING = 0.8
"""Wall time [s] the tests leave a robot to stop after a release before the next key: at least
that much simulated time passes before that key acts (keys keep their wall-clock distances), or
the simulator skipped time, which it does only while the robot is at rest; stopping from 0.2 m/s
at 0.5 m/s^2 takes 0.4 s."""


def _space_after(display: str, echo: Echo, count: int) -> None:
    """Press space once the ``count``-th key event acted and the robot had :data:`STOPPING` to
    stop, and wait for its echo (event ``count + 1``, recorded with the robot's pose and twist at
    rest). Space acts in a later frame of the simulator's loop than the key before it (the key
    acted before its echo reached the test; space is read at the start of a later frame), so once
    it is echoed the window has been handed every frame up to that key's."""
    echo.wait(count)
    time.sleep(STOPPING)
    _xdotool(display, "key", "space")
    echo.wait(count + 1)


def _shot_after(display: str, win: str, echo: Echo, count: int) -> np.ndarray:
    """A screenshot that shows the state after the ``count``-th key event acted, the robot at
    rest: space pressed after it (:func:`_space_after`, event ``count + 1``), then a frame drawn
    after space's echo once the scene stopped changing (:func:`_settled_shot`). Without the later
    key a loaded machine could hand back a frame drawn before the key acted (the free camera after
    2 had acted)."""
    _space_after(display, echo, count)
    return _settled_shot(display, win)


def _stop(sim: subprocess.Popen) -> str:
    """End ``omnikin sim`` as a user would (SIGTERM: a normal end, the report is written) once
    the keys a test needs have acted, whatever the simulated time then; its stderr."""
    sim.send_signal(signal.SIGTERM)
    _, err = sim.communicate(timeout=WAIT)
    return err


PANEL = (slice(0.4, 0.95), slice(5, 240))
"""Where the viewer's left panel (250 px wide, dark) shows: rows as fractions of the height, columns [px]."""


def _panel(rgb: np.ndarray) -> np.ndarray:
    rows, cols = PANEL
    height = rgb.shape[0]
    return rgb[int(rows.start * height) : int(rows.stop * height), cols]


def _panel_shot(display: str, win: str) -> np.ndarray:
    """A screenshot once the viewer's left panel is drawn (or the last one after a while: the
    assertion says what it shows); the viewer acts on its keys in its own thread, at once."""
    deadline = time.monotonic() + WAIT
    shot = _window_shot(display, win)
    while time.monotonic() < deadline and np.mean(_panel(shot).mean(axis=2) < 60) <= 0.5:
        time.sleep(0.3)
        shot = _window_shot(display, win)
    return shot


def _blue(rgb: np.ndarray) -> np.ndarray:
    """The pixels whose colour is the chassis' blue (blue clearly above red and green; the floor
    is grey-white, the sky black, the wheels dark grey)."""
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return (b > 120) & (b > r + 40) & (b > g + 15)


def _blue_fraction(image) -> float:
    """Share of the pixels of ``image`` (PIL) in the chassis' blue."""
    return float(np.mean(_blue(np.asarray(image.convert("RGB"), dtype=int))))


def _window_shot(display: str, win: str) -> np.ndarray:
    """The window's pixels (rows top down, RGB) from a screenshot of the display."""
    from PIL import ImageGrab

    geometry = dict(line.split("=") for line in _xdotool(display, "getwindowgeometry", "--shell", win).split())
    if "X" not in geometry:  # the id went stale: take the window by its name again
        found = _xdotool(display, "search", "--onlyvisible", "--name", "MuJoCo").split()
        assert found, "the simulator's window is gone"
        shell = _xdotool(display, "getwindowgeometry", "--shell", found[-1])
        geometry = dict(line.split("=") for line in shell.split())
    left, top, width, height = (int(geometry[k]) for k in ("X", "Y", "WIDTH", "HEIGHT"))
    shot = ImageGrab.grab(xdisplay=display).crop((left, top, left + width, top + height))
    return np.asarray(shot.convert("RGB"), dtype=int)


def _blue_centre(rgb: np.ndarray) -> np.ndarray:
    """Centroid ``(column, row)`` [px] of the chassis' blue in a window's pixels."""
    rows, cols = np.nonzero(_blue(rgb))
    assert len(rows) > 100, "the chassis is not in the window"
    return np.array([cols.mean(), rows.mean()])


def _green(rgb: np.ndarray) -> np.ndarray:
    """The pixels of the true heading arrow's green (green well above red and blue; the chassis
    is blue, the floor grey, the wheels dark)."""
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return (g > 90) & (g > r + 50) & (g > b + 40)


def _magenta(rgb: np.ndarray) -> np.ndarray:
    """The pixels of the odometry arrow's magenta (red and blue high, green well below both)."""
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return (r > 100) & (b > 100) & (g < 0.6 * np.minimum(r, b)) & (np.abs(r - b) < 0.35 * np.maximum(r, b))


def test_held_keys_drive_turn_and_stop_the_robot_in_a_real_window(display, tmp_path):
    """W held, Q held, camera top, W held with space pressed: each key acts at the simulated time
    of its arrival, so the simulated time between a press and its release is their wall-clock
    distance on arrival to one control period, and the robot moves ``speed`` times that, whatever
    the machine's load (the report's recorded times; the simulation may lag the clock). Q is
    pressed once the robot stopped, as the twist recorded at Q's press shows (a loaded machine may
    skip the simulated time the robot stood still: the gap between W's release and Q is then
    shorter than the test's sleep, but never shorter than the stop)."""
    from PIL import Image

    report = tmp_path / "run.json"
    with _running(
        display, "--duration", "40", "--speed", str(SPEED), "--turn", str(TURN), "--report", str(report), "--echo"
    ) as sim:
        echo = Echo(sim)
        win = _window(display, sim)
        _xdotool(display, "windowfocus", win)
        # the next key is sent once the last one acted (echoed): the two reached the simulator
        # at least the sleep apart, however late a busy machine's window hands it its key events
        _xdotool(display, "keydown", "w")  # forward while held
        echo.wait(1)
        time.sleep(1.0)
        _xdotool(display, "keyup", "w")
        echo.wait(2)
        time.sleep(STOPPING)  # stops within the acceleration limit
        _xdotool(display, "keydown", "q")  # counter-clockwise while held
        echo.wait(3)
        time.sleep(1.0)
        _xdotool(display, "keyup", "q")
        echo.wait(4)
        time.sleep(STOPPING)
        _xdotool(display, "key", "2")  # camera looking down on the robot
        top = _shot_after(display, win, echo, 5)
        Image.fromarray(top.astype(np.uint8)).save(tmp_path / "top.png")  # to look at when it fails
        _xdotool(display, "keydown", "w")
        echo.wait(7)
        time.sleep(1.0)
        _xdotool(display, "key", "space")  # stops although W is still held
        time.sleep(1.2)
        _xdotool(display, "keyup", "w")
        _, err = sim.communicate(timeout=WAIT)
    assert sim.returncode == 0, err
    run = json.loads(report.read_text())
    assert run["end"] == "duration" and run["releases"]
    assert run["sim_time"] == pytest.approx(40.0, abs=PERIOD)
    events = run["events"]
    names = [e["key"] for e in events]
    assert names == ["forward", "release", "turn_left", "release", "camera_top", "stop", "forward", "stop"], names
    # keys act in simulated time at their wall-clock arrival: while a key is held no time is
    # skipped, so a press and its release (or space) are as far apart as on arrival, to one period
    for press, release in ((0, 1), (2, 3), (6, 7)):
        gap = events[release]["t"] - events[press]["t"]
        assert gap == pytest.approx(events[release]["wall"] - events[press]["wall"], abs=PERIOD + 1e-6)

    # W: +x of the robot (heading 0 at the start) at --speed for the time held: the ramp up loses
    # what the ramp down after the release gains (the same acceleration limit both ways)
    held = events[1]["t"] - events[0]["t"]
    after_forward = events[2]["pose"]
    assert held > 0.9  # held 1 s after its press acted
    assert after_forward[0] == pytest.approx(SPEED * held, rel=0.05, abs=0.005)
    assert abs(after_forward[1]) < 0.01 * after_forward[0] and abs(after_forward[2]) < 0.01

    # Q: pressed with the robot at rest (the twist when it acted), then counter-clockwise on the
    # spot at --turn for the time held
    assert math.hypot(*events[2]["twist"][:2]) < 0.005 and abs(events[2]["twist"][2]) < 0.01, events[2]["twist"]
    held = events[3]["t"] - events[2]["t"]
    after_turn = events[4]["pose"]
    assert held > 0.9
    assert after_turn[2] == pytest.approx(TURN * held, rel=0.05, abs=0.01)
    assert math.hypot(after_turn[0] - after_forward[0], after_turn[1] - after_forward[1]) < 0.005
    assert events[6]["pose"] == pytest.approx(after_turn, abs=1e-3)  # at rest until W

    # space: stopped, with W still held, within the stopping distance v^2 / (2 a) (a = 0.5 m/s^2)
    at_space, end = events[7]["pose"], run["pose"]
    assert math.hypot(end[0] - at_space[0], end[1] - at_space[1]) < SPEED**2 / (2 * 0.5) + 0.005
    assert math.hypot(*run["twist"][:2]) < 0.005

    # the window shows the robot: its blue in the middle of the window, seen from above ...
    height, width = top.shape[:2]
    middle = top[height // 3 : 2 * height // 3, width // 3 : 2 * width // 3]
    assert np.mean(_blue(middle)) > 0.1
    # ... and the green heading arrow from its centre along the heading (top camera: world +x to
    # the right, +y up in the window)
    rows, cols = np.nonzero(_green(top))
    assert len(rows) > 50, "no heading arrow in the window"
    chassis = _blue_centre(top)
    direction = math.atan2(-(rows.mean() - chassis[1]), cols.mean() - chassis[0])
    print(f"heading {math.degrees(after_turn[2]):.1f} deg, arrow drawn at {math.degrees(direction):.1f} deg")
    assert math.degrees(abs(direction - after_turn[2])) < 5.0


def test_keys_a_layout_cannot_obey_are_marked_and_say_why_once(display, tmp_path):
    """diff-drive: two fixed wheels on one axle cannot slide sideways (Campion et al.'s type (2,0)),
    so A (vy) is dropped: the robot stays where it is, stderr says why once although A was
    pressed twice, and W still drives (at the default --speed 0.2 m/s)."""
    report = tmp_path / "run.json"
    with _running(display, "--report", str(report), "--echo", robot="diff-drive") as sim:
        echo = Echo(sim)
        win = _window(display, sim)
        _xdotool(display, "windowfocus", win)
        for presses in (2, 4):
            _xdotool(display, "keydown", "a")
            echo.wait(presses - 1)
            time.sleep(0.6)
            _xdotool(display, "keyup", "a")
            echo.wait(presses)
        _xdotool(display, "keydown", "w")
        echo.wait(5)
        time.sleep(1.0)
        _xdotool(display, "keyup", "w")
        _space_after(display, echo, 6)  # the robot stopped: its pose at space is where W took it
        err = _stop(sim)
    assert sim.returncode == 0, err
    run = json.loads(report.read_text())
    names = [e["key"] for e in run["events"]]
    assert names == ["left", "release", "left", "release", "forward", "release", "stop"], names
    notes = [line for line in err.splitlines() if "(left)" in line]
    assert notes == ["omnikin: note: sim: A (left) on diff-drive: its fixed wheels forbid vy"], err
    assert run["events"][4]["pose"] == pytest.approx([0.0, 0.0, 0.0], abs=1e-3)  # A moved nothing
    held = run["events"][5]["t"] - run["events"][4]["t"]  # W: forward for the time held
    stopped = run["events"][6]
    assert math.hypot(*stopped["twist"][:2]) < 0.005, stopped["twist"]
    assert held > 0.5 and stopped["pose"][0] == pytest.approx(0.2 * held, rel=0.05, abs=0.005)
    assert abs(stopped["pose"][1]) < 1e-3
    assert run["commands"]["projected"] == 2 and set(run["not_obeyed"]) == {"left", "right"}


def test_a_termination_signal_closes_the_window_and_exits_like_every_command(display):
    with _running(display) as sim:  # no --duration: runs until stopped
        _window(display, sim)
        sim.send_signal(signal.SIGTERM)
        _, err = sim.communicate(timeout=30)
    # stopping a window is its normal end (0, as for every server); not 139 (a segfault in the
    # X error of a render thread drawing while the process exits)
    assert sim.returncode == 0, err
    assert err.strip().splitlines() == ["omnikin sim: stopped (SIGTERM)"]


def test_without_a_display_the_simulator_says_how_to_get_one(capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    rc, out, err = run_cli(capsys, "sim", "tomasi-omni3", "--duration", "1")
    assert rc == 2
    assert len(err.strip().splitlines()) == 1 and "DISPLAY" in err and "xvfb-run" in err


STEP = math.radians(15.0)  # one press of [ or ]
SLOW = 0.1
"""--speed [m/s] of the camera test: the top camera sees about 1.06 m either side of its middle
(a 694 px wide window at 321 px/m), so the chassis (0.25 m extent) stays in view for 8 s of W
held, five times the 1.5 s the test holds it (a loaded machine hands the window its release late)."""


def _readout_shown(rgb: np.ndarray) -> bool:
    """The readout's overlay in the window's top left corner: a dark box (the floor seen from the
    top camera is white and light grey) holding light text."""
    grey = rgb[10:140, 10:360].mean(axis=2)
    return bool(np.mean(grey < 170) > 0.8 and 0.02 < np.mean(grey > 230) < 0.2)


def test_steering_keys_turn_the_wheels_at_rest_and_the_cameras_show_the_chassis_where_they_should(display, tmp_path):
    """synchro: three centred steered wheels, so steering at rest turns each tyre about its own
    contact point and the robot neither moves nor tips (villasenor-omni3's trailing legs tip it
    over when they swing, docs/physics.md known limits; xr4000's 20 mm trail drags its hubs).

    ``]`` ``]`` ``[`` steer every wheel to +15, +30, +15 deg; then W: the kinematics of
    ``vx`` on a synchro drive is every wheel at 0 deg rolling at ``v / r``, so the wheels steer
    back and the robot drives along its +x axis (heading kept) at ``--speed`` for the time held
    (slow: the chassis stays in the top camera's view however late the release arrives).
    ``]`` pressed while driving does nothing (steering by hand only at rest).

    The top camera looks straight down from ``d = 8 e`` (``e`` the robot's extent, 0.25 m) onto
    the start: a point at height ``z`` moving ``dx`` along +x moves ``dx (H / 2) / ((d - z)
    tan(fovy / 2))`` pixels to the right in a window ``H`` pixels high (pinhole camera). The
    follow camera keeps the chassis in the middle of the window after it drove off."""
    import mujoco
    from PIL import Image

    from omnikin import load_robot
    from omnikin.physics.mjcf import mjcf

    robot = load_robot("synchro")
    report = tmp_path / "run.json"
    with _running(
        display,
        "--camera",
        "top",
        "--speed",
        str(SLOW),
        "--report",
        str(report),
        "--echo",
        robot="synchro",
    ) as sim:
        echo = Echo(sim)
        win = _window(display, sim)
        _xdotool(display, "windowfocus", win)
        for count, key in enumerate(("bracketright", "bracketright", "bracketleft"), start=1):
            _xdotool(display, "key", key)
            echo.wait(count)  # acted: the next key arrives at least 0.8 s later, the wheels steered
            time.sleep(0.8)
        at_start = _settled_shot(display, win)  # the robot where it started (steering moves nothing)
        _xdotool(display, "keydown", "w")
        echo.wait(4)
        time.sleep(1.5)
        _xdotool(display, "keyup", "w")
        top_after = _shot_after(display, win, echo, 5)  # the robot at rest where it stopped
        _xdotool(display, "key", "3")
        time.sleep(0.5)
        _xdotool(display, "keydown", "w")
        time.sleep(0.7)
        _xdotool(display, "key", "bracketright")  # while driving: ignored
        time.sleep(0.8)
        _xdotool(display, "keyup", "w")
        follow_after = _shot_after(display, win, echo, 10)
        _xdotool(display, "key", "Tab")  # not the simulator's: goes on to the viewer (its left panel)
        viewer_panel = _panel_shot(display, win)
        err = _stop(sim)
        shots = {"at_start": at_start, "top_after": top_after, "follow_after": follow_after, "panel": viewer_panel}
        for name, rgb in shots.items():
            Image.fromarray(rgb.astype(np.uint8)).save(tmp_path / f"{name}.png")  # to look at when it fails
    assert sim.returncode == 0, err
    run = json.loads(report.read_text())
    events = run["events"]
    names = [e["key"] for e in events]
    assert names == [
        "steer_left",
        "steer_left",
        "steer_right",
        "forward",
        "release",
        "stop",
        "camera_follow",
        "forward",
        "steer_left",
        "release",
        "stop",
    ], names

    # each event records the steering reached before it: 0, +15, +30, then +15 when W is pressed
    for event, angle in zip(events[:4], (0.0, STEP, 2 * STEP, STEP), strict=True):
        assert event["steer"] == pytest.approx([angle] * 3, abs=math.radians(0.5)), (event["key"], event["steer"])
    # steering at rest moved nothing
    assert math.hypot(*events[3]["pose"][:2]) < 1e-3 and abs(events[3]["pose"][2]) < 1e-3

    # W: every wheel steered back to 0 deg, the robot drove along +x at --speed for the time held
    # (in simulated time: as far apart as the key's press and release arrived, to one period)
    # (space after it found the robot at rest, where the screenshot shows it)
    held = events[4]["t"] - events[3]["t"]
    after = events[5]["pose"]
    assert held == pytest.approx(events[4]["wall"] - events[3]["wall"], abs=PERIOD + 1e-6)
    assert held > 1.4
    assert math.hypot(*events[5]["twist"][:2]) < 0.005, events[5]["twist"]
    assert events[4]["steer"] == pytest.approx([0.0] * 3, abs=math.radians(0.5))
    assert after[0] == pytest.approx(SLOW * held, rel=0.05, abs=0.005)
    assert abs(after[1]) < 0.01 * after[0] and abs(after[2]) < 0.01
    # ] while driving left the steering where the kinematics put it; W drove on for the time held
    assert events[9]["steer"] == pytest.approx([0.0] * 3, abs=math.radians(0.5))
    held_again, end = events[9]["t"] - events[7]["t"], events[10]["pose"]
    assert end[0] - after[0] == pytest.approx(SLOW * held_again, rel=0.05, abs=0.005)
    assert run["steer"] == pytest.approx([0.0] * 3, abs=math.radians(0.5))

    # the top camera did not move: the chassis' top face (z = 1.5 r: thickness r centred at hub
    # height r) moved to the right by the distance driven, at the pinhole camera's scale
    height = at_start.shape[0]
    extent = max(max(abs(w.x), abs(w.y)) + w.radius for w in robot.wheels)
    top_face = 1.5 * robot.wheels[0].radius
    fovy = math.radians(mujoco.MjModel.from_xml_string(mjcf(robot)).vis.global_.fovy)
    px_per_m = (height / 2) / ((8 * extent - top_face) * math.tan(fovy / 2))
    start_px, moved_px = _blue_centre(at_start), _blue_centre(top_after)
    centre = np.array([at_start.shape[1], height]) / 2
    print(f"top camera: chassis at {start_px} px, after {after[0]:.3f} m at {moved_px} px ({px_per_m:.1f} px/m)")
    assert (after[0] + extent) * px_per_m < at_start.shape[1] / 2, f"W held {held:.1f} s: the chassis left the view"
    assert np.hypot(*(start_px - centre)) < 0.02 * height
    assert moved_px[0] - start_px[0] == pytest.approx(after[0] * px_per_m, rel=0.1)
    assert abs(moved_px[1] - start_px[1]) < 0.02 * height

    # the follow camera: the chassis in the middle of the window, although it drove on
    follow_px = _blue_centre(follow_after)
    print(f"follow camera: chassis at {follow_px} px after driving to x = {end[0]:.3f} m")
    assert np.hypot(*(follow_px - centre)) < 0.05 * height

    # the readout is drawn (seen from the top camera, over the light floor)
    assert _readout_shown(at_start) and _readout_shown(top_after)

    # the simulator took the keys over (releases seen) and still hands the viewer the keys it does
    # not use: Tab opened the viewer's left panel (dark) where the grey floor was
    assert run["releases"]
    assert np.mean(_panel(follow_after).mean(axis=2) < 60) < 0.05
    assert np.mean(_panel(viewer_panel).mean(axis=2) < 60) > 0.5


def test_the_on_screen_help_marks_the_keys_a_layout_cannot_obey_and_says_why():
    pytest.importorskip("mujoco")
    from omnikin import load_robot
    from omnikin.physics.interactive import InteractiveSim

    lines = InteractiveSim(load_robot("diff-drive")).key_help()
    assert lines[0].startswith("W/S, A/D*, Q/E move")
    assert lines[1:] == ["* A/D on diff-drive: its fixed wheels forbid vy"]
    assert InteractiveSim(load_robot("tomasi-omni3")).key_help()[0].startswith("W/S, A/D, Q/E move")


AS_BUILT_DIFF_DRIVE = """omnikin: 1
name: diff-drive
wheels:
  - {name: left, type: standard, x: 0.0, y: 0.20625, drive_deg: 0, radius: 0.0825,
     encoder: {ticks_per_rev: 500, gear_ratio: 19.7}, motor: dc}
  - {name: right, type: standard, x: 0.0, y: -0.20625, drive_deg: 0, radius: 0.086625,
     encoder: {ticks_per_rev: 500, gear_ratio: 19.7}, motor: dc}
  - {name: castor, type: castor, x: -0.2, y: 0.0, drive_deg: 0, radius: 0.03, steer: {offset: 0.03}}
"""
"""diff-drive as built: its wheels 25 % further apart (track 0.4125 m instead of 0.33 m) and its
right wheel 5 % larger than the file says; the odometry keeps the file's."""
TRACK, RADIUS = 0.33, 0.0825  # the nominal diff-drive's track [m] and wheel radius [m] (presets/diff-drive.yaml)


def _diff_drive_odometry(segments) -> np.ndarray:
    """Pose ``(x, y, theta)`` a differential drive's odometry gives for ``segments`` of wheel
    angles ``(left, right)`` [rad], each driven at a constant ratio of the two wheels' speeds (a
    straight line or a turn on the spot): each is an arc of length ``ds = r (dl + dr) / 2`` turning
    by ``dtheta = r (dr - dl) / b`` (Siegwart and Nourbakhsh, Introduction to Autonomous Mobile
    Robots, eq. 5.7), whose chord is ``ds sinc(dtheta / 2)`` along ``theta + dtheta / 2``."""
    x = y = theta = 0.0
    for (l0, r0), (l1, r1) in segments:
        dl, dr = RADIUS * (l1 - l0), RADIUS * (r1 - r0)
        ds, dtheta = (dl + dr) / 2, (dr - dl) / TRACK
        chord = ds * np.sinc(dtheta / 2 / math.pi)
        x += chord * math.cos(theta + dtheta / 2)
        y += chord * math.sin(theta + dtheta / 2)
        theta += dtheta
    return np.array([x, y, theta])


def _angle_error(a: float, b: float) -> float:
    return abs(math.remainder(a - b, 2 * math.pi))


def test_the_window_draws_the_odometry_beside_the_truth_where_the_wheels_say(display, tmp_path):
    """diff-drive as built (``--true-robot``: track 25 % wider, right wheel 5 % larger) driven W,
    Q, W: its odometry (the nominal robot's) parts from the truth. The window's two arrows, read
    back from the scene (the report's ``markers``), stand at the true pose (green) and at the
    odometry computed here from the recorded wheel angles with the closed-form arcs of a
    differential drive (magenta, narrower, higher); a screenshot from the top camera shows the
    magenta arrow there, at the pinhole scale ``(H / 2) / ((d - z) tan(fovy / 2))``."""
    import mujoco
    from PIL import Image

    from omnikin import load_robot
    from omnikin.physics.mjcf import mjcf

    true_file = tmp_path / "as-built.yaml"
    true_file.write_text(AS_BUILT_DIFF_DRIVE)
    report = tmp_path / "run.json"
    args = ("--duration", "30", "--true-robot", str(true_file), "--report", str(report), "--echo")
    with _running(display, *args, robot="diff-drive") as sim:
        echo = Echo(sim)
        win = _window(display, sim)
        _xdotool(display, "windowfocus", win)
        for count, (key, held) in enumerate((("w", 1.2), ("q", 2.5), ("w", 1.2)), start=1):
            _xdotool(display, "keydown", key)
            echo.wait(2 * count - 1)
            time.sleep(held)
            _xdotool(display, "keyup", key)
            echo.wait(2 * count)
            time.sleep(STOPPING)  # stopped within the acceleration limits before the next key
        _xdotool(display, "key", "2")  # the top camera, down on where the robot stands
        top = _shot_after(display, win, echo, 7)
        Image.fromarray(top.astype(np.uint8)).save(tmp_path / "top.png")  # to look at when it fails
        _, err = sim.communicate(timeout=WAIT)
    assert sim.returncode == 0, err
    run = json.loads(report.read_text())
    events = run["events"]
    names = [e["key"] for e in events]
    assert names == ["forward", "release", "turn_left", "release", "forward", "release", "camera_top", "stop"], names

    # the odometry from the wheel angles: straight until Q's press, on the spot until the second
    # W's press, straight to the end (each segment also holds the stop after its release)
    marks = [(0.0, 0.0), events[2]["wheels"], events[4]["wheels"], run["wheels"]]
    odometry = _diff_drive_odometry(zip(marks, marks[1:], strict=False))
    truth = np.array(run["pose"])
    drawn_odometry, drawn_truth = np.array(run["markers"]["odometry"]), np.array(run["markers"]["truth"])
    print(f"truth {truth}, odometry (closed form) {odometry}, drawn {drawn_truth[:3]} and {drawn_odometry[:3]}")
    assert odometry[2] == pytest.approx(TURN * (events[3]["t"] - events[2]["t"]), rel=0.1)  # Q turned it
    # the two poses part: the wider true track turns the robot less than its odometry says
    assert math.degrees(_angle_error(truth[2], odometry[2])) > 8.0
    assert math.hypot(*(truth[:2] - odometry[:2])) > 0.02
    # the arrows stand where they should and point where they should
    assert drawn_truth[:2] == pytest.approx(truth[:2], abs=1e-3)
    assert math.degrees(_angle_error(drawn_truth[2], truth[2])) < 0.1
    assert drawn_odometry[:2] == pytest.approx(odometry[:2], abs=0.005)
    assert math.degrees(_angle_error(drawn_odometry[2], odometry[2])) < 0.5
    # the odometry's arrow is narrower and above the truth's (seen where the two cross)
    assert drawn_odometry[4] == pytest.approx(drawn_truth[4] / 2) and drawn_odometry[3] > drawn_truth[3]

    # the top camera looks straight down on where the robot stood when 2 was pressed, from
    # d = 8 e (e the robot's extent): a point (X, Y, z) shows (X - x0, Y - y0) (H / 2) / ((d - z)
    # tan(fovy / 2)) pixels from the window's middle (+x right, +y up). Each arrow, 1.2 e long
    # (docs/physics.md), shows in its colour from its pose along its heading: the middle of its
    # pixels on that ray, between 0.4 and 0.75 of its length from the tail (a wider head ahead)
    robot = load_robot("diff-drive")
    extent = max(max(abs(w.x), abs(w.y)) + w.radius for w in robot.wheels)
    fovy = math.radians(mujoco.MjModel.from_xml_string(mjcf(robot)).vis.global_.fovy)
    height, width = top.shape[:2]
    x0, y0, _ = events[6]["pose"]
    for name, pose, z, colour in (
        ("odometry", odometry, drawn_odometry[3], _magenta),
        ("truth", truth, drawn_truth[3], _green),
    ):
        scale = (height / 2) / ((8 * extent - z) * math.tan(fovy / 2))
        tail = np.array([width / 2 + (pose[0] - x0) * scale, height / 2 - (pose[1] - y0) * scale])
        rows, cols = np.nonzero(colour(top))
        assert len(rows) > 30, f"no {name} arrow in the window"
        offset = np.array([cols.mean(), -rows.mean()]) - np.array([tail[0], -tail[1]])  # +y up
        along = offset @ [math.cos(pose[2]), math.sin(pose[2])] / (1.2 * extent * scale)
        across = abs(offset @ [-math.sin(pose[2]), math.cos(pose[2])])
        print(f"{name} arrow: its middle {along:.2f} of its length ahead of its tail, {across:.1f} px aside")
        assert 0.4 < along < 0.75 and across < 0.03 * height, name


ROOM = """\
omnikin_world: 1
name: box-room
start: [0.5, -0.3, 0]
walls:
  - {points: [[-2, -2], [2, -2], [2, 2], [-2, 2], [-2, -2]], thickness: 0.1, height: 0.5}
"""


def test_a_robot_with_a_lidar_shows_its_scan_of_the_room_in_the_window(display, tmp_path):
    """tomasi-omni3-lidar standing at (0.5, -0.3) in a 4 m room (inner faces at +-1.95 m): the
    window draws a point for each beam that met a wall (all but the 1 % lost), the nearest the
    east face 1.45 m away (the preset's 0.01 m range noise, 1 % dropouts), and no touch."""
    (tmp_path / "room.yaml").write_text(ROOM)
    report = tmp_path / "run.json"
    with _running(
        display,
        "--world",
        str(tmp_path / "room.yaml"),
        "--duration",
        "2",
        "--report",
        str(report),
        robot="tomasi-omni3-lidar",
    ) as sim:
        _, err = sim.communicate(timeout=WAIT)
    assert sim.returncode == 0, err
    run = json.loads(report.read_text())
    drawn, nearest = run["markers"]["scan"]
    assert 330 <= drawn <= 360, drawn
    assert nearest == pytest.approx(1.95 - 0.5, abs=0.05)
    assert run["markers"]["contacts"] == [0] and run["contacts"] == []
