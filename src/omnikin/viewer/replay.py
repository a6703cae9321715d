"""Replay: recorded runs as the viewer shows them, at any time of the run (pure data, no page).

A :class:`Track` is one recorded run: the true poses and the odometry poses, each a
:class:`PoseSeries` on its own times [s] (a report's ``run_poses.csv`` shares them, a bag's
topics need not), and optionally the measured joints (:class:`JointSeries`: a bag's
``joint_states``). Times count from the track's start (0).

Between two samples ``k`` and ``k + 1`` of a pose series the robot moves with the constant
body twist ``xi_k = log(P_k^-1 P_{k+1}) / (t_{k+1} - t_k)`` (the finite difference on SE(2),
the motion of one sample of the simulation), so the pose at ``t`` is the closed form
``P(t) = P_k exp((t - t_k) xi_k)`` (:func:`omnikin.kinematics.se2.exp`: a straight line for
``omega = 0``, an arc otherwise); at a sample time it is the sample. Before the first sample
the pose is the first, after the last the last (the robot at rest).

:class:`TrackReplay` turns a track into the :class:`~omnikin.viewer.live.Snapshot` the page
shows at time ``t``: the interpolated poses, the true twist ``xi_k`` of the interval holding
``t`` (the interval that starts at ``t`` at a sample time; zero outside the run), and the
wheels: per interval the robot's inverse kinematics of ``xi_k`` (:meth:`omnikin.kinematics.robot.Robot.ik`,
wheel speeds and steering angles; steering held through an interval at rest), the wheel angles
their integral from 0; castors (swivel and roll) and the rollers of Swedish wheels as the body's
motion moves them (:class:`~omnikin.physics.joint_motion.JointMotion`, as on the live page),
interval after interval, linear in time within one; measured joints, when the track has them,
replace those of the wheels they name (angles and steering interpolated linearly in time,
speeds their finite differences).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..errors import InputError
from ..kinematics.robot import Robot
from ..kinematics.se2 import between, compose, exp, log
from ..physics.description import PhysicalRobot
from ..physics.joint_motion import JointMotion
from .live import Snapshot, WheelSlots, triple

REST = 1e-12
"""Twist norm [m/s, rad/s] below which an interval is at rest (its steering held)."""


def _interval(t: np.ndarray, at: float) -> int:
    """The interval ``k`` with ``t[k] <= at < t[k + 1]`` (the last at the last sample), or -1
    before the first sample and ``len(t) - 1`` after the last."""
    if at < t[0]:
        return -1
    if at > t[-1]:
        return len(t) - 1
    return min(int(np.searchsorted(t, at, side="right")) - 1, len(t) - 2)


@dataclass(frozen=True)
class PoseSeries:
    """Poses ``(n, 3)`` [m, m, rad] at times ``t`` ``(n,)`` [s], strictly increasing, ``n >= 2``."""

    t: np.ndarray
    poses: np.ndarray

    def __post_init__(self):
        t = np.asarray(self.t, dtype=float)
        p = np.asarray(self.poses, dtype=float).reshape(-1, 3)
        if len(t) < 2 or len(t) != len(p):
            raise InputError(f"a pose series needs two samples or more, one pose per time; got {len(t)} and {len(p)}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(p))):
            raise InputError("a pose series holds a non-finite time or pose")
        if np.any(np.diff(t) <= 0):
            k = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1
            raise InputError(f"pose series: time {t[k]:g} s of sample {k} does not follow {t[k - 1]:g} s")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "poses", p)

    @cached_property
    def twists(self) -> np.ndarray:
        """``(n - 1, 3)``: the body twist ``xi_k`` of each interval [m/s, m/s, rad/s]."""
        return log(between(self.poses[:-1], self.poses[1:])) / np.diff(self.t)[:, None]

    def at(self, time: float) -> np.ndarray:
        """The pose at ``time`` [s] (module docstring), heading in ``[-pi, pi)``."""
        k = _interval(self.t, time)
        if k < 0:
            return compose(self.poses[0], np.zeros(3))
        if k >= len(self.t) - 1:
            return compose(self.poses[-1], np.zeros(3))
        return compose(self.poses[k], exp((time - self.t[k]) * self.twists[k]))

    def twist(self, time: float) -> np.ndarray:
        """The body twist of the interval holding ``time`` (zero outside the series)."""
        k = _interval(self.t, time)
        if k < 0 or k >= len(self.t) - 1:
            return np.zeros(3)
        return self.twists[k].copy()


@dataclass(frozen=True)
class JointSeries:
    """Measured joints at times ``t`` ``(n,)`` [s]: ``angles`` ``(n, len(wheels))`` [rad] of
    the wheels named ``wheels``, ``steer`` ``(n, len(steered))`` [rad] of the wheels named
    ``steered`` (relative to their mounting drive direction)."""

    t: np.ndarray
    wheels: tuple[str, ...]
    angles: np.ndarray
    steered: tuple[str, ...] = ()
    steer: np.ndarray | None = None

    def values(self, time: float) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Angles, speeds (finite difference of the interval holding ``time``, zero outside)
        and steering at ``time``, interpolated linearly."""
        t = self.t
        k = _interval(t, time)
        if k < 0 or k >= len(t) - 1:
            row = 0 if k < 0 else len(t) - 1
            steer = None if self.steer is None else self.steer[row].copy()
            return self.angles[row].copy(), np.zeros(len(self.wheels)), steer
        s = (time - t[k]) / (t[k + 1] - t[k])
        rate = (self.angles[k + 1] - self.angles[k]) / (t[k + 1] - t[k])
        angles = self.angles[k] + s * (self.angles[k + 1] - self.angles[k])
        steer = None if self.steer is None else self.steer[k] + s * (self.steer[k + 1] - self.steer[k])
        return angles, rate, steer


@dataclass(frozen=True)
class Track:
    """One recorded run (module docstring); ``name`` is how the page lists it; ``missing``: the
    pose series the recording lacks (``"truth"``, ``"odometry"``: the other one stands in for
    it); ``robot``: the robot that drove it (None: the replay source's)."""

    name: str
    truth: PoseSeries
    odometry: PoseSeries
    joints: JointSeries | None = None
    missing: tuple[str, ...] = ()
    robot: Robot | None = None

    @property
    def duration(self) -> float:
        """The last time of any series [s]."""
        ends = [self.truth.t[-1], self.odometry.t[-1]] + ([self.joints.t[-1]] if self.joints is not None else [])
        return float(max(ends))


class TrackReplay:
    """``track`` of ``robot`` (drawn from ``description``) as :class:`Snapshot` s (module
    docstring); the wheel arrays follow ``description.wheels`` (castors: zero)."""

    def __init__(self, robot: Robot, description: PhysicalRobot, track: Track):
        self.robot = robot
        self.track = track
        names = [w.name for w in description.wheels]
        joint_motion = JointMotion(robot, robot.rolling_names, description)
        self.slots = WheelSlots.of(robot, description, joint_motion)
        truth = track.truth
        ik = robot.ik(truth.twists, on_infeasible="return")
        self._speeds = np.asarray(ik.wheel_speeds, dtype=float).reshape(len(truth.twists), -1)
        steer = np.asarray(ik.steer_angles, dtype=float).reshape(len(truth.twists), -1)
        moving = np.linalg.norm(truth.twists, axis=1) > REST
        held = np.zeros(steer.shape[1])
        for k in range(len(steer)):  # an interval at rest keeps the steering it had
            if moving[k]:
                held = steer[k]
            else:
                steer[k] = held
        self._steer = steer
        self._angles = np.zeros((len(truth.t), self._speeds.shape[1]))
        np.cumsum(self._speeds * np.diff(truth.t)[:, None], axis=0, out=self._angles[1:])
        self._passive(joint_motion, truth, steer)
        joints = track.joints
        self._joint_rolling = (
            np.array([names.index(n) for n in joints.wheels], dtype=int) if joints is not None else None
        )
        self._joint_steered = (
            np.array([names.index(n) for n in joints.steered], dtype=int) if joints is not None else None
        )

    def _passive(self, joints: JointMotion, truth: PoseSeries, steer: np.ndarray) -> None:
        """Castors and rollers at every sample, as the body's motion moves them (``joints``, the
        live viewer's rule), interval after interval."""
        castors, swedish = len(self.slots.castors), len(self.slots.swedish)
        n = len(truth.t)
        self._swivel = np.zeros((n, castors))
        self._castor_angle = np.zeros((n, castors))
        self._roller_angle = np.zeros((n, swedish))
        self._roller_rate = np.zeros((max(n - 1, 1), swedish))
        if not castors and not swedish:
            return
        joints.update(float(truth.t[0]), np.zeros(3), steer[0] if steer.size else None)
        self._swivel[0] = joints.castor_swivels
        for k in range(n - 1):
            joints.update(float(truth.t[k + 1]), truth.twists[k], steer[k] if steer.size else None)
            self._swivel[k + 1] = joints.castor_swivels
            self._castor_angle[k + 1] = joints.castor_angles
            self._roller_angle[k + 1] = joints.roller_angles
            self._roller_rate[k] = joints.roller_rates

    @property
    def duration(self) -> float:
        return self.track.duration

    def snapshot(self, time: float) -> Snapshot:
        """What the page shows at ``time`` [s]."""
        truth = self.track.truth
        slots = self.slots
        k = _interval(truth.t, time)
        n_int = len(truth.t) - 1
        angles = np.zeros(slots.count)
        speeds = np.zeros(slots.count)
        steer = np.full(slots.count, math.nan)
        if k < 0:
            kinematic_angles, kinematic_speeds, kinematic_steer = self._angles[0], 0.0, self._steer[0]
        elif k >= n_int:
            kinematic_angles, kinematic_speeds, kinematic_steer = self._angles[-1], 0.0, self._steer[-1]
        else:
            dt = time - truth.t[k]
            kinematic_angles = self._angles[k] + self._speeds[k] * dt
            kinematic_speeds = self._speeds[k]
            kinematic_steer = self._steer[k]
        angles[slots.rolling] = kinematic_angles
        speeds[slots.rolling] = kinematic_speeds
        if len(slots.steered):
            steer[slots.steered] = kinematic_steer
        joints = self.track.joints
        if joints is not None:
            j_angles, j_speeds, j_steer = joints.values(time)
            angles[self._joint_rolling] = j_angles
            speeds[self._joint_rolling] = j_speeds
            if j_steer is not None and self._joint_steered is not None and len(self._joint_steered):
                steer[self._joint_steered] = j_steer
        if k < 0 or k >= n_int:
            row = 0 if k < 0 else n_int
            castor_angles, swivels = self._castor_angle[row], self._swivel[row]
            roller_angles, roller_rates = self._roller_angle[row], np.zeros(len(slots.swedish))
        else:
            s = (time - truth.t[k]) / (truth.t[k + 1] - truth.t[k])  # castors and rollers: linear in time
            castor_angles = self._castor_angle[k] + s * (self._castor_angle[k + 1] - self._castor_angle[k])
            swivels = self._swivel[k] + s * (self._swivel[k + 1] - self._swivel[k])
            roller_angles = self._roller_angle[k] + s * (self._roller_angle[k + 1] - self._roller_angle[k])
            roller_rates = self._roller_rate[k]
        if len(slots.castors):
            angles[slots.castors] = castor_angles
            steer[slots.castors] = swivels
        rollers, roller_speeds = slots.rollers(roller_angles, roller_rates)
        pose = truth.at(time)
        odometry = self.track.odometry.at(time)
        twist = truth.twist(time)
        return Snapshot(
            t=float(time),
            truth=triple(pose),
            odometry=triple(odometry),
            twist=triple(twist),
            command=(0.0, 0.0, 0.0),
            target=(0.0, 0.0, 0.0),
            wheel_angles=angles,
            wheel_speeds=speeds,
            steer=steer,
            residual=(),
            roller_angles=rollers,
            roller_speeds=roller_speeds,
            missing=("command", "residual", *self.track.missing),  # a recording has no command, no residual
        )
