"""The viewer page's side panel: driving controls, camera presets, readouts and plots.

- **Drive**: the keys (W/S A/D Q/E held, space stops, ``[``/``]`` steer, 1/2/3 cameras; 4, the
  *run* camera, is a replay's: a live page says it has none), sliders
  for a twist held until changed (Drive) and a Stop button; steering by hand for robots with
  steerable wheels (at rest).
- **Camera**: presets *top* (straight down on the robot, world +x to the right and +y up,
  moving with it), *follow* (behind the robot along its heading, moving with it), *free* (the
  mouse: drag rotates, right-drag moves, wheel zooms) and, on a replay, *run* (straight down on
  the whole of the runs shown; keys 1 2 3 4 in that order), and the size of the view [m] the
  top and follow cameras frame.
  The first view (:class:`FirstView`) looks at the robot from behind and above, from a distance
  that frames :data:`VIEW_SIZE` robot reaches.
- **Readouts**: pose (true and odometry), twist, command, forward-kinematics residual, every
  control step; a table of the joints like Villasenor et al.'s (their Fig. 9): per wheel its
  steering angle and wheel angle [deg], speed and its rollers' speed [rad/s] and the position of
  its hub in the world [m]; a plot of the wheel speeds over the last :data:`PLOT_SPAN` s.

The readout's numbers are also in the ``data-`` attributes of the element ``#omnikin-readout``
(full precision), for programs that read the page.
"""

from __future__ import annotations

import html
import math
import threading
import time
from collections import deque
from collections.abc import Callable

import numpy as np
import viser
import viser.transforms as vtf
import viser.uplot as uplot

from ..physics.description import PhysicalRobot
from .live import PageRobot, Snapshot

PLOT_SPAN = 10.0
"""Time span [s] of the wheel-speed plot."""
CAMERAS = ("top", "follow", "free")
VIEW_SIZE = 8.0
"""Default size of the view of the top and follow cameras, in robot extents."""
FOLLOW_ELEVATION = math.radians(30.0)
CAMERA_SETTLE = 5.0
"""Time [s] after a preset places the cameras during which a page that reports a camera other
than the one it was given is given it again (:meth:`CameraControl.follow`)."""
PLOT_COLOURS = ("#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf")

KEY_HELP = """**Keys** (click the scene first): **W/S** forward/back, **A/D** left/right,
**Q/E** turn left/right (held keys drive, release stops), **space** stop,
**[ ]** steer, **1 2 3** camera free/top/follow."""
REPLAY_KEY_HELP = """**Keys** (click the scene first): **1 2 3 4** camera free/top/follow/run (the driving
keys do nothing on a replay)."""


def _f(value: float) -> str:
    return format(float(value), ".17g")


def robot_extent(description: PhysicalRobot) -> float:
    """The robot's reach from its reference point [m]: the largest ``max(|x|, |y|) + r`` of its
    wheels (hubs at zero steering)."""
    return max(max(abs(w.hub[0]), abs(w.hub[1])) + w.radius for w in description.wheels)


class DriveControls:
    """The Drive folder of a live viewer: key help, a twist held until Stop, steering by hand."""

    def __init__(self, server: viser.ViserServer, live: PageRobot):
        self.live = live
        gui = server.gui
        limits = live.limits
        top_speed = limits.linear if limits.linear is not None else 2 * live.teleop.speed
        top_turn = limits.angular if limits.angular is not None else 2 * live.teleop.turn
        with gui.add_folder("Drive"):
            gui.add_markdown(KEY_HELP)
            self.vx = gui.add_slider("vx [m/s]", -top_speed, top_speed, top_speed / 50, 0.0)
            self.vy = gui.add_slider("vy [m/s]", -top_speed, top_speed, top_speed / 50, 0.0)
            self.omega = gui.add_slider("omega [rad/s]", -top_turn, top_turn, top_turn / 50, 0.0)
            drive = gui.add_button("Drive", hint="drive at the twist of the sliders until Stop")
            stop = gui.add_button("Stop", color="red", hint="every target zero (space)")
            drive.on_click(lambda _: live.set_twist((self.vx.value, self.vy.value, self.omega.value)))
            stop.on_click(lambda _: self.stop())
            if live.can_steer:
                steer = gui.add_button_group("steer (at rest)", ("-15 deg", "+15 deg"))
                steer.on_click(lambda e: live.steer_by(math.radians(15.0 if e.target.value == "+15 deg" else -15.0)))

    def stop(self) -> None:
        for slider in (self.vx, self.vy, self.omega):
            slider.value = 0.0  # type: ignore[misc]  # (viser: a props field shadows the setter for mypy)
        self.live.stop()


class GoalMarker:
    """A goal to drive to: a marker on the floor (drag its arrows to move it, its ring to turn
    it) and the Goal folder: Go (drive there, :class:`~omnikin.runtime.goal.GoalSeeker`, by the
    odometry), the path the layout takes, and whether dropping the marker starts the drive."""

    def __init__(self, server: viser.ViserServer, live: PageRobot):
        self.live = live
        self.controls = server.scene.add_transform_controls(
            "/goal",
            scale=0.4,
            active_axes=(True, True, False),
            disable_sliders=False,
            position=(1.0, 0.0, 0.0),
        )
        server.scene.add_frame("/goal/heading", axes_length=0.15, axes_radius=0.006)
        gui = server.gui
        with gui.add_folder("Goal"):
            self.go_on_drop = gui.add_checkbox("drive when dropped", True)
            go = gui.add_button("Go to the marker", hint="drive there along a path the wheels can make")
            self.status = gui.add_markdown("drag the marker on the floor, then Go")
        go.on_click(lambda _: self.go())
        self.controls.on_update(self._dropped)

    def _dropped(self, event) -> None:
        """A drag of the marker ended: drive there when "drive when dropped" is on."""
        if getattr(event, "phase", None) == "end" and self.go_on_drop.value:
            self.go()

    def pose(self) -> tuple[float, float, float]:
        """The marker's pose ``(x, y, theta)`` [m, m, rad] on the floor (its yaw)."""
        x, y, _ = (float(v) for v in self.controls.position)
        return x, y, float(vtf.SO3(np.asarray(self.controls.wxyz, dtype=float)).compute_yaw_radians())

    def go(self) -> None:
        self.live.notice = ""
        self.live.go_to(self.pose())

    def show(self, s: Snapshot) -> None:
        """The seeker's state in the folder (only when it changed)."""
        seeker = self.live.seeker
        if self.live.fallen:
            text = f"stopped: {html.escape(self.live.fallen)}"
        elif self.live.notice:
            text = f"refused: {html.escape(self.live.notice)}"
        elif seeker is not None:
            text = f"driving: {seeker.strategy}, {seeker.phase}"
        elif self.live.arrived is not None:
            x, y, th = self.live.arrived
            text = f"arrived: the odometry reads x {x:+.3f} m, y {y:+.3f} m, theta {math.degrees(th):+.1f} deg"
            if not self.live.arrived_heading:
                text += " (this layout cannot turn to the marker's heading: it ends where the path ends)"
        else:
            return
        if self.status.content != text:
            self.status.content = text


PATH_COLOUR = (80, 160, 255)
"""Colour of the path followed and its waypoints (RGB)."""
REFERENCE_COLOUR = (255, 200, 0)
"""Colour of the reference point."""
ERROR_COLOUR = (230, 30, 30)
"""Colour of the segment from the robot to the reference point (the tracking error)."""
MAX_CLICKED = 200
"""Most waypoints a page may add by clicking (each click one; a flood stops there)."""
MAX_CLICK_DISTANCE = 1000.0
"""Farthest a clicked waypoint may be from the origin [m] (a click near the horizon meets the
floor kilometres away: no path to follow there)."""
PATH_DRAWN = 4000
"""Most segments the path is drawn with (a longer path is drawn every k-th sample)."""


class PathPanel:
    """A path to follow: waypoints from ``--path`` or shift-clicked on the floor, and the Path
    folder: Follow (plan from the robot's pose and track it:
    :meth:`~omnikin.viewer.live.PageRobot.follow`), Stop, Clear, the heading along it and the
    state with the tracking error. Drawn: the waypoints, the path followed (the trajectory's
    samples), the reference point and a red segment from the robot's odometry to it."""

    def __init__(self, server: viser.ViserServer, live: PageRobot, waypoints=None, options: dict | None = None):
        self.server = server
        self.live = live
        self.options = dict(options or {})
        self.waypoints: list[tuple[float, ...]] = [] if waypoints is None else [tuple(map(float, w)) for w in waypoints]
        self.from_file = waypoints is not None
        self._lock = threading.Lock()  # (clicks and buttons arrive on viser's threads)
        gui = server.gui
        with gui.add_folder("Path"):
            gui.add_markdown("**shift-click** the floor to add waypoints, then Follow")
            self.heading = gui.add_dropdown(
                "heading", ("tangent", "fixed", "free", "given"), initial_value=self._default_heading()
            )
            follow = gui.add_button("Follow the path", hint="plan from the robot's pose within its limits, track it")
            stop = gui.add_button("Stop following", hint="the robot brakes to a stop")
            clear = gui.add_button("Clear waypoints")
            self.status = gui.add_markdown(self._waypoint_text())
        follow.on_click(lambda _: self.follow())
        stop.on_click(lambda _: live.stop_path())
        clear.on_click(lambda _: self.clear())
        server.scene.on_click(modifier="shift")(self._clicked)
        self._drawn_plan: object | None = None
        with self._lock:
            self._draw_waypoints()
        self._reference = server.scene.add_icosphere(
            "/path/reference", radius=0.03, color=REFERENCE_COLOUR, visible=False, cast_shadow=False
        )
        self._error: viser.LineSegmentsHandle | None = None

    def _default_heading(self) -> str:
        if self.waypoints and len(self.waypoints[0]) == 3:
            return "given"
        return "tangent"

    def _waypoint_text(self) -> str:
        n = len(self.waypoints)
        return f"{n} waypoint{'s' if n != 1 else ''}" + (" (from --path)" if self.from_file else "")

    def _clicked(self, event) -> None:
        """A shift-click: the point where the click's ray meets the floor becomes a waypoint."""
        origin = np.asarray(event.ray_origin, dtype=float)
        direction = np.asarray(event.ray_direction, dtype=float)
        length = float(np.linalg.norm(direction))
        if not (origin[2] > 0.0 and length > 0.0 and direction[2] < -1e-6 * length):
            self.live.notice = "a click whose ray does not go down to the floor"
            return
        point = origin - origin[2] / direction[2] * direction
        if not (np.all(np.isfinite(point)) and np.all(np.abs(point[:2]) <= MAX_CLICK_DISTANCE)):
            self.live.notice = f"a click that meets the floor beyond {MAX_CLICK_DISTANCE:g} m"
            return
        with self._lock:
            if len(self.waypoints) >= MAX_CLICKED:
                self.live.notice = f"at most {MAX_CLICKED} waypoints by clicking; Clear to start again"
                return
            self.waypoints.append((float(point[0]), float(point[1])))
            self.from_file = False
            self.live.notice = ""
            if self.heading.value == "given":
                self.heading.value = "tangent"  # type: ignore[misc]
            self._draw_waypoints()
            self.status.content = self._waypoint_text()

    def clear(self) -> None:
        with self._lock:
            self.waypoints = []
            self.from_file = False
            self._draw_waypoints()
            self.status.content = self._waypoint_text()

    def follow(self) -> None:
        if not self.waypoints:
            self.live.notice = "no waypoints: shift-click the floor to add some"
            return
        if self.heading.value == "given" and any(len(w) < 3 for w in self.waypoints):
            self.live.notice = "these waypoints give no headings: choose tangent, fixed or free"
            return
        with self._lock:
            width = min(len(w) for w in self.waypoints)
            points = np.array([w[:width] for w in self.waypoints], dtype=float)
        self.live.notice = ""
        self.live.follow(points, **dict(self.options, heading=self.heading.value))

    def _draw_waypoints(self) -> None:
        """The waypoints on the floor (called under the lock: one drawing at a time)."""
        scene = self.server.scene
        xy = np.array([w[:2] for w in self.waypoints], dtype=float).reshape(-1, 2)
        if len(xy):
            points = np.column_stack((xy, np.full(len(xy), 0.004)))
            scene.add_point_cloud("/path/waypoints", points, colors=PATH_COLOUR, point_size=0.04, point_shape="circle")
        else:
            scene.add_point_cloud("/path/waypoints", np.zeros((0, 3)), colors=PATH_COLOUR, point_size=0.04)

    def show(self, s: Snapshot) -> None:
        """The path followed, the reference point and the error segment, and the state in the
        folder (each sent only when it changed)."""
        follower = self.live.follower
        plan = follower.plan
        if plan is not self._drawn_plan:
            self._drawn_plan = plan
            if plan is not None:
                pose = plan.trajectory.path.pose
                step = max(1, len(pose) // PATH_DRAWN)
                xy = pose[::step, :2]
                if len(pose) > 1 and step > 1:
                    xy = np.vstack((xy, pose[-1:, :2]))
                z = np.full((len(xy), 1), 0.003)
                pts = np.hstack((xy, z))
                self.server.scene.add_line_segments(
                    "/path/followed", np.stack((pts[:-1], pts[1:]), axis=1), colors=PATH_COLOUR, thickness=0.008
                )
        following = follower.following
        self._reference.visible = following
        if following:
            rx, ry, _ = (float(v) for v in follower.reference)
            self._reference.position = (rx, ry, 0.03)
            ox, oy, _ = s.odometry
            segment = np.array([[[ox, oy, 0.03], [rx, ry, 0.03]]])
            self._error = self.server.scene.add_line_segments(
                "/path/error", segment, colors=ERROR_COLOUR, thickness=0.006
            )
        elif self._error is not None:
            self._error.remove()
            self._error = None
        text = (
            self._waypoint_text()
            + "<br>"
            + html.escape("planning the path..." if self.live.planning else follower.summary())
        )
        if follower.state == "following" or follower.state == "done":
            text += f"<br>error to the reference {follower.error * 1e3:.1f} mm"
        if self.live.notice:
            text += f"<br>refused: {html.escape(self.live.notice)}"
        if self.status.content != text:
            self.status.content = text


FIRST_VIEW_AZIMUTH = math.radians(-30.0)
"""Where the first view looks from, about the vertical, from straight behind the robot [rad]."""
FIRST_VIEW_ELEVATION = math.radians(35.0)
"""Elevation of the first view above the floor [rad]."""


class FirstView:
    """The first view of every page that connects (viser's initial camera), kept on the robot
    of reach ``extent`` [m] (:func:`robot_extent`) by :meth:`frame`."""

    def __init__(self, server: viser.ViserServer, extent: float):
        self.server = server
        self.extent = extent
        self.at: tuple[float, float] | None = None  # where it looks [m]

    def frame(self, pose) -> None:
        """Look at the robot's reference point at ``pose`` ``(x, y, theta)`` [m, m, rad] from
        behind (:data:`FIRST_VIEW_AZIMUTH`) and above (:data:`FIRST_VIEW_ELEVATION`), at the
        distance ``d = S / (2 tan(fov / 2))`` at which the camera's vertical field of view spans
        ``S = VIEW_SIZE extent`` [m]. Nothing is sent while the robot is within ``extent`` of
        where it already looks (a message to every page spared)."""
        x, y, theta = (float(v) for v in pose)
        if self.at is not None and math.hypot(x - self.at[0], y - self.at[1]) < self.extent:
            return
        self.at = (x, y)
        camera = self.server.initial_camera
        distance = VIEW_SIZE * self.extent / (2 * math.tan(camera.fov / 2))
        azimuth = theta + FIRST_VIEW_AZIMUTH
        flat = distance * math.cos(FIRST_VIEW_ELEVATION)
        camera.look_at = (x, y, 0.0)
        camera.position = (
            x - flat * math.cos(azimuth),
            y - flat * math.sin(azimuth),
            distance * math.sin(FIRST_VIEW_ELEVATION),
        )


class CameraControl:
    """The Camera folder: presets (module docstring) for every page, the view size, and the
    trails' Clear button when ``clear_trails`` is given; ``fit``, a function returning the box
    ``(x_min, y_min, x_max, y_max)`` [m] of the runs shown, adds the *run* preset."""

    def __init__(
        self,
        server: viser.ViserServer,
        extent: float,
        clear_trails: Callable[[], None] | None = None,
        fit: Callable[[], tuple[float, float, float, float]] | None = None,
    ):
        self.server = server
        self.camera = "free"
        self.pose: tuple[float, float, float] | None = None
        self.extent = extent
        self.fit = fit
        self._placed: tuple | None = None  # what a following camera was last placed for
        # per page: the position and look-at it was given, and when [time.time(), viser's clock]
        self._aims: dict[int, tuple[np.ndarray, np.ndarray, float]] = {}
        self._aimed = 0.0  # when the cameras were last placed [time.monotonic()]
        gui = server.gui
        with gui.add_folder("Camera"):
            self.buttons = gui.add_button_group("preset", CAMERAS + (("run",) if fit is not None else ()))
            self.buttons.on_click(lambda e: self.set(e.target.value))
            self.view_size = gui.add_slider(
                "view size [m]", extent, 40 * extent, extent / 10, round(VIEW_SIZE * extent, 3)
            )
            if clear_trails is not None:
                gui.add_button("Clear trails").on_click(lambda _: clear_trails())

    def action(self, action: str) -> str | None:
        """A page action of the keys: ``camera_free``, ``camera_top``, ``camera_follow``,
        ``camera_run``; one line to tell the page when it asks for a preset this page does not
        have (*run* on a live page), else None."""
        if not action.startswith("camera_"):
            return None
        preset = action.removeprefix("camera_")
        if preset == "run" and self.fit is None:
            return "key 4 (camera run) frames the runs of a replay: a live page has none"
        self.set(preset)
        return None

    def set(self, preset: str) -> None:
        if preset not in CAMERAS and not (preset == "run" and self.fit is not None):
            return
        self.camera = preset
        self._placed = None
        if self.pose is not None:
            self._place(self.pose)
            self._placed = self._placement(self.pose)

    def _placement(self, pose: tuple[float, float, float]) -> tuple:
        """What a following camera's placement depends on (it is sent again only when this
        changes: a camera message redraws every page)."""
        return (pose, float(self.view_size.value), tuple(self.server.get_clients()))

    def follow(self, pose: tuple[float, float, float]) -> None:
        """The robot is at ``pose``: a following camera moves with it; a page whose camera
        is not where it was put is given it again (:meth:`_settle`)."""
        self.pose = pose
        self._settle()
        if self.camera in ("follow", "top"):
            placed = self._placement(pose)
            if placed != self._placed:
                self._place(pose)
                self._placed = placed

    def refit(self) -> None:
        """The runs shown changed: a *run* camera frames them again."""
        if self.camera == "run" and self.pose is not None:
            self._place(self.pose)

    def _place(self, pose: tuple[float, float, float]) -> None:
        if self.camera == "free":
            return
        x, y, theta = pose
        size = float(self.view_size.value)
        if self.camera == "run" and self.fit is not None:
            x0, y0, x1, y1 = self.fit()  # the box of the runs, a robot's reach round it
            x, y = (x0 + x1) / 2, (y0 + y1) / 2
            size = 1.1 * max(x1 - x0, y1 - y0) + 2 * self.extent
        for client_id, client in self.server.get_clients().items():
            camera = client.camera
            if self.camera in ("top", "run"):
                # looking down from a height that frames `size` metres; a hair south of the
                # robot so that the view's up is +y (straight down has no up)
                height = size / (2 * math.tan(camera.fov / 2))
                position = (x, y - 1e-3 * height, height)
            else:
                back = size / 2
                position = (
                    x - back * math.cos(FOLLOW_ELEVATION) * math.cos(theta),
                    y - back * math.cos(FOLLOW_ELEVATION) * math.sin(theta),
                    back * math.sin(FOLLOW_ELEVATION),
                )
            self._aim(client_id, camera, np.array(position), np.array((x, y, 0.0)))
        self._aimed = time.monotonic()

    def _aim(self, client_id: int, camera: viser.CameraHandle, position: np.ndarray, look_at: np.ndarray) -> None:
        before = camera.update_timestamp
        camera.position = position  # (viser moves the look-at point with it: set it after)
        camera.look_at = look_at
        previous = self._aims.get(client_id)
        if (
            camera.update_timestamp == before  # nothing sent: viser believed the page looked there
            and previous is not None
            and np.array_equal(previous[0], position)
            and np.array_equal(previous[1], look_at)
        ):
            return  # the same aim as before: reports since that one still count
        self._aims[client_id] = (position, look_at, time.time())

    def _settle(self) -> None:
        """For :data:`CAMERA_SETTLE` s after :meth:`_place`, a page that reports (after it was
        aimed) a camera other than its aim is aimed again. viser sends a camera's position or
        look-at only when it differs from what the page last reported, so a report that crosses
        the placement on the wire (the page telling where it looked before) makes the server
        believe the page already looks where it was told, and skip telling it: the page would
        keep a view between the old and the new one."""
        if not self._aims or time.monotonic() - self._aimed > CAMERA_SETTLE:
            return
        clients = self.server.get_clients()
        for client_id, (position, look_at, sent) in list(self._aims.items()):
            client = clients.get(client_id)
            if client is None:
                del self._aims[client_id]
                continue
            camera = client.camera
            if camera.update_timestamp <= sent:
                continue  # nothing reported since it was aimed
            tolerance = 1e-6 * float(np.linalg.norm(position - look_at))
            if (
                np.linalg.norm(np.asarray(camera.position) - position) > tolerance
                or np.linalg.norm(np.asarray(camera.look_at) - look_at) > tolerance
            ):  # (a report that matches may be followed by one of the look-at still on its way)
                self._aim(client_id, camera, position, look_at)


class Readouts:
    """The Readouts folder: the readout (every step), the joint table and the wheel-speed plot
    (:meth:`slow`); :meth:`reset` forgets the plot's history (a replay jumping in time)."""

    def __init__(self, server: viser.ViserServer, description: PhysicalRobot):
        self.description = description
        gui = server.gui
        with gui.add_folder("Readouts"):
            self.readout = gui.add_html(readout_html(None))
            self.table = gui.add_html("")
            names = [w.name for w in description.wheels]
            self._times: deque[float] = deque()
            self._speeds: deque[np.ndarray] = deque()
            series = [uplot.Series(label="t [s]")] + [
                uplot.Series(label=name, stroke=PLOT_COLOURS[i % len(PLOT_COLOURS)], width=1.5)
                for i, name in enumerate(names)
            ]
            empty = tuple(np.zeros(1) for _ in range(len(names) + 1))
            self.plot = gui.add_uplot(
                empty, tuple(series), title="wheel speeds [rad/s]", aspect=1.6, scales={"x": {"time": False}}
            )

    def reset(self) -> None:
        self._times.clear()
        self._speeds.clear()

    def fast(self, s: Snapshot) -> None:
        """Every step: the readout and the plot's data."""
        self.readout.content = readout_html(s)
        if self._times and s.t < self._times[-1]:
            self.reset()
        self._times.append(s.t)
        self._speeds.append(s.wheel_speeds.copy())
        while self._times and self._times[0] < s.t - PLOT_SPAN:
            self._times.popleft()
            self._speeds.popleft()

    def slow(self, s: Snapshot) -> None:
        """A few times a second: the joint table and the plot."""
        self.table.content = joint_table_html(self.description, s)
        if len(self._times) >= 2:
            speeds = np.array(self._speeds)
            self.plot.data = (np.array(self._times), *speeds.T)


def readout_html(s: Snapshot | None) -> str:
    """Pose, twist, command and residual of ``s`` as the readout element (module docstring); a
    readout in ``s.missing`` reads ``s.missing_why`` (and ``data-missing`` names them)."""
    if s is None:
        return '<div id="omnikin-readout">waiting for the first step</div>'
    x, y, th = s.truth
    ox, oy, oth = s.odometry
    attributes = {
        "t": s.t,
        "x": x,
        "y": y,
        "theta": th,
        "odom-x": ox,
        "odom-y": oy,
        "odom-theta": oth,
        "vx": s.twist[0],
        "vy": s.twist[1],
        "omega": s.twist[2],
    }
    data = " ".join(f'data-{k}="{_f(v)}"' for k, v in attributes.items())
    if s.missing:
        data += f' data-missing="{html.escape(" ".join(s.missing), quote=True)}"'
    residual = math.sqrt(sum(r * r for r in s.residual)) if s.residual else 0.0
    rows = [
        ("t", f"{s.t:.2f} s"),
        ("pose", f"x {x:+.3f} m, y {y:+.3f} m, theta {math.degrees(th):+.1f} deg"),
        ("odometry", f"x {ox:+.3f} m, y {oy:+.3f} m, theta {math.degrees(oth):+.1f} deg"),
        ("twist", f"vx {s.twist[0]:+.3f} m/s, vy {s.twist[1]:+.3f} m/s, omega {s.twist[2]:+.3f} rad/s"),
        ("command", f"vx {s.command[0]:+.3f}, vy {s.command[1]:+.3f}, omega {s.command[2]:+.3f}"),
        ("FK residual", f"{residual:.2e} rad/s" if s.residual else "- (not measured)"),
    ]
    stands_in = {"truth": " (drawn at the odometry)", "odometry": " (the truth stands in)"}
    for key, row in (("truth", 1), ("odometry", 2), ("twist", 3), ("command", 4), ("residual", 5)):
        if key in s.missing:  # no data: said, never shown as zeros
            rows[row] = (rows[row][0], s.missing_why + stands_in.get(key, ""))
    body = "".join(f"<tr><td>{k}</td><td>{html.escape(v)}</td></tr>" for k, v in rows)
    return f'<div id="omnikin-readout" {data}><table style="font-size:0.8em">{body}</table></div>'


def joint_table_html(description: PhysicalRobot, s: Snapshot) -> str:
    """The joint table of ``s`` (module docstring): per wheel steering and wheel angle, speed,
    hub position in the world."""
    x0, y0, th = s.truth
    c, si = math.cos(th), math.sin(th)
    head = (
        "<tr><th>wheel</th><th>steer [deg]</th><th>angle [deg]</th><th>speed [rad/s]</th>"
        "<th>rollers [rad/s]</th><th>hub x, y [m]</th></tr>"
    )
    rows = []
    for i, w in enumerate(description.wheels):
        hx, hy = w.hub[0], w.hub[1]
        if w.steering is not None and math.isfinite(s.steer[i]):
            px, py = w.steering.pivot
            a = s.steer[i]
            dx, dy = hx - px, hy - py
            hx, hy = px + math.cos(a) * dx - math.sin(a) * dy, py + math.sin(a) * dx + math.cos(a) * dy
        wx, wy = x0 + c * hx - si * hy, y0 + si * hx + c * hy
        steer = f"{math.degrees(s.steer[i]):+.1f}" if math.isfinite(s.steer[i]) else "-"
        speed = s.roller_speeds[i] if i < len(s.roller_speeds) else None
        roller = "-" if speed is None else f"{speed:+.2f}"
        rows.append(
            f"<tr><td>{html.escape(w.name)}</td><td>{steer}</td>"
            f"<td>{math.degrees(s.wheel_angles[i]) % 360:.1f}</td><td>{s.wheel_speeds[i]:+.2f}</td>"
            f"<td>{roller}</td>"
            f"<td>{wx:+.3f}, {wy:+.3f}</td></tr>"
        )
    return f'<table id="omnikin-joints" style="font-size:0.75em">{head}{"".join(rows)}</table>'
