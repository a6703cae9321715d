"""Simulated runs: the robot as built drives a plan commanded by its (nominal) model.

One run, for every trial at once (leading trial axis):

1. the plan is timed and sampled for the *command* robot (:func:`~.motion.sample_plan`);
   its inverse kinematics gives every encoded wheel's commanded angle at each sample;
2. each wheel controller holds its encoder at the commanded count: the encoder ticks are
   the commanded angle over the command model's angle per tick, rounded when quantised.
   They are the same in every trial, and so is the odometry computed from them;
3. the true wheel angle is the ticks times the *true* angle per tick (encoder errors); in
   each sample each wheel's rolling distance gets its slip error and the true robot's
   forward kinematics (:meth:`omnikin.model.Robot.fk_matrix`) turns the wheel increments
   into a body increment; the floor adds its heading error; exact SE(2) integration gives
   the ground truth;
4. the end pose is "measured" with the measurement noise.

The encoded wheels are taken as the driven ones: passive wheels (castors, unencoded
steered wheels) follow the motion and do not drive it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..errors import OmnikinError
from ..integration import integrate_components, integrate_end
from ..model import Robot
from ..odometry import batch_odometry, encoded_wheels
from .errors import NoiseModel
from .limits import MotionLimits
from .motion import Plan, SampledPlan, sample_plan


@dataclass(frozen=True)
class SimulatedRun:
    """Result of :func:`simulate`.

    ``t`` ``(N + 1,)`` [s]; ``ticks`` ``(N + 1, n_enc)`` encoder counts and ``steer``
    ``(N + 1, n_steer)`` [rad] or None (the same in every trial); ``odometry``
    ``(N + 1, 3)`` the odometry of ``odometry_robot`` from those ticks; ``truth``
    ``(trials, N + 1, 3)`` ground truth (or only its end, ``(trials, 1, 3)``, when not
    kept); ``measured`` ``(trials, 3)`` the end pose as measured.
    """

    sampled: SampledPlan
    t: np.ndarray
    ticks: np.ndarray
    steer: Optional[np.ndarray]
    odometry: np.ndarray
    truth: np.ndarray
    measured: np.ndarray

    @property
    def epsilon(self) -> np.ndarray:
        """Return errors ``(trials, 3)``: measured true end pose minus odometry end pose."""
        eps = self.measured - self.odometry[-1]
        eps[:, 2] = (eps[:, 2] + np.pi) % (2 * np.pi) - np.pi
        return eps


def commanded_angles(sampled: SampledPlan, robot: Robot, wheels) -> tuple[np.ndarray, Optional[np.ndarray]]:
    """Commanded wheel angles ``(N + 1, n)`` [rad] of ``wheels`` and steering ``(N + 1, n_steer)``."""
    names = [w.name for w in wheels]
    per_segment = np.zeros((len(sampled.xi), len(names)))
    steer_seg = np.zeros((len(sampled.xi), len(robot.steerable)))
    hint = np.zeros(len(robot.steerable))
    for k, xi in enumerate(sampled.xi):
        if robot.steerable:
            res = robot.ik(xi, steer_hint=hint)
            hint = steer_seg[k] = res.steer_angles
        else:
            robot.ik(xi)      # refuses a plan the command model cannot drive, naming the wheel
        per_segment[k] = robot.jacobian(steer_seg[k], names) @ xi
    angles = np.zeros((len(sampled.progress) + 1, len(names)))
    np.cumsum(per_segment[sampled.segment] * sampled.progress[:, None], axis=0, out=angles[1:])
    steer = None
    if robot.steerable:
        idx = np.concatenate([sampled.segment, sampled.segment[-1:]])
        steer = steer_seg[idx]
    return angles, steer


def simulate(plan: Plan | SampledPlan, true_robot: Robot, command_robot: Robot, *, rate: float = 100.0,
             limits: MotionLimits | None = None, noise: NoiseModel | None = None, trials: int = 1, rng=None,
             odometry_robot: Robot | None = None, keep_truth: bool = True) -> SimulatedRun:
    """Simulate ``trials`` runs of ``plan`` by ``true_robot`` commanded by ``command_robot``.

    ``rng``: a numpy Generator or a seed (None: fresh entropy). ``odometry_robot``
    defaults to ``command_robot`` (the robot executes the path by its own model).
    """
    noise = noise or NoiseModel()
    if not isinstance(trials, (int, np.integer)) or trials < 1:
        raise OmnikinError(f"trials must be a whole number >= 1, got {trials!r}")
    rng = np.random.default_rng(rng)
    odometry_robot = odometry_robot or command_robot
    sampled = plan if isinstance(plan, SampledPlan) else sample_plan(plan, command_robot, rate, limits)
    cmd_wheels = encoded_wheels(command_robot)
    names = [w.name for w in cmd_wheels]
    true_wheels = [true_robot.wheel(n) for n in names]
    missing = [w.name for w in true_wheels if w.encoder is None]
    if missing:
        raise OmnikinError(f"true robot {true_robot.name!r}: wheels {missing} have no encoder")
    angles, steer = commanded_angles(sampled, command_robot, cmd_wheels)
    cmd_rpt = np.array([w.encoder.rad_per_tick for w in cmd_wheels])
    ticks = angles / cmd_rpt
    if noise.quantise:
        ticks = np.round(ticks).astype(np.int64)
    true_rpt = np.array([w.encoder.rad_per_tick for w in true_wheels])
    dtrue = np.diff(ticks, axis=0).T * true_rpt[:, None]          # (n, N) true wheel increments [rad]
    odometry = batch_odometry(odometry_robot, sampled.t, ticks, steer=steer).poses
    truth = _truth(true_robot, names, dtrue, steer, noise, trials, rng, keep_truth)
    measured = truth[:, -1, :].copy()
    if noise.measurement or noise.measurement_theta:
        z = rng.standard_normal((trials, 3))
        measured += z * np.array([noise.measurement, noise.measurement, noise.measurement_theta])
    return SimulatedRun(sampled, sampled.t, ticks, steer, odometry, truth, measured)


TRIAL_BLOCK_SAMPLES = 1 << 15
"""Trials are simulated in blocks of about this many robot-samples, to stay in cache."""


def _truth(robot: Robot, names, dtrue, steer, noise: NoiseModel, trials: int, rng, keep: bool) -> np.ndarray:
    """Ground-truth poses ``(trials, N + 1, 3)`` (or ``(trials, 1, 3)``, the ends, if not ``keep``).

    The noise-free body increments are computed once; each trial adds the body image of its
    wheel slip, ``F (sigma * z)``, and its floor error on the heading. The floor's standard
    deviation per sample uses the noise-free path length of the sample.
    """
    n, m = dtrue.shape
    radius = np.array([robot.wheel(nm).radius for nm in names])
    if robot.steerable:
        mid = steer[:-1] + 0.5 * np.diff(steer, axis=0)
        f = robot.fk_matrix(mid, names)[..., : len(names)]        # (N, 3, n)
        base = np.einsum("kij,jk->ik", f, dtrue)
    else:
        f = robot.fk_matrix(None, names)[:, : len(names)]          # (3, n)
        base = f @ dtrue                                            # (3, N) noise-free increments
    reps = trials if not noise.is_zero else 1
    slip = noise.slip * np.sqrt(np.abs(dtrue) * radius[:, None]) / radius[:, None] if noise.slip else None
    floor = noise.floor * np.sqrt(np.hypot(base[0], base[1])) if noise.floor else None
    out = np.empty((trials, m + 1 if keep else 1, 3))
    block = max(1, TRIAL_BLOCK_SAMPLES // max(m, 1))
    for r0 in range(0, reps, block):
        r1 = min(reps, r0 + block)
        comps = np.broadcast_to(base, (r1 - r0, 3, m)).copy()
        if slip is not None:
            z = slip * rng.standard_normal((r1 - r0, n, m))
            comps += np.einsum("kij,rjk->rik", f, z) if robot.steerable else np.matmul(f, z)
        if floor is not None:
            comps[:, 2] += floor * rng.standard_normal((r1 - r0, m))
        if keep:
            integrate_components(comps[:, 0], comps[:, 1], comps[:, 2], out=out[r0:r1])
        else:
            out[r0:r1, 0] = integrate_end(comps[:, 0], comps[:, 1], comps[:, 2])
    if reps != trials:
        out[1:] = out[0]
    return out
