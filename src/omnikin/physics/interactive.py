"""The interactive simulator of ``omnikin sim``: a robot in MuJoCo's own viewer window, driven
from the keyboard through the runtime (extra ``physics``).

The program descends from the OpenGL simulator of Villasenor et al.'s omnidirectional robot with
steerable legs; here the window is MuJoCo's passive viewer and the robot the physics model of
:class:`~omnikin.physics.backend.PhysicsBackend`, driven by
:class:`~omnikin.runtime.base.BaseRuntime`: every key becomes a velocity command of the
runtime's :class:`~omnikin.runtime.command.CommandFilter`, so the speed and acceleration limits
(:class:`~omnikin.motion.limits.MotionLimits`) and the command timeout act as on the real robot.

**Teleop: held keys drive.** A move key *sets* one component of the target twist (body frame,
``docs/conventions.md``) while it is held: W/S ``vx = +/-speed``, A/D ``vy = +/-speed``, Q/E
``omega = +/-turn`` (counter-clockwise positive); letting it go sets the component back to zero
(unless another key set it since); the other components are kept, so W and Q together drive an
arc; space sets all three to zero. MuJoCo's viewer gives its ``key_callback`` presses only, and
shares these keys with its own shortcuts (W wireframe, S shadows, ...): at the first press the
simulator takes the window's keys over (:meth:`InteractiveSim._take_keys`) to see releases too.
Should that fail, presses alone drive: a target then holds until another key changes it, or,
with ``hold > 0`` [s], until ``hold`` seconds after the last press, when the command filter's
timeout brings the robot to a stop within its acceleration limits. On a robot with fixed
wheels the part of a target its wheels cannot make (``vy`` of a differential drive) is dropped
by the filter.

**Steering by hand** (robots with steerable wheels): ``[`` and ``]`` turn the steering of every
steerable wheel by ``-/+ STEER_STEP`` while the robot stands (target zero); the next motion
steers as the kinematics needs.

**Keys a layout cannot obey** (:func:`~omnikin.runtime.teleop.moves_not_obeyed`: A/D on a
differential drive or a car, Q/E alone on a car) are marked in the on-screen help; pressing one
shows a notice on screen and prints it once on stderr (``omnikin: note: sim: ...``), with the
command filter's reason when it refused the command.

**Camera** (:meth:`InteractiveSim._set_camera`), each from :data:`CAMERA_DISTANCE` times the
robot's extent (the largest ``max(|x|, |y|) + r`` of its wheels) away: 1 free (mouse: left drag
rotates, right drag moves, wheel zooms), 2 top (straight down on the pose where it was chosen,
world +x to the right and +y up in the window; it stays there while the robot drives off),
3 follow (MuJoCo's tracking camera: it keeps the chassis in the middle of the window, seen from
behind at 30 deg elevation along the heading it had when chosen).

**Heading and odometry** (:meth:`InteractiveSim._draw_heading`, geoms of the viewer's
``user_scn``, drawn in every camera and never seen by the physics): a green arrow on top of the
chassis from the robot's reference point (its body frame's origin) along the true heading (body
+x), and beside it a narrower magenta arrow a little higher at the pose the robot's own wheel
odometry estimates (the runtime's :attr:`~omnikin.runtime.base.BaseRuntime.pose`, the exact
odometry of its encoders): where the two agree the green shows on both sides of the magenta,
where they part (an as-built robot, ``true_robot``; slip) the magenta arrow drifts off the
robot. A robot with a lidar shows its latest scan as orange points where the beams met the
world (:meth:`InteractiveSim._scan_points`), and red points mark where touches of the world
began (the latest :data:`CONTACTS_DRAWN`). The colours are the browser viewer's
(``docs/viewer.md``). The window shows time and real-time factor, true pose, odometry pose,
twist, target, wheel speeds and steering angles, and a legend of the two arrows.

**Clock: keys act at their simulated time.** Simulated time ``s`` follows the wall clock ``w``
as ``s = w - w0``; every key event is stamped with the wall time it reached the program and
applied at the first control step (every :data:`CONTROL_PERIOD` simulated seconds) at or after
``w_key - w0``. The simulation runs in control steps until it reaches the clock, drawing a frame
at least every :data:`CATCH_UP` simulated seconds. A machine that keeps up runs in real time; one
that cannot falls behind the clock and catches up later, and the keys wait their turn: a key
held for 2 s of wall time drives 2 s of *simulated* time, whatever the load (to one control
period). Time is skipped (``w0`` moved forward) only while nothing can change by it: no move
key held whose press has acted, the command filter's output zero and the robot at rest
(:meth:`InteractiveSim._at_rest`); and only when the simulation is more than :data:`MAX_LAG`
behind. The clock is then set back to the simulated time or, when key events wait, only so
far that the first of them acts now; waiting events keep their distances. While the robot is driven the lag can grow
without bound on a machine slower than real time; the window then shows how far behind it is.
The real-time factor on screen is the simulated time advanced over the wall time passed in
the last :data:`RTF_WINDOW` seconds; below :data:`SLOW_RTF` the window says the machine cannot
keep up, and stderr says it once.

The run ends when the window is closed, after ``duration`` seconds of *simulated* time (the
clock on screen: a slow machine keeps the window open longer in wall time, and wall time
skipped while nothing moved does not count), or on :class:`KeyboardInterrupt` (or any
exception) raised in the caller's thread; in every case the viewer is closed and its render
thread joined before returning, since a process that exits while the render thread still draws
dies in an X error (``GLXBadDrawable``).
"""

from __future__ import annotations

import math
import os
import queue
import signal
import sys
import threading
import time
from collections import deque
from typing import Any

import numpy as np

from ..errors import InputError
from ..kinematics.robot import Robot
from ..kinematics.se2 import compose
from ..motion.limits import MotionLimits
from ..runtime.base import BaseRuntime, StepResult
from ..runtime.teleop import MOVES, STEER_STEP, Teleop, moves_not_obeyed
from ..world.model import World
from .backend import PhysicsBackend

CONTROL_PERIOD = 0.02
"""Simulated time [s] between two control steps of the runtime (50 Hz)."""
CATCH_UP = 0.25
"""Most simulated time [s] run between two frames when the simulation is behind the clock: the
window stays responsive (a frame at least every 0.25 s of simulated time; software OpenGL under
load draws about 5-10 frames per second)."""
MAX_LAG = 0.5
"""Lag [s] of the simulation behind the clock beyond which time is skipped while nothing is
driven (module docstring, Clock)."""
REST_SPEED = 1e-3
"""Chassis speed [m/s, rad/s] below which the robot counts as standing still (time may be skipped)."""
RTF_WINDOW = 1.0
"""Wall time [s] over which the real-time factor on screen is measured."""
SLOW_RTF = 0.9
"""Real-time factor below which the window says the machine cannot keep up."""
NOTICE_TIME = 4.0
"""Wall time [s] a notice stays on screen."""
TRUTH_RGBA = (30 / 255, 160 / 255, 60 / 255, 1.0)
"""Colour of the true heading arrow (green, the browser viewer's ``TRUTH_COLOUR``: apart from the
blue chassis, grey floor and dark wheels)."""
ODOMETRY_RGBA = (200 / 255, 60 / 255, 200 / 255, 1.0)
"""Colour of the odometry's heading arrow (magenta, the browser viewer's ``ODOMETRY_COLOUR``)."""
ARROW_LENGTH = 1.2
"""Length of both heading arrows as drawn, in units of the robot's extent."""
ARROW_DRAWN = 0.5
"""Length MuJoCo draws an arrow geom (``mjGEOM_ARROW``) as a share of its connector's length
(``size[2]``): measured 0.49 in MuJoCo 4.0.0 (a 0.8 m connector drawn 0.39 m long from above;
a cylinder connector drawn its full length). The arrows' connectors are ``ARROW_LENGTH /
ARROW_DRAWN`` extents long; a test measures the drawn length in a screenshot."""
ARROW_WIDTH = 0.08
"""Width of the true heading arrow in units of the robot's extent (the odometry's is half)."""
SCAN_RGBA = (0.95, 0.35, 0.1, 1.0)
"""Colour of the lidar's scan points (orange, the browser viewer's scan colour)."""
SCAN_POINT = 0.012
"""Radius [m] of a drawn scan point."""
CONTACT_RGBA = (0.9, 0.1, 0.1, 1.0)
"""Colour of the points where a touch of the world began (red)."""
CONTACTS_DRAWN = 20
"""The latest touches drawn."""
SHUTDOWN_WAIT = 60.0
"""Longest wait [s] for the viewer's render thread to end after the window is closed (it ends
within a frame; software OpenGL on a loaded machine may take seconds for one)."""
STOP_SIGNALS = {signal.SIGINT, signal.SIGTERM} | ({signal.SIGHUP} if hasattr(signal, "SIGHUP") else set())
"""Signals held back while the viewer starts (:meth:`InteractiveSim.run`)."""
LEGEND = "green arrow: true pose, magenta arrow: odometry"
"""The legend of the two heading arrows (a line of the keys' help, bottom right)."""
CAMERAS = ("free", "top", "follow")
CAMERA_DISTANCE = 8.0
"""Distance of every camera preset from its point of view, in units of the robot's extent."""

KEY_W, KEY_S, KEY_A, KEY_D, KEY_Q, KEY_E = (ord(c) for c in "WSADQE")
KEY_SPACE = 32
KEY_LEFT_BRACKET, KEY_RIGHT_BRACKET = ord("["), ord("]")
KEY_1, KEY_2, KEY_3 = ord("1"), ord("2"), ord("3")
KEY_NAMES = {ord(c): c for c in "WSADQE[]123"} | {32: "space"}
"""GLFW key codes as the viewer's ``key_callback`` receives them (letters upper case)."""
GLFW_RELEASE, GLFW_PRESS, GLFW_REPEAT = 0, 1, 2


KEY_ACTIONS = {
    KEY_W: "forward",
    KEY_S: "back",
    KEY_A: "left",
    KEY_D: "right",
    KEY_Q: "turn_left",
    KEY_E: "turn_right",
    KEY_SPACE: "stop",
    KEY_LEFT_BRACKET: "steer_right",
    KEY_RIGHT_BRACKET: "steer_left",
    KEY_1: "camera_free",
    KEY_2: "camera_top",
    KEY_3: "camera_follow",
}
"""What each key of the window does (the moves and stop are :class:`~omnikin.runtime.teleop.Teleop`'s)."""
TELEOP_KEYS = frozenset(KEY_ACTIONS)


def require_display() -> None:
    """Refuse to start without an X display (one line naming the way out)."""
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        raise InputError(
            "omnikin sim opens a window and needs a display: set DISPLAY, or run it under a virtual "
            "one with xvfb-run -a omnikin sim ..."
        )


def _viewer_module():
    try:
        import mujoco.viewer
    except ImportError as e:
        raise InputError(f'omnikin sim needs MuJoCo: pip install "omnikin[physics]" ({e})') from None
    return mujoco, mujoco.viewer


class InteractiveSim:
    """``robot`` in MuJoCo's viewer, driven by the keyboard through :class:`BaseRuntime`
    (module docstring). ``true_robot``: the robot as built that the physics simulates (default
    ``robot``; the runtime's odometry keeps the nominal ``robot``, so the two arrows part as they
    would on the real robot); ``limits``: the runtime's motion limits; ``hold`` [s]: the command
    timeout (0: a target holds until changed); ``camera``: the first camera preset;
    ``notices``: where the one-line notices go (default stderr); ``echo``: a text stream that gets
    each entry of :attr:`events` as it happens, one line (:meth:`_record`); ``world``: the world
    drawn and driven in (the robot starts at its start pose; the odometry's arrow is drawn from
    there, as the odometry counts from where the robot started)."""

    def __init__(
        self,
        robot: Robot,
        *,
        true_robot: Robot | None = None,
        speed: float = 0.2,
        turn: float = 0.5,
        hold: float = 0.0,
        camera: str = "free",
        limits: MotionLimits | None = None,
        notices=None,
        echo=None,
        world: World | None = None,
    ):
        if camera not in CAMERAS:
            raise InputError(f"camera must be one of {', '.join(CAMERAS)}, got {camera!r}")
        self.teleop = Teleop(speed, turn)
        self.robot = robot
        self.world = world
        self.start = np.zeros(3) if world is None else np.asarray(world.start, dtype=float)
        self.backend = PhysicsBackend(robot, true_robot, start=self.start, world=world)
        self.runtime = BaseRuntime(robot, self.backend, limits=limits, cmd_vel_timeout=hold)
        self.camera = camera
        self.events: list[dict] = []
        self.not_obeyed = moves_not_obeyed(robot)
        self._notices = notices
        self._echo = echo
        self.notes: list[str] = []  # every notice printed (once each)
        self._notice = ("", -math.inf)  # the notice on screen and its wall time
        # (key, pressed, wall time [s, time.monotonic()] at which the event reached the program)
        self._keys: queue.SimpleQueue[tuple[int, bool, float]] = queue.SimpleQueue()
        self._pending: deque[tuple[float, int, bool, float]] = deque()  # (sim time, key, pressed, wall)
        self._held: set[int] = set()
        self._hooked = False
        self._redelivering = False
        self._viewer_keys = None
        self._glfw_callback = None
        self.releases = False
        self._steer = np.zeros(len(robot.steerable))
        self._last: StepResult | None = None
        self.t = 0.0
        self._start = 0.0  # wall time [s] of the start
        self._origin = 0.0  # wall time [s] of simulated time 0: s = w - origin (module docstring)
        self.skipped = 0.0  # wall time [s] skipped while nothing was driven
        self._pace: deque[tuple[float, float]] = deque()  # (wall, sim) of recent frames
        self.rtf = 1.0
        self.slowest = math.inf  # lowest real-time factor measured over RTF_WINDOW
        self.wall = 0.0  # wall time [s] since the start
        self.markers: dict[str, list[Any]] = {}  # the arrows last drawn (:meth:`_draw_heading`)
        self._scans: dict[str, tuple] = {}  # per lidar: (sensor, the ranges of its latest scan)
        self._nearest: float | None = None  # [m] the nearest range of the latest scans

    # --- keys (called in the viewer's thread: only queued, with their wall time) ----------------
    def _on_key(self, key: int) -> None:
        """The viewer's ``key_callback`` (presses only). The first press takes the window's keys
        over (:meth:`_take_keys`)."""
        if self._redelivering:
            return
        now = time.monotonic()
        if not self._hooked:
            self._take_keys(key)
        self._keys.put((int(key), True, now))

    def _take_keys(self, first_key: int) -> None:
        """Put :meth:`_on_glfw_key` in front of the viewer's own key handler of the window (this
        runs in the viewer's thread, whose current GLFW context is the window): teleop keys get
        presses *and releases*, and do not reach the viewer, whose shortcuts they share (W
        toggles wireframe, S shadows, D the floor, 1-3 geom groups, [ ] cameras); other keys
        (Esc, F1, Tab) go on to it. The first press already reached it: a shortcut it toggled
        is toggled back by giving it the press once more. Without the GLFW bindings the
        viewer's presses alone drive (module docstring).

        This needs the bindings' raw ``glfwSetKeyCallback``, which returns the C function it
        replaces. The public ``glfw.set_key_callback`` cannot chain: it returns only a callback
        set through the bindings themselves, ``None`` for the viewer's, which is set in C++
        (checked with pyGLFW 2.11 and MuJoCo 4.0.0), so Esc, F1 and Tab would stop reaching
        the viewer."""
        self._hooked = True
        try:
            import glfw

            window = glfw.get_current_context()
            set_callback = glfw._glfw.glfwSetKeyCallback  # type: ignore[attr-defined]
            self._glfw_callback = set_callback.restype(self._on_glfw_key)
            self._viewer_keys = set_callback(window, self._glfw_callback)
        except Exception:  # noqa: BLE001 (private API of the bindings: fall back to presses)
            self._viewer_keys = None
            return
        self.releases = True
        if first_key in TELEOP_KEYS and self._viewer_keys:
            self._redelivering = True
            try:
                self._viewer_keys(window, first_key, 0, GLFW_PRESS, 0)
            finally:
                self._redelivering = False

    def _on_glfw_key(self, window, key, scancode, action, mods) -> None:
        if key in TELEOP_KEYS:
            if action != GLFW_REPEAT:
                self._keys.put((int(key), action == GLFW_PRESS, time.monotonic()))
        elif self._viewer_keys:
            self._viewer_keys(window, key, scancode, action, mods)

    def _drain(self) -> None:
        """Give each key event that arrived its simulated time ``w - w0`` (module docstring,
        Clock), never before the present or an earlier event, and queue it."""
        while True:
            try:
                key, pressed, wall = self._keys.get_nowait()
            except queue.Empty:
                return
            if key not in KEY_ACTIONS:
                continue
            at = max(wall - self._origin, self.t, self._pending[-1][0] if self._pending else 0.0)
            self._pending.append((at, key, pressed, wall))

    def _apply_due(self, viewer) -> None:
        """Apply the queued key events whose simulated time has come (at this control step)."""
        while self._pending and self._pending[0][0] <= self.t + 1e-9:
            _, key, pressed, wall = self._pending.popleft()
            self._apply(viewer, key, pressed, wall)

    def _apply(self, viewer, key: int, pressed: bool, wall: float) -> None:
        action = KEY_ACTIONS[key]
        if self.releases and action in MOVES:  # move keys held since their press acted
            (self._held.add if pressed else self._held.discard)(key)
        if not pressed:
            if self.teleop.release(action):
                self._record("release", wall)
                if not self.runtime.command(self.teleop.target.copy(), self.t):
                    # what the keys still hold is refused (a car's Q/E alone): stop rather than
                    # keep driving what the released key asked for
                    self._notify(f"{KEY_NAMES[key]} released: {self.runtime.filter.stats.last_reject_reason}; stopping")
                    self.runtime.command(np.zeros(3), self.t)
            return
        self.teleop.press(action)
        self._record(action, wall)
        if action.startswith("camera_"):
            self.camera = action.removeprefix("camera_")
            self._set_camera(viewer)
        elif action.startswith("steer_"):
            self._turn_steering(STEER_STEP if action == "steer_left" else -STEER_STEP)
        else:
            stats = self.runtime.filter.stats
            projected = stats.projected
            if not self.runtime.command(self.teleop.target.copy(), self.t):
                self._notify(f"{KEY_NAMES[key]} ({action}): {stats.last_reject_reason}; refused")
            elif stats.projected > projected and action in self.not_obeyed:
                self._notify(f"{KEY_NAMES[key]} ({action}) on {self.robot.name}: {self.not_obeyed[action]}")

    def _notify(self, text: str) -> None:
        """Show ``text`` on screen for :data:`NOTICE_TIME` s; print it on stderr the first time."""
        self._notice = (text, time.monotonic())
        self._note_once(text)

    def _note_once(self, text: str) -> None:
        """``omnikin: note: sim: text`` on stderr, the first time only (kept in :attr:`notes`)."""
        if text not in self.notes:
            self.notes.append(text)
            print(f"omnikin: note: sim: {text}", file=self._notices or sys.stderr, flush=True)

    def _record(self, key: str, wall: float) -> None:
        """One entry of :attr:`events`: the action, simulated time [s] at which it acted, wall time
        [s] since the start at which its key arrived, true pose, true twist (body frame: ``vx``,
        ``vy`` [m/s], ``omega`` [rad/s]; whether the robot was still moving when the key acted),
        odometry pose, the encoded wheels' angles (:meth:`wheel_angles`) and the steering angles
        the joints had reached
        (:meth:`steer_reached`); echoed as one line ``T s  KEY  x X m  y Y m
        theta TH rad`` when the simulator has an ``echo`` stream."""
        event = {
            "t": self.t,
            "wall": wall - self._start,
            "key": key,
            "pose": self.backend.truth.tolist(),
            "twist": self.backend.sim.twist.tolist(),
            "odometry_pose": list(self.runtime.pose),
            "wheels": self.wheel_angles(),
            "steer": self.steer_reached(),
        }
        self.events.append(event)
        if self._echo is not None:
            x, y, th = event["pose"]
            print(
                f"{self.t:.3f} s  {key}  x {x:+.4f} m  y {y:+.4f} m  theta {th:+.4f} rad", file=self._echo, flush=True
            )

    def wheel_angles(self) -> list[float]:
        """Angles [rad] of the encoded wheels (the runtime's order, ``robot.encoded_names``) as the
        runtime last read them from the encoders (ticks times the nominal scale): what its
        odometry integrated (empty before the first control step)."""
        return [] if self._last is None else [float(a) for a in self._last.state.positions]

    def steer_reached(self) -> list[float]:
        """Steering angles [rad] of the steerable wheels (file order) at the last control step,
        as the runtime measured them (empty without steerable wheels)."""
        state = self._last.state if self._last is not None else None
        return [] if state is None or state.steer is None else [float(a) for a in state.steer]

    def _turn_steering(self, angle: float) -> None:
        """Turn every steerable wheel by ``angle`` [rad] while the robot stands still."""
        if not len(self._steer) or np.any(self.teleop.target) or np.any(self.runtime.filter.current):
            return
        self._steer = self._current_steer() + angle
        self.runtime.steer_to(self._steer)

    def _current_steer(self) -> np.ndarray:
        return self._last.steer if self._last is not None and self._last.steer is not None else self._steer

    # --- camera --------------------------------------------------------------------------------------
    def _set_camera(self, viewer) -> None:
        mujoco = self.backend.sim._mj
        cam = viewer.cam
        size = max(max(abs(w.x), abs(w.y)) + w.radius for w in self.robot.wheels)
        pose = self.backend.sim.pose
        with viewer.lock():
            if self.camera == "follow":
                cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
                cam.trackbodyid = self.backend.sim._chassis
                cam.distance = CAMERA_DISTANCE * size
                cam.elevation = -30.0
                cam.azimuth = math.degrees(pose[2])  # the direction it looks: from behind
            else:
                cam.type = mujoco.mjtCamera.mjCAMERA_FREE
                cam.lookat[:] = (pose[0], pose[1], 0.0)
                cam.distance = CAMERA_DISTANCE * size
                cam.elevation = -90.0 if self.camera == "top" else -30.0
                cam.azimuth = 90.0 if self.camera == "top" else 135.0

    # --- heading arrows ------------------------------------------------------------------------------
    def _draw_heading(self, viewer) -> None:
        """Two arrows on top of the chassis, :data:`ARROW_LENGTH` times the robot's extent long,
        geoms of the viewer's ``user_scn`` drawn in every camera (module docstring): the truth's
        (green, :data:`ARROW_WIDTH` wide) from the robot's reference point along its heading (body +x);
        the odometry's (magenta, half as wide, 1.5 widths higher: clear of the truth's shaft,
        which MuJoCo draws about 0.75 widths thick, and above its head) from the odometry's
        ``(x, y)`` along its ``theta``. What the scene then holds is kept in :attr:`markers`
        (:meth:`_read_markers`)."""
        scn = viewer.user_scn
        if scn is None:
            return
        mujoco = self.backend.sim._mj
        model, data = self.backend.sim.model, self.backend.sim.data
        geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "chassis")
        half = np.abs(data.geom_xmat[geom].reshape(3, 3)) @ model.geom_aabb[geom][3:]
        top = float(data.geom_xpos[geom][2] + half[2])
        size = max(max(abs(w.x), abs(w.y)) + w.radius for w in self.robot.wheels)
        width = ARROW_WIDTH * size
        arrows = (
            (self.backend.truth, top + 0.01 * size, width, TRUTH_RGBA),
            (
                compose(self.start, np.asarray(self.runtime.pose)),
                top + 0.01 * size + 1.5 * width,
                0.5 * width,
                ODOMETRY_RGBA,
            ),
        )
        with viewer.lock():
            scn.ngeom = len(arrows)
            for g, ((x, y, th), z, w, rgba) in zip(scn.geoms, arrows, strict=False):
                start = np.array([x, y, z])
                end = start + ARROW_LENGTH / ARROW_DRAWN * size * np.array([math.cos(th), math.sin(th), 0.0])
                mujoco.mjv_initGeom(
                    g, mujoco.mjtGeom.mjGEOM_ARROW, np.zeros(3), np.zeros(3), np.eye(3).ravel(), np.array(rgba)
                )
                mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_ARROW, w, start, end)
            self.markers = self._read_markers(scn)
            points = self._scan_points()
            touches = [(c.point[0], c.point[1], 0.02) for c in self.backend.contacts[-CONTACTS_DRAWN:]]
            spheres = [(p, SCAN_POINT, SCAN_RGBA) for p in points]
            spheres += [(p, 2 * SCAN_POINT, CONTACT_RGBA) for p in touches]
            spheres = spheres[: max(0, scn.maxgeom - scn.ngeom)]
            for g, (position, radius, rgba) in zip(scn.geoms[scn.ngeom :], spheres, strict=False):
                mujoco.mjv_initGeom(
                    g,
                    mujoco.mjtGeom.mjGEOM_SPHERE,
                    np.array([radius, 0.0, 0.0]),
                    np.asarray(position, dtype=float),
                    np.eye(3).ravel(),
                    np.array(rgba),
                )
            scn.ngeom += len(spheres)
            self.markers["scan"] = [len(points), self._nearest]
            self.markers["contacts"] = [len(touches)]

    def _scan_points(self) -> list[tuple[float, float, float]]:
        """Where the beams of each lidar's latest scan met a wall or an obstacle (world frame,
        at the lidar's height), drawn from the robot's true pose of this frame (a scan is at most
        one lidar period older); the readings since the previous frame are drained from the
        back-end (:meth:`~omnikin.physics.backend.PhysicsBackend.sensor_readings`)."""
        readings = self.backend.sensor_readings()
        if readings is not None:
            for record in readings.scans:
                if len(record.t):
                    self._scans[record.sensor.name] = (record.sensor, record.ranges[-1])
        x, y, theta = (float(v) for v in self.backend.truth)
        c, s = math.cos(theta), math.sin(theta)
        points: list[tuple[float, float, float]] = []
        nearest = math.inf
        for lidar, ranges in self._scans.values():
            m = lidar.mount
            ox, oy = x + c * m.x - s * m.y, y + s * m.x + c * m.y
            seen = np.isfinite(ranges) & (ranges > 0.0)
            angles = theta + m.yaw + lidar.angles()[seen]
            hit = ranges[seen]
            points += [(ox + r * math.cos(a), oy + r * math.sin(a), m.z) for r, a in zip(hit, angles, strict=True)]
            nearest = min(nearest, float(hit.min()) if len(hit) else math.inf)
        self._nearest = nearest if math.isfinite(nearest) else None
        return points

    @staticmethod
    def _read_markers(scn) -> dict[str, list[Any]]:
        """The arrows in ``scn`` as drawn: ``{"truth": [x, y, heading, z, width, length], "odometry":
        [...]}`` [m, rad]: the arrow's tail, the direction of its axis (the third column of the
        geom's rotation), its width and its drawn length (``size[2]`` times :data:`ARROW_DRAWN`),
        read back from the geoms."""
        out = {}
        for name, g in zip(("truth", "odometry"), scn.geoms[: scn.ngeom], strict=False):
            axis = np.asarray(g.mat).reshape(3, 3)[:, 2]
            x, y, z = (float(v) for v in g.pos)
            heading = math.atan2(float(axis[1]), float(axis[0]))
            out[name] = [x, y, heading, z, float(g.size[0]), ARROW_DRAWN * float(g.size[2])]
        return out

    # --- readout -------------------------------------------------------------------------------------
    def _pace_update(self, wall: float) -> None:
        """Real-time factor over the last :data:`RTF_WINDOW` s of wall time (module docstring)."""
        self._pace.append((wall, self.t))
        while len(self._pace) > 2 and wall - self._pace[1][0] >= RTF_WINDOW:
            self._pace.popleft()
        w0, s0 = self._pace[0]
        if wall - w0 >= RTF_WINDOW:
            self.rtf = (self.t - s0) / (wall - w0)
            self.slowest = min(self.slowest, self.rtf)
            if self.rtf < SLOW_RTF:
                self._notify_slow()

    def _notify_slow(self) -> None:
        self._note_once(
            "this machine cannot keep up: the simulation runs slower than the clock (the window shows the "
            "real-time factor); keys act at their simulated time"
        )

    @property
    def lag(self) -> float:
        """How far [s] the simulation is behind the clock."""
        return max(0.0, self.wall - (self._origin - self._start) - self.t)

    def key_help(self) -> list[str]:
        """The keys, one line; a pair of move keys the robot cannot obey is marked ``*`` and
        followed by a line saying why (:func:`~omnikin.runtime.teleop.moves_not_obeyed`)."""
        pairs = {"W/S": ("forward", "back"), "A/D": ("left", "right"), "Q/E": ("turn_left", "turn_right")}
        marked = {
            keys: next((self.not_obeyed[a] for a in acts if a in self.not_obeyed), "") for keys, acts in pairs.items()
        }
        moves = ", ".join(keys + ("*" if why else "") for keys, why in marked.items())
        return [f"{moves} move, space stop, [ ] steer, 1 2 3 camera"] + [
            f"* {keys} on {self.robot.name}: {why}" for keys, why in marked.items() if why
        ]

    def readout(self) -> str:
        """Time, true pose, odometry pose, twist and wheel speeds, one quantity a line (the window's
        top left overlay)."""
        x, y, th = self.backend.truth
        ox, oy, oth = self.runtime.pose
        vx, vy, w = self.backend.sim.twist
        speeds = " ".join(f"{s:+.2f}" for s in self.backend.sim.wheel_speeds)
        target = self.teleop.target
        lines = [
            f"t {self.t:7.2f} s simulated   real-time factor {self.rtf:.2f}   camera {self.camera}",
            f"truth    x {x:+.3f} m  y {y:+.3f} m  theta {math.degrees(th):+.1f} deg",
            f"odometry x {ox:+.3f} m  y {oy:+.3f} m  theta {math.degrees(oth):+.1f} deg",
            f"twist vx {vx:+.3f} m/s  vy {vy:+.3f} m/s  omega {w:+.3f} rad/s",
            f"target vx {target[0]:+.2f}  vy {target[1]:+.2f}  omega {target[2]:+.2f}",
            f"wheels [rad/s] {speeds}",
        ]
        if len(self._steer):
            steer = " ".join(f"{math.degrees(a):+.0f}" for a in self.backend.sim.steer_angles)
            lines.append(f"steering [deg] {steer}")
        if self.rtf < SLOW_RTF or self.lag > CATCH_UP:
            lines.append(f"SLOW: the machine cannot keep up, {self.lag:.1f} s behind the clock")
        if self.backend.fallen:  # the back-end stopped the wheels (docs/physics.md)
            lines.insert(0, f"stopped: {self.backend.fallen}")
        return "\n".join(lines)

    def help_text(self) -> str:
        """The notice of the last few seconds (if any), the keys and the arrows' :data:`LEGEND`
        (the bottom right overlay)."""
        text, since = self._notice
        lines = [text] if text and time.monotonic() - since < NOTICE_TIME else []
        return "\n".join(lines + self.key_help() + [LEGEND])

    # --- the loop ------------------------------------------------------------------------------------
    def run(self, duration: float | None = None) -> str:
        """Open the window and run until it is closed (``"closed"``) or ``duration`` [s] of
        simulated time have passed (``"duration"``); the window is closed and its thread ended
        either way, also when an exception (Ctrl-C) leaves."""
        mujoco, viewer_module = _viewer_module()
        require_display()
        before = set(threading.enumerate())
        sim = self.backend.sim
        # simulated time 0 is the window's opening: keys pressed while the loop gets ready keep
        # their distances (the simulation starts behind and catches up)
        self._start = self._origin = time.monotonic()
        # Ctrl-C or SIGTERM while the viewer starts would leave its render thread drawing while
        # the process exits (an X error, a segfault): their handlers wait until it can be closed.
        # (Blocking the signals in this thread would not do: another thread, e.g. a BLAS
        # worker's, would take them, and Python runs the handler here all the same.)
        held: list[int] = []
        previous: dict = {}

        def restore() -> None:
            for s, handler in previous.items():
                signal.signal(s, handler)

        try:
            # a handler C code set (None: it cannot be put back from Python) or SIG_IGN is left
            # alone; each one is recorded before it is swapped, so that a pending signal raising
            # in the middle leaves none swapped
            for sig in STOP_SIGNALS if threading.current_thread() is threading.main_thread() else ():
                handler = signal.getsignal(sig)
                if handler is not None and handler != signal.SIG_IGN:
                    previous[sig] = handler
                    signal.signal(sig, lambda signum, frame: held.append(signum))
            viewer = viewer_module.launch_passive(
                sim.model, sim.data, key_callback=self._on_key, show_left_ui=False, show_right_ui=False
            )
        except BaseException:
            restore()
            raise
        render_threads = [t for t in threading.enumerate() if t not in before]
        try:
            restore()
            for s in held:  # a signal that came while the viewer started acts now, inside try
                signal.raise_signal(s)
            self._set_camera(viewer)
            self._last = self.runtime.step(0.0)
            self._draw_heading(viewer)
            viewer.sync()
            end = math.inf if duration is None else duration
            while viewer.is_running():
                now = time.monotonic()
                self.wall = now - self._start
                self._drain()
                # the simulated time the clock asks for, at most CATCH_UP before the next frame
                reach = min(now - self._origin, end, self.t + CATCH_UP)
                self._apply_due(viewer)
                while self.t + CONTROL_PERIOD <= reach + 1e-9:
                    self.t += CONTROL_PERIOD
                    self._last = self.runtime.step(self.t)
                    self._apply_due(viewer)
                if self.t + CONTROL_PERIOD > end + 1e-9:
                    self._draw_heading(viewer)  # the arrows of the final state (the report's markers)
                    viewer.sync()
                    return "duration"
                self._skip(now)
                self._pace_update(self.wall)
                self._draw_heading(viewer)
                viewer.set_texts(
                    [
                        (None, mujoco.mjtGridPos.mjGRID_TOPLEFT, self.readout(), None),
                        (None, mujoco.mjtGridPos.mjGRID_BOTTOMRIGHT, self.help_text(), None),
                    ]
                )
                viewer.sync()
                ahead = self.t + CONTROL_PERIOD - (time.monotonic() - self._origin)
                if ahead > 0:
                    time.sleep(ahead)
            return "closed"
        finally:
            self.wall = time.monotonic() - self._start
            viewer.close()
            for t in render_threads:
                t.join(SHUTDOWN_WAIT)

    def _skip(self, now: float) -> None:
        """Skip the time the simulation is behind the clock at ``now`` (time.monotonic() of this
        frame's start) when it is more than :data:`MAX_LAG`, the robot is at rest and no key that
        has acted is held (module docstring): the clock is set back to the simulated time, or,
        when key events wait, only so far that the first of them acts now; the waiting events
        keep their distances (a press and its release stay as far apart)."""
        lag = now - self._origin - self.t
        if lag <= MAX_LAG or self._held or not self._at_rest():
            return
        if self._pending:
            lag = min(lag, self._pending[0][0] - self.t)
            self._pending = deque((at - lag, key, pressed, wall) for at, key, pressed, wall in self._pending)
        self._origin += lag
        self.skipped += lag

    def _at_rest(self) -> bool:
        """Nothing driven and nothing moving: the command filter's output zero, the chassis still
        (every component of its twist below :data:`REST_SPEED`) and every steering joint at the
        angle last commanded (within 0.5 deg)."""
        sim = self.backend.sim
        if np.any(self.runtime.filter.current) or np.any(np.abs(sim.twist) > REST_SPEED):
            return False
        steer = self._last.steer if self._last is not None else None
        return steer is None or not len(steer) or bool(np.all(np.abs(sim.steer_angles - steer) < math.radians(0.5)))

    def report(self, reason: str) -> dict:
        """What the run did, for ``--report``: final pose and twist (ground truth, odometry), the
        encoded wheels' angles the odometry integrated (:meth:`wheel_angles`), the two arrows as
        the window last drew them (:attr:`markers`, with ``scan``: the scan points drawn and the
        nearest range [m], and ``contacts``: the touches drawn), steering angles reached [rad], key presses
        with their simulated time, wall arrival time, true pose and twist, odometry pose, wheel
        angles and steering; the clock: simulated and wall time [s], wall time skipped while
        nothing was driven, lowest real-time factor measured (null: the run was too short); in a
        world, the contacts (time [s], body, point [m])."""
        return {
            "robot": self.robot.name,
            "end": reason,
            "sim_time": self.t,
            "wall_time": self.wall,
            "skipped": self.skipped,
            "slowest_real_time_factor": self.slowest if math.isfinite(self.slowest) else None,
            "pose": self.backend.truth.tolist(),
            "twist": self.backend.sim.twist.tolist(),
            "odometry_pose": list(self.runtime.pose),
            "wheels": self.wheel_angles(),
            "markers": self.markers,
            "steer": self.steer_reached(),
            "target": self.teleop.target.tolist(),
            "fallen": self.backend.fallen,
            "contacts": [{"time": c.time, "body": c.body, "point": list(c.point)} for c in self.backend.contacts],
            "presses": dict(self.teleop.presses),
            "releases": self.releases,
            "not_obeyed": dict(self.not_obeyed),
            "notes": list(self.notes),
            "events": self.events,
            "commands": {
                "accepted": self.runtime.filter.stats.accepted,
                "rejected": self.runtime.filter.stats.rejected,
                "projected": self.runtime.filter.stats.projected,
                "timeouts": self.runtime.filter.stats.timeouts,
            },
        }
