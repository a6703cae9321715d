"""The physics engine as an :class:`~omnikin.simulation.engine.Engine`, and the one factory of
engines by name.

:class:`PhysicsEngine` drives plans with :func:`~omnikin.physics.run.simulate_physics`, makes
:class:`~omnikin.physics.backend.PhysicsBackend` back-ends and estimates runs with
:func:`~omnikin.physics.cost.physics_run_cost`, at its time ``step`` [s]. Importing this module
does not import ``mujoco`` (the extra ``physics``): the simulation imports it when a model is
first built.

:func:`engine_named` turns a name of :data:`ENGINE_NAMES` into an engine; it lives here because
this is the lowest layer that sees both engines. Only argument parsers, the API's entry points
(which accept a name or an engine) and the readers of files that store an engine's name call it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

from ..common.messages import shorten
from ..common.rng import make_rng
from ..control.time_optimal import WheelLimits
from ..errors import InputError
from ..kinematics.robot import Robot
from ..motion.limits import MotionLimits
from ..motion.plans import Plan
from ..motion.timing import SampledPlan, check_rate_range
from ..sensors.readings import sensor_cost
from ..simulation.engine import Engine, KinematicEngine, Progress, SimulatedBackend, contact_problems
from ..simulation.error_models import NoiseModel
from ..simulation.kinematic import RunCost, SimulatedRun, run_cost
from ..world.collision import Footprint
from ..world.model import World
from .mjcf import DEFAULT_STEP, time_step


def check_physics_noise(noise) -> None:
    """Refuse a noise model for the physics engine: it has none of its own, its random errors
    are those of the roller contact.

    Parameters
    ----------
    noise : str, NoiseModel or None
        The noise a user gave; None (not given) passes.

    Raises
    ------
    InputError
        In one line, for any ``noise`` but None.
    """
    if noise is not None:
        raise InputError(
            f"noise (--noise) {shorten(noise if isinstance(noise, str) else type(noise).__name__)}: the physics "
            "engine has no random error model (slip comes from the wheels' roller contact, its encoders count "
            "whole ticks); drop --noise"
        )


@dataclass(frozen=True)
class PhysicsEngine(Engine):
    """MuJoCo (:mod:`omnikin.physics`): the robot as built as a body with wheels, rollers,
    ramped PI servos and encoders, stepped at ``step`` [s]. It implements
    :class:`~omnikin.simulation.engine.Engine` (the methods without a docstring of their own are
    documented there).

    It refuses any noise (:func:`check_physics_noise`). :meth:`backend` is a
    :class:`~omnikin.physics.backend.PhysicsBackend` at ``step`` (``rng`` does not apply: the
    physics is deterministic); :meth:`problems` and :meth:`summary` are those of the run,
    :meth:`~omnikin.physics.run.PhysicsRun.problems` and
    :meth:`~omnikin.physics.run.PhysicsRun.summary` (none for a run of another engine).
    :meth:`cost`: the memory is the kinematic engine's per sample
    (:func:`~omnikin.simulation.kinematic.run_cost`) over the plan and the tail after it
    (:data:`~omnikin.physics.run.TAIL_MAX`; ``timed`` False), or over the samples of the
    simulated time's upper bound; the time is :func:`~omnikin.physics.cost.physics_run_cost` (the
    plan sampled, the step's cost measured on ``true_robot``'s model unless its size alone
    exceeds ``budget`` [s]).

    Parameters
    ----------
    step : float
        The time step [s] of the simulation, within :data:`~omnikin.physics.mjcf.STEP_RANGE`
        (default :data:`~omnikin.physics.mjcf.DEFAULT_STEP`, 2 ms).
    world : World, optional
        The world the robot drives in: its walls, obstacles and patches are bodies of the model
        (:func:`~omnikin.physics.mjcf.mjcf`), each run starts at its start pose and reports its
        contacts (None: an empty floor).

    Attributes
    ----------
    name : str
        ``"physics"``.
    has_noise_model : bool
        False: the random errors come from the wheels' contacts and whole encoder ticks.
    measured_cost : bool
        True: :meth:`cost` builds the model and times its steps (seconds).
    drives_as_commanded : bool
        False: :meth:`problems` says how a run did not.
    default_noise : None
        No noise model.
    """

    step: float = field(default=DEFAULT_STEP)
    world: World | None = None

    name: ClassVar[str] = "physics"
    has_noise_model: ClassVar[bool] = False
    measured_cost: ClassVar[bool] = True
    drives_as_commanded: ClassVar[bool] = False
    default_noise: ClassVar[str | None] = None

    def __post_init__(self):
        object.__setattr__(self, "step", time_step(self.step, "step (--step)"))

    @classmethod
    def made_with(cls, *, noise=None, step: float | None = None, world: World | None = None) -> PhysicsEngine:
        """The engine for the options a user gave (:func:`engine_named`).

        Parameters
        ----------
        noise : str, NoiseModel or None
            Must be None (:func:`check_physics_noise`).
        step : float, optional
            The time step [s], within :data:`~omnikin.physics.mjcf.STEP_RANGE` (None: 2 ms).
        world : World, optional
            The world the robot drives in (None: an empty floor).

        Returns
        -------
        PhysicsEngine
            The engine at ``step``.

        Raises
        ------
        InputError
            In one line: a ``noise`` given, a ``step`` out of range.
        """
        check_physics_noise(noise)
        return cls(time_step(step, "step (--step)"), world)

    @property
    def options(self) -> dict[str, Any]:
        return {"step": self.step} if self.world is None else {"step": self.step, "world": self.world}

    def noise_model(self, noise) -> None:
        check_physics_noise(noise)
        return None

    def check_rate(self, rate, name: str = "rate") -> float:
        """:meth:`Engine.check_rate`: within the range, and a period of whole time steps (the
        encoders are read after whole steps, :func:`~omnikin.physics.run.check_rate_steps`).

        Parameters
        ----------
        rate : float
            Sample rate [Hz], within :data:`~omnikin.motion.timing.RATE_RANGE`, whose period
            ``1 / rate`` is a whole number ``n >= 1`` of time steps: ``rate = 1 / (n step)``
            (500, 250, 166.67, ... Hz at 2 ms).
        name : str
            What the rate is called in the error (``--rate``; the whole-step error names
            ``--rate`` itself).

        Returns
        -------
        float
            ``rate`` [Hz] as a float.

        Raises
        ------
        InputError
            In one line: a rate outside the range (naming ``name``), or a period of no whole
            number of steps (naming the nearest rates that are).
        """
        from .run import check_rate_steps

        rate = check_rate_range(rate, name)
        check_rate_steps(rate, self.step)
        return rate

    def drive(
        self,
        plan: Plan | SampledPlan,
        true_robot: Robot,
        command_robot: Robot,
        *,
        rate: float = 100.0,
        limits: MotionLimits | None = None,
        noise: NoiseModel | None = None,
        rng=None,
        progress: Progress | None = None,
        sensor_rng=None,
    ) -> SimulatedRun:
        """:meth:`Engine.drive` by :func:`~omnikin.physics.run.simulate_physics` at this engine's
        time step; the random stream only sets where each wheel's rollers start.

        Parameters
        ----------
        plan : Plan or SampledPlan
            The path; a :class:`~omnikin.motion.plans.Plan` is timed and sampled for ``command_robot``
            at ``rate`` within ``limits`` (:func:`~omnikin.motion.timing.sample_plan`).
        true_robot, command_robot : Robot
            The robot as built (simulated in MuJoCo) and the model that commands it (the same
            wheels).
        rate : float
            Sample rate [Hz] of the encoders; it is not checked against whole time steps here
            (:meth:`check_rate` does that).
        limits : MotionLimits, optional
            Speed and acceleration limits the plan is timed with.
        noise : NoiseModel, optional
            Must be None (:func:`check_physics_noise`).
        rng : numpy.random.Generator, int or None
            Draws each rolling wheel's starting roller phase uniformly from ``[0, 1)`` of its
            roller period (None: every wheel at phase 0, the run is deterministic).
        progress : callable, optional
            Called with the simulated time and the plan's duration [s] now and then.
        sensor_rng : numpy.random.Generator or None
            The stream of the sensors' errors (None: exact readings); the run's ``sensing``
            holds what the robot's IMUs and lidars read (:mod:`omnikin.physics.sensing`).

        Returns
        -------
        SimulatedRun
            A :class:`~omnikin.physics.run.PhysicsRun`: ``t`` ``(N + 1,)`` [s], ``ticks`` and
            ``readings`` ``(N + 1, n_enc)`` (whole ticks), ``odometry`` ``(N + 1, 3)`` [m, m, rad],
            ``truth`` ``(1, N + 1, 3)``, ``measured`` ``(1, 3)`` (world frame, starting at the
            origin), and what did not go as commanded (:meth:`problems`).

        Raises
        ------
        InputError
            In one line: a ``noise`` given, a rate outside the range, robots or a plan the
            engine cannot drive or resolve.
        """
        from .run import simulate_physics

        check_physics_noise(noise)
        phase: Any = 0.0 if rng is None else make_rng(rng).random(len(true_robot.rolling))
        return simulate_physics(
            plan,
            true_robot,
            command_robot,
            rate=rate,
            limits=limits,
            step=self.step,
            progress=progress,
            roller_phase=phase,
            world=self.world,
            sensor_rng=sensor_rng,
        )

    def backend(
        self,
        robot: Robot,
        true_robot: Robot | None = None,
        *,
        noise: NoiseModel | None = None,
        rng=None,
        max_lag: float | None = None,
        sensor_rng=None,
    ) -> SimulatedBackend:
        from .backend import PhysicsBackend

        check_physics_noise(noise)
        start = (0.0, 0.0, 0.0) if self.world is None else self.world.start
        return PhysicsBackend(
            robot, true_robot, start=start, step=self.step, max_lag=max_lag, world=self.world, sensor_rng=sensor_rng
        )

    def cost(
        self,
        plan: Plan,
        true_robot: Robot,
        command_robot: Robot,
        *,
        rate: float = 100.0,
        budget: float | None = None,
        timed: bool = True,
    ) -> RunCost:
        from ..motion.timing import sample_plan
        from .cost import physics_run_cost
        from .run import TAIL_MAX

        plan_cost = run_cost(plan, command_robot, rate)
        per_sample = plan_cost.bytes / max(plan_cost.samples, 1.0)
        shapes = 0 if self.world is None else len(self.world.bodies)
        if not timed:
            sensed, _ = sensor_cost(true_robot, plan_cost.simulated + TAIL_MAX, shapes)
            return RunCost(plan_cost.samples, plan_cost.bytes + per_sample * TAIL_MAX * rate + sensed, math.nan)
        sampled = sample_plan(plan, command_robot, rate)
        estimate = physics_run_cost(sampled, true_robot, command_robot, self.step, budget=budget)
        samples = estimate.simulated * rate
        sensed_bytes, sensed_seconds = sensor_cost(true_robot, estimate.simulated, shapes)
        return RunCost(
            samples, per_sample * samples + sensed_bytes, estimate.seconds + sensed_seconds, estimate.simulated
        )

    def problems(self, run: SimulatedRun) -> list[str]:
        from .run import PhysicsRun

        return (run.problems() if isinstance(run, PhysicsRun) else []) + contact_problems(run)

    def summary(self, run: SimulatedRun) -> dict[str, Any]:
        from .run import PhysicsRun

        return run.summary() if isinstance(run, PhysicsRun) else {}

    def motor_limits(self, robot: Robot) -> WheelLimits | None:
        from .description import describe

        wheels = describe(robot).wheels
        motors = [(w.motor, w.radius) for w in wheels if w.motor is not None]
        if not motors:
            return None
        speed = min(motor.max_speed for motor, _ in motors)
        accel = min(motor.max_accel / radius for motor, radius in motors)
        steering = [w.steering.max_rate for w in wheels if w.steering is not None and w.steering.actuated]
        return WheelLimits(float(speed), float(accel), float(min(steering, default=math.inf)))


ENGINES: dict[str, type[KinematicEngine] | type[PhysicsEngine]] = {
    KinematicEngine.name: KinematicEngine,
    PhysicsEngine.name: PhysicsEngine,
}
"""The engines by name."""

ENGINE_NAMES: tuple[str, ...] = tuple(ENGINES)
"""The names an engine is chosen by (``--engine``, study files, report documents)."""


def engine_class(name) -> type[KinematicEngine] | type[PhysicsEngine]:
    """The class of the engine called ``name``, for its class attributes (e.g. what a report
    document's ``engine`` field says about the run) without making an engine.

    Parameters
    ----------
    name : str
        One of :data:`ENGINE_NAMES`.

    Returns
    -------
    type
        :class:`~omnikin.simulation.engine.KinematicEngine` or :class:`PhysicsEngine`.

    Raises
    ------
    InputError
        In one line naming the choices, for any other ``name``.
    """
    if not isinstance(name, str) or name not in ENGINES:
        raise InputError(f"engine (--engine) must be one of {', '.join(ENGINE_NAMES)}, got {shorten(name)}")
    return ENGINES[name]


def engine_named(name, *, noise=None, step: float | None = None, world: World | None = None) -> Engine:
    """The engine called ``name`` made with the options a user gave.

    Parameters
    ----------
    name : str
        One of :data:`ENGINE_NAMES`; anything else is refused in one line naming the choices.
    noise : str, NoiseModel or None
        Random errors given with it: the physics engine refuses any (it has no random error
        model); the kinematic engine takes them with each run (:meth:`Engine.noise_model`).
    step : float, optional
        The physics engine's time step [s] (None: 2 ms); the kinematic engine refuses one.
    world : World, optional
        The world the robot drives in (None: an empty floor); the kinematic engine gets the
        footprints of the physics description (:func:`~omnikin.physics.description.footprint`).

    Returns
    -------
    Engine
        :class:`~omnikin.simulation.engine.KinematicEngine` or :class:`PhysicsEngine`.

    Raises
    ------
    InputError
        In one line: an unknown ``name``, an option of the other engine, a ``step`` out of
        range.
    """
    kind = engine_class(name)
    if world is None:
        return kind.made_with(noise=noise, step=step)
    if not isinstance(world, World):
        raise InputError(f"world (--world): expected an omnikin World, got {type(world).__name__}")
    world = world.checked()  # a World built by hand is checked as make_world and world files check
    if kind is KinematicEngine:
        return KinematicEngine.made_with(noise=noise, step=step, world=world, footprint_of=robot_footprint)
    return PhysicsEngine.made_with(noise=noise, step=step, world=world)


@functools.lru_cache(maxsize=16)
def robot_footprint(robot: Robot) -> Footprint:
    """``robot`` seen from above, as its physical description has it (body frame, m); kept for
    the last robots asked about (a study drives the same robot many times)."""
    from .description import describe, footprint

    return footprint(describe(robot))


def as_engine(engine, *, noise=None, step: float | None = None) -> Engine:
    """``engine`` as an engine object; the API's entry points accept an engine or its name.

    Parameters
    ----------
    engine : str or Engine
        A name of :data:`ENGINE_NAMES`, made through :func:`engine_named` (which refuses the
        other engine's options), or an :class:`~omnikin.simulation.engine.Engine`, taken as it
        is.
    noise : str, NoiseModel or None
        With a name: as for :func:`engine_named`. With an engine object: not checked here, but
        where a run takes it (:meth:`~omnikin.simulation.engine.Engine.noise_model`).
    step : float, optional
        With a name: the physics engine's time step [s]. With an engine object: must be None
        (the object carries its own).

    Returns
    -------
    Engine
        The engine.

    Raises
    ------
    InputError
        In one line: neither a name nor an engine (an engine class included), an unknown name
        or an option it refuses, a ``step`` beside an engine object.
    """
    if isinstance(engine, str):
        return engine_named(engine, noise=noise, step=step)
    if isinstance(engine, type):  # an engine class passes the protocol's check of its methods
        raise InputError(f"engine: give an engine object, e.g. {engine.__name__}(), not the class {engine.__name__}")
    if not isinstance(engine, Engine):
        raise InputError(f"engine must be one of {', '.join(ENGINE_NAMES)} or an Engine object, got {shorten(engine)}")
    if step is not None:
        raise InputError(f"step: give the time step to the engine object ({engine!r}), not beside it")
    return engine
