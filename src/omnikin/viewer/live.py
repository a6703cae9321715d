"""The robot the viewer drives: an engine, the runtime, and the inputs of the page.

:class:`LiveRobot` joins a wheel back-end (``kinematic``: :class:`~omnikin.simulation.backend.SimBackend`,
the robot moved exactly by its wheels; ``physics``: :class:`~omnikin.physics.backend.PhysicsBackend`,
MuJoCo with rollers, extra ``physics``) and :class:`~omnikin.runtime.base.BaseRuntime`, whose
command filter (speed and acceleration limits, command timeout) every input passes, as on the
real robot. Inputs arrive from other threads (the page's keys, its controls) and are queued;
:meth:`LiveRobot.step` applies them, runs one control step at the given time and returns a
:class:`Snapshot` of everything the page shows.

Inputs: key messages of :mod:`omnikin.viewer.front` (held keys through
:class:`~omnikin.runtime.teleop.Teleop`; a held key whose page has been silent for
:data:`KEY_SILENCE` s is released, so a closed tab or a lost link stops the robot), a twist set
on the page's controls (held until changed or stopped), a stop, and steering by hand (robots
with steerable wheels, at rest). While a target is non-zero it is offered to the runtime at
every step, so the command timeout only acts when the inputs stop.

A physics robot that tips over is stopped by its back-end
(:attr:`omnikin.physics.backend.PhysicsBackend.fallen`); :attr:`PageRobot.fallen` then holds the
one line the page shows and :attr:`PageRobot.tell` says once on the terminal.

Record (as ``omnikin sim --echo``): each key action that changed what the robot does is kept in
:attr:`PageRobot.events` (the last :data:`MAX_EVENTS`) and, with an :attr:`PageRobot.echo` stream,
printed as one line ``T s  ACTION  x X m  y Y m  theta TH rad``: ``T`` the simulated time [s] of
the control step from which the action acts (the step made at the key's arrival; the command
filter's acceleration ramp starts there), ``ACTION`` the key's action (``forward``, ``left``,
``turn_left``, ``stop``, ``camera_top``, ...; ``release`` when a released key stops a motion), and
the true pose at that step (world frame) [m, m, rad].
"""

from __future__ import annotations

import math
import queue
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import TextIO

import numpy as np

from ..control.follower import FollowPlan, PathFollower, PlanWorker, plan_follow
from ..errors import InputError
from ..kinematics.robot import Robot
from ..kinematics.se2 import between
from ..motion.limits import MotionLimits
from ..physics.description import PhysicalRobot, describe
from ..physics.joint_motion import JointMotion
from ..runtime.base import BaseRuntime, StepResult
from ..runtime.goal import GoalSeeker
from ..runtime.teleop import MOVES, STEER_STEP, Teleop
from ..simulation.engine import Engine, KinematicEngine
from ..world.model import World

KINEMATIC = KinematicEngine()
"""The default engine of the live robot (the kinematic one, no options)."""
KEY_SILENCE = 1.0
"""Time [s] after which a held key whose page sent nothing (no ``alive``, sent every 0.1 s while a
key is down) is released: ten heartbeats, so that a page whose thread is busy drawing a frame in
software (100-300 ms on a loaded machine without a GPU) does not stop the robot."""
MAX_SUBSTEPS = 8
"""Inputs that get a control step of their own at their arrival, per step; later ones in the
same step (a flood) are applied at the step's time, so the work per step stays bounded."""
MIN_SUBSTEP = 0.001
"""Shortest interval [s] between two control steps made for arrivals."""
MAX_EVENTS = 10000
"""Key actions kept in :attr:`PageRobot.events` (older ones are dropped: a long session stays small)."""
CATCH_UP_STEP = 0.02
"""Longest interval [s] of simulated time between two control steps of a simulated robot
(:class:`LiveRobot`; the viewer's control period): a loop that runs late (a busy machine) makes
the steps it missed, so the motion between two inputs does not depend on the wall clock's pace."""
MAX_CATCH_UP = 100
"""At most this many steps made up per call of :meth:`PageRobot.step` (2 s of simulated time);
a longer stall is crossed in one step, so the work per step stays bounded."""


def triple(values) -> tuple[float, float, float]:
    """Three numbers (a pose or a twist) as the plain floats a :class:`Snapshot` holds."""
    a, b, c = (float(v) for v in values)
    return a, b, c


@dataclass(frozen=True)
class WheelSlots:
    """Where each group of wheels sits in a :class:`Snapshot`'s per-wheel arrays (the order of
    the physical description's wheels): the robot's rolling and steered wheels (file order), the
    castors of :class:`~omnikin.physics.joint_motion.JointMotion` and the Swedish wheels."""

    count: int
    rolling: np.ndarray
    steered: np.ndarray
    castors: np.ndarray
    swedish: np.ndarray

    @classmethod
    def of(cls, robot: Robot, description: PhysicalRobot, joints: JointMotion) -> WheelSlots:
        names = [w.name for w in description.wheels]

        def slots(group) -> np.ndarray:
            return np.array([names.index(n) for n in group], dtype=int)

        swedish = [w.name for w in description.wheels if w.rollers is not None]
        return cls(
            len(names), slots(robot.rolling_names), slots(robot.steer_names), slots(joints.castor_names), slots(swedish)
        )

    def rollers(self, angles, rates) -> tuple[tuple[float | None, ...], tuple[float | None, ...]]:
        """Per wheel the roller angle and speed of each Swedish wheel (``angles``, ``rates`` in
        description order of the Swedish wheels), None for the others."""
        out_angles: list[float | None] = [None] * self.count
        out_rates: list[float | None] = [None] * self.count
        for slot, angle, rate in zip(self.swedish, angles, rates, strict=True):
            out_angles[slot], out_rates[slot] = float(angle), float(rate)
        return tuple(out_angles), tuple(out_rates)


@dataclass(frozen=True)
class Snapshot:
    """One control step as the page shows it. Poses ``(x, y, theta)`` [m, m, rad] in the world
    frame; twists ``(vx, vy, omega)`` [m/s, m/s, rad/s] in the body frame. Per wheel
    (description order, castors included): ``wheel_angles`` [rad] and ``wheel_speeds`` [rad/s]
    of the true wheels, ``steer`` [rad] relative to the mounting drive direction (NaN: not
    steered; a castor's swivel). ``residual``: the forward-kinematics residual of the odometry
    [rad/s]. ``roller_angles`` [rad] and ``roller_speeds`` [rad/s] per wheel (None: no rollers):
    the roller in contact, as the body motion implies (:mod:`omnikin.physics.joint_motion`).
    ``missing``: the readouts without data (``truth``, ``odometry``, ``twist``, ``command``,
    ``residual``), which the page shows as ``missing_why`` ("not recorded"), never as zeros."""

    t: float
    truth: tuple[float, float, float]
    odometry: tuple[float, float, float]
    twist: tuple[float, float, float]
    command: tuple[float, float, float]
    target: tuple[float, float, float]
    wheel_angles: np.ndarray
    wheel_speeds: np.ndarray
    steer: np.ndarray
    residual: tuple[float, ...]
    roller_angles: tuple[float | None, ...] = ()
    roller_speeds: tuple[float | None, ...] = ()
    missing: tuple[str, ...] = ()
    missing_why: str = "not recorded"


class PageRobot:
    """A robot the page drives (module docstring): its inputs, held keys and goal seeker.
    Subclasses say how a control step runs (:meth:`_control`), where the robot thinks it is
    (:attr:`pose`) and whether it steers by hand (:meth:`_turn_steering`). ``speed`` [m/s] and
    ``turn`` [rad/s]: what a held key sets; ``limits``: the speeds and accelerations the page's
    sliders and the goal seeker use."""

    def __init__(self, robot: Robot, *, speed: float = 0.2, turn: float = 0.5, limits: MotionLimits | None = None):
        self.teleop = Teleop(speed, turn)
        self.robot = robot
        self.limits = limits or MotionLimits()
        self.description: PhysicalRobot = describe(robot)
        self._inputs: queue.SimpleQueue[tuple[float | None, str, object]] = queue.SimpleQueue()
        self.clock: Callable[[], float] | None = None  # the time [s] of step()'s clock, for arrivals
        self._set_twist = np.zeros(3)
        self._held: dict[object, set[str]] = {}  # per key channel ("source"): the move keys it holds
        self._heard: dict[object, float] = {}  # ... and when it last sent anything [s]
        self.notice = ""  # the last input refused, in one line (the page shows it)
        self.fallen = ""  # once the simulated robot tipped over: that, in one line (page and terminal)
        self.tell: Callable[[str], None] | None = None  # says a line on the terminal (omnikin view sets it)
        self.seeker: GoalSeeker | None = None
        self.arrived: tuple[float, float, float] | None = None  # the odometry's pose at the last goal reached
        self.arrived_heading = True  # whether the seeker steered the heading to the goal's
        self.t = 0.0
        self._caught_up = 0  # steps made up in this step() call
        self.echo: TextIO | None = None  # gets each key action as it acts (module docstring)
        self.events: deque[dict] = deque(maxlen=MAX_EVENTS)
        self.follower = PathFollower()  # a path followed (:meth:`follow`)
        self.path_options: dict = {"heading": "given", "smooth": True, "blend": 0.0}
        self._planner = PlanWorker(self._plan)  # plans off the control loop, the latest Follow winning

    can_steer = False
    """Whether the page's steering keys and buttons turn the wheels."""
    catch_up = False
    """Whether :meth:`step` makes the control steps a late loop missed (:data:`CATCH_UP_STEP`)."""

    @property
    def pose(self) -> tuple[float, float, float]:
        """The pose the robot steers to a goal by (its odometry) [m, m, rad]."""
        raise NotImplementedError

    def _control(self, t: float) -> Snapshot:
        """One control step at ``t`` [s] with the targets as they are."""
        raise NotImplementedError

    def _turn_steering(self, angle: float) -> None:
        """Turn the steerable wheels by ``angle`` [rad] (robots that steer by hand)."""

    @property
    def shown_pose(self) -> tuple[float, float, float]:
        """The pose a key action is recorded with [m, m, rad] (the true pose where there is one)."""
        return self.pose

    start = np.zeros(3)
    """Where the robot started in its world, ``(x, y, theta)`` [m, m, rad]: the page draws in the
    frame of its odometry, which starts there (zero on an empty floor)."""

    @property
    def world(self) -> World | None:
        """The world the robot drives in (None: an empty floor, or one the page does not know)."""
        return None

    def obstacle_poses(self) -> np.ndarray | None:
        """Where the world's obstacles are now, ``(n, 3)`` [m, m, rad] world frame, when something
        moves them (the physics engine); None when they stay where the world file puts them."""
        return None

    def _record(self, action: str) -> None:
        """One entry of :attr:`events`: ``action`` acts from the last control step (:attr:`t` [s]);
        echoed as one line (module docstring) when there is an :attr:`echo` stream."""
        x, y, th = self.shown_pose
        self.events.append({"t": self.t, "key": action, "pose": [x, y, th]})
        if self.echo is not None:
            print(
                f"{self.t:.3f} s  {action}  x {x:+.4f} m  y {y:+.4f} m  theta {th:+.4f} rad", file=self.echo, flush=True
            )

    def close(self) -> None:
        """Release what the robot holds (engine, link)."""

    # --- inputs (any thread) --------------------------------------------------------------------
    def _put(self, kind: str, value: object) -> None:
        """Queue an input with the time it arrived (:attr:`clock`; None: at the next step)."""
        self._inputs.put((None if self.clock is None else self.clock(), kind, value))

    def key(self, message: dict) -> None:
        """A key message of the page (:func:`omnikin.viewer.front.parse_key_message`)."""
        self._put("key", message)

    def set_twist(self, twist) -> None:
        """Drive at ``twist`` (on-screen controls) until it is changed or stopped."""
        self._put("twist", np.asarray(twist, dtype=float).reshape(3).copy())

    def stop(self) -> None:
        """Stop: every target zero; the robot decelerates within its limits."""
        self._put("stop", None)

    def go_to(self, goal) -> None:
        """Drive to ``goal`` ``(x, y, theta)`` [m, m, rad] (:class:`~omnikin.runtime.goal.GoalSeeker`,
        steering by the odometry); a key, a twist or a stop cancels it."""
        self._put("goal", goal)  # checked when applied: a bad goal is refused there, in one line

    def follow(self, waypoints, **options) -> None:
        """Follow the path through ``waypoints`` ``(n, 2|3)`` [m, m, rad] (world frame) from
        where the robot is (:func:`~omnikin.control.follower.plan_follow`: ``heading``,
        ``smooth``, ``blend``, default :attr:`path_options`), timed within the robot's limits and
        tracked by its controller, steering by the odometry; a key, a twist, a stop or a goal
        stops it. A path that cannot be followed is refused in one line (:attr:`notice`)."""
        self._put("path", (np.array(waypoints, dtype=float), dict(self.path_options, **options)))

    def stop_path(self) -> None:
        """Stop following the path; the robot brakes to a stop."""
        self._put("path_stop", None)

    def steer_by(self, angle: float) -> None:
        """Turn every steerable wheel by ``angle`` [rad] (robot at rest; ignored while it moves)."""
        self._put("steer", float(angle))

    # --- the control step -------------------------------------------------------------------------
    def _apply_input(self, t: float, kind: str, value: object) -> list[str]:
        """Apply one input that arrived at ``t`` [s]; returns the page actions that are not teleop
        (camera presets)."""
        actions: list[str] = []
        if kind in ("key", "twist", "stop"):
            self.seeker = None  # the user takes over
        if kind in ("twist", "stop", "goal"):
            self._stop_path(f"the page's {'goal' if kind == 'goal' else 'controls'} took over")
        if kind == "key":
            assert isinstance(value, dict)
            source = value.get("source")
            held = self._held.setdefault(source, set())
            self._heard[source] = t
            kind_of = value["type"]
            if kind_of == "press":
                action = value["action"]
                if action == "stop":
                    self._set_twist[:] = 0.0
                if action in ("steer_left", "steer_right"):
                    self._turn_steering(STEER_STEP if action == "steer_left" else -STEER_STEP)
                elif self.teleop.press(action):
                    self._stop_path("a key took over")
                    if action in MOVES:
                        held.add(action)
                else:
                    actions.append(action)
                self._record(action)
            elif kind_of == "release":
                held.discard(value["action"])
                if self.teleop.release(value["action"]):
                    self._record("release")
            elif kind_of == "release_all":
                self._release(source)
        elif kind == "twist":
            assert isinstance(value, np.ndarray)
            self._set_twist = value
        elif kind == "stop":
            self.teleop.release_all()
            self._set_twist[:] = 0.0
        elif kind == "goal":
            limits = self.limits
            self.seeker = GoalSeeker(
                self.robot,
                value,  # type: ignore[arg-type]
                speed=min(self.teleop.speed, limits.linear or math.inf),
                turn=min(self.teleop.turn, limits.angular or math.inf),
                accel=limits.linear_accel,
                angular_accel=limits.angular_accel,
            )
            self.teleop.release_all()
            self._set_twist[:] = 0.0
        elif kind == "steer":
            assert isinstance(value, float)
            self._turn_steering(value)
        elif kind == "path":
            assert isinstance(value, tuple)
            points, chosen = value
            self._planner.request(waypoints=points, pose=np.array(self.pose, dtype=float), options=chosen)
        elif kind == "path_stop":
            self._stop_path("Stop pressed")
        return actions

    def _stop_path(self, why: str) -> None:
        """Stop the path followed, and drop one being planned."""
        if self._planner.cancel() and not self.follower.following:
            self.follower.drop(f"{why} while the path was planned")
        self.follower.stop(why)

    def _plan(self, generation: int, waypoints: np.ndarray, pose: np.ndarray, options: dict) -> FollowPlan:
        """The planning thread (:class:`~omnikin.control.follower.PlanWorker`): the path from
        ``pose``, within the robot's limits."""
        return plan_follow(self.robot, waypoints, pose, body=self.limits, rate=1.0 / CATCH_UP_STEP, **options)

    def _start_planned(self, t: float) -> None:
        """Begin a path whose planning has finished at ``t`` [s] (the targets of the keys, the
        controls and the goal dropped), or say in one line why it cannot be followed."""
        result = self._planner.take()
        if result is None:
            return
        if isinstance(result, Exception):
            self.follower.refuse(str(result))
            self.notice = str(result)
            return
        assert isinstance(result, FollowPlan)
        self.seeker = None
        self.teleop.release_all()
        self._set_twist[:] = 0.0
        self.notice = ""
        self.follower.begin(result, t)

    @property
    def planning(self) -> bool:
        """Whether a path is being planned."""
        return self._planner.busy

    @property
    def target(self) -> np.ndarray:
        """The twist asked for now: held keys' components, else the controls' twist (the goal
        seeker's is in :meth:`step`)."""
        keys = self.teleop.target
        return keys.copy() if np.any(keys) else self._set_twist.copy()

    def _seek(self, t: float) -> np.ndarray | None:
        """The goal seeker's twist at the odometry's pose; None without a goal (dropped once reached).
        The pose is the last step's: the twist acts from this step to the next, 1.5 steps later on
        average."""
        if self.seeker is None:
            return None
        twist = self.seeker.twist(self.pose, lead=1.5 * max(0.0, t - self.t))
        if twist is None:
            self.arrived = self.pose
            self.arrived_heading = self.seeker.controls_heading
            self.seeker = None
            return np.zeros(3)
        return twist

    def step(self, t: float) -> tuple[Snapshot, list[str]]:
        """Apply the inputs and run one control step at time ``t`` [s]; the snapshot and the page
        actions the caller handles (camera presets). An input that arrived between the last step
        and ``t`` (its :attr:`clock` time) gets a control step at its arrival first, so a loop that
        runs late does not delay what the input does; a simulated robot (:attr:`catch_up`) also gets
        the steps that a late loop missed, every :data:`CATCH_UP_STEP` s of simulated time."""
        actions: list[str] = []
        substeps = 0
        self._caught_up = 0
        for _ in range(self._inputs.qsize()):  # what is queued now; later inputs wait for the next step
            try:
                at, kind, value = self._inputs.get_nowait()
            except queue.Empty:
                break
            if at is not None and self.t + MIN_SUBSTEP < at < t and substeps < MAX_SUBSTEPS:
                self._catch_up(at)
                self._control(at)
                substeps += 1
            try:
                actions += self._apply_input(t if at is None else min(at, t), kind, value)
            except InputError as e:  # a page's input never stops the viewer: it is refused, and said
                self.notice = str(e)
        for source in [s for s, held in self._held.items() if held and t - self._heard[s] > KEY_SILENCE]:
            self._release(source)  # that page fell silent with a key held
        self._catch_up(t)
        return self._control(t), actions

    def _catch_up(self, until: float) -> None:
        """Control steps every :data:`CATCH_UP_STEP` s from the last one while ``until`` [s] is
        more than one and a half of them away (:attr:`catch_up` robots; at most :data:`MAX_CATCH_UP`
        per :meth:`step`)."""
        while self.catch_up and until - self.t > 1.5 * CATCH_UP_STEP and self._caught_up < MAX_CATCH_UP:
            self._control(self.t + CATCH_UP_STEP)
            self._caught_up += 1

    def _release(self, source) -> None:
        """Every key ``source`` (a page's key channel) holds, let go; the others' stay held."""
        released = False
        for action in self._held.pop(source, set()):
            released = self.teleop.release(action) or released
        self._heard.pop(source, None)
        if released:
            self._record("release")


class LiveRobot(PageRobot):
    """``robot`` simulated behind the page (module docstring): ``engine`` the
    :class:`~omnikin.simulation.engine.Engine` whose back-end moves it (default the kinematic
    engine without noise: the robot moves exactly as its wheels turn; a name becomes an engine in
    the argument parser, :func:`omnikin.physics.engines.engine_named`), ``limits`` and
    ``timeout`` [s] the runtime's command filter."""

    def __init__(
        self,
        robot: Robot,
        engine: Engine = KINEMATIC,
        *,
        speed: float = 0.2,
        turn: float = 0.5,
        limits: MotionLimits | None = None,
        timeout: float = 0.5,
    ):
        super().__init__(robot, speed=speed, turn=turn, limits=limits)
        self.engine = engine
        self.backend = engine.backend(robot)
        self.start = np.asarray(self.backend.start, dtype=float)  # the page's frame: where it started
        # simulated joints (physics) are read; the others follow the commands (kinematic)
        self._joints = self.backend.joints
        self.runtime = BaseRuntime(robot, self.backend, limits=self.limits, cmd_vel_timeout=timeout)
        self.can_steer = bool(robot.steerable)
        self.catch_up = True
        self.joints = JointMotion(robot, robot.rolling_names, self.description)  # castors, rollers
        self.slots = WheelSlots.of(robot, self.description, self.joints)
        self._angles = np.zeros(self.slots.count)
        self._moved = np.zeros(3)  # the twist the kinematic robot moved at since the last step
        self._speeds = np.zeros(self.slots.count)  # the kinematic wheels' speeds over the coming interval
        self._steer_hand = np.zeros(len(robot.steerable))
        self._last: StepResult | None = None

    @property
    def pose(self) -> tuple[float, float, float]:
        return triple(self.runtime.pose)

    def _turn_steering(self, angle: float) -> None:
        if not len(self._steer_hand) or np.any(self.target) or np.any(self.runtime.filter.current):
            return
        current = self._last.steer if self._last is not None and self._last.steer is not None else self._steer_hand
        self._steer_hand = np.asarray(current, dtype=float) + angle
        self.runtime.steer_to(self._steer_hand)

    @property
    def shown_pose(self) -> tuple[float, float, float]:
        return triple(self._seen(self.backend.truth))

    def _seen(self, pose) -> np.ndarray:
        """``pose`` (world frame) in the page's frame, the odometry's: from where the robot started."""
        return between(self.start, np.asarray(pose, dtype=float))

    @property
    def world(self) -> World | None:
        return self.engine.options.get("world")

    def obstacle_poses(self) -> np.ndarray | None:
        sim = getattr(self.backend, "sim", None)
        return None if sim is None or self.world is None else sim.obstacle_poses()

    def _control(self, t: float) -> Snapshot:
        """One control step at ``t`` [s] with the targets as they are (a path followed commands
        from the pose just measured)."""
        dt = max(0.0, t - self.t)
        self._start_planned(t)
        if self.follower.following:
            self.t = t
            state = self.runtime.sense(t)
            twist = self.follower.command(t, self.runtime.pose)
            target = np.zeros(3) if twist is None else twist  # (None: the end settled, brake)
            self.runtime.command(target, t)
            result = self.runtime.act(t, state)
        else:
            seeking = self._seek(t)
            target = self.target if seeking is None else seeking
            if np.any(target) or np.any(self.runtime.filter.target):
                self.runtime.command(target, t)
            self.t = t
            result = self.runtime.step(t)
        self._last = result
        fallen = self.backend.fallen
        if fallen and not self.fallen:  # the back-end stopped the wheels: say so once, drop the targets
            self.fallen = f"{fallen}; its wheels are stopped"
            self.seeker = None
            self.follower.stop("the robot tipped over")
            self.teleop.release_all()
            self._set_twist[:] = 0.0
            self.runtime.filter.halt()
            if self.tell is not None:
                self.tell(self.fallen)
        return self._snapshot(result, target, dt)

    def _snapshot(self, result: StepResult, target: np.ndarray, dt: float) -> Snapshot:
        slots = self.slots
        speeds = np.zeros(slots.count)
        steer = np.full(slots.count, np.nan)
        joints = self._joints
        if joints is not None:
            self._angles[slots.rolling] = joints.wheel_angles
            speeds[slots.rolling] = joints.wheel_speeds
            if len(slots.steered):
                steer[slots.steered] = joints.steer_angles
            moved = joints.twist
        else:
            moved = self._moved
            self._moved = np.asarray(result.command, dtype=float)
            self._angles += self._speeds * dt  # the speeds the wheels turned at since the last step
            speeds[slots.rolling] = result.wheel_speeds
            self._speeds = speeds
            if len(slots.steered) and result.steer is not None:
                steer[slots.steered] = result.steer
        self.joints.update(result.t, moved, result.state.steer)
        if len(slots.castors):
            self._angles[slots.castors] = self.joints.castor_angles
            steer[slots.castors] = self.joints.castor_swivels
        rollers, roller_speeds = slots.rollers(self.joints.roller_angles, self.joints.roller_rates)
        return Snapshot(
            t=result.t,
            truth=triple(self._seen(self.backend.truth)),
            odometry=triple(result.pose),
            twist=triple(result.twist),
            command=triple(result.command),
            target=triple(target),
            wheel_angles=self._angles.copy(),
            wheel_speeds=speeds,
            steer=steer,
            residual=tuple(float(v) for v in result.residual),
            roller_angles=rollers,
            roller_speeds=roller_speeds,
        )

    def close(self) -> None:
        self.backend.close()
