"""``omnikin view --replay``: recorded runs played back in the browser, with a timeline.

:class:`ReplayViewer` serves, through the front server (:mod:`omnikin.viewer.front`: the
camera keys 1/2/3 work, the driving keys do nothing), a page with the robot drawn from its
physical description (:class:`~omnikin.viewer.scene.RobotDrawing`), the ground grid, the
UMBmark square of the report's side, and a **Replay** folder: the run selector, the time
slider [s], Play/Pause, the playback speed; the whole true and odometry paths of the selected
run are drawn, the robot and the odometry frame at the slider's time, with the readouts of
:mod:`omnikin.viewer.panel` (pose, twist, joint table, wheel-speed plot) from
:class:`~omnikin.viewer.replay.TrackReplay`.

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
from .panel import CameraControl, Readouts, robot_extent
from .replay import TrackReplay
from .replay_sources import ReplaySource
from .scene import RobotView, draw_world
from .serving import CONTROL_PERIOD, SLOW_PERIOD, PageServers

SPEEDS = ("0.25", "0.5", "1", "2", "4", "8", "16")
"""Playback speeds offered (times real time)."""
TIME_STEP = 0.01
"""Resolution of the time slider [s]."""


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
                self.run_choice = gui.add_dropdown("run", names, initial_value=names[0])
                self.slider = gui.add_slider("time [s]", 0.0, 1.0, TIME_STEP, 0.0)
                self.play_button = gui.add_button("Play", hint="play from the slider's time; again: pause")
                self.speed = gui.add_dropdown("speed [x real time]", SPEEDS, initial_value="1")
                self.status = gui.add_html("")
            self.camera = CameraControl(self.server, robot_extent(self.description))
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

    def _request(self, what: str) -> None:
        with self._lock:
            self._actions.append(what)
        self._wake.set()

    # --- state ---------------------------------------------------------------------------------
    def _select(self, name: str) -> None:
        track = next(tr for tr in self.source.tracks if tr.name == name)
        self.replay = TrackReplay(self.source.robot, self.description, track)
        self.t = 0.0
        self.playing = False
        duration = self.replay.duration
        with self.server.atomic():
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
            self.t = min(max(float(self.slider.value), 0.0), self.replay.duration)
        elif action == "toggle":
            self.set_playing(not self.playing)
        else:
            self.camera.action(action)

    def set_playing(self, playing: bool) -> None:
        """Play from the current time (from the start when at the end) or pause."""
        assert self.replay is not None
        if playing and self.t >= self.replay.duration:
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
                if self.t >= self.replay.duration:
                    self.t = self.replay.duration
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
            if self.playing:
                self.slider.value = round(self.t / TIME_STEP) * TIME_STEP  # type: ignore[misc]
            self.status.content = status_html(self.replay.track.name, self.t, self.replay.duration, self.playing)
            self.readouts.fast(s)
            self.camera.follow(s.truth)
            if slow:
                self.readouts.slow(s)
        self.server.flush()

    def close(self) -> None:
        """Stop the loop and the servers."""
        self._closed.set()
        self._wake.set()
        self.servers.stop()
