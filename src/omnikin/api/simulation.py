"""``omnikin.simulate``: one simulated run, as ``omnikin simulate`` makes it."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..common.resource_limits import DEFAULT_MEMORY, DEFAULT_TIME
from ..kinematics.robot import Robot
from ..simulation.error_models import SystematicErrors
from ..simulation.kinematic import RunCost, SimulatedRun
from .common import as_built, require_callable, require_viz, robot_of

DEFAULT_PATH = "square cw rotate 4"
"""The path of ``omnikin simulate`` without ``--path``."""


@dataclass(frozen=True)
class Simulation:
    """A simulated run (:func:`simulate`): ``run`` holds the times [s], encoder ticks, odometry,
    ground truth and measured end pose (:class:`~omnikin.simulation.kinematic.SimulatedRun`);
    ``injected`` the systematic errors drawn (None for a given true robot).

    Attributes
    ----------
    robot : Robot
        The nominal robot: the model that commands the run and reads its encoders.
    true_robot : Robot
        The robot as built that drove it.
    injected : SystematicErrors or None
        The systematic errors drawn from the ``errors`` profile; None for a given ``true_robot``.
    path : str
        The path driven, in the runs-file grammar (or the plan's name).
    run : SimulatedRun
        Times ``t`` ``(N + 1,)`` [s]; encoder ``ticks`` and counter ``readings``
        ``(N + 1, n_enc)``; ``steer`` ``(N + 1, n_steer)`` [rad] or None; ``odometry``
        ``(N + 1, 3)`` and ground truth ``truth`` ``(1, N + 1, 3)`` poses ``(x, y, theta)``
        [m, m, rad] in the world frame (``odom``), starting at the origin; ``measured``
        ``(1, 3)`` the true end pose.
    end_error : ndarray, shape (3,)
        True end pose minus odometry end pose ``(x [m], y [m], theta [rad])``, world frame,
        ``theta`` wrapped to ``[-pi, pi)``.
    """

    robot: Robot
    true_robot: Robot
    injected: SystematicErrors | None
    path: str
    run: SimulatedRun

    @property
    def end_error(self) -> np.ndarray:
        """True end pose minus odometry end pose ``(x [m], y [m], theta [rad])``."""
        from ..kinematics.se2 import wrap_angle

        d = self.run.truth[0, -1] - self.run.odometry[-1]
        d[2] = wrap_angle(d[2])
        return d

    def plot(self):
        """True path and odometry [m] (a matplotlib ``Figure``)."""
        require_viz()
        from ..viz.runs import run_figure

        return run_figure(self.run, f"{self.robot.name}: {self.path}")


@dataclass(frozen=True)
class SimulationCost:
    """What a run of :func:`simulate` is estimated to cost, before it starts (its ``on_cost``).

    The physics engine is estimated in two steps: first before the plan is sampled
    (``duration`` and ``seconds`` None), then with its model built and timed (the same
    ``samples`` and ``memory``); the kinematic engine once, with everything.

    Attributes
    ----------
    samples : float
        Samples of the plan at the rate (an upper bound,
        :func:`~omnikin.simulation.kinematic.run_cost`).
    memory : float
        The run's arrays for those samples [bytes] (physics: with room for the longest tail the
        run may add after the plan).
    duration : float or None
        The simulated time [s] (physics: the run's, its steering waits and its tail at their
        limits); None before the physics engine is timed.
    seconds : float or None
        The wall time [s] of the run; None before the physics engine is timed.
    """

    samples: float
    memory: float
    duration: float | None
    seconds: float | None


def _cost_of(size: RunCost, estimate: RunCost) -> SimulationCost:
    """The :class:`SimulationCost` of an engine's estimates: ``size`` (untimed: the plan's samples
    and memory) and ``estimate`` (timed: the simulated duration [s] and the wall time [s])."""
    return SimulationCost(size.samples, size.bytes, estimate.simulated, estimate.seconds)


def simulate(
    robot,
    path=DEFAULT_PATH,
    *,
    true_robot=None,
    errors="typical",
    noise=None,
    seed: int = 1,
    rate: float = 100.0,
    engine="kinematic",
    step: float | None = None,
    max_memory: float = DEFAULT_MEMORY,
    max_time: float = DEFAULT_TIME,
    progress: Callable[[float, float], None] | None = None,
    on_cost: Callable[[SimulationCost], None] | None = None,
    sensors: bool = True,
) -> Simulation:
    """Simulate ``robot`` as built driving ``path`` commanded by its nominal model
    (``omnikin simulate``, without the bag).

    ``path``: a :class:`~omnikin.motion.plans.Plan` (plans add: ``line(4) + spin(math.pi)``) or a path
    in the runs-file grammar (:func:`omnikin.motion.plans.parse_plan`); ``true_robot`` (robot file or
    Robot) replaces the seeded draw of the
    ``errors`` profile; ``noise``: random errors (profile name or
    :class:`~omnikin.simulation.error_models.NoiseModel`; default ``"typical"``); ``rate`` [Hz], within
    :data:`~omnikin.motion.timing.RATE_RANGE` as for ``omnikin simulate``. The seed's first
    stream draws the robot as built (the same robot as ``omnikin umbmark --seed``), its second
    the run, as ``omnikin simulate`` does. A run estimated to need more than ``max_memory``
    [bytes] or ``max_time`` [s] is refused before it starts
    (:func:`~omnikin.simulation.kinematic.run_cost`, the estimate ``omnikin simulate`` checks
    against ``--max-memory`` and ``--max-time``).

    ``engine``: what drives the run, an :class:`~omnikin.simulation.engine.Engine` or its name
    (:func:`~omnikin.physics.engines.engine_named`, with ``step``). ``"physics"`` drives the
    robot as built in MuJoCo instead (:class:`~omnikin.physics.engines.PhysicsEngine`,
    ``omnikin simulate --engine physics``) at time step ``step`` [s] (default 2 ms): the same
    plan, rate and robot as built; ``noise`` must then be left out (the physics has no random
    error model).

    Parameters
    ----------
    robot : str, os.PathLike or Robot
        The nominal robot: a preset name, a robot file or a :class:`~omnikin.kinematics.robot.Robot`.
    path : str or Plan, default "square cw rotate 4"
        What to drive, from the origin along body +x.
    true_robot : str, os.PathLike or Robot, optional
        The robot as built, with the wheels of ``robot``; replaces the draw from ``errors``.
    errors : str or ErrorProfile, default "typical"
        Systematic-error profile the robot as built is drawn from (unused with ``true_robot``).
    noise : str or NoiseModel, optional
        Random errors of the kinematic engine; default ``"typical"``. Refused by the physics
        engine.
    seed : int, default 1
        Seed (>= 0) of the robot as built and the run.
    rate : float, default 100.0
        Sample rate [Hz] of encoders, odometry and ground truth, within
        :data:`~omnikin.motion.timing.RATE_RANGE`.
    engine : str or Engine, default "kinematic"
        What drives the run: an :class:`~omnikin.simulation.engine.Engine` or its name
        (``"kinematic"``, ``"physics"``).
    step : float, optional
        Physics time step [s]; default 2 ms. Physics only.
    max_memory : float, default DEFAULT_MEMORY
        Largest memory [bytes] the run may be estimated to need.
    max_time : float, default DEFAULT_TIME
        Largest run time [s] the run may be estimated to need.
    progress : callable, optional
        Called now and then with the simulated time and the plan's duration [s] (the engine's
        :meth:`~omnikin.simulation.engine.Engine.drive`: physics only; the kinematic run is one
        vectorised computation).
    on_cost : callable, optional
        Called with each estimate (:class:`SimulationCost`) before this function checks it
        against ``max_memory`` and ``max_time``; it may raise to refuse the run (``omnikin
        simulate`` checks it against its options, with the time of writing its outputs and the
        stamps its outputs can hold). An engine that knows the run's time without being timed
        (kinematic) is estimated once; one that must build its model first (physics) twice:
        its memory before the plan is sampled, then its duration and time.
    sensors : bool, default True
        Read the robot's IMUs and lidars into the run's ``sensing`` (False: the run reads none,
        saving their time and memory when nothing uses them; the motion and the other errors
        are the same either way).

    Returns
    -------
    Simulation
        The robots, the errors drawn, the path and the run.

    Raises
    ------
    InputError
        A bad path, rate, seed, profile or step, ``noise`` with the physics engine, or a
        ``true_robot`` with other wheels than ``robot``.
    InfeasibleTwistError
        A path the nominal robot cannot drive (e.g. a sideways leg for a differential drive).
    ResourceLimitError
        A run estimated to need more than ``max_memory`` or ``max_time``.
    PhysicsError
        The physics engine failed (:class:`~omnikin.errors.DivergedError`: MuJoCo's state diverged).
    """
    from ..common.resource_limits import require_within
    from ..evaluation.pipeline import RUN_STREAMS
    from ..evaluation.procedure import ARGUMENTS, streams
    from ..motion.plans import Plan, parse_plan
    from ..motion.timing import check_rate_range
    from ..physics.engines import as_engine

    require_callable(progress=progress, on_cost=on_cost)
    check_rate_range(rate, "rate")
    engine = as_engine(engine, noise=noise, step=step)
    noise_model = engine.noise_model(noise)
    nominal = robot_of(robot)
    if not sensors:
        nominal = dataclasses.replace(nominal, sensors=())
    plan = path if isinstance(path, Plan) else parse_plan(str(path))
    size = engine.cost(plan, nominal, nominal, rate=rate, timed=False)  # the plan's samples and memory
    seeds = streams(seed, RUN_STREAMS)
    true, injected = as_built(nominal, true_robot, errors, seeds["robot"])
    if not sensors:
        true = dataclasses.replace(true, sensors=())

    def within(**estimate) -> None:  # memory, seconds and what to change: refused beyond the limits
        samples = f"{size.samples:.3g} samples"
        require_within("simulate", max_memory=max_memory, max_time=max_time, names=ARGUMENTS, size=samples, **estimate)

    def told(estimate: SimulationCost) -> None:
        if on_cost is not None:
            on_cost(estimate)

    # an engine that must be timed to know the run's time (physics: its model built) is told of
    # the memory alone first, then of the duration and time once timed
    untimed = math.isnan(size.seconds)
    told(SimulationCost(size.samples, size.bytes, None, None) if untimed else _cost_of(size, size))
    sensing = "the sensors' rates or beams, " if any(s.type in ("imu", "lidar") for s in nominal.sensors) else ""
    within(memory=size.bytes, hint=f"lower rate, {sensing}or shorten path")  # before any of the run is made
    estimate = engine.cost(plan, true, nominal, rate=rate, budget=max_time)
    if untimed:
        told(_cost_of(size, estimate))
    cheaper = "shorten path or raise step" if engine.measured_cost else "lower rate or shorten path"
    cheaper = f"lower {sensing}{cheaper}" if sensing else cheaper
    within(seconds=estimate.seconds, hint=cheaper)
    # the run's stream draws its random errors, for an engine with a model of them; the sensors'
    # stream their errors: none under a noise model without random errors (--noise none), those
    # of the robot file's sensors in the physics engine (which takes no --noise)
    noisy_sensors = noise_model is None or not noise_model.is_zero
    run = engine.drive(
        plan,
        true,
        nominal,
        rate=rate,
        noise=noise_model,
        rng=seeds["run"] if noise_model else None,
        progress=progress,
        sensor_rng=np.random.default_rng(seeds["sensors"]) if noisy_sensors else None,
    )
    return Simulation(nominal, true, injected, path.name if isinstance(path, Plan) else str(path), run)
