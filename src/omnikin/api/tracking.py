"""``omnikin.track``: a robot driving a path at the speed its wheels allow, tracked by a
controller, as ``omnikin track`` runs it.

The path is timed by :func:`~omnikin.control.trajectory.plan_trajectory` within the wheel limits
(the fastest timing under every wheel's speed and acceleration limit), then driven by the
controller through the runtime (:func:`~omnikin.evaluation.tracking.track`) in the kinematic or
the physics engine, the controller steering by the robot's odometry. The robot starts at rest at
the path's first pose: the run is made in the frame of that pose and its poses are given back in
the path's frame (the world frame of the path file or built-in path).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..common.resource_limits import DEFAULT_MEMORY, DEFAULT_TIME
from ..control.controllers import build_controller, check_controller, default_controller
from ..control.path import Path, moved
from ..control.trajectory import Trajectory, control_period
from ..evaluation.tracking import TrackingRun
from ..kinematics.robot import Robot
from ..simulation.error_models import SystematicErrors
from .common import as_built, require_callable, require_viz, robot_of

DEFAULT_CONTROLLER = None
"""The controller of :func:`track` when none is named: ``feedback`` for a layout that translates in
any direction, ``mpc`` for one with fixed wheels that do not steer (a differential drive),
``pursuit`` for one with fixed and steered wheels (a car)
(:func:`~omnikin.control.controllers.default_controller`)."""
DEFAULT_RATE = 50.0
"""Control rate [Hz] of :func:`track`."""


TICK_SECONDS = {"feedback": 1e-3, "pursuit": 1e-3, "mpc": 3e-3}
"""Computing time [s] of one control tick apart from the physics engine's steps, by controller
(runtime, controller, back-end, the run's records: measured 0.5 to 1.4 ms with the feedback
controller on a loaded 2-core machine, the MPC's solve 2.2 ms at p95 more)."""
MIN_TICKS = 10
"""Fewest control ticks a run's reference may last: a rate slower than that samples nothing of
the motion (one tick of a 12 s circle at 0.1 Hz, a "perfect" run of a robot that never moved)."""


@dataclass(frozen=True)
class TrackingCost:
    """What a run of :func:`track` is estimated to cost, once its reference is planned and
    before it is driven (its ``on_cost``).

    Attributes
    ----------
    ticks : float
        Control ticks: the reference's duration and the settling time at the rate.
    memory : float
        The run's arrays [bytes].
    seconds : float
        Computing time [s]: the ticks, and for the physics engine its time steps at the cost
        measured on the model (:func:`omnikin.physics.cost.measure_step_seconds`).
    step : float or None
        The physics engine's time step [s]; None for the kinematic engine.
    """

    ticks: float
    memory: float
    seconds: float
    step: float | None


@dataclass(frozen=True)
class Tracking:
    """A path tracked by a controller (:func:`track`).

    Attributes
    ----------
    robot : Robot
        The nominal robot: the runtime's and the controller's model.
    true_robot : Robot
        The robot as built that drove.
    injected : SystematicErrors or None
        The systematic errors drawn from the ``errors`` profile; None for a given true robot.
    trajectory : Trajectory
        The timed reference, in the path's frame.
    controller : str
        The controller's name (:data:`~omnikin.control.controllers.CONTROLLERS`).
    engine : str
        The engine's name.
    run : TrackingRun
        The run at the control ticks ``(n,)``: times [s], truth, odometry and reference poses
        ``(n, 3)`` [m, m, rad] in the path's frame, the commanded body twists ``(n, 3)`` and
        wheel speeds ``(n, n_wheels)`` [rad/s], the count of saturated commands, the
        controller's wall time per tick [s].
    step : float or None
        The physics engine's time step [s]; None for the kinematic engine.
    """

    robot: Robot
    true_robot: Robot
    injected: SystematicErrors | None
    trajectory: Trajectory
    controller: str
    engine: str
    run: TrackingRun
    step: float | None = None

    def in_start_frame(self, poses) -> np.ndarray:
        """Poses of the path's frame (the run's) seen from the frame fixed where the robot
        started (REP 105's odom: what its wheels' odometry reads back).

        Parameters
        ----------
        poses : array_like, shape (n, 3)
            ``x, y, theta`` [m, m, rad] in the path's frame.

        Returns
        -------
        numpy.ndarray, shape (n, 3)
            The same poses in the start frame, headings kept continuous.
        """
        from ..kinematics.se2 import inverse

        return seen_from(inverse(self.trajectory.path.pose[0]), poses)

    @property
    def path(self) -> Path:
        """The path, in its own frame."""
        return self.trajectory.path

    def summary(self) -> dict[str, Any]:
        """The numbers of ``omnikin track --json``: ``duration_s`` (the reference's),
        ``path_length_m`` (distance the centre travels along it), ``rms_error_m`` and
        ``max_error_m`` (the truth's distance to the path), ``rms_heading_error_rad``,
        ``max_wheel_speed_rad_s`` (commanded), ``saturated_samples`` (commands scaled down to
        the wheel limit) and ``largest_excess_percent`` (by how much the controller's largest
        ask went beyond the limit, 0 if never), ``solve_time_ms`` (the controller's wall time per tick: ``p50``,
        ``p95``, ``max``), and the end pose error ``end_error_m`` (truth's distance from the
        path's end)."""
        from ..evaluation.tracking import tracking_errors

        run = self.run
        errors = tracking_errors(run, self.trajectory)
        solve_ms = run.solve_time * 1e3
        end = self.trajectory.path.pose[-1]
        return {
            "robot": self.robot.name,
            "path": self.path.name,
            "controller": self.controller,
            "engine": self.engine,
            "step_s": self.step,
            "rate_hz": float(1.0 / (run.t[1] - run.t[0])) if len(run.t) > 1 else None,
            "max_wheel_speed_limit_rad_s": self.trajectory.limits.speed,
            "max_wheel_accel_limit_rad_s2": self.trajectory.limits.accel,
            "duration_s": self.trajectory.duration,
            "path_length_m": self.path.travel,
            **errors,
            "end_error_m": float(np.hypot(*(run.truth[-1, :2] - end[:2]))),
            "max_wheel_speed_rad_s": float(np.max(np.abs(run.wheel_speeds))) if run.wheel_speeds.size else 0.0,
            "saturated_samples": int(run.saturated),
            "largest_excess_percent": self._largest_excess(),
            "samples": len(run.t),
            "solve_time_ms": {
                "p50": float(np.percentile(solve_ms, 50)),
                "p95": float(np.percentile(solve_ms, 95)),
                "max": float(np.max(solve_ms)),
            },
        }

    def _largest_excess(self) -> float:
        """``100 (max |w| / limit - 1)`` over the wheel speeds the controller's twists ask
        (before the runtime's saturation), at least 0 [%]."""
        asked = self.robot.ik(
            self.run.command, on_infeasible="return"
        ).wheel_speeds  # (steering not reached: as far as it goes)
        finite = np.abs(asked[np.isfinite(asked)])
        largest = float(np.max(finite)) if finite.size else 0.0
        return max(0.0, 100.0 * (largest / self.trajectory.limits.speed - 1.0))

    def plot(self):
        """The path, the reference, the truth and the odometry [m]; the truth's distance to the
        path over time [mm]; the commanded wheel speeds against their limit [rad/s] (a
        matplotlib ``Figure``)."""
        require_viz()
        from ..viz.tracking import tracking_figure

        return tracking_figure(self)


def track(
    robot,
    path,
    *,
    controller: str | None = DEFAULT_CONTROLLER,
    engine="kinematic",
    step: float | None = None,
    true_robot=None,
    errors="none",
    noise=None,
    seed: int = 1,
    rate: float = DEFAULT_RATE,
    max_wheel_speed: float = 12.0,
    max_wheel_accel: float = 40.0,
    heading=None,
    blend: float | None = None,
    smooth: bool = False,
    settle: float = 1.0,
    max_memory: float = DEFAULT_MEMORY,
    max_time: float = DEFAULT_TIME,
    on_cost: Callable[[TrackingCost], None] | None = None,
) -> Tracking:
    """Track ``path`` with ``robot`` at the speed its wheels allow (``omnikin track``).

    Parameters
    ----------
    robot : str, os.PathLike or Robot
        The nominal robot: a preset name, a robot file or a Robot.
    path : str, os.PathLike or Path
        A :class:`~omnikin.control.path.Path`, a path file (CSV or YAML waypoints,
        :mod:`omnikin.io.path_file`) or a built-in path (``"figure8 1"``, ``"circle 0.5"``,
        ``"square 1 0.2"``: :func:`~omnikin.control.path.parse_path`).
    controller : str, optional
        One of :data:`~omnikin.control.controllers.CONTROLLERS`; default ``feedback`` for a
        layout that translates in any direction, ``mpc`` for a differential drive, ``pursuit``
        for a car (:data:`DEFAULT_CONTROLLER`).
    engine : str or Engine, default "kinematic"
        ``"kinematic"`` or ``"physics"`` (MuJoCo, extra ``physics``), or an engine object.
    step : float, optional
        Physics time step [s] (default 2 ms); physics only.
    true_robot : str, os.PathLike or Robot, optional
        The robot as built; replaces the draw from ``errors``.
    errors : str or ErrorProfile, default "none"
        Systematic errors the robot as built is drawn from (the default: built as designed).
    noise : str or NoiseModel, optional
        Random errors of the kinematic engine (default none); refused by the physics engine.
    seed : int, default 1
        Seed (>= 0) of the robot as built and of the noise.
    rate : float, default 50
        Control rate [Hz].
    max_wheel_speed, max_wheel_accel : float, default 12 and 40
        Every wheel's speed [rad/s] and acceleration [rad/s^2] limit: the reference is the
        fastest within them, the runtime saturates commands to the speed limit. In physics the
        motors' own limits apply too (:meth:`~omnikin.simulation.engine.Engine.motor_limits`:
        their speed limit and their torque's acceleration, from the physical fields).
    heading : str or float, optional
        How the path's heading is set (``tangent``, ``fixed``, ``free`` or an angle [rad]) when
        ``path`` is text or a file without headings; default that of the built-in path (fixed for
        the circle and the figure-eight, tangent for the square) or tangent for a file, and
        tangent for every path of a layout with fixed wheels.
    blend : float, optional
        Path files: radius [m] of the arcs that cut the corners (default: stop at them).
    smooth : bool, default False
        Path files: a smooth curve through the waypoints.
    settle : float, default 1
        Time [s] the controller holds the path's end after the reference ends.
    max_memory, max_time : float
        Largest memory [bytes] and computing time [s] the run may be estimated to need
        (:class:`TrackingCost`); a run beyond them is refused before it is driven.
    on_cost : callable, optional
        Called with the estimate before it is checked; it may raise to refuse the run.

    Returns
    -------
    Tracking

    Raises
    ------
    InputError
        A bad path, robot, controller, limit, rate, seed or profile; a path the robot cannot
        drive (one line naming where along it and why).
    PhysicsError
        The physics engine failed.
    """
    from ..common.messages import shorten
    from ..common.resource_limits import require_within
    from ..control.time_optimal import WheelLimits
    from ..control.trajectory import plan_trajectory
    from ..errors import InputError
    from ..evaluation.pipeline import RUN_STREAMS
    from ..evaluation.procedure import ARGUMENTS, streams
    from ..evaluation.tracking import track as drive
    from ..io.path_file import is_path_file, load_path
    from ..kinematics.se2 import inverse
    from ..physics.engines import as_engine

    require_callable(on_cost=on_cost)
    if controller is not None:
        check_controller(controller)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"seed must be a whole number >= 0, got {shorten(seed)}")
    nominal = robot_of(robot)
    if controller is None:
        controller = default_controller(nominal)
    if heading is None and nominal.fixed and not isinstance(path, Path) and not is_path_file(path):
        # a built-in path's own default may be a fixed heading; tangent is the only heading a
        # layout with fixed wheels can hold along a curve (a file's default is tangent already,
        # and a file may give its headings)
        heading = "tangent"
    control_period(rate)
    if isinstance(settle, bool) or not (isinstance(settle, (int, float)) and 0 <= settle <= 3600):
        raise InputError(f"settle must be in [0, 3600] s, got {shorten(settle)}")
    for option, value in (("max_wheel_speed", max_wheel_speed), ("max_wheel_accel", max_wheel_accel)):
        if isinstance(value, bool) or not (isinstance(value, (int, float)) and 0 < value < math.inf):
            raise InputError(
                f"{option} (--{option.replace('_', '-')}) must be a finite number > 0, got {shorten(value)}"
            )
    engine = as_engine(engine, noise=noise, step=step)
    if engine.options.get("step") is not None:
        from ..physics.run import check_rate_steps

        check_rate_steps(rate, engine.options["step"])
    noise_model = None if noise is None else engine.noise_model(noise)
    limits = WheelLimits(speed=max_wheel_speed, accel=max_wheel_accel)
    seeds = streams(seed, RUN_STREAMS)
    true, injected = as_built(nominal, true_robot, errors, seeds["robot"])
    motors = engine.motor_limits(true)
    if motors is not None:  # the motors' own limits apply too (physics: from the physical fields)
        # (not the steering servos' rate: the controllers do not model the steering's lag, and a
        # reference slowed to it was tracked worse by steered layouts, docs/control.md)
        limits = WheelLimits(speed=min(limits.speed, motors.speed), accel=min(limits.accel, motors.accel))
    if isinstance(path, Path):
        if heading is not None or blend is not None or smooth:
            raise InputError("heading, blend and smooth shape a path given as text or a file, not a Path")
        geometry = path
    else:
        geometry = load_path(path, heading=heading, blend=blend, smooth=smooth)
    trajectory = plan_trajectory(nominal, geometry, limits)
    if trajectory.duration * rate < MIN_TICKS:
        raise InputError(
            f"rate (--rate) {rate:g} Hz gives {math.floor(trajectory.duration * rate) + 1} control tick(s) over the "
            f"{trajectory.duration:.3g} s reference: at least {MIN_TICKS}; raise the rate"
        )
    cost = tracking_cost(true, engine, trajectory.duration + settle, rate, controller)
    if on_cost is not None:
        on_cost(cost)
    require_within(
        "track",
        memory=cost.memory,
        seconds=cost.seconds,
        max_memory=max_memory,
        max_time=max_time,
        names=ARGUMENTS,
        hint="lower rate, shorten the path or raise max_wheel_speed",
        size=f"{cost.ticks:.3g} control ticks",
    )
    # the run in the frame of the path's start (the robot starts there, at rest), given back in the path's
    start = trajectory.path.pose[0].copy()
    world = getattr(engine, "world", None)
    if world is not None:  # the path is in the world's frame: the robot starts at its first pose
        engine = dataclasses.replace(engine, world=dataclasses.replace(world, start=tuple(float(v) for v in start)))
    local = dataclasses.replace(trajectory, path=moved(trajectory.path, inverse(start)))
    law = build_controller(controller, nominal, local, rate=rate)
    run = drive(
        nominal,
        local,
        law,
        engine=engine,
        true_robot=true,
        rate=rate,
        noise=noise_model,
        rng=seeds["run"] if noise_model is not None else None,
        settle=settle,
    )

    run = dataclasses.replace(
        run,
        truth=seen_from(start, run.truth),
        odometry=seen_from(start, run.odometry),
        reference=seen_from(start, run.reference),
    )
    return Tracking(nominal, true, injected, trajectory, controller, engine.name, run, engine.options.get("step"))


def seen_from(frame, poses) -> np.ndarray:
    """``poses`` ``(n, 3)`` [m, m, rad] given in the frame whose pose is ``frame`` (in the frame
    ``frame`` is given in), headings kept continuous."""
    from ..kinematics.se2 import compose

    out = compose(np.asarray(frame, dtype=float), np.asarray(poses, dtype=float))
    out[:, 2] = np.unwrap(out[:, 2])
    return out


def tracking_cost(true_robot: Robot, engine, seconds: float, rate: float, controller: str = "feedback") -> TrackingCost:
    """The :class:`TrackingCost` of driving ``seconds`` [s] of simulated time at ``rate`` [Hz]
    in ``engine`` with ``controller`` (for the physics engine its step cost is measured on
    ``true_robot``'s model)."""
    ticks = math.floor(seconds * rate) + 1.0
    columns = 16 + len(true_robot.rolling) + len(true_robot.encoded_names) + len(true_robot.steerable)
    memory = ticks * columns * 8 * 3  # the run's arrays, moved to the path's frame
    computing = ticks * TICK_SECONDS[controller]
    step = engine.options.get("step")
    if step is not None:
        from ..physics.cost import measure_step_seconds

        per_step, built = measure_step_seconds(true_robot, step)
        computing += built + seconds / step * per_step
    return TrackingCost(ticks, float(memory), float(computing), step)
