"""The engine interface: what simulates a robot as built, whichever way it is simulated.

:class:`Engine` states what every user of a simulation (``omnikin simulate``, the UMBmark study,
a sweep's trials, the viewer's live robot, ``omnikin ros --backend``) asks of it, so that each
holds one engine object and none asks which engine it holds:

- :meth:`Engine.drive`: a plan driven by the robot as built, commanded by its (nominal) model,
  gives a :class:`~omnikin.simulation.kinematic.SimulatedRun` (times [s], encoder counts and the
  counters' readings, steering [rad], the odometry of the readings, ground truth, the measured
  end pose);
- :meth:`Engine.backend`: the runtime's wheel back-end on the robot as built, for a stream of
  wheel commands (:class:`omnikin.runtime.backends.WheelBackend`);
- :meth:`Engine.cost`: what a run will take (samples, memory [bytes], computing time [s]), for
  the budget checks (:func:`omnikin.common.resource_limits.require_within`);
- its validity checks: :meth:`Engine.check_rate` (a sample rate it can read the encoders at),
  :meth:`Engine.noise_model` (the random errors it takes), :meth:`Engine.problems` (the ways a
  run did not drive as commanded);
- :attr:`Engine.name` (written in reports, bags, tick-log comments and study tables) and
  :attr:`Engine.options` (what it was made with).

Two engines implement it: :class:`KinematicEngine` (here: the wheels turn as commanded, slip
and floor errors from a :class:`~omnikin.simulation.error_models.NoiseModel`) and
:class:`omnikin.physics.engines.PhysicsEngine` (MuJoCo: rollers, motors, contacts; extra
``physics``). A name becomes an engine in one place, :func:`omnikin.physics.engines.engine_named`
(the lowest layer that sees both engines); only the argument parsers and the readers of files
that store the name call it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from ..control.time_optimal import WheelLimits
from ..kinematics.robot import Robot
from ..motion.limits import MotionLimits
from ..motion.plans import Plan
from ..motion.timing import SampledPlan, check_rate_range
from ..runtime.backends import WheelBackend
from ..sensors.readings import sensor_cost
from ..world.collision import Collider, Contact, Footprint
from ..world.model import World
from . import kinematic
from .error_models import NoiseModel, noise_profile
from .kinematic import RunCost, SimulatedRun

Progress = Callable[[float, float], None]
"""Called now and then with the simulated time and the plan's duration [s]."""


class SimulatedJoints(Protocol):
    """The joints of a robot as built whose wheels are simulated, not turned as commanded
    (:attr:`SimulatedBackend.joints`; physics: :class:`~omnikin.physics.simulator.PhysicsSim`)."""

    @property
    def wheel_angles(self) -> np.ndarray:
        """Angles ``(n,)`` [rad] of the rolling wheels (file order) since the start."""
        ...

    @property
    def wheel_speeds(self) -> np.ndarray:
        """Speeds ``(n,)`` [rad/s] of the rolling wheels (file order)."""
        ...

    @property
    def steer_angles(self) -> np.ndarray:
        """Steering angles ``(m,)`` [rad] of the steerable wheels (file order)."""
        ...

    @property
    def twist(self) -> np.ndarray:
        """True body twist ``(vx [m/s], vy [m/s], omega [rad/s])`` (body frame)."""
        ...


class SimulatedBackend(WheelBackend, Protocol):
    """A runtime wheel back-end on a simulated robot (:meth:`Engine.backend`): a
    :class:`~omnikin.runtime.backends.WheelBackend` that also knows where the robot truly is."""

    @property
    def truth(self) -> np.ndarray:
        """True pose ``(x [m], y [m], theta [rad])`` of the robot as built (world frame, heading
        wrapped to ``[-pi, pi)``)."""
        ...

    @property
    def start(self) -> np.ndarray:
        """Where the robot started, ``(x [m], y [m], theta [rad])`` in the world frame: the origin
        of its odometry (REP 105's odom; zero on an empty floor, the world's start pose in a world)."""
        ...

    @property
    def contacts(self) -> list[Contact]:
        """Where the robot began to touch a body of the world (empty on an empty floor)."""
        ...

    @property
    def joints(self) -> SimulatedJoints | None:
        """The simulated joints (physics: the wheels' and steering joints' true angles and
        speeds, and the body's true twist), or None when the wheels turn as commanded
        (kinematic: a front end draws them from the commands)."""
        ...

    @property
    def fallen(self) -> str:
        """One line saying how the robot fell (tipped over, could not stand) and that the back-end
        stopped its wheels; empty while it stands (kinematic: always, it cannot fall)."""
        ...


@runtime_checkable
class Engine(Protocol):
    """What simulates a robot as built (module docstring).

    Attributes
    ----------
    name : str
        The engine's name (``"kinematic"``, ``"physics"``): what reports, bags, tick logs and
        study tables store, and what :func:`omnikin.physics.engines.engine_named` reads.
    has_noise_model : bool
        True when the engine draws its random errors from a
        :class:`~omnikin.simulation.error_models.NoiseModel` (``--noise``); False when they come
        from the simulation itself (physics: the wheels' contacts, whole encoder ticks).
    measured_cost : bool
        True when :meth:`cost` builds and times the robot's model (seconds, not microseconds;
        its time steps dominate, a coarser step makes it cheaper): a caller sizing many small
        jobs treats a run of it as expensive.
    drives_as_commanded : bool
        True when every run on an empty floor drives as commanded by construction (kinematic);
        False when a run may not, and :meth:`problems` says how (physics: wheels lagging or
        slipping). In a world, a run that touched a wall or obstacle did not, in either engine
        (:func:`contact_problems`).
    default_noise : str or None
        The noise profile a run takes when none is given (None: no noise model).
    """

    name: ClassVar[str]
    has_noise_model: ClassVar[bool]
    measured_cost: ClassVar[bool]
    drives_as_commanded: ClassVar[bool]
    default_noise: ClassVar[str | None]

    @property
    def options(self) -> dict[str, Any]:
        """The options the engine was made with, by name (physics: ``step`` [s])."""
        ...

    def noise_model(self, noise) -> NoiseModel | None:
        """The random error model a run of this engine takes for the ``noise`` a user gave.

        Parameters
        ----------
        noise : str, NoiseModel or None
            A profile name of :data:`~omnikin.simulation.error_models.NOISE`, a model, or None
            (not given).

        Returns
        -------
        NoiseModel or None
            Kinematic: the model (a name looked up in
            :data:`~omnikin.simulation.error_models.NOISE`; None: :attr:`default_noise`,
            ``typical``). Physics: None.

        Raises
        ------
        InputError
            In one line: kinematic, an unknown profile name; physics, any ``noise`` but None (it
            has no random error model).
        """
        ...

    def check_rate(self, rate, name: str = "rate") -> float:
        """``rate`` checked as a sample rate the engine can read the encoders at.

        Parameters
        ----------
        rate : float
            Sample rate [Hz]; it must lie in :data:`~omnikin.motion.timing.RATE_RANGE` (5 Hz to
            10 kHz; physics: also a period of whole time steps, :meth:`PhysicsEngine.check_rate
            <omnikin.physics.engines.PhysicsEngine.check_rate>`).
        name : str
            What the rate is called in the error (the option or argument: ``--rate``).

        Returns
        -------
        float
            ``rate`` [Hz] as a float.

        Raises
        ------
        InputError
            In one line naming ``name``, when the engine cannot sample a run at ``rate``.
        """
        ...

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
        """One run of ``plan`` by ``true_robot`` (the robot as built) commanded by ``command_robot``.

        Parameters
        ----------
        plan : Plan or SampledPlan
            The path; a :class:`~omnikin.motion.plans.Plan` is timed and sampled for ``command_robot``
            at ``rate`` within ``limits`` (:func:`~omnikin.motion.timing.sample_plan`).
        true_robot, command_robot : Robot
            The robot as built and the model that commands it (the same wheels).
        rate : float
            Sample rate [Hz] of the encoders (:meth:`check_rate`).
        limits : MotionLimits, optional
            Speed and acceleration limits the plan is timed with.
        noise : NoiseModel, optional
            Random errors (:meth:`noise_model`; physics: None).
        rng : numpy.random.Generator, int or None
            The run's random stream: kinematic, its slip, floor and measurement noise (None:
            fresh entropy); physics, each rolling wheel's starting roller phase, drawn uniformly
            from ``[0, 1)`` of its roller period (None: every wheel at phase 0).
        progress : callable, optional
            Called with the simulated time and the plan's duration [s] now and then (physics;
            the kinematic engine's run is one vectorised computation and does not call it).
        sensor_rng : numpy.random.Generator or None
            The stream of the errors of the robot's IMUs and lidars (None: exact readings); the
            run's ``sensing`` holds what they read (a single run, in either engine).

        Returns
        -------
        SimulatedRun
            One trial: ``t`` ``(N + 1,)`` [s], ``ticks`` and ``readings`` ``(N + 1, n_enc)``,
            ``odometry`` ``(N + 1, 3)`` [m, m, rad], ``truth`` ``(1, N + 1, 3)``, ``measured``
            ``(1, 3)`` (world frame, starting at the origin).

        Raises
        ------
        InputError
            In one line: a rate the engine cannot sample at (:meth:`check_rate`), robots or a plan
            it cannot drive, a ``noise`` it does not take.
        """
        ...

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
        """The runtime's wheel back-end: ``true_robot`` (default ``robot``) simulated in real time,
        commanded and read with ``robot``'s wheels.

        Parameters
        ----------
        robot, true_robot : Robot
            The nominal model (wheel order, encoder scale of the readings) and the robot as built.
        noise : NoiseModel, optional
            Kinematic: the slip of the wheels (None: none, the robot moves exactly as its wheels
            turn). Physics: None (any other is refused in one line).
        rng : numpy.random.Generator, int or None
            Kinematic: the stream of the slip. Physics: not used (its back-end is deterministic).
        max_lag : float, optional
            Physics: the most simulated time [s] the back-end may lag the caller's clock before it
            drops time (None: never drops). Kinematic: not used (its back-end never lags).
        sensor_rng : numpy.random.Generator or None
            Physics: the stream of the errors of the robot's IMUs and lidars, which its back-end
            reads (``sensor_readings()``; None: exact). Kinematic: not used (its back-end reads
            no sensors yet).

        Returns
        -------
        SimulatedBackend
            A wheel back-end whose ``truth`` is the true pose ``(x [m], y [m], theta [rad])``.
        """
        ...

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
        """What one run of :meth:`drive` will take.

        Parameters
        ----------
        plan : Plan
            The path.
        true_robot, command_robot : Robot
            As for :meth:`drive`.
        rate : float
            Sample rate [Hz].
        budget : float, optional
            Physics: computing time [s] beyond which a model whose size alone says so is not
            built (its size bound is the estimate). Kinematic: not used.
        timed : bool
            False: only what is known without sampling the plan or building a model (the
            samples and memory of the plan; physics: ``seconds`` NaN), to refuse a run too
            large for memory before any of it is made. Kinematic: the same either way (its
            estimate never samples the plan).

        Returns
        -------
        RunCost
            ``samples``, ``bytes`` [bytes] at the peak, ``seconds`` [s] of computing time and
            ``simulated`` [s], the simulated time (physics: its upper bound).
        """
        ...

    def problems(self, run: SimulatedRun) -> list[str]:
        """The ways ``run`` did not drive as commanded.

        Parameters
        ----------
        run : SimulatedRun
            A run of this engine's :meth:`drive`.

        Returns
        -------
        list of str
            One phrase per problem (physics: wheels lagging or slipping, steering or rest not
            reached, :meth:`~omnikin.physics.run.PhysicsRun.problems`); empty when it drove as
            commanded (kinematic: always, it drives as commanded by construction).
        """
        ...

    def summary(self, run: SimulatedRun) -> dict[str, Any]:
        """The counts behind :meth:`problems`, for a JSON summary.

        Parameters
        ----------
        run : SimulatedRun
            A run of this engine's :meth:`drive`.

        Returns
        -------
        dict
            JSON-ready values by name (physics: :meth:`~omnikin.physics.run.PhysicsRun.summary`:
            saturated commands, the seconds each wheel lagged or slipped, the rim [m] each wheel
            fell short of its command, steering not reached, at rest); empty for the kinematic
            engine.
        """
        ...

    def motor_limits(self, robot: Robot) -> WheelLimits | None:
        """The wheel speed [rad/s], wheel acceleration [rad/s^2] and steering rate [rad/s] the
        engine's motors can give ``robot``, the least over its wheels.

        Parameters
        ----------
        robot : Robot
            The robot as built.

        Returns
        -------
        WheelLimits or None
            Physics: each motor's speed limit, its command ramp's rim acceleration over the
            wheel's radius, and the steering servos' rate, from the physical fields and their
            defaults (:func:`~omnikin.physics.description.describe`); None for the kinematic
            engine, whose wheels turn and steer as commanded.
        """
        ...


@dataclass(frozen=True)
class KinematicEngine(Engine):
    """The kinematic simulation (:mod:`omnikin.simulation.kinematic`): each wheel turns as its motor
    turns it when commanded, slip and floor errors from a noise model, the true robot's forward
    kinematics and exact SE(2) integration give the ground truth. It implements :class:`Engine`
    (the methods without a docstring of their own are documented there).

    Its one option is the ``world`` the robot drives in (None: an empty floor), with
    ``footprint_of``, what gives a robot's footprint there (the physics description's:
    :func:`omnikin.physics.engines.engine_named` passes it); in a world each run starts at the
    world's start pose and stops at first contact with a wall or obstacle
    (:class:`~omnikin.world.collision.Collider`), its contacts kept. The random errors are
    given to each run (:meth:`drive`'s ``noise``).
    :meth:`drive` is :func:`~omnikin.simulation.kinematic.simulate_kinematic`, :meth:`backend` a
    :class:`~omnikin.simulation.backend.SimBackend` (it never lags: ``max_lag`` does not apply),
    :meth:`cost` :func:`~omnikin.simulation.kinematic.run_cost` (computed without sampling the
    plan, so ``timed`` changes nothing and ``budget`` is not used).

    Attributes
    ----------
    name : str
        ``"kinematic"``.
    has_noise_model : bool
        True: the random errors come from a
        :class:`~omnikin.simulation.error_models.NoiseModel` (:meth:`noise_model`).
    measured_cost : bool
        False: :meth:`cost` is computed from the plan alone (microseconds).
    drives_as_commanded : bool
        True: :meth:`problems` is empty on an empty floor (in a world, the runs that touched
        its bodies).
    default_noise : str
        ``"typical"``, the profile of a run given no noise.
    """

    world: World | None = None
    footprint_of: Callable[[Robot], Footprint] | None = None

    name: ClassVar[str] = "kinematic"
    has_noise_model: ClassVar[bool] = True
    measured_cost: ClassVar[bool] = False
    drives_as_commanded: ClassVar[bool] = True
    default_noise: ClassVar[str | None] = "typical"

    def __post_init__(self):
        if self.world is not None and not isinstance(self.world, World):
            from ..errors import InputError

            raise InputError(f"world: expected an omnikin World, got {type(self.world).__name__}")
        if self.world is not None and self.footprint_of is None:
            from ..errors import InputError

            raise InputError("a kinematic engine in a world needs footprint_of (engine_named gives it)")

    @classmethod
    def made_with(
        cls,
        *,
        noise=None,
        step: float | None = None,
        world: World | None = None,
        footprint_of: Callable[[Robot], Footprint] | None = None,
    ) -> KinematicEngine:
        """The engine for the options a user gave (:func:`omnikin.physics.engines.engine_named`).

        Parameters
        ----------
        noise : str, NoiseModel or None
            Not checked here: :meth:`noise_model` checks it where a run takes it.
        step : float, optional
            Must be None: a time step [s] belongs to the physics engine.
        world : World, optional
            The world the robot drives in (None: an empty floor).
        footprint_of : callable, optional
            A robot's :class:`~omnikin.world.collision.Footprint`; needed with a ``world``.

        Returns
        -------
        KinematicEngine
            The engine (it has no options).

        Raises
        ------
        InputError
            In one line, when a ``step`` is given.
        """
        from ..errors import InputError

        if step is not None:
            raise InputError(
                "step (--step) is the time step of the physics engine: choose the physics engine (--engine physics) "
                "or leave the step out"
            )
        return cls(world, footprint_of)

    @property
    def options(self) -> dict[str, Any]:
        return {} if self.world is None else {"world": self.world}

    def collider(self, robot: Robot) -> Collider | None:
        """Where ``robot`` may go in the engine's world.

        Parameters
        ----------
        robot : Robot
            The robot as built (its footprint is asked of ``footprint_of``).

        Returns
        -------
        Collider or None
            Its footprint among the world's walls and obstacles; None on an empty floor.
        """
        if self.world is None or self.footprint_of is None:
            return None
        return Collider(self.world, self.footprint_of(robot))

    def noise_model(self, noise) -> NoiseModel:
        if isinstance(noise, NoiseModel):
            return noise
        return noise_profile(str(self.default_noise) if noise is None else noise)

    def check_rate(self, rate, name: str = "rate") -> float:
        return check_rate_range(rate, name)

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
        trials: int = 1,
        sensor_rng=None,
    ) -> SimulatedRun:
        """:meth:`Engine.drive` by :func:`~omnikin.simulation.kinematic.simulate_kinematic`, ``trials`` runs at
        once (each its own draw of the noise).

        Parameters
        ----------
        plan : Plan or SampledPlan
            The path; a :class:`~omnikin.motion.plans.Plan` is timed and sampled for ``command_robot``
            at ``rate`` within ``limits`` (:func:`~omnikin.motion.timing.sample_plan`).
        true_robot, command_robot : Robot
            The robot as built and the model that commands it (the same wheels).
        rate : float
            Sample rate [Hz] of the encoders, within :data:`~omnikin.motion.timing.RATE_RANGE`.
        limits : MotionLimits, optional
            Speed and acceleration limits the plan is timed with.
        noise : NoiseModel, optional
            Slip, floor and end-pose measurement errors (None: none; the encoders still count
            whole ticks).
        rng : numpy.random.Generator, int, sequence of them, or None
            The stream of the noise (None: fresh entropy), or one per trial.
        progress : callable, optional
            Not called: the run is one vectorised computation.
        trials : int
            Number of runs of the plan, each with its own draw of the noise.
        sensor_rng : numpy.random.Generator or None
            The stream of the errors of the robot's IMUs and lidars (None: exact readings); a
            single run keeps their readings (``sensing``), many trials none.

        Returns
        -------
        SimulatedRun
            ``t`` ``(N + 1,)`` [s], ``ticks`` and ``readings`` ``(N + 1, n_enc)`` and ``odometry``
            ``(N + 1, 3)`` [m, m, rad], the same for every trial (the encoders count the
            commanded turn; slip moves only the truth); ``truth`` ``(trials, N + 1, 3)`` and
            ``measured`` ``(trials, 3)`` of each trial (world frame, starting at the origin).

        Raises
        ------
        InputError
            In one line: a rate outside the range, ``trials`` not a whole number >= 1, robots
            whose wheels differ or a true wheel without encoder, a plan without motion.
        """
        return kinematic.simulate_kinematic(  # looked up in its module when called, as a stand-in there is
            plan,
            true_robot,
            command_robot,
            rate=rate,
            limits=limits,
            noise=noise,
            trials=trials,
            rng=rng,
            collider=self.collider(true_robot),
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
        from .backend import SimBackend

        collider = self.collider(true_robot or robot)
        start = (0.0, 0.0, 0.0) if self.world is None else self.world.start
        return SimBackend(robot, true_robot, noise, rng=rng, start=start, collider=collider)

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
        cost = kinematic.run_cost(plan, command_robot, rate)
        collider = self.collider(true_robot) if self.world is not None else None
        shapes = 0 if collider is None else len(collider.shapes.rects) + len(collider.shapes.circles)
        extra_bytes, extra_seconds = sensor_cost(true_robot, cost.simulated, shapes)
        return dataclasses.replace(cost, bytes=cost.bytes + extra_bytes, seconds=cost.seconds + extra_seconds)

    def problems(self, run: SimulatedRun) -> list[str]:
        return contact_problems(run)

    def summary(self, run: SimulatedRun) -> dict[str, Any]:
        return {}

    def motor_limits(self, robot: Robot) -> WheelLimits | None:
        return None


def contact_problems(run: SimulatedRun) -> list[str]:
    """One phrase per trial of ``run`` that touched a body of its world (the first contact
    named): in a world, such a run did not drive as commanded (empty on an empty floor)."""
    out = []
    for trial, contacts in enumerate(run.contacts):
        if contacts:
            first = contacts[0]
            which = f"trial {trial + 1} " if len(run.contacts) > 1 else ""
            more = f" ({len(contacts)} contacts)" if len(contacts) > 1 else ""
            out.append(f"{which}touched {first.body!r} at t = {first.time:.4g} s and stopped there{more}")
    return out
