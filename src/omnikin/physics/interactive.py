"""The interactive simulator of ``omnikin sim``: a robot in MuJoCo's own viewer window, driven
from the keyboard through the runtime (extra ``physics``).

The program descends from the OpenGL simulator of Villasenor et al.'s omnidirectional robot with
steerable legs; here the window is MuJoCo's passive viewer and the robot the physics model of
:class:`~omnikin.physics.backend.PhysicsBackend`, driven by
:class:`~omnikin.runtime.base.BaseRuntime`: every key becomes a velocity command of the
runtime's :class:`~omnikin.runtime.command.CommandFilter`, so the speed and acceleration limits
(:class:`~omnikin.limits.MotionLimits`) and the command timeout act as on the real robot.

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

**Camera** (:meth:`InteractiveSim._set_camera`), each from :data:`CAMERA_DISTANCE` times the
robot's extent (the largest ``max(|x|, |y|) + r`` of its wheels) away: 1 free (mouse: left drag
rotates, right drag moves, wheel zooms), 2 top (straight down on the pose where it was chosen,
world +x to the right and +y up in the window; it stays there while the robot drives off),
3 follow (MuJoCo's tracking camera: it keeps the chassis in the middle of the window, seen from
behind at 30 deg elevation along the heading it had when chosen). The window shows pose, twist,
target, wheel speeds and steering angles.

Clock: the simulation runs in real time when the machine keeps up (else slower); control steps
every :data:`CONTROL_PERIOD` simulated seconds. The run ends when the window is closed, after
``duration`` seconds of wall-clock time, or on :class:`KeyboardInterrupt` (or any exception)
raised in the caller's thread; in every case the viewer is closed and its render thread joined
before returning, since a process that exits while the render thread still draws dies in an X
error (``GLXBadDrawable``).
"""

from __future__ import annotations

import math
import os
import queue
import threading
import time

import numpy as np

from ..errors import InputError
from ..limits import MotionLimits
from ..model import Robot
from ..runtime.base import BaseRuntime, StepResult
from ..runtime.teleop import Teleop
from .backend import PhysicsBackend

CONTROL_PERIOD = 0.02
"""Simulated time [s] between two control steps of the runtime (50 Hz)."""
STEER_STEP = math.radians(15.0)
"""Steering turned by one press of ``[`` or ``]`` [rad]."""
CATCH_UP = 0.25
"""Most simulated time [s] run between two frames when the simulation falls behind the clock:
the window stays responsive (a frame at least every 0.25 s of simulated time; software OpenGL
under load draws about 5-10 frames per second), and a machine too slow for real time runs it slower."""
SHUTDOWN_WAIT = 5.0
"""Longest wait [s] for the viewer's render thread to end after the window is closed."""
CAMERAS = ("free", "top", "follow")
CAMERA_DISTANCE = 8.0
"""Distance of every camera preset from its point of view, in units of the robot's extent."""

KEY_W, KEY_S, KEY_A, KEY_D, KEY_Q, KEY_E = (ord(c) for c in "WSADQE")
KEY_SPACE = 32
KEY_LEFT_BRACKET, KEY_RIGHT_BRACKET = ord("["), ord("]")
KEY_1, KEY_2, KEY_3 = ord("1"), ord("2"), ord("3")
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
    (module docstring). ``limits``: the runtime's motion limits; ``hold`` [s]: the command
    timeout (0: a target holds until changed); ``camera``: the first camera preset."""

    def __init__(
        self,
        robot: Robot,
        *,
        speed: float = 0.2,
        turn: float = 0.5,
        hold: float = 0.0,
        camera: str = "free",
        limits: MotionLimits | None = None,
    ):
        if camera not in CAMERAS:
            raise InputError(f"camera must be one of {', '.join(CAMERAS)}, got {camera!r}")
        self.teleop = Teleop(speed, turn)
        self.robot = robot
        self.backend = PhysicsBackend(robot)
        self.runtime = BaseRuntime(robot, self.backend, limits=limits, cmd_vel_timeout=hold)
        self.camera = camera
        self.events: list[dict] = []
        self._keys: queue.SimpleQueue[tuple[int, bool]] = queue.SimpleQueue()
        self._hooked = False
        self._redelivering = False
        self._viewer_keys = None
        self._glfw_callback = None
        self.releases = False
        self._steer = np.zeros(len(robot.steerable))
        self._last: StepResult | None = None
        self.t = 0.0

    # --- keys (called in the viewer's thread: only queued) --------------------------------------
    def _on_key(self, key: int) -> None:
        """The viewer's ``key_callback`` (presses only). The first press takes the window's keys
        over (:meth:`_take_keys`)."""
        if self._redelivering:
            return
        if not self._hooked:
            self._take_keys(key)
        self._keys.put((int(key), True))

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
                self._keys.put((int(key), action == GLFW_PRESS))
        elif self._viewer_keys:
            self._viewer_keys(window, key, scancode, action, mods)

    def _apply_keys(self, viewer) -> None:
        while True:
            try:
                key, pressed = self._keys.get_nowait()
            except queue.Empty:
                return
            action = KEY_ACTIONS.get(key)
            if action is None:
                continue
            if not pressed:
                if self.teleop.release(action):
                    self._record("release")
                    self.runtime.command(self.teleop.target.copy(), self.t)
                continue
            self.teleop.press(action)
            self._record(action)
            if action.startswith("camera_"):
                self.camera = action.removeprefix("camera_")
                self._set_camera(viewer)
            elif action.startswith("steer_"):
                self._turn_steering(STEER_STEP if action == "steer_left" else -STEER_STEP)
            else:
                self.runtime.command(self.teleop.target.copy(), self.t)

    def _record(self, key: str) -> None:
        """One entry of :attr:`events`: the action, simulated time [s], true pose and the
        steering angles the joints had reached (:meth:`steer_reached`)."""
        self.events.append(
            {"t": self.t, "key": key, "pose": self.backend.truth.tolist(), "steer": self.steer_reached()}
        )

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

    # --- readout -------------------------------------------------------------------------------------
    def readout(self) -> str:
        """Pose, twist and wheel speeds, one quantity a line (the window's overlay)."""
        x, y, th = self.backend.truth
        vx, vy, w = self.backend.sim.twist
        speeds = " ".join(f"{s:+.2f}" for s in self.backend.sim.wheel_speeds)
        target = self.teleop.target
        lines = [
            f"t {self.t:7.2f} s   camera {self.camera}",
            f"pose  x {x:+.3f} m  y {y:+.3f} m  theta {math.degrees(th):+.1f} deg",
            f"twist vx {vx:+.3f} m/s  vy {vy:+.3f} m/s  omega {w:+.3f} rad/s",
            f"target vx {target[0]:+.2f}  vy {target[1]:+.2f}  omega {target[2]:+.2f}",
            f"wheels [rad/s] {speeds}",
        ]
        if len(self._steer):
            steer = " ".join(f"{math.degrees(a):+.0f}" for a in self.backend.sim.steer_angles)
            lines.append(f"steering [deg] {steer}")
        lines.append("W/S A/D Q/E move, space stop, [ ] steer, 1 2 3 camera")
        if self.backend.fallen:  # the back-end stopped the wheels (docs/physics.md)
            lines.insert(0, f"stopped: {self.backend.fallen}")
        return "\n".join(lines)

    # --- the loop ------------------------------------------------------------------------------------
    def run(self, duration: float | None = None) -> str:
        """Open the window and run until it is closed (``"closed"``) or ``duration`` [s] of wall
        time have passed (``"duration"``); the window is closed and its thread ended either way,
        also when an exception (Ctrl-C) leaves."""
        mujoco, viewer_module = _viewer_module()
        require_display()
        before = set(threading.enumerate())
        sim = self.backend.sim
        viewer = viewer_module.launch_passive(
            sim.model, sim.data, key_callback=self._on_key, show_left_ui=False, show_right_ui=False
        )
        render_threads = [t for t in threading.enumerate() if t not in before]
        try:
            self._set_camera(viewer)
            self._last = self.runtime.step(0.0)
            viewer.sync()
            start = time.monotonic()
            reason = "closed"
            while viewer.is_running():
                wall = time.monotonic() - start
                if duration is not None and wall >= duration:
                    reason = "duration"
                    break
                self._apply_keys(viewer)
                behind = min(wall, self.t + CATCH_UP)  # simulated time to reach before drawing
                while self.t + CONTROL_PERIOD <= behind:
                    self.t += CONTROL_PERIOD
                    self._last = self.runtime.step(self.t)
                viewer.set_texts((None, mujoco.mjtGridPos.mjGRID_TOPLEFT, self.readout(), None))
                viewer.sync()
                ahead = self.t + CONTROL_PERIOD - (time.monotonic() - start)
                if ahead > 0:
                    time.sleep(ahead)
            return reason
        finally:
            viewer.close()
            for t in render_threads:
                t.join(SHUTDOWN_WAIT)

    def report(self, reason: str) -> dict:
        """What the run did, for ``--report``: final pose and twist (ground truth, odometry),
        steering angles reached [rad], key presses with their simulated time, pose and steering."""
        return {
            "robot": self.robot.name,
            "end": reason,
            "sim_time": self.t,
            "pose": self.backend.truth.tolist(),
            "twist": self.backend.sim.twist.tolist(),
            "odometry_pose": list(self.runtime.pose),
            "steer": self.steer_reached(),
            "target": self.teleop.target.tolist(),
            "fallen": self.backend.fallen,
            "presses": dict(self.teleop.presses),
            "releases": self.releases,
            "events": self.events,
            "commands": {
                "accepted": self.runtime.filter.stats.accepted,
                "rejected": self.runtime.filter.stats.rejected,
                "timeouts": self.runtime.filter.stats.timeouts,
            },
        }
