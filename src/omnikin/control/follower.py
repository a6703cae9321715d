"""Following a path that arrives while the robot runs: the ROS node's ``plan``, the viewer's
waypoints (:class:`PathFollower`).

A path arrives as waypoints ``(x, y, theta)`` in the frame of the robot's odometry, and is made
into a trajectory from where the robot is (:func:`plan_follow`):

- consecutive waypoints less than :data:`MERGE` apart are one (the later one's heading kept);
- when the first waypoint is more than :data:`JOIN` from the robot, the path starts at the
  robot's pose and goes to it first;
- the waypoints become a smooth curve through them (``smooth``; a planner's dense path), or
  straight segments with corners cut by arcs (``blend``) or stopped at;
- the heading is the waypoints' own (``given``), or :data:`~omnikin.control.path.HEADINGS`;
  a layout with fixed wheels follows the tangent whatever is asked, the only heading it can
  hold;
- the timing is the fastest within :data:`MARGIN` of the wheels' limits and the body's (the
  runtime's command filter's: :func:`~omnikin.control.time_optimal.body_rows`), from rest to
  rest;
- the controller is :func:`~omnikin.control.controllers.build_controller`'s.

:class:`PathFollower` then gives, at each control tick, the twist for the pose the robot has,
until the trajectory has ended and :data:`SETTLE` seconds more have passed; it keeps the
tracking error for reports (the pose's distance to the reference point and to the path, its
heading error). It is a state machine without threads or clocks: the caller passes the time
(any clock, seconds) and plans where it likes (the ROS node on a worker thread).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..common.messages import shorten
from ..errors import InputError
from ..kinematics.robot import Robot
from ..kinematics.se2 import wrap_angle
from ..motion.limits import MotionLimits
from .controllers import Controller, build_controller
from .path import HEADINGS, polyline, spline
from .time_optimal import WheelLimits
from .trajectory import Trajectory, plan_trajectory

MERGE = 1e-3
"""Consecutive waypoints closer than this [m] are one waypoint."""
JOIN = 0.01
"""A path whose first waypoint is farther than this [m] from the robot starts at the robot."""
SETTLE = 1.0
"""Time [s] the controller holds the path's end after the trajectory ends."""
MARGIN = 0.95
"""The trajectory is timed within this share of every limit, the wheels' and the body's: the rest
is the controller's, to correct the pose. A reference at the limits themselves leaves it none
(a robot one control tick late on a reference at full speed stays late, overshoots the stops
and, the command filter holding it, oscillates about them: on an L-shaped path of two 1 m legs
in the kinematic engine it strayed 80 mm from the path and ended 53 mm from its end, where with
the margin it ends on the path to the micrometre)."""
MAX_WAYPOINTS = 100_000
"""Most waypoints a path may have (a planner's path of 1 km at 1 cm)."""
MAX_LENGTH = 200.0
"""Longest path [m] followed (waypoints to waypoints): its timing takes some 3 s of one core and
bounded memory; a longer one is refused (send it in parts)."""
START_HEADING = 0.1
"""Largest difference [rad] between a robot with fixed wheels' heading and the direction in which
a path leaves it: such a robot cannot turn onto a path that leaves sideways or backwards."""
FOLLOW_HEADINGS = ("given", *HEADINGS)
"""How a followed path's heading is set: the waypoints' own, or a :data:`~omnikin.control.path.HEADINGS` mode."""


@dataclass(frozen=True, eq=False)
class FollowPlan:
    """A path made ready to follow (:func:`plan_follow`).

    Attributes
    ----------
    trajectory : Trajectory
        The timed reference, in the odometry's frame, from the robot's pose when it was planned.
    controller : Controller
        The controller that tracks it.
    name : str
        What the path is called in reports.
    waypoints : int
        The waypoints received.
    """

    trajectory: Trajectory
    controller: Controller
    name: str
    waypoints: int


def waypoint_array(waypoints, name: str) -> np.ndarray:
    """Waypoints ``(n, 2)`` or ``(n, 3)`` [m, m, rad] as a float array ``(n, 3)`` (heading 0 where
    none is given), at most :data:`MAX_WAYPOINTS`; one line naming the path for anything else."""
    try:
        w = np.asarray(waypoints, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"path {name!r}: waypoints are not numbers ({shorten(str(exc))})") from None
    if w.ndim != 2 or w.shape[1] not in (2, 3):
        raise InputError(f"path {name!r}: waypoints must be rows of (x, y) or (x, y, theta), got shape {w.shape}")
    if len(w) == 0:
        raise InputError(f"path {name!r}: no waypoints")
    if len(w) > MAX_WAYPOINTS:
        raise InputError(f"path {name!r}: {len(w)} waypoints, more than {MAX_WAYPOINTS}")
    bad = np.flatnonzero(~np.all(np.isfinite(w), axis=1))
    if bad.size:
        raise InputError(f"path {name!r}: waypoint {int(bad[0])} is not finite")
    if w.shape[1] == 2:
        w = np.column_stack((w, np.zeros(len(w))))
    return w


def plan_follow(
    robot: Robot,
    waypoints,
    pose,
    *,
    limits: WheelLimits | None = None,
    body: MotionLimits | None = None,
    controller: str | None = None,
    heading: str = "given",
    smooth: bool = True,
    blend: float = 0.0,
    rate: float = 50.0,
    name: str = "plan",
) -> FollowPlan:
    """The trajectory and controller that follow ``waypoints`` from ``pose`` (module docstring).

    Parameters
    ----------
    robot : Robot
        The robot (the controller's and the timing's model).
    waypoints : array_like, shape (n, 2) or (n, 3)
        ``(x, y[, theta])`` [m, m, rad] in the odometry's frame, ``1 <= n <=`` :data:`MAX_WAYPOINTS`.
    pose : array_like, shape (3,)
        The robot's pose ``(x, y, theta)`` [m, m, rad] now, same frame.
    limits : WheelLimits, optional
        The wheels' limits (the trajectory is timed within :data:`MARGIN` of them); default none
        beyond the body's ``wheel`` and each wheel's ``max_speed`` (a runtime's own).
    body : MotionLimits, optional
        The body's limits (the runtime's command filter's; the same margin).
    controller : str, optional
        :data:`~omnikin.control.controllers.CONTROLLERS`; default by layout.
    heading : str, default "given"
        :data:`FOLLOW_HEADINGS` (a layout with fixed wheels: tangent, whatever is asked).
    smooth : bool, default True
        A smooth curve through the waypoints; else straight segments.
    blend : float, default 0
        Not ``smooth``: radius [m] of the arcs that cut the corners (0: stop at them).
    rate : float, default 50
        Control rate [Hz].
    name : str
        What the path is called in messages.

    Raises
    ------
    InputError
        Bad waypoints, a path that does not go anywhere or that the robot cannot drive, a bad
        option: one line naming the path.
    """
    if heading not in FOLLOW_HEADINGS:
        raise InputError(f"heading must be one of {', '.join(FOLLOW_HEADINGS)}, got {shorten(heading)}")
    w = waypoint_array(waypoints, name)
    here = np.asarray(pose, dtype=float).reshape(3)
    if math.hypot(w[0, 0] - here[0], w[0, 1] - here[1]) > JOIN:
        w = np.vstack((here, w))
    else:
        w[0, :2] = here[:2]  # (the robot is where the path starts, to the centimetre)
    merged = [w[0].copy()]
    for row in w[1:]:  # consecutive waypoints within MERGE: one, with the later one's heading
        if math.hypot(row[0] - merged[-1][0], row[1] - merged[-1][1]) < MERGE:
            merged[-1][2] = row[2]
        else:
            merged.append(row.copy())
    w = np.array(merged)
    if len(w) < 2:
        raise InputError(
            f"path {name!r}: it does not go anywhere (every waypoint within {MERGE * 1e3:g} mm of the robot)"
        )
    steps = np.hypot(*np.diff(w[:, :2], axis=0).T)
    if float(steps.sum()) > MAX_LENGTH:
        raise InputError(
            f"path {name!r}: {float(steps.sum()):.6g} m of waypoints, longer than {MAX_LENGTH:g} m: send it in parts"
        )
    pursuit = controller == "pursuit" or (controller is None and robot.fixed and robot.steerable)
    mode = "tangent" if robot.fixed or pursuit else heading
    options: dict = {"name": name}
    if mode == "given":
        options["theta"] = w[:, 2]
    else:
        options["heading"] = mode
    if smooth:  # (a robot with fixed wheels leaves along its heading)
        path = spline(w[:, :2], start_direction=here[2] if robot.fixed else None, **options)
    else:
        path = polyline(w[:, :2], blend=blend, **options)
    if robot.fixed:  # it can only start along its heading
        off = float(wrap_angle(path.pose[0, 2] - here[2]))
        if abs(off) > START_HEADING:
            raise InputError(
                f"path {name!r} leaves the robot at {math.degrees(path.pose[0, 2]):.0f} deg, but robot {robot.name!r} "
                f"faces {math.degrees(here[2]):.0f} deg and has fixed wheels: it cannot turn onto the path there "
                "(turn it first, or start the path along its heading)"
            )
    limits = WheelLimits(speed=math.inf, accel=math.inf) if limits is None else limits
    inner = WheelLimits(speed=MARGIN * limits.speed, accel=MARGIN * limits.accel, steer_rate=limits.steer_rate)
    if body is not None:
        body = MotionLimits(
            **{
                name: None if getattr(body, name) is None else MARGIN * getattr(body, name)
                for name in ("linear", "angular", "linear_accel", "angular_accel", "wheel")
            }
        )
    trajectory = plan_trajectory(robot, path, inner, body)
    law = build_controller(controller, robot, trajectory, rate=rate)
    return FollowPlan(trajectory, law, name, len(waypoints))


class PathFollower:
    """The state of following one path at a time (module docstring).

    ``state`` is ``idle`` (no path yet), ``following``, ``done`` (the trajectory ended and
    settled), ``stopped`` (:meth:`stop`: a command, an empty path) or ``refused`` (:meth:`refuse`:
    a path that could not be followed); ``note`` says what stopped or refused it.
    """

    def __init__(self, settle: float = SETTLE):
        self.settle = float(settle)
        self.plan: FollowPlan | None = None
        self.state = "idle"
        self.note = ""
        self.start = 0.0
        self.elapsed = 0.0
        self.reference = np.zeros(3)
        self._tree = None
        self._reset_errors()

    def _reset_errors(self) -> None:
        self.error = math.nan  # [m] the pose's distance to the reference point, last tick
        self.distance = math.nan  # [m] the pose's distance to the path, last tick
        self.heading_error = math.nan  # [rad] against the path's heading at the nearest sample
        self.max_distance = 0.0
        self._sum2 = 0.0
        self.ticks = 0

    @property
    def following(self) -> bool:
        """Whether a path is being followed."""
        return self.state == "following"

    @property
    def rms_distance(self) -> float:
        """RMS [m] of the distance to the path over the ticks of the path followed (NaN before any)."""
        return math.sqrt(self._sum2 / self.ticks) if self.ticks else math.nan

    def begin(self, plan: FollowPlan, t: float) -> None:
        """Follow ``plan`` from time ``t`` [s] (the trajectory's time 0)."""
        from scipy.spatial import cKDTree

        self.plan = plan
        self.start = float(t)
        self.elapsed = 0.0
        self.state = "following"
        self.note = ""
        self.reference = plan.trajectory.path.pose[0].copy()
        self._tree = cKDTree(plan.trajectory.path.pose[:, :2])
        self._reset_errors()

    def stop(self, why: str) -> bool:
        """Stop following (``why``: what stopped it); True if a path was being followed."""
        if not self.following:
            return False
        self.state, self.note = "stopped", why
        return True

    def drop(self, why: str) -> None:
        """A path being planned was dropped before it was followed (``why``)."""
        self.state, self.note = "stopped", why

    def refuse(self, why: str) -> bool:
        """A path could not be followed (``why``, one line): no path is followed from now; True if
        one was being followed (the caller stops the robot)."""
        was = self.following
        self.state, self.note, self.plan = "refused", why, None
        return was

    def command(self, t: float, pose) -> np.ndarray | None:
        """The body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] for the robot at ``pose``
        ``(x, y, theta)`` [m, m, rad] at time ``t`` [s] (the clock of :meth:`begin`); None when no
        path is being followed (from the tick after the end on: ``state`` becomes ``done``, and
        the caller stops the robot)."""
        if not self.following or self.plan is None:
            return None
        trajectory = self.plan.trajectory
        self.elapsed = max(0.0, float(t) - self.start)
        if self.elapsed > trajectory.duration + self.settle:
            self.state = "done"
            return None
        p = np.asarray(pose, dtype=float)
        ref, _, _ = trajectory.at(min(self.elapsed, trajectory.duration))
        self.reference = ref
        self.error = math.hypot(p[0] - ref[0], p[1] - ref[1])
        self.distance, self.heading_error = self._off_path(p)
        self.max_distance = max(self.max_distance, self.distance)
        self._sum2 += self.distance**2
        self.ticks += 1
        return np.asarray(self.plan.controller.command(self.elapsed, p), dtype=float)

    def _off_path(self, p: np.ndarray) -> tuple[float, float]:
        """The distance [m] of ``p`` to the polyline through the path's samples (the segments on
        either side of the nearest sample: exact, the samples being 2 mm apart on a path that
        does not come back within a millimetre of itself) and its heading error [rad] against
        the path's heading there."""
        assert self._tree is not None and self.plan is not None
        samples = self.plan.trajectory.path.pose
        _, k = self._tree.query(p[:2])
        best, heading = math.inf, 0.0
        for a in (k - 1, k):
            if 0 <= a < len(samples) - 1:
                seg = samples[a + 1, :2] - samples[a, :2]
                rel = p[:2] - samples[a, :2]
                f = min(max(float(rel @ seg) / max(float(seg @ seg), 1e-300), 0.0), 1.0)
                d = math.hypot(rel[0] - f * seg[0], rel[1] - f * seg[1])
                if d < best:
                    best = d
                    heading = float(wrap_angle(p[2] - (samples[a, 2] + f * (samples[a + 1, 2] - samples[a, 2]))))
        return best, heading

    def values(self) -> list[tuple[str, str]]:
        """What a report shows, as ``(key, value)`` text pairs: the state, what stopped or refused
        a path, and of the path followed last its size, the time along it, the reference point
        and the tracking errors (of the last tick; the largest and RMS distance to the path over
        its ticks)."""
        out = [("path_state", self.state)]
        if self.note:
            out.append(("path_note", self.note))
        if self.plan is not None:
            trajectory = self.plan.trajectory
            out += [
                ("path_name", self.plan.name),
                ("path_waypoints", str(self.plan.waypoints)),
                ("path_length_m", f"{float(trajectory.path.s[-1]):.6g}"),
                ("path_duration_s", f"{trajectory.duration:.6g}"),
                ("path_elapsed_s", f"{min(self.elapsed, trajectory.duration + self.settle):.6g}"),
                ("reference_x_m", f"{self.reference[0]:.6g}"),
                ("reference_y_m", f"{self.reference[1]:.6g}"),
                ("reference_theta_rad", f"{self.reference[2]:.6g}"),
                ("error_to_reference_m", f"{self.error:.6g}"),
                ("distance_to_path_m", f"{self.distance:.6g}"),
                ("heading_error_rad", f"{self.heading_error:.6g}"),
                ("max_distance_to_path_m", f"{self.max_distance:.6g}"),
                ("rms_distance_to_path_m", f"{self.rms_distance:.6g}"),
            ]
        return out

    def summary(self) -> str:
        """One line: what the follower is doing."""
        if self.state == "refused":
            return f"path refused: {self.note}"
        if self.plan is None or (self.state == "stopped" and self.note.endswith("while the path was planned")):
            return "no path yet" if self.state == "idle" else f"path dropped: {self.note}"
        trajectory = self.plan.trajectory
        head = f"path {self.plan.name!r} ({float(trajectory.path.s[-1]):.3g} m in {trajectory.duration:.3g} s)"
        if self.state == "following":
            off = "" if math.isnan(self.distance) else f", {self.distance * 1e3:.3g} mm from the path"
            return f"following {head}: {min(self.elapsed, trajectory.duration):.3g} s along{off}"
        if self.state == "done":
            return f"done {head}: at most {self.max_distance * 1e3:.3g} mm from the path"
        return f"stopped {head}: {self.note}"


class PlanWorker:
    """Plans paths on a thread of its own, one at a time, the latest request winning: a request
    made while another is planned supersedes it (its result is dropped), and :meth:`cancel` drops
    both. The thread is a daemon: a program that stops does not wait for a plan.

    ``job`` is called on the worker thread with the keyword arguments of :meth:`request` and
    returns a :class:`FollowPlan` (or raises: an :class:`~omnikin.errors.OmnikinError` is the
    result; anything else becomes an :class:`~omnikin.errors.InputError` naming it)."""

    def __init__(self, job):
        import threading

        self._job = job
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._generation = 0
        self._request: tuple[int, dict] | None = None
        self._result: tuple[int, object] | None = None
        self._thread = threading.Thread(target=self._run, name="omnikin-plan", daemon=True)
        self._thread.start()

    @property
    def busy(self) -> bool:
        """Whether a request is waiting or being planned."""
        with self._lock:
            return self._request is not None or self._planning

    _planning = False

    def request(self, **kwargs) -> None:
        """Plan with ``kwargs`` (superseding any request before)."""
        with self._lock:
            self._generation += 1
            self._request = (self._generation, kwargs)
            self._result = None
        self._wake.set()

    def cancel(self) -> bool:
        """Drop the request waiting or being planned, and a result not taken; True if there was one."""
        with self._lock:
            had = self._request is not None or self._planning or self._result is not None
            self._generation += 1
            self._request = None
            self._result = None
        return had

    def take(self):
        """The result of the latest request once it is planned (a :class:`FollowPlan` or the
        exception that refused it), once; None before (or when there is none)."""
        with self._lock:
            if self._result is None or self._result[0] != self._generation:
                return None
            result, self._result = self._result[1], None
            return result

    def current(self, generation: int) -> bool:
        """Whether ``generation`` is still the latest request (a job may stop early when not)."""
        return generation == self._generation

    def _run(self) -> None:
        from ..errors import OmnikinError

        while True:
            self._wake.wait()
            with self._lock:
                self._wake.clear()
                if self._request is None:
                    continue
                generation, kwargs = self._request
                self._request = None
                self._planning = True
            result: object
            try:
                result = self._job(generation=generation, **kwargs)
            except OmnikinError as exc:
                result = exc
            except Exception as exc:  # (a bug: reported as the request's refusal, the thread lives on)
                result = InputError(f"planning failed ({type(exc).__name__}: {shorten(str(exc))}); a bug in omnikin")
            with self._lock:
                self._planning = False
                if generation == self._generation:
                    self._result = (generation, result)
