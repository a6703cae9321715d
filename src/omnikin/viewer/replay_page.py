"""``omnikin view --replay``: recorded runs played back in the browser, with a timeline.

:class:`ReplayViewer` serves, through the front server (:mod:`omnikin.viewer.front`: the
camera keys 1/2/3/4 work, 4 the *run* camera, the driving keys do nothing), a page with the robot drawn from its
physical description (:class:`~omnikin.viewer.scene.RobotDrawing`), the ground grid, the
UMBmark square of the report's side, and a **Replay** folder: the run selector, the time
slider [s], Play/Pause, the playback speed; the whole true and odometry paths of the selected
run are drawn, the robot and the odometry's arrow at the slider's time, with the readouts of
:mod:`omnikin.viewer.panel` (pose, twist, joint table, wheel-speed plot) from
:class:`~omnikin.viewer.replay.TrackReplay`; a readout the recording has no data for (the
command, the residual, a pose topic a bag lacks) says "not recorded".

**Shown together** (a checkbox per run): other runs beside the selected one (before and after
calibration; the runs of several files, :func:`~omnikin.viewer.replay_sources.combine`), each
in a colour of its own (:data:`RUN_COLOURS`: its true path, its odometry's path paler, a
see-through robot with its heading arrow at the slider's time, its name at its path's end);
the time slider runs to the longest of the runs shown. Cameras: the presets of
:class:`~omnikin.viewer.panel.CameraControl`, *top* and *follow* moving with the selected run's
robot, *run* framing every run shown; the first view looks at the selected run's robot.

Loop: every :data:`~omnikin.viewer.app.CONTROL_PERIOD` s of wall time, while playing, the time
advances by the wall time elapsed times the speed (and stops at the run's end); the scene is
drawn when the time or the run changed (slider, run selector, playing). The element
``#omnikin-replay`` carries the run's name, the time, the duration and whether it plays in its
``data-`` attributes, for programs that read the page.
"""

from __future__ import annotations

import html
import math
import threading
import time

import numpy as np

from .live import Snapshot
from .panel import REPLAY_KEY_HELP, CameraControl, FirstView, Readouts, robot_extent
from .replay import Track, TrackReplay
from .replay_sources import ReplaySource
from .scene import RobotDrawing, RobotView, Trail, draw_world
from .serving import CONTROL_PERIOD, SLOW_PERIOD, PageServers

SPEEDS = ("0.25", "0.5", "1", "2", "4", "8", "16")
"""Playback speeds offered (times real time)."""
TIME_STEP = 0.01
"""Resolution of the time slider [s]."""
RUN_COLOURS = ((230, 120, 20), (40, 110, 230), (150, 90, 40), (0, 150, 150), (120, 60, 220), (200, 40, 90))
"""Colours of the runs shown beside the selected one, the first one free in turn (the selected
run keeps green for the truth and magenta for the odometry)."""
GHOST_OPACITY = 0.4
"""Opacity of the robots of the runs shown beside the selected one."""


def paler(colour) -> tuple[int, int, int]:
    """``colour`` half way to white (a run's odometry path beside its true path)."""
    r, g, b = (int(round((c + 255) / 2)) for c in colour)
    return r, g, b


class ShownRun:
    """A run shown beside the selected one (module docstring), drawn under ``/runs/{index}``."""

    def __init__(self, scene, index: int, replay: TrackReplay, description, colour):
        self.replay = replay
        self.colour = colour
        root = f"/runs/{index}"
        self.root = scene.add_frame(root, show_axes=False)
        self.drawing = RobotDrawing(scene, description, f"{root}/robot", opacity=GHOST_OPACITY, heading_colour=colour)
        track = replay.track
        for key, series, shade in (("truth", track.truth, colour), ("odometry", track.odometry, paler(colour))):
            trail = Trail(scene, f"{root}/{key}", shade, capacity=10**6, spacing=0.0)
            for x, y, _ in series.poses:
                trail.add(float(x), float(y))
            trail.flush()
        x, y, _ = track.truth.poses[-1]
        scene.add_label(f"{root}/name", track.name, position=(float(x), float(y), 0.05), font_screen_scale=0.7)

    def show(self, t: float) -> None:
        s = self.replay.snapshot(t)
        self.drawing.update(s.truth, s.wheel_angles, s.steer, s.roller_angles)

    def remove(self) -> None:
        self.root.remove()


def status_html(name: str, t: float, duration: float, playing: bool) -> str:
    """The replay's status element (module docstring)."""
    state = "playing" if playing else "paused"
    return (
        f'<div id="omnikin-replay" data-run="{html.escape(name, quote=True)}" data-t="{t!r}" '
        f'data-duration="{duration!r}" data-playing="{str(playing).lower()}" style="font-size:0.8em">'
        f"{html.escape(name)}: {t:.2f} of {duration:.2f} s, {state}</div>"
    )


class ReplayViewer:
    """The replay page of ``source`` (module docstring), served at ``host``/``port`` (0: a
    free port, see :attr:`url`)."""

    def __init__(self, source: ReplaySource, host: str = "127.0.0.1", port: int = 8080):
        from ..physics.description import describe

        if not source.tracks:
            raise ValueError("a replay needs at least one track")
        self.source = source
        self.description = describe(source.robot)
        self.shown: dict[str, ShownRun] = {}  # the runs shown beside the selected one, by name
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._closed = threading.Event()
        self._actions: list[str] = []
        self.servers = PageServers(host, port, self._on_key)
        self.server = self.servers.viser
        try:  # (Ctrl-C while the page is being built stops the servers too)
            scene = self.server.scene
            reach = max(float(np.abs(s.poses[:, :2]).max()) for tr in source.tracks for s in (tr.truth, tr.odometry))
            side = source.side or 0.0
            extent = max(5.0, side + 1.0, math.ceil(reach) + 1.0)
            draw_world(scene, extent, side)
            self.robot = RobotView(scene, self.description, capacity=10**6, spacing=0.0)
            self.trails = self.robot.trails
            gui = self.server.gui
            names = [tr.name for tr in source.tracks]
            with gui.add_folder("Replay"):
                gui.add_markdown(f"**{html.escape(source.label)}** (robot {html.escape(source.robot.name)})")
                gui.add_markdown(REPLAY_KEY_HELP)
                self.run_choice = gui.add_dropdown("run", names, initial_value=names[0])
                self.slider = gui.add_slider("time [s]", 0.0, 1.0, TIME_STEP, 0.0)
                self.play_button = gui.add_button("Play", hint="play from the slider's time; again: pause")
                self.speed = gui.add_dropdown("speed [x real time]", SPEEDS, initial_value="1")
                self.status = gui.add_html("")
                with gui.add_folder("shown together", expand_by_default=len(names) <= 8):
                    self.together = {name: gui.add_checkbox(name, False) for name in names}
            for name, box in self.together.items():
                box.on_update(self._together_request(name))
            self.extent = robot_extent(self.description)
            self.camera = CameraControl(self.server, self.extent, fit=self.box)
            self.first_view = FirstView(self.server, self.extent)
            self.readouts = Readouts(self.server, self.description)
            self.run_choice.on_update(lambda _: self._request("run"))
            self.slider.on_update(lambda e: self._request("seek") if e.client_id is not None else None)
            self.play_button.on_click(lambda _: self._request("toggle"))
            self.playing = False
            self.t = 0.0
            self.replay: TrackReplay | None = None
            self.last: Snapshot | None = None
            self.frames = 0
            self._select(names[0])
        except BaseException:
            self.servers.stop()
            raise

    @property
    def url(self) -> str:
        return self.servers.url

    # --- page events (viser's and the front server's threads) ------------------------------------
    def _on_key(self, message: dict) -> None:
        if message.get("type") == "press" and str(message.get("action", "")).startswith("camera_"):
            with self._lock:
                self._actions.append(message["action"])
            self._wake.set()

    def _together_request(self, name: str):
        """The handler of run ``name``'s "shown together" checkbox."""
        return lambda _: self._request(f"together {name}")

    def _request(self, what: str) -> None:
        with self._lock:
            self._actions.append(what)
        self._wake.set()

    # --- state ---------------------------------------------------------------------------------
    def _track(self, name: str) -> Track:
        return next(tr for tr in self.source.tracks if tr.name == name)

    def _replay(self, track: Track) -> TrackReplay:
        return TrackReplay(track.robot or self.source.robot, self.description, track)

    @property
    def duration(self) -> float:
        """The longest of the runs shown [s]."""
        assert self.replay is not None
        return max([self.replay.duration] + [run.replay.duration for run in self.shown.values()])

    def box(self) -> tuple[float, float, float, float]:
        """``(x_min, y_min, x_max, y_max)`` [m] of the true and odometry paths of the runs shown."""
        assert self.replay is not None
        tracks = [self.replay.track] + [run.replay.track for run in self.shown.values()]
        points = np.vstack([series.poses[:, :2] for tr in tracks for series in (tr.truth, tr.odometry)])
        (x0, y0), (x1, y1) = points.min(axis=0), points.max(axis=0)
        return float(x0), float(y0), float(x1), float(y1)

    def _together(self, name: str) -> None:
        """The checkbox of run ``name`` changed: show it beside the selected run, or no more."""
        assert self.replay is not None
        wanted = bool(self.together[name].value) and name != self.replay.track.name
        with self.server.atomic():
            if wanted and name not in self.shown:
                index = [tr.name for tr in self.source.tracks].index(name)
                used = {run.colour for run in self.shown.values()}
                colour = next(
                    (c for c in RUN_COLOURS if c not in used), RUN_COLOURS[len(self.shown) % len(RUN_COLOURS)]
                )
                self.shown[name] = ShownRun(
                    self.server.scene, index, self._replay(self._track(name)), self.description, colour
                )
            elif not wanted and name in self.shown:
                self.shown.pop(name).remove()
            self.slider.max = max(self.duration, TIME_STEP)
            self.camera.refit()

    def _select(self, name: str) -> None:
        track = self._track(name)
        self.replay = self._replay(track)
        self.t = 0.0
        self.playing = False
        if name in self.shown:  # the selected run is drawn as the robot, not beside it
            self.shown.pop(name).remove()
        for other, box in self.together.items():
            if box.value and other != name and other not in self.shown:
                self._together(other)
        duration = self.duration
        self.first_view.at = None  # another run: its robot
        self.first_view.frame(track.truth.poses[0])
        with self.server.atomic():
            self.camera.refit()
            self.slider.max = max(duration, TIME_STEP)
            self.slider.value = 0.0  # type: ignore[misc]  # (viser: a props field shadows the setter for mypy)
            self.play_button.label = "Play"
            for key, series in (("truth", track.truth), ("odometry", track.odometry)):
                trail = self.trails[key]
                trail.clear()
                for x, y, _ in series.poses:
                    trail.add(float(x), float(y))
                trail.flush()
            self.readouts.reset()

    def _handle(self, action: str) -> None:
        assert self.replay is not None
        if action == "run":
            self._select(str(self.run_choice.value))
        elif action == "seek":
            self.t = min(max(float(self.slider.value), 0.0), self.duration)
        elif action.startswith("together "):
            self._together(action.removeprefix("together "))
        elif action == "toggle":
            self.set_playing(not self.playing)
        else:
            self.camera.action(action)

    def set_playing(self, playing: bool) -> None:
        """Play from the current time (from the start when at the end) or pause."""
        assert self.replay is not None
        if playing and self.t >= self.duration:
            self.t = 0.0
        self.playing = playing
        self.play_button.label = "Pause" if playing else "Play"

    def run(self, duration: float | None = None) -> str:
        """Serve until :meth:`close` (``"closed"``) or ``duration`` [s] of wall time
        (``"duration"``)."""
        start = time.monotonic()
        last = start
        slow_next = 0.0
        drawn: tuple[str, float] | None = None
        while not self._closed.is_set():
            now = time.monotonic()
            if duration is not None and now - start >= duration:
                return "duration"
            with self._lock:
                actions, self._actions = self._actions, []
            for action in actions:
                self._handle(action)
            assert self.replay is not None
            if self.playing:
                self.t += (now - last) * float(self.speed.value)
                if self.t >= self.duration:
                    self.t = self.duration
                    self.set_playing(False)
            last = now
            state = (self.replay.track.name, self.t)
            if state != drawn or now - start >= slow_next:
                self._draw(drawn is None or state[0] != drawn[0] or now - start >= slow_next)
                if now - start >= slow_next:
                    slow_next = now - start + SLOW_PERIOD
                drawn = state
            self._wake.wait(max(0.0, CONTROL_PERIOD - (time.monotonic() - now)))
            self._wake.clear()
        return "closed"

    def _draw(self, slow: bool) -> None:
        assert self.replay is not None
        s = self.replay.snapshot(self.t)
        self.last = s
        self.frames += 1
        with self.server.atomic():
            self.robot.show(s)
            for run in self.shown.values():
                run.show(self.t)
            if self.playing:
                self.slider.value = round(self.t / TIME_STEP) * TIME_STEP  # type: ignore[misc]
            self.status.content = status_html(self.replay.track.name, self.t, self.duration, self.playing)
            self.readouts.fast(s)
            self.camera.follow(s.truth)
            if slow:
                self.readouts.slow(s)
                self.first_view.frame(s.truth)  # a page opened now sees the robot
        self.server.flush()

    def close(self) -> None:
        """Stop the loop and the servers."""
        self._closed.set()
        self._wake.set()
        self.servers.stop()
