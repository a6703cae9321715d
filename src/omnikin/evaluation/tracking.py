"""A controller tracking a trajectory in an engine, through the runtime (:func:`track`), and how
well it did (:func:`tracking_errors`).

Every control tick ``t_k = k / rate`` the runtime reads the wheels and updates its odometry
(:meth:`~omnikin.runtime.base.BaseRuntime.sense`); the controller computes a body twist from that
pose (the pose the robot has, as on a real robot, not the truth) and offers it to the runtime,
whose command filter saturates it to the wheels' speed limit keeping its direction; the runtime
commands the wheels (:meth:`~omnikin.runtime.base.BaseRuntime.act`), which the engine's back-end
holds until the next tick. After the reference ends the controller holds its last pose for
``settle`` seconds. Time is simulated: nothing here waits on the wall clock.

The errors are the ground truth's distance to the *path* (the nearest point of its samples,
2 mm apart), not to the moving reference point: a robot on the path but late is on the path.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np

from ..control.controllers import Controller
from ..control.trajectory import Trajectory, control_period
from ..errors import InputError
from ..kinematics.robot import Robot
from ..kinematics.se2 import between, wrap_angle
from ..motion.limits import MotionLimits
from ..runtime.base import BaseRuntime
from ..simulation.engine import Engine, KinematicEngine
from ..world.collision import Contact


@dataclass(frozen=True, kw_only=True)
class TrackingRun:
    """One tracked trajectory, sampled at the control ticks ``(n,)``.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Tick times [s].
    truth, odometry, reference : ndarray, shape (n, 3)
        The true pose, the runtime's odometry and the reference pose ``(x, y, theta)``
        [m, m, rad], in the frame where the robot started (that of its odometry).
    command : ndarray, shape (n, 3)
        The controller's body twist [m/s, m/s, rad/s].
    wheel_speeds : ndarray, shape (n, n_wheels)
        The wheel speeds commanded [rad/s] after the runtime's saturation.
    wheel_angles : ndarray, shape (n, n_encoded)
        The encoded wheels' angles the runtime read [rad] (the encoder counts times the
        nominal robot's angle per tick, in ``robot.encoded_names`` order).
    steer : ndarray, shape (n, n_steer), or None
        The steering angles the runtime read [rad] (None for a robot without steered wheels).
    saturated : int
        Commands the runtime scaled down to the wheel limit.
    solve_time : ndarray, shape (n,)
        Wall time [s] of each controller call (a pace of the machine: for reports, never for
        assertions).
    contacts : tuple of Contact
        Where the robot began to touch a body of the engine's world (world frame; empty on an
        empty floor).
    """

    t: np.ndarray
    truth: np.ndarray
    odometry: np.ndarray
    reference: np.ndarray
    command: np.ndarray
    wheel_speeds: np.ndarray
    wheel_angles: np.ndarray
    steer: np.ndarray | None
    saturated: int
    solve_time: np.ndarray
    contacts: tuple[Contact, ...] = ()


def track(
    robot: Robot,
    trajectory: Trajectory,
    controller: Controller,
    *,
    engine: Engine | None = None,
    true_robot: Robot | None = None,
    rate: float = 50.0,
    noise=None,
    rng=None,
    settle: float = 1.0,
) -> TrackingRun:
    """Drive ``controller`` along ``trajectory`` in ``engine`` (module docstring).

    Parameters
    ----------
    robot : Robot
        The nominal robot: the runtime's model (inverse kinematics, odometry).
    trajectory : Trajectory
        The timed reference; its wheel speed limit and body limits are the runtime's.
    controller : Controller
        Gives the body twist at each tick.
    engine : Engine, optional
        Default the kinematic engine.
    true_robot : Robot, optional
        The robot as built (default ``robot``).
    rate : float
        Control rate [Hz].
    noise : NoiseModel, optional
        The kinematic engine's wheel slip (None: none).
    rng : numpy.random.Generator, int or None
        The slip's random stream.
    settle : float
        Time [s] the last pose is held after the reference ends.

    Returns
    -------
    TrackingRun
    """
    engine = KinematicEngine() if engine is None else engine
    control_period(rate)
    if not (isinstance(settle, (int, float)) and math.isfinite(settle) and 0 <= settle <= 3600):
        raise InputError(f"settle must be in [0, 3600] s, got {settle!r}")
    backend = engine.backend(robot, true_robot, noise=noise, rng=rng)
    wheel = trajectory.limits.speed
    body = trajectory.body or MotionLimits(linear=None, angular=None, linear_accel=None, angular_accel=None)
    limits = dataclasses.replace(body, wheel=min(wheel, body.wheel or math.inf) if math.isfinite(wheel) else body.wheel)
    runtime = BaseRuntime(robot, backend, limits=limits, cmd_vel_timeout=0.0)
    n = int(math.floor((trajectory.duration + settle) * rate + 1e-9)) + 1
    t = np.arange(n) / rate
    truth = np.empty((n, 3))
    odometry = np.empty((n, 3))
    command = np.empty((n, 3))
    speeds = np.empty((n, len(robot.rolling)))
    angles = np.empty((n, len(robot.encoded_names)))
    steer = np.empty((n, len(robot.steerable))) if robot.steerable else None
    solve = np.empty(n)
    try:
        for k in range(n):
            state = runtime.sense(float(t[k]))
            pose = runtime.pose
            start = time.perf_counter()
            twist = np.asarray(controller.command(float(t[k]), pose), dtype=float)
            solve[k] = time.perf_counter() - start
            runtime.command(twist, float(t[k]))
            step = runtime.act(float(t[k]), state)
            truth[k] = between(backend.start, backend.truth)  # from where it started, as the odometry
            odometry[k] = pose
            command[k] = twist
            speeds[k] = step.wheel_speeds
            angles[k] = state.positions
            if steer is not None:
                steer[k] = state.steer
        contacts = tuple(backend.contacts)
    finally:
        backend.close()
    reference, _, _ = trajectory.at(t)
    return TrackingRun(
        t=t,
        truth=truth,
        odometry=odometry,
        reference=reference,
        command=command,
        wheel_speeds=speeds,
        wheel_angles=angles,
        steer=steer,
        saturated=runtime.filter.stats.saturated,
        solve_time=solve,
        contacts=contacts,
    )


PATH_TIE = 1e-3
"""Path points this much [m] farther than the nearest still count as nearest for the heading
error: a turn in place puts many headings at one position, and a closed path its start and
end."""


def distance_to_path(poses: np.ndarray, path: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance [m] of each pose's position ``(n, 3)`` to the polyline through the path's samples
    ``(m, 3)``, and its heading error [rad] against the path's heading at the foot: the smallest
    ``|wrap(theta - theta_path)|`` among the segments within :data:`PATH_TIE` of the nearest,
    signed.

    The segments looked at are those next to the samples within ``d0 + longest segment +``
    :data:`PATH_TIE` of the point (``d0`` its distance to the nearest sample, by a k-d tree):
    every segment that can hold the foot, in time ``O(n log m)`` and memory ``O(n + m)``."""
    from scipy.spatial import cKDTree

    xy = path[:, :2]
    seg = np.diff(xy, axis=0)
    length2 = np.maximum(np.einsum("ij,ij->i", seg, seg), 1e-300)
    turn = np.diff(path[:, 2])
    tree = cKDTree(xy)
    d0, _ = tree.query(poses[:, :2])
    reach = d0 + float(np.sqrt(length2.max())) + PATH_TIE
    dist = np.empty(len(poses))
    heading = np.empty(len(poses))
    last = len(seg) - 1
    for i, near in enumerate(tree.query_ball_point(poses[:, :2], reach)):
        idx = np.asarray(near, dtype=int)
        k = np.unique(np.clip(np.concatenate((idx - 1, idx)), 0, last))
        rel = poses[i, :2] - xy[k]
        f = np.clip(np.einsum("ij,ij->i", rel, seg[k]) / length2[k], 0.0, 1.0)
        d = np.hypot(rel[:, 0] - f * seg[k, 0], rel[:, 1] - f * seg[k, 1])
        best = d.min()
        err = wrap_angle(poses[i, 2] - (path[k, 2] + f * turn[k]))
        err = np.where(d <= best + PATH_TIE, err, np.inf)
        dist[i] = best
        heading[i] = err[np.argmin(np.abs(err))]
    return dist, heading


def tracking_errors(run: TrackingRun, trajectory: Trajectory) -> dict[str, float]:
    """The truth's distance to the path [m] (RMS and largest) and its heading error against the
    path's heading at the nearest sample [rad] (RMS), over every tick."""
    dist, heading = distance_to_path(run.truth, trajectory.path.pose)
    return {
        "rms_error_m": float(np.sqrt(np.mean(dist**2))),
        "max_error_m": float(np.max(dist)),
        "rms_heading_error_rad": float(np.sqrt(np.mean(heading**2))),
    }
