"""``omnikin view ROBOT``: the robot in 3D in the browser, driven from the page.

:class:`LiveViewer` puts together the scene (:mod:`omnikin.viewer.scene`), the robot and its
runtime (:mod:`omnikin.viewer.live`), the page's controls and readouts
(:mod:`omnikin.viewer.panel`) and the front server (:mod:`omnikin.viewer.front`) that carries
the keyboard. The viser server listens on loopback only; the user's address is the front's.

Clock: real time. A control step runs every :data:`CONTROL_PERIOD` s of wall time, and at
once when a key message arrives (the pose a key changes is on the page within a step); the
scene is sent after every step, the trails, table and plots every :data:`SLOW_PERIOD` s.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from ..kinematics.se2 import inverse
from ..motion.plans import UMBMARK_SIDE
from .live import PageRobot, Snapshot
from .panel import CameraControl, DriveControls, FirstView, GoalMarker, PathPanel, Readouts, robot_extent
from .scene import RobotView, WorldDrawing, draw_world
from .serving import CONTROL_PERIOD, SLOW_PERIOD, PageServers


class LiveViewer:
    """The viewer of a live robot (module docstring): ``live`` drives it, ``host``/``port`` is
    where the page is served (port 0: a free one, see :attr:`url`); ``umbmark_side`` [m] draws
    the UMBmark squares (0: none); ``waypoints`` ``(n, 2|3)`` [m, m, rad] a path to follow from
    the start (``omnikin view --path``), ``path_options`` how (``smooth``, ``blend``: the
    :class:`~omnikin.viewer.panel.PathPanel`'s Follow)."""

    def __init__(
        self,
        live: PageRobot,
        host: str = "127.0.0.1",
        port: int = 8080,
        *,
        umbmark_side: float = UMBMARK_SIDE,
        waypoints=None,
        path_options: dict | None = None,
    ):
        self.live = live
        self._start = time.monotonic()  # the robot's clock: seconds since the viewer was made
        live.clock = self.clock
        self._wake = threading.Event()
        self._closed = threading.Event()
        self.servers = PageServers(host, port, self._on_key)
        self.server = self.servers.viser
        try:  # (Ctrl-C while the page is being built stops the servers too)
            self.server.on_client_disconnect(self._on_page_gone)
            world = getattr(live, "world", None)
            extent_of_world = 0.0
            if world is not None:
                low_x, low_y, high_x, high_y = world.floor_bounds
                extent_of_world = max(abs(low_x), abs(low_y), abs(high_x), abs(high_y)) + float(
                    np.hypot(*live.start[:2])
                )
            draw_world(self.server.scene, max(5.0, umbmark_side + 1.0, extent_of_world), umbmark_side)
            self.world = WorldDrawing(self.server.scene, world, inverse(live.start)) if world is not None else None
            self.robot = RobotView(self.server.scene, live.description)
            self.trails = self.robot.trails
            self.drive = DriveControls(self.server, live)
            extent = robot_extent(live.description)
            self.camera = CameraControl(self.server, extent, clear_trails=self.robot.clear_trails)
            self.first_view = FirstView(self.server, extent)
            self.first_view.frame(live.pose)
            self.readouts = Readouts(self.server, live.description)
            self.goal = GoalMarker(self.server, live)
            self.path = PathPanel(self.server, live, waypoints, path_options)
        except BaseException:
            self.servers.stop()
            raise
        self.last: Snapshot | None = None
        self.steps = 0

    @property
    def url(self) -> str:
        return self.servers.url

    def clock(self) -> float:
        """The robot's time [s] (wall clock since the viewer was made)."""
        return time.monotonic() - self._start

    def _on_page_gone(self, client) -> None:
        """The last page closed: whatever it set (a twist, a goal) stops; nobody is watching."""
        if not [c for c in self.server.get_clients() if c != client.client_id]:
            self.live.stop()
            self._wake.set()

    def _on_key(self, message: dict) -> None:
        self.live.key(message)
        self._wake.set()

    def run(self, duration: float | None = None) -> str:
        """Serve until :meth:`close` (``"closed"``) or ``duration`` [s] of wall time
        (``"duration"``); a :class:`KeyboardInterrupt` leaves through the caller."""
        start = time.monotonic()
        slow_next = 0.0
        while not self._closed.is_set():
            now = self.clock()
            if duration is not None and time.monotonic() - start >= duration:
                return "duration"
            snapshot, actions = self.live.step(now)
            self.last = snapshot
            self.steps += 1
            for action in actions:
                told = self.camera.action(action)
                if told is not None:
                    self.live.notice = told
            with self.server.atomic():
                self._draw(snapshot)
                self.readouts.fast(snapshot)
                self.goal.show(snapshot)
                self.path.show(snapshot)
                self.camera.follow(snapshot.truth)
                if now >= slow_next:
                    slow_next = now + SLOW_PERIOD
                    for trail in self.trails.values():
                        trail.flush()
                    self.readouts.slow(snapshot)
                    self.first_view.frame(snapshot.truth)  # a page opened now sees the robot
            self.server.flush()
            self._wake.wait(max(0.0, CONTROL_PERIOD - (self.clock() - now)))
            self._wake.clear()
        return "closed"

    def _draw(self, s: Snapshot) -> None:
        self.robot.show(s)
        if self.world is not None:
            poses = self.live.obstacle_poses()
            if poses is not None:
                self.world.move(poses)
        self.trails["truth"].add(s.truth[0], s.truth[1])
        self.trails["odometry"].add(s.odometry[0], s.odometry[1])

    def close(self) -> None:
        """Stop the loop, the servers and the engine."""
        self._closed.set()
        self._wake.set()
        self.servers.stop()
        self.live.close()
